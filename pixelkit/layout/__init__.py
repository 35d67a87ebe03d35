"""Layout of the pixel and its column, drawn from the netlist and signed off.

Rooms: the technology as the generators see it (``techview``: rules by name, ``canvas``: shapes
with nets and spacing checks), the device primitives (``primitives``), routing (``route``), one
generator per circuit (``pixel``: the 5T subpixel, ``dual``: the dual pixel, ``columns``: the
column circuit and the dual pixel with its columns), the library of cells (``library``), the
checks before drawing (``rules``, ``fit``), extraction and pictures (``extract``, ``compare``,
``render``), the command's flow (``flow``) and sign-off (``signoff``: the foundry deck's fetch
and DRC run, the kit's LVS). docs/layout-signoff.md says what is checked by what.
"""
