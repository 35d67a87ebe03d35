"""Pixel families other than the dual pixel: each a package with its design schema,
generators, stimuli, closed-form model, decoder and experiment.

- ``wdr``: the self-adjusting-exposure wide-dynamic-range pixel (SEEDS_BRIEF section 4)
- ``ratio``: the ratio-based translinear HDR pixel (SEEDS_BRIEF section 5)
"""
