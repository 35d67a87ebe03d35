"""Bright sources: pixels far beyond full well, with and without anti-blooming.

A headlight at night puts pixels 10 - 1000x beyond full well. Per array, with EC holding
the PD in reset while the rows wait (``timing.ec_hold``, anti-blooming) and without, at
1 - 1000 full wells over the array's own ``t_int``, on a dual column of a frame with its
AFE (rows dark, bright, dark; the bright charge carried over the experiment window, and the
pixel's real light after the exposure ends, ``circuits.array.array_bench``):

- **output**: the bright row's double-sampled signal (and the AFE's output), as a fraction
  of the full-well signal. Double sampling subtracts a reset level taken after FD is reset;
  if charge keeps reaching FD after that reset, the reset level falls and the pixel reads
  *dark*: the "black sun" (``black_sun``: below half the full-well signal).
- **charge onto FD after its reset**: from RST opening to the reset-level sample,
  ``C_FD`` dV_FD in electrons, against what the storage node's own shielding lets in over
  that time (I / gse, ``physics.fd.pls_current``: the independent part). The excess is
  the PD overflowing through TG (blooming), which anti-blooming removes.
- **recovery**: the dark row read after the bright one minus the dark row read before it
  (column and AFE output).

``holds``: the anti-blooming settings run, ``True`` / ``False`` forced on both arrays, ``None``
each array's own (``timing.ec_hold``; off where the design does not set it). The report's quick
profile runs the design as it is; the full profile both settings.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..constants import Q

#: Over-exposure factors, in full wells over the array's own t_int.
FACTORS = (1.0, 10.0, 100.0, 1000.0)
QUICK_FACTORS = (1.0, 1000.0)
#: Anti-blooming on and off, forced on both arrays.
HOLDS = (True, False)
#: Below this fraction of the full-well signal an over-exposed pixel reads as a black sun.
BLACK_SUN = 0.5
KINDS = ("primary", "secondary")
ROWS = 3          # dark, bright, dark
#: bright sources of the storage-light table, in times the background
STORAGE_FACTORS = (1e3, 1e4, 1e5)
#: single wavelengths of the storage-light table (nm)
LINES_NM = (450, 550, 650, 750, 850, 950)


def full_well_current(design, kind: str) -> float:
    """The photocurrent that takes the PD by the design's swing over its t_int (A)."""
    from .scene import i_floor
    sub = getattr(design, kind)
    return i_floor(design, kind, sub.t_int, design.pixel.v_pd_reset - design.pixel.swing)


def _with_hold(design, hold: bool):
    return replace(design, **{k: replace(getattr(design, k), timing=replace(getattr(design, k).timing, ec_hold=hold))
                              for k in KINDS})


def _anti_blooming(design, kind: str) -> bool:
    return bool(getattr(design, kind).timing.ec_hold)


def decks(design, factors=FACTORS, holds=HOLDS) -> list:
    """(design run, factor, array, deck): one frame deck per factor, anti-blooming setting and array: the
    array's first column of a dual column, ``ROWS`` rows (dark, ``factor`` full wells, dark) with its AFE, the
    charge of the array's t_int over the experiment window and its real light after it. One deck per array,
    as the frame's reference (``chip.frame``: the arrays share only ideal sources; in one deck their two row
    clocks interleave every step, ~30 % more CPU), and one column (:func:`_first_column`)."""
    from ..circuits.array import Tile, array_bench
    t_w = design.experiment.t_window
    comp = {k: getattr(design, k).t_int / t_w for k in KINDS}
    fw = {k: full_well_current(design, k) * comp[k] for k in KINDS}   # as simulated in the window
    n = design.secondary_per_pixel
    out = []
    for hold in holds:
        d = design if hold is None else _with_hold(design, hold)
        for f in factors:
            ip = np.array([[0.0], [f * fw["primary"]], [0.0]])
            is_ = np.array([[0.0] * n, [f * fw["secondary"]] * n, [0.0] * n])
            for kind in KINDS:
                net = array_bench(d, ip, is_, tile=Tile((kind,), tuple(range(ROWS)), (0,)), t_exp=t_w,
                                  with_afe=True, compression=comp,
                                  title=f"bright_{'design' if hold is None else 'ab' if hold else 'noab'}_{f:g}_{kind}")
                out.append((d, f, kind, _first_column(net, kind, n)))
    return out


def _first_column(net, kind: str, n: int):
    """``net`` without the elements of the array's other columns: the figures read column 0, and the
    secondary's other columns of the dual column (``col_s_1`` ...) are copies of it under the same
    light that share only ideal sources with it (``circuits.array``: own bias, load, sampler and AFE;
    no coupling between the columns of one array's deck), 2/3 of the deck's time."""
    others = [f"col_s_{j}" for j in range(1, n)] if kind == "secondary" else []

    def theirs(node):
        return any(node == c or node.endswith(f"_{c}") for c in others)
    return replace(net, elements=tuple(e for e in net.elements if not any(map(theirs, e.nodes))))


