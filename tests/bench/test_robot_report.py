"""What a user sees of a robot scene (legsim_bench.report.robot_plots, report.tables, `check`):
the plots start at the first physical sample, not the RESET's; every contact event gets its
own snapshot, named on its foot; robot scenes write samples.csv and reference.csv (the
verdict's RobotModel run where it applies) with units in the header. robot_swing through
legsim_cli is the run: the left foot lifts off and touches down; the report's event times are
checked against the run's own events, its stance forces against RobotModel's statics."""
from __future__ import annotations

import argparse
import csv
import math
from pathlib import Path

import numpy as np
import pytest

from legsim_bench import cli
from legsim_bench.hil.runner import record
from legsim_bench.reference.robot import RobotModel
from legsim_bench.report import robot_plots as rp
from legsim_bench.scene import cli_path, load_scene

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def swing_checked(tmp_path_factory):
    if not cli_path(ROOT).is_file():
        pytest.skip(f"{cli_path(ROOT)} not built (cmake --build --preset host --target legsim_cli)")
    rec = record(load_scene("robot_swing", ROOT), None)
    assert rec["complete"], rec["errors"]
    out = tmp_path_factory.mktemp("robot_swing")
    ev, files = cli._check_one(rec, out, argparse.Namespace(no_plots=True, brief=True), ROOT)
    return rec, ev, out, files


@pytest.fixture(scope="module")
def swing_events(swing_checked):
    """The run's own contact events (legsim_cli's samples): [(t, kind)], one lift-off of the
    left foot after its lower actuator's step at 0.05 s (the scene's), then one touchdown."""
    rec = swing_checked[0]
    ev = [(s["t"], kind) for s in rec["cli_output"]["samples"] for kind in s["events"]]
    assert [k for _, k in ev] == ["liftoff", "touchdown"] and 0.05 < ev[0][0] < ev[1][0]
    return ev


@pytest.fixture(scope="module")
def stand_normal():
    """N on each foot of robot_swing's stance (both feet stuck, at the scene's lengths):
    RobotModel's statics."""
    sc = load_scene("robot_swing", ROOT)
    model = RobotModel.from_toml(sc.model_path)
    st = model.statics(lengths=sc.lengths)
    assert st.residual < 1e-9 and np.all(st.holds)
    return dict(zip(model.foot_names, (float(n) for n in st.normal)))


