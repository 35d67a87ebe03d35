"""The extraction cache keys on the design's fields the drawing and the extraction read
(``pixelkit.layout.pex.readtrace``): a bias voltage changed finds the stored extraction, a drawn field changed
draws again, and every field the trace calls unread is one the extraction does not depend on (checked by
changing them all and extracting again from nothing: the independent path is the extraction itself)."""
import copy
import dataclasses
from dataclasses import replace

import pytest

from conftest import ROOT
from pixelkit.layout.pex import overlay
from pixelkit.layout.pex.readtrace import reading, value_at

GF = ROOT / "designs" / "dual_pixel_gf180.toml"


@pytest.fixture(scope="module")
def design():
    from pixelkit.design import load_design
    return load_design(GF)


def test_the_trace_records_leaf_reads_and_whole_objects(design):
    cls = type(design.pixel)
    with reading(design) as reads:
        _ = design.pixel.devices.tg_w
        _ = design.afe.c11
    assert reads == {("pixel", "devices", "tg_w"), ("afe", "c11")}
    with reading(design) as reads:
        copy.deepcopy(design.pixel.devices)        # a copy takes the object whole
    assert ("pixel", "devices") in reads
    with reading(design) as reads:
        dataclasses.replace(design.pixel, swing=1.0)
    assert ("pixel", "v_pd_reset") in reads       # replace reads every field by name
    assert "__getattribute__" not in cls.__dict__  # the classes are as they were
    assert value_at(design, ("pixel", "devices", "tg_w")) == design.pixel.devices.tg_w


def test_traces_in_two_threads_take_turns_and_leave_the_classes_as_they_were(design):
    import threading
    cls = type(design.afe)
    seen = []

    def trace(field):
        with reading(design) as reads:
            getattr(design.afe, field)
            entered.set()
            go.wait(5)
        seen.append(reads)
    entered, go = threading.Event(), threading.Event()
    t = threading.Thread(target=trace, args=("c11",))
    t.start()
    entered.wait(5)
    entered.clear()
    u = threading.Thread(target=trace, args=("c12",))
    u.start()
    # the second waits for the first (without the lock it enters at once, patches over the first's tracer, and
    # the first's exit leaves the second's reads untraced and a tracer on the class: the last assert). The
    # wait can only pass when it should not (a thread slower than 0.2 s to start), never fail when it should.
    assert not entered.wait(0.2)
    go.set()
    t.join(5)
    u.join(5)
    assert {("afe", "c11")} in seen and {("afe", "c12")} in seen
    assert "__getattribute__" not in cls.__dict__


def _fresh(monkeypatch, tmp_path, name):
    monkeypatch.setenv("PIXELKIT_CACHE", str(tmp_path / name))
    monkeypatch.setattr(overlay, "_CACHE", {})
    monkeypatch.setattr(overlay, "_READS", {})


def _scaled(obj, reads, path=()):
    """``obj`` with every float field the trace did not record (and no parent of it) times 0.9."""
    if not dataclasses.is_dataclass(obj):
        return obj
    changes = {}
    for f in dataclasses.fields(obj):
        p = path + (f.name,)
        v = getattr(obj, f.name)
        if dataclasses.is_dataclass(v):
            changes[f.name] = _scaled(v, reads, p)
        elif isinstance(v, float) and p not in reads and not any(p[:k] in reads for k in range(len(p))):
            changes[f.name] = v * 0.9
    return replace(obj, **changes)


def test_a_bias_change_finds_the_extraction_and_a_drawn_change_draws(design, monkeypatch, tmp_path):
    _fresh(monkeypatch, tmp_path, "a")
    view = overlay.post_layout_view(design, afe=False)
    (sets,) = overlay._READS.values()
    reads = sets[0]
    assert ("afe", "c11") in reads and ("pixel", "devices", "sf_w") in reads
    assert not {("pixel", "v_pd_reset"), ("pixel", "v_fd_reset"), ("afe", "vref"), ("primary", "t_int")} & reads
    monkeypatch.setattr(overlay, "_CACHE", {})          # from the store, as another process finds it
    monkeypatch.setattr(overlay, "_READS", {})

    def no_drawing(*a, **k):
        raise AssertionError("drawn again")
    import pixelkit.layout.pex as pex
    monkeypatch.setattr(pex, "chip_geometry", no_drawing)
    biased = replace(design, pixel=replace(design.pixel, v_pd_reset=1.7, v_fd_reset=1.9),
                     afe=replace(design.afe, vref=1.1))
    assert overlay.post_layout_view(biased, afe=False).post_layout == view.post_layout
    with pytest.raises(AssertionError, match="drawn again"):
        overlay.post_layout_view(replace(design, afe=replace(design.afe, c11=design.afe.c11 * 1.2)), afe=False)
    # every float the trace calls unread changed at once, extracted from nothing: the same extraction
    monkeypatch.undo()
    _fresh(monkeypatch, tmp_path, "b")
    other = _scaled(design, reads)
    assert other.pixel.v_pd_reset != design.pixel.v_pd_reset
    assert _same(overlay.post_layout_view(other, afe=False).post_layout, view.post_layout)


def _same(a, b, rel=1e-12):
    """Two extractions equal in every name and structure and in every number to ``rel`` (the extraction's
    sums are not bit-for-bit in their order: one run read 3.67879824870319e-17 F against
    3.678798248703189e-17 for the same pair; a field the drawing reads, scaled by 0.9, moves them by %)."""
    import math
    if dataclasses.is_dataclass(a):
        return type(a) is type(b) and _same(dataclasses.asdict(a), dataclasses.asdict(b), rel)
    if isinstance(a, dict):
        return isinstance(b, dict) and a.keys() == b.keys() and all(_same(a[k], b[k], rel) for k in a)
    if isinstance(a, (list, tuple)):
        return isinstance(b, (list, tuple)) and len(a) == len(b) and all(_same(x, y, rel) for x, y in zip(a, b))
    if isinstance(a, float) and isinstance(b, float):
        return math.isclose(a, b, rel_tol=rel, abs_tol=0.0)
    return a == b
