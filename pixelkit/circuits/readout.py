"""The readout as the layout draws it: the AFE with its transistor-level op-amp as one cell per
column, each column's circuit with its AFE, and the arrays with their readout.

These are the simulation's own subcircuits (``afe.sc_afe``, ``opamp.opamp_ota``,
``column.column_cell``, ``dual_pixel``) connected as ``array.array_bench`` connects them
(each column: its load bias, its load, the S1X / S2X samplers to the AFE input, the AFE), with
one change a layout needs: an ideal current source cannot be drawn, so the op-amp's bias
source ``Ib`` is left out and the node it fed becomes a pin (``nb``), where a reference
current enters - as the column's ``nbias`` already does. The AFE always draws the OTA: a
behavioural macromodel has no layout.
"""
from __future__ import annotations

from ..spice.netlist import Element, Subckt
from .afe import PORTS as AFE_PORTS, sc_afe
from .column import CELL_PORTS, column_cell, pre_clock
from .opamp import PORTS as OPAMP_PORTS, ota
from .rowdriver import NAME as DRIVER, boosted, driven_lines, driver_input

BIAS = "nb"
KINDS = ("primary", "secondary")
SUFFIX = {"primary": "p", "secondary": "s"}


def exposed_bias(sc: Subckt, name: str, pin: str = BIAS) -> Subckt:
    """``sc`` without its ideal current sources; the node they fed (not a supply) becomes ``pin``."""
    fed = {e.nodes[1] for e in sc.elements if e.name.upper().startswith("I")}
    if len(fed) != 1:
        raise ValueError(f"{sc.name}: expected one biased node, found {sorted(fed)}")
    node = fed.pop()
    elems = tuple(Element(e.name, tuple(pin if n == node else n for n in e.nodes), e.value, e.params)
                  for e in sc.elements if not e.name.upper().startswith("I"))
    return Subckt(name, (*sc.ports, pin), elems, sc.params, sc.models)


def opamp_cell(design) -> Subckt:
    """``opamp_ota`` with its bias pin (``inp inn out vdd nb``)."""
    return exposed_bias(ota(design), "opamp_ota_cell")


def afe_cell(design, kind: str = "secondary") -> Subckt:
    """The AFE as drawn (``afe_<kind>``: one per column pitch, the same circuit): ``sc_afe`` on the
    OTA, ports ``in out vref p1 p1b p2 p2b vdd nb``."""
    sc = sc_afe(design)
    elems = tuple(Element(e.name, (*e.nodes, BIAS), "opamp_ota_cell") if e.value in ("opamp_ota", "opamp_macro")
                  else e for e in sc.elements)
    return Subckt(f"afe_{kind}", (*AFE_PORTS, BIAS), elems, sc.params)


#: ports of a column's readout (its circuit and its AFE): the column circuit's, the AFE's
#: clocks, reference and bias, and its output (and the precharge clock ``pre`` of an array that has one)
READOUT_PORTS = ("vdd", "col", "nbias", "s1", "s1b", "s2", "s2b", "vref", "p1", "p1b", "p2", "p2b", "nb", "out")


def readout_cell(design, kind: str) -> Subckt:
    """One column's readout: ``column_<kind>`` whose sampler output is the AFE input."""
    pre = pre_clock(design, kind)
    col = Element("Xcol", ("vdd", "col", "nbias", "in", "s1", "s1b", "s2", "s2b", *pre), f"column_{kind}")
    afe = Element("Xafe", ("in", "out", "vref", "p1", "p1b", "p2", "p2b", "vdd", "nb"), f"afe_{kind}")
    return Subckt(f"readout_{kind}", (*READOUT_PORTS, *pre), (col, afe))


def readout_cells(design) -> list:
    """The subcircuits below a readout: op-amp, AFE, column circuits, readouts (children first)."""
    return [opamp_cell(design), afe_cell(design, "primary"), afe_cell(design, "secondary"),
            column_cell(design, "primary"), column_cell(design, "secondary"),
            readout_cell(design, "primary"), readout_cell(design, "secondary")]


def chip_ports(design, rows: int, cols: int, afe: bool) -> tuple:
    """Pins of an R x C array with its readout, as its layout brings them to the edge."""
    n = design.secondary_per_pixel
    out = ["vdd", "vpdr", "vrst", "ec_p", "tg_p", "ec_s", "tg_s"]
    out += [f"{k}_{r}" for r in range(rows) for k in ("rs_p", "rst_p", "rs_s", "rst_s")]
    ncol = {"primary": cols, "secondary": n * cols}
    for kind in KINDS:
        s = SUFFIX[kind]
        out += [f"{c}_{s}" for c in ("s1", "s1b", "s2", "s2b")]
        out += pre_clock(design, kind, f"pre_{s}")
        if afe:
            out += [f"{c}_{s}" for c in ("p1", "p1b", "p2", "p2b")]
        for j in range(ncol[kind]):
            out.append(f"nbias_{s}_{j}")
            out += [f"nb_{s}_{j}", f"out_{s}_{j}"] if afe else [f"out_{s}_{j}"]
    if afe:
        out.append("vref")
    if boosted(design):   # the gate-drive choice: each driven line's driver input is the pin, the rail a pin
        driven = set(driven_lines(rows))
        out = [driver_input(p) if p in driven else p for p in out] + ["vgate"]
    return tuple(out)


def chip(design, rows: int, cols: int, afe: bool) -> Subckt:
    """The R x C array (``array.pixel_array``'s connections: EC and TG global, RST and RS per
    row) with every column's circuit and, ``afe``, its AFE (``array.array_bench``'s); with the
    boosted gate drive the row drivers (``circuits.rowdriver``) between the pins ``<line>_in`` and
    the EC / TG / RST lines, on the rail ``vgate``."""
    from .array import pixel_array
    n = design.secondary_per_pixel
    arr = pixel_array(design, rows, cols)
    elems = [Element("Xarr", arr.ports, arr.name)]
    ncol = {"primary": cols, "secondary": n * cols}
    for kind in KINDS:
        s = SUFFIX[kind]
        pre = pre_clock(design, kind, f"pre_{s}")
        for j in range(ncol[kind]):
            col = f"col_{s}_{j}"
            if afe:
                elems.append(Element(f"Xro_{s}{j}", ("vdd", col, f"nbias_{s}_{j}", f"s1_{s}", f"s1b_{s}", f"s2_{s}",
                                                     f"s2b_{s}", "vref", f"p1_{s}", f"p1b_{s}", f"p2_{s}", f"p2b_{s}",
                                                     f"nb_{s}_{j}", f"out_{s}_{j}", *pre), f"readout_{kind}"))
            else:
                elems.append(Element(f"Xc_{s}{j}", ("vdd", col, f"nbias_{s}_{j}", f"out_{s}_{j}", f"s1_{s}",
                                                    f"s1b_{s}", f"s2_{s}", f"s2b_{s}", *pre), f"column_{kind}"))
    if boosted(design):   # the row drivers on the boosted rail (circuits.rowdriver)
        elems += [Element(f"Xdrv_{line}", (driver_input(line), line, "vdd", "vgate"), DRIVER)
                  for line in driven_lines(rows)]
    return Subckt(f"chip_{rows}x{cols}{'_afe' if afe else ''}", chip_ports(design, rows, cols, afe), tuple(elems))


__all__ = ["afe_cell", "opamp_cell", "readout_cell", "readout_cells", "chip", "chip_ports", "CELL_PORTS",
           "OPAMP_PORTS", "READOUT_PORTS"]
