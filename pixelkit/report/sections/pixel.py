"""The pixel read by role (families ``pixel4t`` and ``netlist``): its figures beside their derivations.

What ``pixelkit simulate`` prints for such a design (``families.<family>.experiment``: the role
measurements of ``rolepix``, the decks ``verify`` runs), as the report's tables and pictures: every
figure with the closed form it is checked against where the family has one (the 4T generator's:
``families.pixel4t.model``, ``physics.ppd``; a designer's netlist has none), the CDS output against
the charge (the ladder), and for the 4T the charge left in the PPD against the TG level and the
transfer curve, SPICE against the closed form.
"""
from __future__ import annotations

from . import Checked, Figure, Section, Table

TITLE = "The pixel read by role: figures against their derivations"

#: (key of the experiment, label, unit, key of its derivation or None, relative / absolute diff tolerance)
ROWS = (
    ("conversion_gain_uV_per_e", "conversion gain at the S/H", "uV/e-", "conversion_gain_model_uV_per_e", 0.01, 0.0),
    ("full_well_e", "full well at the CDS output", "e-", None, 0.01, 0.0),
    ("read_noise_e", "read noise, true CDS (.noise)", "e-", None, 0.02, 0.0),
    ("image_lag_pct", "image lag (of the bright frame)", "%", None, 0.0, 0.01),
    ("image_lag_e", "image lag", "e-", "image_lag_model_e", 0.0, 2.0),
    ("dark_current_e_per_s", "dark current", "e-/s", "dark_current_model_e_per_s", 0.03, 0.0),
    ("power_chip_W", "array power", "W", "power_estimate_W", 0.01, 0.0),
)


def _family(design) -> str:
    from ...family import family_of
    return family_of(design.source)


def _experiment(ctx) -> dict:
    from ...family import FAMILIES, _attr
    fam = _family(ctx.design)
    module, name = FAMILIES[fam][2], FAMILIES[fam][3]
    return ctx.shared("pixel.experiment", lambda: _attr(module, name)(ctx.design, backend=ctx.backend, jobs=ctx.jobs))


def _save(ctx, fig, ax, xlabel: str, ylabel: str, name: str):
    import matplotlib.pyplot as plt
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.legend()
    ax.grid(True, which="both", alpha=0.3)
    path = ctx.figure(name)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def _plots(ctx, r: dict) -> list[Figure]:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    out = []
    lad = r["ladder"]
    fig, ax = plt.subplots(figsize=(5.5, 3.6))
    ax.loglog(lad["electrons"], [max(v, 1e-6) for v in lad["signal_V"]], "o-", label="SPICE (CDS output)")
    cg = r["conversion_gain_uV_per_e"] * 1e-6
    ax.loglog(lad["electrons"], [n * cg for n in lad["electrons"]], "--", label="conversion gain x charge")
    path = _save(ctx, fig, ax, "electrons in the window", "CDS output (V)", "pixel_ladder.png")
    out.append(Figure(path.name, "The CDS output against the charge in the window: linear at the conversion "
                                 "gain, then saturated (the full well)"))
    tc = r.get("transfer_curve") or {}
    if "t_s" in tc:
        fig, ax = plt.subplots(figsize=(5.5, 3.6))
        ax.semilogy([t * 1e6 for t in tc["t_s"]], tc["spice_e"], "o", label="SPICE (PPD charge node)")
        ax.semilogy([t * 1e6 for t in tc["t_s"]], tc["model_e"], "-", label="closed form Q(t)")
        path = _save(ctx, fig, ax, f"time into a TG pulse at {tc['tg_high_V']:.2f} V (us)", "electrons in the PPD",
                     "pixel_transfer.png")
        out.append(Figure(path.name, "Charge transfer over the TG-edge barrier: the PPD's charge against the "
                                     "thermionic-emission closed form (docs/pixel4t.md)"))
    return out


def build(ctx) -> Section:
    from ...family import ROLE_FAMILIES
    fam = _family(ctx.design)
    if fam not in ROLE_FAMILIES:
        return Section.unavailable(TITLE, "the dual pixel's figures are in the sections below")
    r = _experiment(ctx)
    rows, checked = [], []
    for key, label, unit, model, rel, ab in ROWS:
        if key not in r:
            continue
        d = r.get(model) if model else None
        rows.append([label, unit, r[key], "-" if d is None else d])
        checked.append(Checked(f"pixel.{key}", float(r[key]), unit, tol_rel=rel, tol_abs=ab,
                               note=f"{label}; derivation {d:.4g}" if d is not None else label))
    tables = [Table("pixel_figures", "The pixel's figures (SPICE) and their derivations", ["figure", "unit", "SPICE",
                                                                                            "derivation"], rows)]
    text = [f"Family '{fam}': the role measurements (docs/pixel4t.md), the decks 'pixelkit verify' runs at the "
            "nominal condition."]
    if fam == "pixel4t":
        pf = r["ppd_full_well"]
        rows.append(["PPD full well in bright light (charge node)", "e-", pf["spice_e"], pf["model_e"]])
        rows.append(["FD kT/C a non-correlated read would add", "e-", "-", r["fd_ktc_ncds_e"]])
        checked.append(Checked("pixel.ppd_full_well_e", float(pf["spice_e"]), "e-", tol_rel=0.005,
                               note=f"the PPD's charge node; overflow balance {pf['model_e']:.5g} e-"))
        tables.append(Table("pixel_lag_vs_tg", "Electrons the read's transfer leaves in the PPD against the TG high "
                                               "level (a frame at half the full well)",
                            ["TG high (V)", "barrier (V)", "tau (s)", "SPICE (e-)", "closed form (e-)"],
                            [[x["tg_high_V"], x["barrier_V"], x["tau_s"], x["left_spice_e"], x["left_model_e"]]
                             for x in r["lag_vs_tg"]]))
        text.append("The pinned photodiode is behavioural (GF180MCU has no pinned implant); its parameters are "
                    "stand-ins typical of the class, not a process's measurements (docs/pixel4t.md).")
    else:
        text.append("A designer's netlist has no closed forms: its figures are SPICE's alone.")
    flags = []
    if r["read_noise_e"] > 10:
        flags.append(f"read noise {r['read_noise_e']:.3g} e-: a 4T pixel with true CDS reads a few electrons")
    return Section(TITLE, text=text, tables=tables, figures=_plots(ctx, r), checked=checked,
                   data={k: v for k, v in r.items() if k != "wall_s"}, flags=flags)
