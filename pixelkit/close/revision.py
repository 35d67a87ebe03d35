"""``pixelkit close`` as a whole: one close (``close.run.Closer``) per combination of the circuit
choices among the knobs, the best of them, and the files: the revision (when one passes) and the
path beside it, ``<stem>.close.json``."""
from __future__ import annotations

from ..errors import ConfigError
from .choices import choose
from .run import cpu_s


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
    r = choose(design, backend, jobs, scheduler, tell, say)
    r["cpu_s"] = cpu_s() - cpu0
    r["json"] = str(path)
    if r["passes"]:
        body = revision_text(design, r["overrides"], out, r)
        r["out"], r["out_sha256"] = str(out), digest(body)
    write_atomic(path, json.dumps(json_record(r), indent=1, default=json_default) + "\n")
    if r["passes"]:
        write_atomic(out, body)
    return r
