"""Pixel families other than the dual pixel: each a package with its design schema,
generators, stimuli, closed-form model, decoder and experiment.

- ``wdr``: the self-adjusting-exposure wide-dynamic-range pixel [Zhou2017]
- ``ratio``: the ratio-based translinear HDR pixel [Sun2016]
"""
