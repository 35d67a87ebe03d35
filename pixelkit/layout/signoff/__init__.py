"""Sign-off: the technology's DRC deck fetched and checked (``decks``) and run by KLayout in batch
mode (``drc``); the kit's LVS with KLayout's Python API (``lvs``) against the kit's netlist of the
drawn cells (``schematic``)."""
