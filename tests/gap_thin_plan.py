"""A thinned surrogate build plan, so a test can run ``pixelkit gap surrogate`` end to end in ~20 decks.

The full plan (``pixelkit.gap.buildplan``: 22 grid charges, three temperatures, eight light currents, nine
perturbation sites at up to six amplitudes and twelve charges) runs ~350 decks, minutes on two cores. The
thinned plan keeps every kind of unit and both rounds of the build (the validation decks on the dual-pixel
bench first, whose reset levels pivot the ``col_g`` site's decks), with fewer of each: the code path the
command runs is the full one, its tables are coarser, and the error the surrogate states (measured on its
validation decks) is the coarser tables' own.

``python tests/gap_thin_plan.py ARGS`` runs ``pixelkit ARGS`` under the thinned plan (what the test runs in
a subprocess); ``thin(setattr)`` applies it in a process (``monkeypatch.setattr``), for reading the written
file back (the file's key is the key of the plan's decks).
"""
from __future__ import annotations

import sys

N_GRID = 12
#: (module, attribute) -> value; the sites kept: a charge site, the conductance site whose decks wait for the
#: first round's pivots, a capacitance site; one amplitude each (the tables' largest)
PLAN = {
    ("buildplan", "N_GRID"): N_GRID,
    ("buildplan", "VAL_PICK"): (3, 7, 9),
    ("buildplan", "VAL_T_PICK"): (1,),
    ("buildplan", "TEMP_OFFSETS_K"): (28.0,),
    ("buildplan", "TEMP_Q_PICK"): (0, 4, 8, 11),
    ("buildplan", "LIGHT_Q_PICK"): (4, 8),
    ("responses", "Q_PICK"): (0, 6, 11),
}
SITES_KEPT = ("fd", "col_g", "c_fd")


def _largest(amps):
    return lambda arr, q_max: (max(amps(arr, q_max), key=abs),)


def thin(setattr) -> None:
    """Apply the thinned plan through ``setattr(module, name, value)``."""
    from pixelkit.gap import buildplan, responses
    mods = {"buildplan": buildplan, "responses": responses}
    for (mod, name), value in PLAN.items():
        setattr(mods[mod], name, value)
    setattr(buildplan, "LIGHT_I", buildplan.LIGHT_I[:1])
    setattr(responses, "SITES", {k: responses.Site(s.kind, s.edit, _largest(s.amps))
                                 for k, s in responses.SITES.items() if k in SITES_KEPT})


if __name__ == "__main__":
    thin(setattr)
    from pixelkit.cli import entry
    sys.argv = ["pixelkit", *sys.argv[1:]]
    entry()
