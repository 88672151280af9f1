"""legsim beside the robot peers (legsim-bench robot-peers,
bench/legsim_bench/benchmarks/peers/robot_results.py and legsim_robot.py).

legsim, driven through its Python API from each scene's start, follows the bench's
reference on Fig. 7 Scene A (RK4 to round-off level, generalized-alpha at second
order); every engine's cost is the smallest of its timed runs; the results table
puts legsim's rows, errors and costs beside the peers'.

Needs liblegsim.so (the host CMake build, target legsim; LEGSIM_LIB_DIR overrides
where it is looked for): skipped, with that reason, only if it is not built.
"""
from __future__ import annotations

import re

import numpy as np
import pytest

import legsim
from legsim_bench.benchmarks.peers import legsim_robot as lr
from legsim_bench.benchmarks.peers import robot_results as rr
from legsim_bench.benchmarks.peers import robot_scenes as rs
from legsim_bench.benchmarks.peers import siconos_robot as sr

if not legsim.library_available("double"):
    pytest.skip("liblegsim.so is not built (cmake --build build/host, or set LEGSIM_LIB_DIR)",
                allow_module_level=True)


@pytest.fixture(scope="module")
def fig7():
    s = rs.setup("fig7_a")
    return s, rs.reference(s, np.arange(0, 101) * 1e-3)


def test_legsim_follows_the_reference_on_fig7(fig7):
    sc, ref = fig7
    rk4 = lr.compare(sc, 1e-3, "rk4", ref=ref)
    assert rk4["ok"] and rk4["states"] == ["stuck", "stuck"]
    assert rk4["n_steps"] == 100 and len(rk4["t"]) == 101
    assert rk4["err_z"] < 1e-8 and rk4["err_NT"] < 1e-5
    assert 0.0 < rk4["per_step_s"] < 0.01
    # generalized-alpha: second order (error / 4 when h / 2)
    g1 = lr.compare(sc, 1e-3, "galpha", ref=ref)
    g2 = lr.compare(sc, 5e-4, "galpha", ref=ref)
    assert g1["ok"] and g2["ok"]
    assert 1e-8 < g1["err_z"] < 1e-4
    assert 3.0 < g1["err_z"] / g2["err_z"] < 5.0


def test_legsim_cost_is_the_smallest_timed_run(fig7, monkeypatch):
    sc, ref = fig7
    times = iter([3000, 1000, 2000])   # ns per legsim_step(sim, 100) call
    monkeypatch.setattr(lr.lc, "timed_step", lambda sim, n: next(times))
    c = lr.compare(sc, 1e-3, "rk4", ref=ref, repeats=3)
    assert c["per_step_s"] == pytest.approx(1000e-9 / 100, rel=1e-12)


def test_siconos_cost_is_the_smallest_run(monkeypatch):
    calls = []

    def fake_compare(name, h, ref=None):
        return {"per_step_s": 0.030, "err_z": 1e-4, "err_NT": 0.1, "ok": True}

    def fake_run(name, h, every=1):
        calls.append((name, h, every))
        return {"per_step_s": [0.020, 0.025][len(calls) - 1]}

    monkeypatch.setattr(sr, "compare", fake_compare)
    monkeypatch.setattr(sr, "run", fake_run)
    c = rr.siconos_compare("fig7_a", 5e-4, ref={}, repeats=3)
    assert c["per_step_s"] == 0.020
    assert calls == [("fig7_a", 5e-4, 2)] * 2


def test_table_puts_legsim_beside_the_peers():
    rows = rr.collect(scenes=("fig7_a",), mujoco_h=(1e-3,), siconos_h=(), legsim_h=(1e-3,), repeats=1)
    engines = [(r["engine"].split()[0], r["method"]) for r in rows]
    assert engines[:2] == [("legsim", "RK4 + projection"), ("legsim", "generalized-alpha")]
    assert ("mujoco", "rk4") in engines
    assert all(r["ok"] and r["per_step_s"] > 0 for r in rows)
    before = rr.results.snapshot()
    md = rr.markdown(rows, before, before)
    table = [line for line in md.splitlines() if line.startswith("| legsim") or line.startswith("| mujoco")]
    assert len(table) == 3
    for line, r in zip(table, rows):
        cells = [c.strip() for c in line.strip("|").split("|")]
        assert len(cells) == 8
        assert float(cells[4]) == pytest.approx(r["err_z"], rel=0.01)
        assert float(cells[6]) == pytest.approx(r["per_step_s"] * 1e6, abs=0.051)
        # per simulated second = per step / h
        assert float(cells[7]) == pytest.approx(float(cells[6]) / 1e3 / r["h"], rel=0.01, abs=0.06)
    assert re.search(r"cost per simulated s \(ms\)", md)
