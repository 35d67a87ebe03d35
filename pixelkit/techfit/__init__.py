"""The technology's devices measured in ngspice: figures the analytic models take as arguments.

- ``ekv``: the EKV parameters of an NMOS size, fitted to the model library's own operating
  points (``models_for``: the pixel's follower, column load and row switch);
- ``pdcard``: whether a foundry photodiode card's reverse current is a thermal one.

They build decks with the kit's device generators (``circuits``) and run them (``spice``), so
they sit above both; ``tech`` only describes the process (docs/module-layers.md).
"""