def _rows(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def test_a_can_recording_starts_at_the_first_step_not_at_the_reset(robot):
    """The RESET's sample (step 0) carries the assembly's multipliers as ground forces (32.6 N
    per foot for the stand), not forces of the dynamics: the trajectory leaves it out, as
    legsim_cli writes null for its first sample's forces."""
    import legsim
    from model_files import ROBOT

    model = legsim.Model.from_toml(ROBOT)
    nb = len(model.body_names)

    def sample(step, N, events=()):
        return {"t": step * 1e-3, "step": step, "q": [0.0] * (3 * nb),
                "contacts": [{"state": "stuck", "normal": N, "tangential": 0.0, "x": x, "y": 0.0,
                              "events": list(events) if x < 0 else []} for x in (0.6, -0.6)]}
    rec = {"legs": 2, "complete": True,
           "samples": [sample(0, 32.6), sample(1, 158.9), sample(2, 158.9, ["liftoff"]), sample(3, 150.0)]}
    traj = rp.RobotTrajectory.from_recording(rec, model, robot.box_size)
    assert traj.t.tolist() == [1e-3, 2e-3, 3e-3]
    assert traj.normal[0].tolist() == [158.9, 158.9]
    # the per-foot events of ST_CONTACT name their foot
    assert traj.events == [[], [f"{model.contact_names[1]} liftoff"], []]
    assert traj.event_samples() == [(1, f"{model.contact_names[1]} liftoff")]


def test_the_cli_run_starts_at_its_first_solved_sample(swing_checked, stand_normal):
    rec, ev, out, files = swing_checked
    first = rec["cli_output"]["samples"][1]
    rows = _rows(out / "samples.csv")
    assert float(rows[0]["t_s"]) == pytest.approx(first["t"])
    assert float(rows[0]["right.foot.N_N"]) == first["contacts"]["right.foot"]["normal"]
    # the stand's weight on each foot, from the first row on: no jump from a non-physical value
    N0 = [float(r["right.foot.N_N"]) for r in rows[:40]]
    assert max(N0) - min(N0) < 1e-6 and N0[0] == pytest.approx(stand_normal["right.foot"], abs=1e-3)


def test_every_contact_event_has_its_snapshot_named_on_its_foot(swing_checked, swing_events, tmp_path):
    rec, ev, out, files = swing_checked
    traj, _ = cli._robot_trajectories(rec, ev)
    events = traj.event_samples()
    assert [(float(traj.t[k]), what) for k, what in events] == \
        [(t, f"left.foot {kind}") for t, kind in swing_events]
    idx = rp.snapshot_samples(traj, n=4)
    assert {k for k, _ in events} <= set(idx.tolist())
    assert len(idx) == 6 and list(idx) == sorted(idx)
    _, drawn = rp.plot_snapshots(traj, tmp_path / "snap.png")
    titles = [a.box.axes.get_title() for a in drawn]
    stamps = [f"t = {t:.4g} s" for t, _ in swing_events]   # plot_snapshots' title
    assert [t for t in titles if "liftoff" in t or "touchdown" in t] == \
        [t for t in titles if any(x in t for x in stamps)]
    assert sum("left.foot liftoff" in t for t in titles) == 1
    assert sum("left.foot touchdown" in t for t in titles) == 1


def test_robot_scenes_write_samples_and_reference_csv_with_units(swing_checked, swing_events, stand_normal):
    rec, ev, out, files = swing_checked
    assert {"samples", "reference"} <= set(files)
    rows = _rows(out / "samples.csv")
    n = len(rec["cli_output"]["samples"]) - 1
    assert len(rows) == n
    head = list(rows[0])
    assert head[:4] == ["t_s", "box.x_m", "box.y_m", "box.phi_rad"] and head[-1] == "events"
    assert {"left.foot.state", "left.foot.N_N", "left.foot.T_N", "left.foot.x_m"} <= set(head)
    lift = [r for r in rows if r["events"]]
    assert [r["events"] for r in lift] == [f"left.foot {kind}" for _, kind in swing_events]
    assert [float(r["t_s"]) for r in lift] == pytest.approx([t for t, _ in swing_events], abs=1e-9)
    (t_lift, _), (t_down, _) = swing_events
    between = [r for r in rows if t_lift + 1e-4 < float(r["t_s"]) < t_down - 1e-4]
    assert between and all(r["left.foot.state"] == "free" for r in between)
    # the reference: the verdict's RobotModel run (both feet stuck) up to the lift-off, and
    # it is the run's own curve there (the scene's check: 1e-9 m)
    ref = _rows(out / "reference.csv")
    r_t = [float(r["t_s"]) for r in ref]
    assert r_t[-1] < t_lift and len(ref) >= 40
    by_t = {round(float(r["t_s"]), 6): r for r in rows}
    for r in ref[1:]:
        s = by_t[round(float(r["t_s"]), 6)]
        assert abs(float(r["box.y_m"]) - float(s["box.y_m"])) < 1e-9
        if float(r["t_s"]) < 0.0495:   # the command's step at 0.05 s: its sample holds the step before's forces
            assert abs(float(r["right.foot.N_N"]) - float(s["right.foot.N_N"])) < 1e-3
    assert math.isclose(float(ref[1]["left.foot.N_N"]), stand_normal["left.foot"], abs_tol=1e-3)


def test_check_draws_the_robot_with_its_reference(swing_checked, swing_events, tmp_path):
    rec, ev, out, files = swing_checked
    pytest.importorskip("matplotlib")
    traj, ref = cli._robot_trajectories(rec, ev)
    assert ref is not None and ref.foot_names == traj.foot_names
    path = rp.plot_time_series(traj, tmp_path / "ts.png", reference=ref)
    assert path.stat().st_size > 10_000
    assert np.all(np.diff(ref.t) > 0) and ref.t[-1] < swing_events[0][0]
