"""Shipped surrogates: the nominal surrogate of a design, stored with the key of the decks that made it.

Building the surrogate runs 355 full-chain decks (``buildplan``: packed four chains to a deck;
3.6 min on two cores at a light load). For the designs the kit ships, ``surrogates/<design>.json`` holds the
built surrogate and the key of its decks: the SHA-256 of every deck's text
(the col_g site decks with the stored reset levels as pivots), of the content
of the model files they read and of the ngspice version. ``load_nominal``
uses a stored surrogate only when its key is the key of the decks this kit
would run for the design, and only after a check against fresh SPICE runs:

- ``check_decks``: four full-chain decks at charges between the sweep's grid
  points, one plain and three with a perturbation on each chain (every site of
  ``responses`` and the readout-light current on vm; the op-amp's gain on every
  chain of the last, with each chain's own site) at amplitudes between
  the tables'; every probe must match the stored tables within ``CHECK_TOL_V``
  plus the surrogate's stated error (plain deck) or plus ``CHECK_TOL_REL`` of
  the response (perturbed decks).

Otherwise (no file, another key, a failed check: said on stderr) the surrogate
is built from SPICE; the engine's cache keeps its decks. ``pixelkit gap
surrogate DESIGN`` rebuilds and writes the file. The kit ships the reference design's
(``dual_pixel_revA``) and the thesis [Thesis2019] read's.
"""
from __future__ import annotations

import hashlib
import json
import sys
from pathlib import Path

import numpy as np

from . import responses
from . import buildplan
from .nominal import ARRAYS, Nominal, build_nominal, grids, predict

STORE_DIR = Path(__file__).with_name("surrogates")
CHECK_TOL_V = 0.5e-3
CHECK_TOL_REL = 0.02
FORMAT = 2


def deck_key(design, pivots: dict) -> str:
    """The key of the decks ``build_nominal`` runs for ``design`` (site pivots as given): the text of decks of
    every kind of unit (``buildplan``: sweep, temperature, readout light, each site, the validation decks) at
    the first of its charges, every unit (its charge, amplitude, temperature), every grid charge
    and the packing's version. A deck between those differs from them only in its units, which the key
    holds (all decks' text cost seconds of a cold diagnosis); the check decks then run fresh SPICE at
    charges between the grid's."""
    from ..spice.batch import ngspice_version
    from ..tech.modellib import content_fingerprint
    g = grids(design)
    allu = [u for a in ARRAYS for u in buildplan.validation_units(a) + buildplan.units(design, g, a)]
    ends = {}
    for u in allu:
        ends.setdefault((u.array, u.kind, u.site, u.dT), []).append(u)
    sample = [u for us in ends.values() for u in us if u.k == min(v.k for v in us)]
    nets = [j.net for j in buildplan.jobs(design, g, sample, pivots)]
    h = hashlib.sha256(f"format {FORMAT}\0ngspice {ngspice_version()}\0".encode())
    h.update(repr(([g[a].tolist() for a in ARRAYS], buildplan.PACKING, sorted(pivots.items()),
                   [(u.array, u.kind, u.k, u.site, u.j, u.amp, u.dT) for u in allu])).encode())
    for n in nets:
        h.update(n.text().encode())
        h.update(b"\0")
    h.update(content_fingerprint(tuple(sorted({str(inc.file) for n in nets for inc in n.includes}))).encode())
    return h.hexdigest()


def _pivots(nom: Nominal) -> dict:
    return nom.pivots or {a: float(nom.v_rst[a].mean()) for a in ARRAYS}


def path_for(design) -> Path:
    return STORE_DIR / f"{design.name}.json"


def write(design, nom: Nominal, path: Path | None = None) -> Path:
    from ..fileio import write_atomic
    path = path or path_for(design)
    doc = {"format": FORMAT, "design": design.name, "key": deck_key(design, _pivots(nom)), "nominal": nom.as_dict()}
    return write_atomic(path, json.dumps(doc, sort_keys=True))


def read(design, path: Path | None = None) -> Nominal | None:
    """The stored surrogate of ``design`` when its key is the key of this kit's decks, else None."""
    path = path or path_for(design)
    try:
        doc = json.loads(path.read_text())
        nom = Nominal.from_dict(doc["nominal"], design.tech.photodiode)
    except (OSError, ValueError, KeyError, TypeError):
        return None
    if doc.get("format") != FORMAT or doc.get("key") != deck_key(design, _pivots(nom)):
        return None
    return nom