def figures(design, factors=FACTORS, backend="batch", jobs=None, holds=HOLDS) -> list[dict]:
    """Per array, anti-blooming setting and factor: the bright row's output (column and AFE),
    the charge onto its FD after RST (the reset-level droop, e-) against its own light, and the
    next dark row's recovery."""
    from ..camera.spicenoise import sf_gain
    from ..circuits.array import frame_timings
    from ..measure.pixel import levels
    from ..physics.fd import pls_current, response
    from ..spice import simulate_many
    from ..techfit.ekv import models_for
    plan = decks(design, factors, holds)
    res = simulate_many([net for *_, net in plan], backend=backend, jobs=jobs, failed="keep")
    a_sf = sf_gain(design)
    sf_models = models_for(design)
    c_fd = {k: response(design, k, a_sf, sf_models)["c_fd_F"] for k in KINDS}
    tm = frame_timings(design, design.experiment.t_window, ROWS)
    out, full = [], {}
    for (d, f, kind, _), r in zip(plan, res):
        s = "p" if kind == "primary" else "s"
        hold = _anti_blooming(d, kind)
        row = {"array": kind, "anti_blooming": hold, "full_wells": f,
               "current_A": f * full_well_current(design, kind)}
        if isinstance(r, Exception):
            out.append({**row, "failed": r.message})
            continue
        t, col = tm[kind], f"col_{s}_0"
        sig = [levels(r, col, t, k) for k in range(ROWS)]
        ds = [b - a for a, b in sig]
        afe = [float(r.at(f"out_{col}", t.t_reset_level(k))) for k in range(ROWS)]
        fd = f"x{s}_1_0.fd"
        t0, t1 = t.rst_window(1)[1] + t.edge, t.t_reset_level(1)
        droop = float(r.at(fd, t0)) - float(r.at(fd, t1))
        row.update(signal_V=ds[1], afe_V=afe[1], reset_level_V=sig[1][1],
                   fd_after_reset_e=c_fd[kind] * droop / Q,
                   fd_light_e=pls_current(design, row["current_A"], kind) * (t1 - t0) / Q,
                   recovery_V=ds[2] - ds[0], recovery_afe_V=afe[2] - afe[0])
        if f == 1.0:
            full[(hold, kind)] = ds[1]
        out.append(row)
    for row in out:
        ref = full.get((row["anti_blooming"], row["array"]))
        if "signal_V" in row and ref:
            row["of_full_well_signal"] = row["signal_V"] / ref
            row["black_sun"] = bool(row["of_full_well_signal"] < BLACK_SUN)
    return out


def storage_lights(design) -> dict:
    """The lights of the storage table: the scene's halogen, a white LED, single wavelengths."""
    from ..physics.photo import Spectrum
    out = {f"halogen {design.scene.spectrum_temperature:g} K": Spectrum.blackbody(design.scene.spectrum_temperature),
           "white LED": Spectrum.white_led()}
    out.update({f"{nm} nm": Spectrum.monochromatic(nm * 1e-9) for nm in LINES_NM})
    return out


def storage_table(design, swing: dict, a_sf: float, response=None, factors=STORAGE_FACTORS, halo=None) -> list[dict]:
    """The storage node's light over a frame's readout, around a bright source: per array, light (the
    scene's halogen, a white LED, single wavelengths) and source (``factors`` x the background, as the
    sizing's background photocurrent), the charge FD collects while the last row waits
    ((rows - 1) row times, the source lit then) and the column signal it makes (A_sf q / C_FD per
    electron, linear, clipped at the measured ``swing``), with geometric light (the drawn mask opening,
    ``pixel.gse``) and, given the collection model's ``response``, modelled (each light's effective
    opening and GSE, ``layout.pex.lightfigures``). Under the source the pixels' exposure saturates; the
    rows are what a source lit only while the frame is read leaves (an LED headlight's PWM off during
    the exposure), and what the storage node adds to a pixel the exposure did not saturate.

    Those figures are every pixel lit at the source's level (the model's periodic cell). Given also the
    model's ``halo`` (``layout.pex.halo``), the source imaged on one dual pixel: its own storage node with
    its neighbours dark (``alone_*``) and the storage node of its worst neighbour (``neighbour_*``: the
    halo, carriers from the lit pixel; ``neighbour``: the offset in cells)."""
    from ..optimize.sizing import light
    from ..physics.fd import capacitances
    j_bg = light(design).j_bg
    drawn = {"primary": design.primary.area if design.primary.mask_opening is None else design.primary.mask_opening,
             "secondary": design.secondary.area if design.secondary.mask_opening is None else design.secondary.mask_opening}
    c_fd = {k: capacitances(design, k, a_sf)["c_fd_F"] for k in KINDS}
    lights = storage_lights(design)
    figs, halos = {}, {}
    if response is not None:
        from ..layout.pex.lightfigures import figures
        figs = {name: figures(design, response, spec) for name, spec in lights.items()}
        if halo is not None:
            from ..layout.pex.halo import figures as halo_figures
            halos = {name: halo_figures(design, response, halo, spec) for name, spec in lights.items()}
    rows = []
    for kind in KINDS:
        sub = getattr(design, kind)
        t = (sub.rows - 1) / sub.f_read
        for name in lights:
            for f in factors:
                row = {"array": kind, "light": name, "source_x_background": f, "wait_s": t}

                def put(prefix, area, gse):
                    electrons = f * j_bg * area / gse * t / Q
                    v = a_sf * electrons * Q / c_fd[kind]
                    row[f"{prefix}_gse"] = gse
                    row[f"{prefix}_fd_e"] = electrons
                    row[f"{prefix}_of_swing"] = min(v / swing[kind], 1.0)
                put("geometric", drawn[kind], design.pixel.gse)
                if name in figs:
                    fg = figs[name]
                    area = fg["primary_area_m2"] if kind == "primary" else fg["effective_opening_m2"]
                    put("modelled", area, fg["gse_primary"] if kind == "primary" else fg["gse_secondary"])
                    if name in halos:
                        hg = halos[name][kind]
                        put("alone", area, hg["gse_alone"])
                        put("neighbour", area, hg["gse_neighbour"])
                        row["neighbour"] = hg["neighbour"]
                rows.append(row)
    return rows
