"""``pixelkit close`` as a whole: one close (``close.run.Closer``) per combination of the circuit
choices among the knobs, the best of them, and the files: the revision (when one passes) and the
path beside it, ``<stem>.close.json``."""
from __future__ import annotations

from ..errors import ConfigError
from .knobs import Space
from .run import Closer


def close_design(design, out, backend: str = "batch", jobs=None, scheduler=None, tell=None, say=None) -> dict:
    """``pixelkit close``: the loop (for each combination of circuit choices), then
    ``<out stem>.close.json`` (the path) beside ``out`` and, when a revision passes, ``out`` (its design
    file). Returns the result (``passes``, ``status``, ...)."""
    import json
    from pathlib import Path

    from ..fileio import check_output, json_default, write_atomic
    from .output import digest, json_record, revision_text
    from .yields import check_samples
    if design.close is None:
        raise ConfigError(design.source, "close", None, "a [close] table naming the knobs close may move "
                          "(docs/close.md)")
    if not design.spec:
        raise ConfigError(design.source, "spec", None, "a [spec] table with at least one spec (docs/verify.md)")
    out = check_output(Path(out))
    path = check_output(out.with_name(out.stem + ".close.json"))
    check_samples(design)
    cpu0 = cpu_s()
    r = _choose(design, backend, jobs, scheduler, tell, say)
    r["cpu_s"] = cpu_s() - cpu0
    r["json"] = str(path)
    if r["passes"]:
        body = revision_text(design, r["overrides"], out, r)
        r["out"], r["out_sha256"] = str(out), digest(body)
    write_atomic(path, json.dumps(json_record(r), indent=1, default=json_default) + "\n")
    if r["passes"]:
        write_atomic(out, body)
    return r


def cpu_s() -> float:
    """CPU seconds (user + system) of this process and of every child it waited for: with the batch
    backend, every ngspice run (the shared backend's pool workers count when they end)."""
    import resource
    me, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime


def _choose(design, backend, jobs, scheduler, tell, say) -> dict:
    """One close per combination of the circuit choices (one close without any); the best: the passing
    revision with the best objective, else the best compromise (the largest smallest margin)."""
    import itertools
    numeric = [k for k in design.close.knobs if not k.choices]
    choice = [k for k in design.close.knobs if k.choices]
    if not choice:
        return Closer(design, backend, jobs, scheduler, tell, say, numeric).run()
    runs = []
    for combo in itertools.product(*(k.choices for k in choice)):
        setting = {k.name: c for k, c in zip(choice, combo)}
        label = " [" + ", ".join(f"{k} = {v}" for k, v in setting.items()) + "]"
        (say or (lambda _t: None))(f"close{label}: solving the numeric knobs with this choice")
        base, active, left_out = _under(design, setting, numeric)
        r = Closer(base, backend, jobs, scheduler, tell, say, active, refuse_idle=False, label=label).run()
        r["setting"], r["left_out"], r["label"] = setting, left_out, label.strip(" []")
        runs.append(r)
    for k in numeric:
        if all(k.name in r["left_out"] or k.name in r["idle"] for r in runs):
            raise ConfigError(design.source, f"close.knobs.{k.name}", k.name, "a knob some spec depends on with "
                              "one of the choices: it moved no figure of any spec at its binding conditions with any")
    sense = design.close.goal[0]
    passing = [r for r in runs if r["passes"]]
    if passing:
        best = (min if sense == "min" else max)(passing, key=lambda r: r["objective"]["value"])
    else:
        best = max(runs, key=lambda r: -1e300 if r["smallest_margin_pct"] is None else r["smallest_margin_pct"])
    out = dict(best)
    out["overrides"] = {**best["setting"], **best["overrides"], **{k: None for k in best["left_out"]}}
    from .knobs import written
    absent = {k.name for k in numeric if _value(design, k.name) is None or not written(design, k.name)}
    out["knobs"] = ([{"key": k.name, "choices": list(k.choices), "start": str(_value(design, k.name)),
                      "value": best["setting"][k.name]} for k in choice]
                    + [dict(k, start="(absent)") if k["key"] in absent else k for k in best["knobs"]]
                    + [{"key": k, "start": str(_value(design, k)), "value": "(left out)"} for k in best["left_out"]])
    out["iterations"] = [dict(i, choice=r["label"]) for r in runs for i in r["iterations"]]
    out["spice_runs"] = sum(r["spice_runs"] for r in runs)
    out["spice_cached"] = sum(r["spice_cached"] for r in runs)
    out["wall_s"] = sum(r["wall_s"] for r in runs)
    out["choices"] = [{"choice": r["label"], "status": r["status"], "passes": r["passes"],
                       "objective": r["objective"]["value"], "objective_shown": r["objective"]["shown"],
                       "smallest_margin_pct": r["smallest_margin_pct"], "left_out": r["left_out"], "idle": r["idle"],
                       "conflict": (r.get("conflict") or {}).get("text"), "chosen": r is best} for r in runs]
    return out


def _value(design, key):
    from ..verify.close_table import value_of
    return value_of(design, key)


def _under(design, setting: dict, numeric: list):
    """(the design with the choices of ``setting``, the numeric knobs it has, those it leaves out): a
    knob the design file refuses with this choice (pixel.v_gate with gate_drive = "supply") is left out,
    an absent one starts at the middle of its bounds."""
    from ..sweep.space import design_with
    space = Space(tuple(numeric))
    x0, _notes = space.start(design)
    values = {**setting, **space.overrides(x0)}
    left_out: list = []
    names = {k.name for k in numeric}
    pl = getattr(design, "post_layout", None)
    while True:
        try:
            base = design_with(design, values)
            if pl is not None:   # the post-layout view, as the command asked
                from ..layout.pex.overlay import post_layout_view
                base = post_layout_view(base, pl.afe)
            break
        except ConfigError as exc:
            if exc.field in names and values.get(exc.field) is not None:
                values[exc.field] = None
                left_out.append(exc.field)
                continue
            key = next(iter(setting))
            raise ConfigError(design.source, f"close.knobs.{key}.choices", setting[key],
                              f"a choice the design can take ({exc.field} = {exc.value!r}: expected {exc.allowed})"
                              ) from None
    return base, [k for k in numeric if k.name not in left_out], left_out
