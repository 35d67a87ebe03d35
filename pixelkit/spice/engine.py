"""Run netlists: options, cache, backends, retries and parallel workers.

``simulate(netlist)`` runs one deck, ``simulate_many(netlists, jobs=N)`` runs many
over the machine's cores (threads driving ngspice processes for the batch
backend; spawned worker processes, each with one shared ngspice, for the shared
backend). Both return :class:`Result` objects in input order.

Retry policy: a run that fails (no convergence, timestep too small, truncated
time axis) is re-run once with the looser options of ``options.RETRIES``; the
result then says so in ``meta["retried"]``. A run that still fails raises
:class:`SimulationError` naming the deck, the analysis and ngspice's message.
"""
from __future__ import annotations

import atexit
import multiprocessing as mp
import os
from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor
from contextlib import contextmanager
from dataclasses import replace

import numpy as np

from ..errors import SimulationError
from . import cache as cache_mod
from . import flatlib, scratch
from .batch import abort_runs, ngspice_version, run_batch
from .netlist import Netlist
from .options import DEFAULTS, RETRIES, failure_lines, merged
from .result import Result, vector_key

BACKENDS = ("batch", "shared")
_POOL = None


def _pool(jobs: int) -> ProcessPoolExecutor:
    global _POOL
    if _POOL is None or _POOL._max_workers != jobs:
        if _POOL is not None:
            _POOL.shutdown(wait=True)
        _POOL = ProcessPoolExecutor(max_workers=jobs, mp_context=mp.get_context("spawn"),
                                    max_tasks_per_child=200, initializer=scratch.worker_init,
                                    initargs=(str(scratch.root()), os.getpid()))
    return _POOL


def _stop_everything():
    """On an interrupt: kill running ngspice processes and shared-backend workers, drop queued runs."""
    global _POOL
    abort_runs()
    if _POOL is not None:
        for proc in list(getattr(_POOL, "_processes", {}).values()):
            proc.terminate()
        # no cancel_futures: the broken pool fails the queued futures itself (cancelling them
        # too races with that and prints an InvalidStateError traceback on Python 3.11)
        _POOL.shutdown(wait=False)
        _POOL = None


@atexit.register
def _close_pool():
    if _POOL is not None:
        _POOL.shutdown(wait=False, cancel_futures=True)


def _shared_worker(job):
    from .shared import run_shared
    return run_shared(*job)


def default_jobs() -> int:
    """``$PIXELKIT_JOBS`` (set by the CLI's ``--jobs``), else the machine's cores, at most 8."""
    env = os.environ.get("PIXELKIT_JOBS", "")
    return int(env) if env.isdigit() and int(env) > 0 else max(1, min(os.cpu_count() or 1, 8))


def _prepare(net: Netlist, options) -> Netlist:
    opts = merged(DEFAULTS, net.options)
    if options:
        opts = merged(opts, options)
    return replace(net, options=opts)


def _to_result(net: Netlist, plots, lines, wall, backend) -> Result | None:
    """A Result if the run produced the analysis completely, else None."""
    if not plots:
        return None
    data = plots[-1]["data"]
    vectors = {vector_key(k): np.asarray(v) for k, v in data.items()}
    time = vectors.pop("time", np.zeros(0))
    if net.analysis.kind == "tran":
        if time.size < 2 or time[-1] < net.analysis.stop * (1 - 1e-6):
            return None
    meta = {"backend": backend, "title": net.title, "analysis": net.analysis.kind,
            "options": dict(net.options), "ngspice_version": ngspice_version(),
            "wall_s": wall, "cached": False}
    return Result(np.real(time).astype(float), vectors, meta)


def _message(lines) -> str:
    bad = failure_lines(lines)
    if not bad:
        bad = [ln.strip() for ln in lines if ln.strip()][-3:]
    return "; ".join(dict.fromkeys(bad))[:800] or "no output"


_OBSERVERS: list = []


@contextmanager
def observe(callback):
    """Call ``callback(event, n)`` while the block runs: ``"cached"`` (n decks served from the
    cache), ``"queued"`` (n decks handed to ngspice, retries included) and ``"finished"`` (one
    deck done), from whichever thread runs the batch. The report's progress line uses it."""
    _OBSERVERS.append(callback)
    try:
        yield
    finally:
        _OBSERVERS.remove(callback)


def _notify(event: str, n: int = 1) -> None:
    for callback in list(_OBSERVERS):
        callback(event, n)


def _finishing(runs):
    for out in runs:
        _notify("finished")
        yield out


