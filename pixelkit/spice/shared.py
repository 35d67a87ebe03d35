"""Shared-library backend: PySpice's ``NgSpiceShared``, hardened.

As measured with PySpice 1.5 and ngspice 39:
- PySpice treats any stderr line that does not start with ``Warning:`` as an
  error, so successful gmin stepping or BSIM notes look like failures. Here the
  output is only collected; failure is decided from the run itself (a new plot
  with the full time axis) by the caller.
- Memory grows run after run unless the plots and circuits are removed:
  ``destroy all`` and ``remcirc`` after every run.
- One ngspice per process: the instance lives in a worker process (spawned,
  never forked from a parent that holds one); the pool recycles workers.
- The worker works in its own scratch folder (``scratch.worker_folder``) with
  the kit's ``.spiceinit``, entered before ngspice starts, so no ``.spiceinit``
  from the user's folder or home runs; model files are reached through links
  made there.
- The deck is handed to ``ngSpice_Circ`` split at ``\n`` only (PySpice's
  ``load_circuit`` splits with ``str.splitlines``, which also breaks at
  ``\v``, ``\f``, U+2028 ...; the writer refuses those characters anyway), and
  a refused deck is reported as a failed run with ngspice's own message, not as
  PySpice's ``NameError``.
"""
from __future__ import annotations

import logging
import os
import time

import numpy as np

from . import scratch

_ENGINE = None


def _library_hint():
    if "NGSPICE_LIBRARY_PATH" not in os.environ:
        for cand in ("/usr/lib/x86_64-linux-gnu/libngspice.so", "/usr/lib/x86_64-linux-gnu/libngspice.so.0",
                     "/usr/lib/aarch64-linux-gnu/libngspice.so.0", "/usr/lib/libngspice.so.0"):
            if os.path.exists(cand):
                os.environ["NGSPICE_LIBRARY_PATH"] = cand
                break


def _engine():
    global _ENGINE
    if _ENGINE is None:
        scratch.worker_folder()  # before ngspice reads any .spiceinit
        _library_hint()
        logging.getLogger("PySpice").setLevel(logging.CRITICAL)
        from PySpice.Spice.NgSpice.Shared import NgSpiceShared, ffi

        class Quiet(NgSpiceShared):
            """Collects ngspice's output; never turns a stderr note into an exception."""

            @staticmethod
            def _send_char(message_c, ngspice_id, user_data):
                self = ffi.from_handle(user_data)
                message = ffi.string(message_c).decode("utf-8", "replace")
                prefix, _, content = message.partition(" ")
                (self._stderr if prefix == "stderr" else self._stdout).append(content)
                return 0

        _ENGINE = Quiet.new_instance()
        _ENGINE.exec_command("set num_threads=1")
    return _ENGINE


def _vectors(ng, plot: str) -> dict:
    from PySpice.Spice.NgSpice.Shared import FFI, ffi
    lib = ng._ngspice_shared
    names_c = lib.ngSpice_AllVecs(plot.encode())
    out, i = {}, 0
    while names_c[i] != FFI.NULL:
        name = ffi.string(names_c[i]).decode()
        info = lib.ngGet_Vec_Info(f"{plot}.{name}".encode())
        n = info.v_length
        if info.v_compdata == FFI.NULL:
            arr = np.frombuffer(ffi.buffer(info.v_realdata, n * 8), dtype=np.float64).copy()
        else:
            tmp = np.frombuffer(ffi.buffer(info.v_compdata, n * 16), dtype=np.float64)
            arr = tmp[0::2] + 1j * tmp[1::2]
        out[name] = arr
        i += 1
    return out


def run_shared(deck_text: str, links: dict | None = None) -> tuple[list[dict], list[str], float]:
    """Run one deck in this process's ngspice; same return shape as ``run_batch``."""
    from PySpice.Spice.NgSpice.Shared import FFI, ffi
    ng = _engine()
    folder = scratch.worker_folder()
    scratch.set_links(folder, links or {})
    ng._stdout, ng._stderr = [], []
    before = set(ng.plot_names)
    t0 = time.perf_counter()
    keep = [ffi.new("char[]", ln.encode("ascii")) for ln in deck_text.split("\n") if ln.strip()]
    keep.append(ffi.new("char[]", b""))
    lib = ng._ngspice_shared
    scratch.mark_running(folder, os.getpid())
    try:
        rc = lib.ngSpice_Circ(ffi.new("char *[]", [*keep, FFI.NULL]))
        if rc == 0:
            lib.ngSpice_Command(b"run")
    finally:
        scratch.clear_running(folder)
    wall = time.perf_counter() - t0
    new = [p for p in ng.plot_names if p not in before and p != "const"]
    plots = [{"plotname": p, "data": _vectors(ng, p)} for p in new] if rc == 0 else []
    output = list(ng._stdout) + list(ng._stderr)
    if rc != 0:
        output.append(f"error: ngspice refused the deck (ngSpice_Circ returned {rc})")
    lib.ngSpice_Command(b"destroy all")
    lib.ngSpice_Command(b"remcirc")
    return plots, output, wall
