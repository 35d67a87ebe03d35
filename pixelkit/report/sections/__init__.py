"""Sections of the design report (``pixelkit report``): one module and one template block each.

How to add a section
====================

1. Write one module ``pixelkit/report/sections/<key>.py`` exposing::

       TITLE = "Noise"                       # the heading in the report

       def build(ctx: Context) -> Section:    # compute, draw, return
           r = my_capability(ctx.design, quick=ctx.quick, backend=ctx.backend, jobs=ctx.jobs)
           fig = ctx.figure("noise_spectrum.png")          # a path beside the HTML
           my_plot(r, fig)                                 # write the picture there
           return Section(
               TITLE,
               text=["One paragraph: what was simulated, against what independent path."],
               tables=[Table("noise_budget", "Noise budget (e- rms)",
                             ["source", "primary", "secondary"],
                             [["kTC", 31.2, 16.4], ["SF", 8.0, 8.0]])],
               figures=[Figure(fig.name, "Output-referred noise spectrum")],
               checked=[Checked("noise.read_e", 35.1, "e-", tol_rel=0.02, tol_abs=0.5)],
               data={"spectrum_V2_per_Hz": r.psd.tolist()})

   - ``ctx.design``: the frozen Design; ``ctx.quick``: the light test profile (fewer points,
     no long sweeps; every table and figure must still appear); ``ctx.backend`` / ``ctx.jobs``:
     pass them to ``simulate_many``; ``ctx.progress(stage, done, total)``: tell the terminal
     where you are; ``ctx.shared(name, fn)``: a result other sections reuse, computed once
     (``ctx.experiment()`` is the thesis [Thesis2019] experiment, ``ctx.measured`` the ``--measured`` CSV
     or None).
   - Every ``Table`` is written as ``<name>.csv`` beside the HTML and every ``data`` dict as
     ``data_<key>.json``: the data behind each figure and table. Table cells are numbers or text.
   - Every ``Checked`` figure goes to ``summary.json`` under its ``name`` (unique over the
     report: prefix it with your key). The revision diff (``--baseline``) compares it against
     the baseline's value with the tolerance stated here: it has moved when
     ``|new - old| > max(tol_rel * |old|, tol_abs)``, and then the command exits non-zero.
     Tables are diffed cell by cell too (reported, not failing).
   - Other files you write beside the HTML (a GDS, netlists: ``ctx.figure("netlists/x.cir")``)
     go in ``files`` (relative paths) so the section cache keeps them too.
   - When your capability cannot run for this design, return
     ``Section.unavailable(TITLE, "why, in one sentence")``: the report says so plainly. When it
     needs an input the user did not give, return ``Section.needs_input(TITLE, "--measured", "what
     it adds")``: the report and the command's summary say which input (never "failed").
   - A figure far outside what a modern pixel of its kind reaches goes in ``flags`` with the
     reason ("read noise 402 e-: ..."): the section shows it boxed, summary.json lists it.
   - ``ctx.reference`` is True when the design is the test chip of [Thesis2019]
     (``experiments.reference``): only then set the dissertation's printed values beside the kit's.
   - A section that reads a file besides the design exposes ``inputs(ctx) -> dict`` (e.g. that file's
     hash): the section cache keys on it too.
   - Raise PixelkitError for user errors; any other exception is shown in the section as
     "failed: ..." and the rest of the report still builds (and the command exits non-zero).

2. Optionally add one template block ``pixelkit/report/templates/sections/<key>.html.j2``.
   It receives ``s`` (your Section) and ``f`` (number formatting: ``f(x)`` -> 4 significant
   digits); ``{% include "sections/_generic.html.j2" %}`` renders the default (text, tables,
   figures in order). Without a file the generic block is used.

3. If ``<key>`` is already in ``REGISTRY`` below (a planned section), you are done: the
   report switches from "not yet available" to your section. Otherwise add one
   ``(key, title, owner)`` entry in ``REGISTRY`` where it belongs in the reading order.

Section outputs are cached (key: the pixelkit source tree, the design's content, the
options), so a re-run with nothing changed rebuilds nothing.
"""
from __future__ import annotations

import importlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

#: Reading order of the report: (module key, title, who provides it).
#: A planned section whose module does not exist yet says "not yet available".
REGISTRY: list[tuple[str, str, str]] = [
    ("signoff", "Sign-off: specs over corners, Monte Carlo yield, power", "report"),
    ("closure", "Design closure (pixelkit close)", "issue 40 (close)"),
    ("summary", "Design summary", "report"),
    ("schematics", "Schematics of the generated circuits", "report"),
    ("model_vs_spice", "Analytic model vs SPICE (fig. A.1 - A.3)", "report"),
    ("sizing", "Sizing: mask opening and integration times", "report"),
    ("afe", "AFE transfer and its error", "report"),
    ("array", "2 x 2 array readout (fig. 3.13)", "report"),
    ("bright", "Bright sources: over-exposure, black sun, blooming", "issue 27 (timing, settling, over-exposure)"),
    ("layout", "Layout", "report"),
    ("layout_signoff", "Layout sign-off", "issue 29 (readout layout, arrays, shield)"),
    ("post_layout", "Post-layout vs schematic", "issue 30 (extraction)"),
    ("light_map", "Light map: what the shield leaves open", "issue 30 (extraction)"),
    ("light", "Light collection: the masked secondary and the storage node by wavelength", "issue 48 (light)"),
    ("noise", "Noise", "issue 11 (noise / virtual camera)"),
    ("camera", "Virtual camera: EMVA 1288 figures", "issue 11 (noise / virtual camera)"),
    ("frame", "Frame-level models", "issue 15 (frame-level models)"),
    ("variation", "Sweeps, corners and Monte Carlo", "issue 14 (sweeps / corners / Monte Carlo)"),
    ("gap", "Sim-to-real diagnosis (--measured)", "report"),
    ("inputs", "Input checks: plausibility and model library", "issue 9 (hostile input)"),
    ("reproducibility", "Reproducibility", "report"),
]

#: The report of a pixel read by role (families ``pixel4t`` and ``netlist``: docs/pixel4t.md): its sign-off
#: and its figures against their derivations; the dual pixel's sections do not apply to it.
ROLE_REGISTRY: list[tuple[str, str, str]] = [
    ("signoff", "Sign-off: specs over corners, Monte Carlo yield, power", "report"),
    ("pixel", "The pixel read by role: figures against their derivations", "issue 47 (pixel)"),
]


@dataclass
class Table:
    name: str                 # file stem of the CSV, unique in the report
    caption: str
    columns: list[str]        # with units, e.g. "C_jdep (fF)"
    rows: list[list[Any]]


@dataclass
class Figure:
    file: str                 # file name beside the HTML (from ctx.figure(...).name)
    caption: str


@dataclass
class Checked:
    name: str                 # unique over the report, "<section key>.<figure>"
    value: float              # in ``unit`` (SI unless the unit says otherwise)
    unit: str
    tol_rel: float = 0.0
    tol_abs: float = 0.0
    note: str = ""


@dataclass
class Section:
    title: str
    text: list[str] = field(default_factory=list)
    tables: list[Table] = field(default_factory=list)
    figures: list[Figure] = field(default_factory=list)
    checked: list[Checked] = field(default_factory=list)
    data: dict = field(default_factory=dict)
    files: list[str] = field(default_factory=list)   # other files written beside the HTML (relative paths)
    available: bool = True
    why: str = ""             # why not available (or why it failed)
    failed: bool = False
    key: str = ""             # filled in by the builder
    needs: str = ""           # the input the user did not give (an option or a design-file table)
    flags: list[str] = field(default_factory=list)   # implausible figures, each with its reason

    @classmethod
    def unavailable(cls, title: str, why: str) -> "Section":
        return cls(title, available=False, why=why)

    @classmethod
    def needs_input(cls, title: str, needs: str, why: str) -> "Section":
        """The section needs ``needs`` (e.g. ``--measured``), which the user did not give."""
        return cls(title, available=False, needs=needs, why=why)

    @property
    def status(self) -> str:
        """available | failed | needs <input> | not yet available (summary.json, the CLI, the HTML)."""
        if self.available:
            return "available"
        if self.failed:
            return "failed"
        return f"needs {self.needs}" if self.needs else "not yet available"


