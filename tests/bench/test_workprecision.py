"""The work-precision benchmark's machinery (bench/legsim_bench/benchmarks/workprecision.py,
compiled.py, drivers/*.c): the error over the trajectory, the ratio's interpolation, and the
compiled drivers against the Python bindings of the same engines.

The drivers are compiled into a temporary directory (cc); the MuJoCo driver against the
mujoco wheel's libmujoco and headers, the legsim driver against the library the legsim
Python API loads. Runtime about 15 s (two short callgrind runs).
"""
from __future__ import annotations

import math
import shutil

import numpy as np
import pytest

from legsim_bench.benchmarks import compiled, workprecision as wp

ROOT = wp.REPO_ROOT


# ---- the error over the trajectory ------------------------------------------------------------

def test_error_is_the_largest_coordinate_deviation_over_the_window_only():
    t = np.arange(11) * 0.1
    q_ref = np.zeros((11, 3))
    q = q_ref.copy()
    q[0, 1] = 5.0     # before the window (t = 0): not counted
    q[4, 2] = -2e-6   # inside: the largest
    q[10, 0] = 1e-6   # the last sample counts
    assert wp.trajectory_error(t, q, t, q_ref, t_from=0.1) == 2e-6
    assert wp.trajectory_error(t, q, t, q_ref, t_from=0.0) == 5.0
    assert wp.trajectory_error(t, q, t, q_ref, t_from=0.5) == 1e-6


def test_error_refuses_trajectories_sampled_at_other_times():
    t = np.arange(11) * 0.1
    with pytest.raises(ValueError):
        wp.trajectory_error(t, np.zeros((11, 2)), t + 1e-3, np.zeros((11, 2)))
    with pytest.raises(ValueError):
        wp.trajectory_error(t[:5], np.zeros((5, 2)), t, np.zeros((11, 2)))
    with pytest.raises(ValueError):
        wp.trajectory_error(t, np.zeros((11, 2)), t, np.zeros((11, 2)), t_from=2.0)


def test_every_step_size_lands_on_the_samples():
    for h in wp.STEPS:
        k = wp.SAMPLE_DT / h
        assert abs(k - round(k)) < 1e-9, h
    assert wp.T_FROM / wp.SAMPLE_DT == pytest.approx(round(wp.T_FROM / wp.SAMPLE_DT))


# ---- the ratio's interpolation ------------------------------------------------------------------

def _power_law(C, p, K, hs):
    """Error C h^p at cost K / h: a straight line in log-log (slope -p)."""
    return [(C * h ** p, K / h) for h in hs]


def test_cost_at_error_interpolates_exactly_along_a_power_law():
    hs = (1e-2, 1e-3, 1e-4)
    pts = _power_law(1.0, 4, 1e6, hs)       # errors 1e-8, 1e-12, 1e-16
    for E in (1e-9, 1e-10, 1e-13):
        h = E ** 0.25                        # the step that gives E exactly
        c, kind = wp.cost_at_error(pts, E)
        assert kind == "interp" and c == pytest.approx(1e6 / h, rel=1e-12)
    assert wp.cost_at_error(pts, 1e-6) == (1e8, "range")     # the largest step is better
    c, kind = wp.cost_at_error(pts, 1e-17)
    assert kind == "unreached" and math.isnan(c)


def test_the_front_drops_points_that_cost_more_for_no_better_error():
    # the 1e-5 step hit round-off: more cost, no better error; the front skips it
    pts = [(1e-6, 1.0), (1e-9, 10.0), (2e-9, 100.0)]
    assert wp.front(pts) == [(1e-6, 1.0), (1e-9, 10.0)]
    assert wp.cost_at_error(pts, 1e-9)[0] == pytest.approx(10.0)