def simulate_many(netlists, backend: str = "batch", jobs: int | None = None, options=None,
                  use_cache: bool = True, failed: str = "raise") -> list[Result]:
    """Run every netlist (in parallel), each through the cache and the retry policy.

    A deck that still fails after the retries: ``failed="raise"`` raises its SimulationError
    once every other deck of the batch is done (and cached); ``"keep"`` puts the
    SimulationError in its place in the returned list, so one bad point never costs the others.
    """
    if backend not in BACKENDS:
        raise SimulationError("-", "-", f"unknown backend {backend!r}; allowed: {', '.join(BACKENDS)}")
    jobs = jobs or default_jobs()
    nets = [_prepare(n, options) for n in netlists]
    results: list[Result | None] = [None] * len(nets)
    keys = []
    version = ngspice_version()
    for i, n in enumerate(nets):
        k = _key(n, version, backend)
        keys.append(k)
        if use_cache:
            results[i] = cache_mod.load(k)
    todo = [i for i, r in enumerate(results) if r is None]
    if len(todo) < len(nets):
        _notify("cached", len(nets) - len(todo))
    failures: dict[int, str] = {}
    logs: dict[int, list] = {}  # every attempt's ngspice output, kept with a failed deck
    given_up: dict[int, SimulationError] = {}
    for round_, loosen in enumerate((None, *RETRIES)):
        if not todo:
            break
        decks = [nets[i] if loosen is None else replace(nets[i], options=merged(nets[i].options, loosen))
                 for i in todo]
        _notify("queued", len(decks))
        try:
            outs = _run(decks, backend, jobs)
        except BaseException:
            _stop_everything()
            raise
        still = []
        for i, deck, (plots, lines, wall) in zip(todo, decks, outs):
            res = _to_result(deck, plots, lines, wall, backend)
            if res is None:
                failures[i] = _message(lines)
                logs.setdefault(i, []).append((_options_text(deck.options), lines))
                if round_ == len(RETRIES):
                    try:
                        _give_up(deck, failures[i], logs[i], backend)
                    except SimulationError as exc:
                        given_up[i] = exc
                    continue
                still.append(i)
                continue
            if loosen is not None:
                res.meta["retried"] = {"reason": failures.get(i, "failed"), "options": dict(loosen)}
            if use_cache and loosen is None:
                cache_mod.save(keys[i], res)
            elif use_cache:  # under its own key; the strict key only says where it went
                own = _key(deck, version, backend)
                cache_mod.save(own, res)
                cache_mod.save_redirect(keys[i], own, res.meta["retried"]["reason"])
            results[i] = res
        todo = still
    if given_up and failed == "raise":
        raise given_up[min(given_up)]
    for i, exc in given_up.items():
        results[i] = exc
    return results


def _options_text(options) -> str:
    return " ".join(f"{k}={v}" for k, v in options)


def _give_up(deck, message, logs, backend="batch"):
    """Keep the deck and the logs of every attempt, then raise in the user's terms (with the
    forward-biased node, of its array, where a transient stopped: ``failure_site``)."""
    from . import failures
    from .failure_site import locate
    folder = failures.keep(deck, deck.text(), logs)
    site = locate(deck, message, lambda d: _to_result(d, *_run([d], backend, 1)[0], backend))
    message = f"{message}; {site}" if site else message
    raise SimulationError(deck.title, deck.analysis.text(), message, what=failures.describe(deck),
                          folder=folder, tried=[label for label, _ in logs], hints=failures.hints(message))


def _key(net: Netlist, version: str, backend: str) -> str:
    return cache_mod.key(net.text(), tuple(inc.file for inc in net.includes), version, backend)


def _run(decks, backend, jobs):
    from ..progress import progress
    texts = [flatlib.run_deck(d.text(), d.model_links(), d.includes, scratch.root()) for d in decks]
    bar = dict(total=len(texts), desc=f"ngspice ({decks[0].title}...)") if len(texts) > 1 else None
    if backend == "batch":
        if jobs == 1 or len(texts) == 1:
            return list(_finishing(run_batch(*t) for t in (progress(texts, **bar) if bar else texts)))
        ex = ThreadPoolExecutor(max_workers=jobs)
        try:  # no 'with': on an interrupt, queued runs are dropped, not waited for
            runs = _finishing(ex.map(lambda t: run_batch(*t), texts))
            return list(progress(runs, **bar) if bar else runs)
        finally:
            ex.shutdown(wait=False, cancel_futures=True)
    pool = _pool(jobs)  # submit, not map: map cancels pending futures on an interrupt, which races
    futures = [pool.submit(_shared_worker, t) for t in texts]  # the broken-pool handling (3.11)
    runs = _finishing(f.result() for f in futures)
    return list(progress(runs, **bar) if bar else runs)


def simulate(netlist: Netlist, backend: str = "batch", options=None, use_cache: bool = True) -> Result:
    return simulate_many([netlist], backend=backend, jobs=1, options=options, use_cache=use_cache)[0]