@dataclass
class Context:
    design: Any
    out_dir: Path
    quick: bool = False
    backend: str = "batch"
    jobs: int | None = None
    measured: Path | None = None
    progress: Callable[..., None] = lambda stage, done=None, total=None: None
    waves: tuple = ()         # specs whose waveform the sign-off shows besides the failing ones ("all": every one)
    exhaustive: bool = False   # no early stop anywhere (the sign-off's Monte Carlo runs its full count)
    _memo: dict = field(default_factory=dict)
    _started: dict = field(default_factory=dict)

    def figure(self, name: str) -> Path:
        """Where to write a picture (or any file) called ``name`` (beside the HTML)."""
        path = self.out_dir / name
        path.parent.mkdir(parents=True, exist_ok=True)
        return path

    def shared(self, name: str, fn: Callable[[], Any]) -> Any:
        """Compute ``fn()`` once per report and hand the same object to every section (the result
        of ``start(name, ...)`` when that started it: waited for, its error raised here)."""
        if name not in self._memo:
            started = self._started.pop(name, None)
            self._memo[name] = started.result() if started is not None else fn()
        return self._memo[name]

    def start(self, name: str, fn: Callable[[], Any]) -> None:
        """Run ``fn()`` in a background thread from now on (a section's ``prefetch``); ``shared(name,
        ...)`` hands its result over. Only SPICE and numbers there: no pictures (matplotlib is not
        thread-safe), no other section's ``shared`` results."""
        import threading
        from concurrent.futures import Future
        if name in self._memo or name in self._started:
            return
        fut: Future = Future()

        def run():
            try:
                fut.set_result(fn())
            except BaseException as exc:  # noqa: BLE001 - handed to whoever asks for the result
                fut.set_exception(exc)

        self._started[name] = fut
        threading.Thread(target=run, name=f"report-{name}", daemon=True).start()

    def background(self) -> bool:
        """Whether work started by ``start`` is still running."""
        return any(not f.done() for f in self._started.values())

    def status(self, name: str) -> Callable[[int, int, str], None]:
        """A ``status(done, total, what)`` callback for long work (``verify``'s): ``progress_text``
        shows its count and an estimate of its time left."""
        import time
        t0 = time.monotonic()

        def tell(done: int, total: int, what: str) -> None:
            self._memo.setdefault("_status", {})[name] = (done, total, what, time.monotonic() - t0)
        return tell

    def progress_text(self) -> str:
        """What the long work told ``status``: "sign-off 120/345 tasks, ~1:20 left (now ...)"."""
        out = []
        for name, (done, total, what, elapsed) in list(self._memo.get("_status", {}).items()):
            if total and done < total:
                left = elapsed / done * (total - done) if done else None
                eta = f", ~{int(left // 60)}:{int(left % 60):02d} left" if left is not None else ""
                out.append(f"{name} {done}/{total} tasks{eta}" + (f" (now {what})" if what else ""))
        return "; ".join(out)

    @property
    def reference(self) -> bool:
        """Whether the design is the test chip of [Thesis2019] (then the report compares with it)."""
        if "reference" not in self._memo:
            from ...experiments.reference import is_reference
            self._memo["reference"] = is_reference(self.design)
        return self._memo["reference"]

    def experiment(self) -> dict:
        """The thesis experiment (fig. A.1 - A.3) of the design."""
        from ...experiments.thesis import run_experiment
        return self.shared("experiment", lambda: run_experiment(self.design, backend=self.backend,
                                                                jobs=self.jobs))


def load_section(key: str):
    """The module of section ``key``, or None when it has not been written yet."""
    try:
        return importlib.import_module(f"{__name__}.{key}")
    except ModuleNotFoundError as exc:
        if exc.name == f"{__name__}.{key}":
            return None
        raise