# the check decks: per chain, (site, grid index after which the charge lies halfway, amplitude: a fraction of
# the site's largest, or the current on the AFE's vm for "i_vm"); None = the plain deck. The op-amp's gain
# (a_ol) is one macromodel shared by every AFE of a deck: the last deck carries it on every chain, on top of
# each chain's own site (``A_OL_CHECK``; predicted as the two terms together, as a two-effect fit does). Four
# decks: two rounds of the engine's two jobs on 2 cores.
CHECK = (
    {"primary": None, "s0": None, "s1": None, "s2": None},
    {"primary": ("fd", 9, 0.3), "s0": ("col_g", 15, 0.8), "s1": ("load", 9, -0.8), "s2": ("p1_vm", 12, 0.8)},
    {"primary": ("rst_fd", 9, 0.8), "s0": ("i_vm", 11, -11.5e-9), "s1": ("i_vm", 6, 3e-9), "s2": ("fd", 13, 0.6)},
    {"primary": ("sf_w", 11, 0.25), "s0": ("c11", 12, -0.7), "s1": ("c_fd", 5, -0.35), "s2": ("c_fd", 8, 0.5)},
)
A_OL_CHECK = 0.15      # the last deck's op-amp gain change, a fraction of the a_ol table's largest (4.5: ~1 % of AFE gain; its product with a chain's own site, which the tables do not hold, stays below 0.2 mV)
PLAIN_K = {"primary": 6, "s0": 13, "s1": 4, "s2": 17}


def check_decks(design, nom: Nominal) -> list:
    """[(deck, chains, {chain index: (charge, terms)})]: see the module docstring."""
    from . import chains as ch
    from . import circuit_edits as ce
    mid = {a: (nom.q_grid[a][1:] + nom.q_grid[a][:-1]) / 2 for a in ARRAYS}
    out = []
    for j, spec in enumerate(CHECK):
        q = {s: mid[responses_arr(s)][PLAIN_K[s] if v is None else v[1]] for s, v in spec.items()}
        net, cs = ch.standard(design, q["primary"], tuple(q[s] for s in SUBS[1:]), f"gapcheck{j}")
        want = {}
        for i, (s, v) in enumerate(spec.items()):
            arr = responses_arr(s)
            if v is None:
                want[i] = (q[s], None)
            elif v[0] == "i_vm":
                net = ce.add_to_subckt(net, cs[i].afe, ce.vm_current(design, arr, v[2]))
                want[i] = (q[s], {"i_vm": v[2]})
            else:
                amp = v[2] * max(abs(x) for x in responses.SITES[v[0]].amps(arr, nom.q_grid[arr][-1]))
                net = responses.SITES[v[0]].edit(net, design, cs[i], amp, _pivots(nom))
                want[i] = (q[s], {v[0]: amp})
        if j == len(CHECK) - 1:
            amp = A_OL_CHECK * max(abs(x) for x in responses.SITES["a_ol"].amps("primary", nom.q_grid["primary"][-1]))
            net = responses.SITES["a_ol"].edit(net, design, cs[0], amp, _pivots(nom))
            want = {i: (q, dict(terms or {}, a_ol=amp)) for i, (q, terms) in want.items()}
        out.append((net, cs, want))
    return out


def responses_arr(s: str) -> str:
    return "primary" if s == "primary" else "secondary"


SUBS = ("primary", "s0", "s1", "s2")


def check(design, nom: Nominal, backend: str = "batch") -> dict:
    """Largest deviation of fresh SPICE from the stored surrogate on the check decks, and whether it passes."""
    from ..circuits.testbench import timings
    from ..measure.pixel import levels
    from ..spice import simulate_many
    from .nominal import t_float
    decks = check_decks(design, nom)
    res = simulate_many([d for d, _, _ in decks], backend=backend)
    tm = timings(design, design.experiment.t_window)
    worst, ok, rows = 0.0, True, []
    for r, (_, cs, want) in zip(res, decks):
        for i, (q, terms) in want.items():
            arr, col, s = cs[i].array, cs[i].col, cs[i].col
            f_read = getattr(design, arr).f_read
            X = {"arr": np.array([ARRAYS.index(arr)] * 2), "q": np.array([q, q]), "afe": np.array([False, True]),
                 "t_float": np.full(2, t_float(design, f_read, arr))}
            want_v = predict(nom, X, terms)
            got = np.array([levels(r, col, tm[arr])[0], float(r.at(cs[i].out, tm[arr].t_reset_level(0)))])
            base = predict(nom, X)
            tol = CHECK_TOL_V + (CHECK_TOL_REL * np.abs(want_v - base) if terms else
                                 np.array([nom.error["pixel_max_V"], nom.error["afe_max_V"]]))
            dev = np.abs(got - want_v)
            rows.append({"chain": s, "site": terms and "+".join(terms), "deviation_V": dev.tolist(),
                         "tolerance_V": np.broadcast_to(tol, (2,)).tolist()})
            worst = max(worst, float(np.max(dev)))
            ok &= bool(np.all(dev <= tol))
    return {"passed": ok, "max_deviation_V": worst, "decks": len(decks), "probes": rows}


def load_nominal(design, backend: str = "batch") -> Nominal:
    """The stored surrogate when it is this kit's and passes ``check``; else one built from SPICE."""
    nom = read(design)
    if nom is not None:
        c = check(design, nom, backend)
        if c["passed"]:
            nom.error = dict(nom.error, store_check=c)
            return nom
        sys.stderr.write(f"pixelkit: warning: the stored surrogate {path_for(design)} deviates from SPICE by "
                         f"{c['max_deviation_V'] * 1e3:.2f} mV on its check decks; building it from SPICE\n")
    return build_nominal(design, backend)
