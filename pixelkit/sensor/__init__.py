"""Frame-level models: what a pixel decision does to the image and to the measured speed.

One concept per module:

- ``timing``: per-row reset, exposure and read times of global shutter, rolling
  readout and rolling electronic shutter (T_readout = N_row Row_length / f_pixclk).
- ``exposure``: the independent image path: a time-stepped exposure of moving
  rectangles, pixel by pixel and row by row (no closed form inside).
- ``rolling``: closed-form rolling-shutter sizes, edges and skew (the kit's
  derivation, and the published forms of [Rychazhnikov2008a] / [Rychazhnikov2008b] for comparison).
- ``compensation``: two opposite-scanning sensors undo the distortion.
- ``speed``: speed from a trace ([Thesis2019] eq. 2.1 - 2.5) and its error budget
  (eq. 2.6 - 2.11).
- ``double_exposure``: primary and secondary images of the dual pixel.
- ``lowgse``: the double exposure emulated on a conventional global-shutter
  sensor through its parasitic light sensitivity (GSE).
- ``trace``: trace extraction from a simulated image.
- ``pictures``: the figures.
"""
