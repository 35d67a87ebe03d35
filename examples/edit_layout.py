"""Edit the GF180 reference layout the way a designer does in KLayout, for docs/tutorial.md.

    python examples/edit_layout.py IN.gds OUT.gds move-line [remove-via] [open-shield]

Run with any Python that has KLayout's module (``pip install klayout``; the kit's environment has it),
or paste the body of an edit into KLayout's macro editor. The edits, on the layout that
``pixelkit layout designs/dual_pixel_gf180.toml --afe`` writes (coordinates in um, cell-local):

- ``move-line``: the secondary subpixel's RST row line (metal3, y 4.36 - 4.64) moved 0.1 um up,
  toward the VRST line (y 4.97): 0.23 um apart where the foundry asks 0.28 (M3.2a), and its via
  pad no longer enclosing the via2 under it;
- ``remove-via``: the via2 that joins the secondary's TG gate stack to its TG row line (at 7.48,
  3.715) deleted: the transfer gates float;
- ``open-shield``: a strip of the top-metal shield over the secondary columns' circuits opened
  (cell SHIELD_READOUT_S, y 373.745 - 378.045: over the P-channel samplers and their n-well).

Each edit checks that what it changes is there first, so a drawing that moved makes this script
fail rather than edit something else.
"""
import sys

import klayout.db as kdb


def _layer(ly, layer, datatype):
    li = ly.find_layer(layer, datatype)
    if li is None:
        sys.exit(f"edit_layout: the layout has no layer {layer}/{datatype}")
    return li


def move_line(ly):
    cell = ly.cell("SECONDARY")
    m3 = _layer(ly, 42, 0)
    line = next((s for s in cell.shapes(m3).each() if s.bbox().bottom == 4310 and s.bbox().width() == 8000), None)
    if line is None:
        sys.exit("edit_layout: no RST line (metal3 from y 4.31 um, 8 um wide) in SECONDARY")
    line.transform(kdb.Trans(0, 100))         # database units of 1 nm: 0.1 um up


def remove_via(ly):
    cell = ly.cell("SECONDARY")
    v2 = _layer(ly, 38, 0)
    via = next((s for s in cell.shapes(v2).each() if s.bbox() == kdb.Box(7480, 3715, 7740, 3975)), None)
    if via is None:
        sys.exit("edit_layout: no via2 at (7.48, 3.715) um in SECONDARY")
    cell.shapes(v2).erase(via)


def open_shield(ly):
    cell = ly.cell("SHIELD_READOUT_S")
    if cell is None:
        sys.exit("edit_layout: no cell SHIELD_READOUT_S (draw the chip with --afe and the full shield)")
    m5 = _layer(ly, 81, 0)
    strip = kdb.Region(kdb.Box(0, 373745, 8000, 378045))
    shield = kdb.Region(cell.shapes(m5))
    if (shield & strip).area() != strip.area():
        sys.exit("edit_layout: the shield does not cover the strip to open")
    cell.shapes(m5).clear()
    cell.shapes(m5).insert(shield - strip)


EDITS = {"move-line": move_line, "remove-via": remove_via, "open-shield": open_shield}

if __name__ == "__main__":
    if len(sys.argv) < 4 or any(e not in EDITS for e in sys.argv[3:]):
        sys.exit(__doc__)
    layout = kdb.Layout()
    layout.read(sys.argv[1])
    for edit in sys.argv[3:]:
        EDITS[edit](layout)
    layout.write(sys.argv[2])
