"""The extraction's far field computed in a forked process beside the 2.5D terms (``pex.beside``): the same
couplings as computed in one process, and a child that dies leaves the answer to the caller."""
import os

import pytest

from conftest import ROOT
from pixelkit.design import load_design
from pixelkit.layout.pex import beside as B
from pixelkit.layout.pex import cell_geometry
from pixelkit.layout.pex.capacitance import capacitances


@pytest.fixture(autouse=True)
def own_threads(monkeypatch):
    """``beside`` forks only where the caller has no other thread than the deck waiters: threads other tests
    of the session left behind (a progress bar's monitor, a server's) are hidden from it; the threads a test
    starts itself stay visible."""
    import threading
    before, real = set(threading.enumerate()) - {threading.current_thread()}, threading.enumerate
    monkeypatch.setattr(threading, "enumerate", lambda: [t for t in real() if t not in before])


def test_far_field_beside_gives_the_couplings_of_one_process(monkeypatch):
    """The dual pixel's cell with the far field in a child and
    in the caller: every coupling equal to 1e-12 relative (the sums are not bit-for-bit in order)."""
    d = load_design(ROOT / "designs" / "dual_pixel_gf180.toml")
    geo = cell_geometry(d, "DUALPIX")
    forked = []
    real = B.beside

    def spy(fn, size, *args):
        r = real(fn, size, *args)
        forked.append(isinstance(r, B._Result))
        return r
    monkeypatch.setattr("pixelkit.layout.pex.capacitance.beside", spy)
    monkeypatch.setattr(B, "MIN_POLYGONS", 0)
    a = capacitances(geo, d.tech.stack)
    monkeypatch.setattr(B, "MIN_POLYGONS", 10 ** 9)
    b = capacitances(geo, d.tech.stack)
    assert forked == [True, False]
    assert set(a.c) == set(b.c) and len(a.c) > 50
    for k, v in b.c.items():
        assert a.c[k] == pytest.approx(v, rel=1e-12, abs=0), k


def test_a_child_that_dies_leaves_the_answer_to_the_caller(monkeypatch):
    parent = os.getpid()

    def work(x):
        if os.getpid() != parent:
            os._exit(1)                    # the child dies without an answer
        return {"x": x * 2}
    monkeypatch.setattr(B, "MIN_POLYGONS", 0)
    r = B.beside(work, 1, 21)
    assert isinstance(r, B._Result)
    assert r() == {"x": 42}


def test_no_fork_beside_a_thread_but_beside_a_deck_waiter(monkeypatch):
    """A thread that may hold a lock: computed in the caller; the sign-off's deck waiter (blocked in waitpid):
    forked."""
    import threading
    monkeypatch.setattr(B, "MIN_POLYGONS", 0)
    for name, forks in (("some-worker", False), ("pixelkit-wait-deck", True)):
        stop = threading.Event()
        t = threading.Thread(target=stop.wait, name=name, daemon=True)
        t.start()
        try:
            r = B.beside(lambda: 7, 1)
            assert isinstance(r, B._Result) == forks, name
            assert r() == 7
        finally:
            stop.set()
            t.join()
