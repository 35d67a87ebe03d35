"""Where independent simulation tasks run: local workers by default, or a Dask cluster.

``run_tasks(fn, tasks, jobs=, scheduler=)`` calls the module-level function
``fn(task)`` for every task and yields ``(index, outcome)`` as each one finishes, with a
progress bar. ``fn`` does its own work through the kit's engine (and its cache), so a
finished task is on disk the moment it finishes: an interrupted run loses only the
tasks that were running.

- local (default): ``jobs`` threads; each drives its own ngspice process (batch
  backend), so the cores work in parallel while Python waits.
- ``scheduler="tcp://host:port"``: a Dask distributed scheduler (``dask.distributed``);
  ``fn`` and the tasks are pickled to its workers, which must have pixelkit installed
  and see the same model files. A ``Client`` object may be passed instead of an address.
"""
from __future__ import annotations

import re
from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait

from ..errors import ConfigError
from ..progress import command_bar


def run_tasks(fn, tasks, jobs: int | None = None, scheduler=None, desc: str = "simulating", more=None,
              label=None, status=None):
    """Yield ``(index, fn(task))`` as tasks finish. ``more()``, if given, is called after each
    outcome has been handed to the caller and returns further tasks to run (indices continue
    after the ones given so far; an empty list adds nothing): a sequential Monte Carlo adds
    its next stage only when the one before has not decided. ``label(task)``: what a task
    simulates, shown after the count for the oldest task still running; ``status(done, total,
    label)``: told the same after every task (a report shows its sign-off's progress so)."""
    tasks = list(tasks)
    if not tasks:
        return
    if scheduler is not None:
        yield from _dask(fn, tasks, scheduler, desc, more)
        return
    from .engine import default_jobs
    jobs = max(1, int(jobs or default_jobs()))
    with command_bar(desc, total=len(tasks), unit="tasks") as bar:
        tell = _teller(bar, tasks, label, status)
        if jobs == 1:
            i = 0
            while i < len(tasks):
                tell(i, i)
                out = fn(tasks[i])
                bar.update(1)
                yield i, out
                i += 1
                _extend(tasks, more, bar)
            tell(None, i)
            return
        with ThreadPoolExecutor(max_workers=jobs) as ex:
            futs = {ex.submit(fn, t): i for i, t in enumerate(tasks)}
            pending = set(futs)
            tell(0, 0)
            try:
                while pending:
                    done, pending = wait(pending, return_when=FIRST_COMPLETED)
                    for f in sorted(done, key=futs.get):
                        bar.update(1)
                        yield futs[f], f.result()
                        for t in _extend(tasks, more, bar):
                            g = ex.submit(fn, t)
                            futs[g] = len(futs)
                            pending.add(g)
                    tell(min((futs[f] for f in pending), default=None), len(futs) - len(pending))
            except BaseException:
                for f in futs:
                    f.cancel()
                raise


def _teller(bar, tasks, label, status):
    """``tell(i, done)``: task ``i`` is the oldest still running (None: all done), ``done`` finished
    (counted here: a bar inside a command's own bar is silent and counts nothing)."""
    def tell(i, done):
        what = label(tasks[i]) if label is not None and i is not None else ""
        if what:
            bar.set_postfix_str(f"now {what}", refresh=False)
        if status is not None:
            status(done, len(tasks), what)
    return tell


def _extend(tasks: list, more, bar) -> list:
    """The tasks ``more()`` adds (appended to ``tasks``, the bar's total grown)."""
    new = list(more()) if more else []
    if new:
        tasks += new
        bar.total = len(tasks)
        bar.refresh()
    return new


_ADDRESS = re.compile(r"^(?:(?:tcp|tls|ucx)://)?(\[[0-9A-Fa-f:.]{2,45}\]|[A-Za-z0-9][A-Za-z0-9.-]{0,252}):([0-9]{1,5})$")


def check_address(scheduler) -> str:
    """``scheduler`` if it is a Dask scheduler address (``[tcp|tls|ucx://]HOST:PORT``, port 1-65535):
    checked before anything connects, so a malformed address never reaches the network layer."""
    m = _ADDRESS.match(scheduler) if isinstance(scheduler, str) else None
    if not m or not 1 <= int(m.group(2)) <= 65535:
        raise ConfigError("", "--scheduler", scheduler,
                          "a Dask scheduler address [tcp://|tls://|ucx://]HOST:PORT (port 1-65535), "
                          "e.g. tcp://127.0.0.1:8786")
    return scheduler


def _client(scheduler):
    try:
        from dask.distributed import Client
    except ImportError:  # pragma: no cover - declared dependency
        raise ConfigError("", "scheduler", scheduler, "dask[distributed] installed") from None
    if isinstance(scheduler, Client):
        return scheduler, False
    check_address(scheduler)
    try:
        return Client(scheduler, timeout="20s"), True
    except (OSError, TimeoutError) as exc:
        raise ConfigError("", "scheduler", scheduler,
                          f"a reachable Dask scheduler ({type(exc).__name__}: {exc})") from None


def _dask(fn, tasks, scheduler, desc, more=None):
    from dask.distributed import as_completed as dask_completed
    client, own = _client(scheduler)
    try:
        futs = client.map(fn, tasks, pure=False)
        index = {f.key: i for i, f in enumerate(futs)}
        with command_bar(f"{desc} (dask)", total=len(tasks), unit="tasks") as bar:
            done = dask_completed(futs)
            try:
                for f in done:
                    bar.update(1)
                    yield index[f.key], f.result()
                    new = _extend(tasks, more, bar)
                    if new:
                        added = client.map(fn, new, pure=False)
                        index.update({g.key: len(index) + k for k, g in enumerate(added)})
                        futs += added
                        done.update(added)
            except BaseException:
                client.cancel(futs)
                raise
    finally:
        if own:
            client.close()