def test_ratio_takes_each_sides_cheapest_method_and_only_converged_peers():
    def pts_of(method, C, p, K):
        return [wp.Point(method, "upper_step_50N", h, ok=True, err=e, instr=K,
                         wall_min=K * 1e-9 / h * wp.SCENES["upper_step_50N"].t_end)
                for h, (e, _) in zip((1e-2, 1e-3, 1e-4), _power_law(C, p, K, (1e-2, 1e-3, 1e-4)))]

    L1, L2 = wp.LEGSIM_METHODS[0], wp.LEGSIM_METHODS[2]
    P1, P2 = wp.MUJOCO_METHODS[0], wp.MUJOCO_METHODS[2]
    pts = (pts_of(L1, 1.0, 4, 40_000) + pts_of(L2, 1.0, 2, 20_000)
           + pts_of(P1, 10.0, 2, 120_000) + pts_of(P2, 1e-3, 8, 1_000))
    conv = {(P1.key, "upper_step_50N"): (True, ""), (P2.key, "upper_step_50N"): (False, "")}
    rows = {r["E"]: r for r in wp.ratio_table(pts, [L1, L2, P1, P2], "upper_step_50N", conv, "instr")}
    r = rows[1e-6]
    # legsim: the RK4-like curve is already at 1e-8 at its largest step h = 1e-2 (cost 40k / h),
    # cheaper than the galpha-like one at h = 1e-3 (20k / h)
    assert r["legsim"] == L1.key and r["k_legsim"] == "range"
    assert r["c_legsim"] == pytest.approx(40_000 / 1e-2)
    assert rows[1e-10]["legsim"] == L1.key and rows[1e-10]["k_legsim"] == "interp"
    assert rows[1e-10]["c_legsim"] == pytest.approx(40_000 / 10 ** -2.5)
    assert rows[1e-10]["peer"] is None and math.isnan(rows[1e-10]["ratio"])  # P1 stops at 1e-7
    # the peer P2 would be cheaper but did not converge: P1 at h = sqrt(1e-7)
    assert r["peer"] == P1.key and r["c_peer"] == pytest.approx(120_000 / math.sqrt(1e-7))
    assert r["ratio"] == pytest.approx(r["c_legsim"] / r["c_peer"])
    # wall time: the same choice and the same ratio here (cost proportional to instructions)
    rw = {x["E"]: x for x in wp.ratio_table(pts, [L1, L2, P1, P2], "upper_step_50N", conv, "wall")}
    assert rw[1e-6]["ratio"] == pytest.approx(r["ratio"])


# ---- the compiled drivers against the Python bindings -------------------------------------------

@pytest.fixture(scope="module")
def drivers(tmp_path_factory):
    if shutil.which(compiled.cc()) is None:
        pytest.skip("no C compiler")
    out = tmp_path_factory.mktemp("wp_drivers")
    try:
        return out, wp.Engines(out, with_peers=True)
    except Exception as e:  # noqa: BLE001 - no liblegsim: say which
        if "liblegsim" in str(e) or "LibraryNotFound" in type(e).__name__:
            pytest.skip(f"liblegsim not built: {e}")
        raise


def test_mujoco_driver_steps_exactly_as_the_python_binding(drivers):
    mujoco = pytest.importorskip("mujoco")
    out, eng = drivers
    if eng.mujoco_exe is None:
        pytest.skip(f"MuJoCo driver not built: {eng.mujoco_why}")
    for m in (wp.MUJOCO_METHODS[0], wp.MUJOCO_METHODS[2]):  # RK4, Euler
        h = 1e-3
        xml = eng.mjcf(m, h)
        run = compiled.Run(eng.mujoco_exe, (eng.run(m, "upper_step_50N", h).args[0], 0.1, 50.0, 0.0))
        t, qpos = run.trajectory(0.02)
        model = mujoco.MjModel.from_xml_string(xml)
        assert model.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_ISLAND
        assert tuple(model.eq_solref[0]) == (2 * h, 1.0)
        d = mujoco.MjData(model)
        d.ctrl[:] = (50.0, 0.0)
        expect = [d.qpos.copy()]
        for _ in range(5):
            for _ in range(20):
                mujoco.mj_step(model, d)
            expect.append(d.qpos.copy())
        np.testing.assert_allclose(t, np.arange(6) * 0.02, atol=1e-15)
        assert np.max(np.abs(qpos - np.array(expect))) <= 1e-13, m.key
        assert np.max(np.abs(qpos[-1])) > 1e-3  # it moved


def test_legsim_driver_steps_exactly_as_the_python_api(drivers):
    import legsim
    out, eng = drivers
    for m in (wp.LEGSIM_METHODS[0], wp.LEGSIM_METHODS[2]):
        h = 1e-3
        run = compiled.Run(eng.legsim_exe, (m.integrator, h, 0.1, 50.0, 0.0, wp.LEGSIM_DISABLE, m.tol))
        t, q = run.trajectory(0.02)
        c = legsim.Sim(precision="double", integrator=m.integrator, step=h, newton_tol=m.tol,
                       disable=wp.LEGSIM_DISABLE)
        c.assemble_pose("stand")
        c.command_force(0, 50.0)
        c.command_force(1, 0.0)
        expect = [c.q]
        for _ in range(5):
            c.step(20)
            expect.append(c.q)
        assert np.max(np.abs(q - np.array(expect))) <= 1e-13, m.key
        assert np.max(np.abs(q[-1] - q[0])) > 1e-3


def test_callgrind_counts_the_steps_only(drivers):
    """Instructions in run_steps() grow with the steps and exclude the set-up: 40 steps cost
    twice 20 steps to within 5 %, for both drivers."""
    if shutil.which("valgrind") is None:
        pytest.skip("valgrind not installed")
    out, eng = drivers
    meths = [wp.LEGSIM_METHODS[0]] + ([wp.MUJOCO_METHODS[0]] if eng.mujoco_exe else [])
    for m in meths:
        run = eng.run(m, "upper_step_50N", 1e-3)
        n20, c20 = run.instructions(20, out / f"cg20_{m.engine}")
        n40, c40 = run.instructions(40, out / f"cg40_{m.engine}")
        assert (c20, c40) == (20, 40)
        assert n40 / n20 == pytest.approx(2.0, rel=0.05), m.key
        assert 1_000 < n20 / 20 < 1_000_000, m.key


def test_callgrind_total_reads_the_summary_line():
    assert compiled.callgrind_total("events: Ir\nfn=x\n1 5\nsummary: 12345\n") == 12345
    assert compiled.callgrind_total("totals: 77\n") == 77
    with pytest.raises(compiled.DriverError):
        compiled.callgrind_total("events: Ir\n")


def test_the_command_end_to_end_writes_costs_and_the_ratio(drivers, tmp_path, capsys):
    """A tiny run with the peers and callgrind: every point has an error, a wall time and an
    instruction count, and the ratio in the Markdown is the one the CSV's curves give."""
    import csv

    from legsim_bench import cli
    out, eng = drivers
    if eng.mujoco_exe is None or shutil.which("valgrind") is None:
        pytest.skip("needs the MuJoCo driver and valgrind")
    rc = cli.main(["workprecision", "--quick", "--scenes", "upper_step_50N", "--step-sizes", "1e-2",
                   "2e-3", "--count-steps", "20", "--target-s", "0.01", "--min-reps", "1",
                   "--max-reps", "1", "-o", str(tmp_path)])
    assert rc == 0, capsys.readouterr().err
    rows = list(csv.DictReader(open(tmp_path / "workprecision_quick.csv")))
    assert len(rows) == 2 * len(eng.methods())
    for r in rows:
        assert r["ok"] == "1", r
        assert 0 < float(r["max_error"]) < 10 and float(r["wall_min_s"]) > 0
        assert 1_000 < float(r["instructions_per_step"]) < 1_000_000 and r["steps_counted"] == "20"

    def best(engine):
        got = []
        for key in {r["method"] for r in rows if r["method"].startswith(engine)}:
            c, kind = wp.cost_at_error([(float(r["max_error"]), float(r["instructions_per_sim_s"]))
                                        for r in rows if r["method"] == key], 1e-4)
            if kind != "unreached":
                got.append(c)
        return min(got)

    ratio = best("legsim/") / best("mujoco/")
    md = (tmp_path / "workprecision_quick.md").read_text()
    line = next(x for x in md.splitlines() if x.startswith("| 1e-04 |"))
    assert float(line.split("|")[2]) == pytest.approx(ratio, rel=5e-3)  # printed to 3 digits
