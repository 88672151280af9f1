"""The robot's driven analyses with the feet on the ground, box_load and the swing through
legsim_cli and the bench (docs/design/robot-on-ground.md section 8): each against RobotModel.
"""
from __future__ import annotations

import json
import subprocess

import numpy as np
import pytest

from legsim_bench.hil.cli_run import record_analysis
from legsim_bench.verdict.analyses import evaluate_analysis, robot_arrays, robot_reference, robot_statics_reference
from legsim_bench.scene import load_scene

from test_robot_scenes import ROOT, _cli


def _bench(name):
    """A robot scene run in legsim_cli (record_analysis) and checked (evaluate_analysis)."""
    _cli()
    sc = load_scene(name, ROOT)
    rec = record_analysis(sc, root=ROOT)
    assert not rec["errors"], rec["errors"]
    return sc, rec["cli_output"], evaluate_analysis(rec, sc, ROOT)


def test_robot_inverse_dynamics_scene_passes_against_robot_model():
    """Three lengths drive, the left lower follows, a 30 N sideways load on the box:
    actuator forces, reactions and ground forces against RobotModel.inverse_dynamics."""
    sc, out, ev = _bench("robot_inverse_dynamics")
    assert ev.passed, [(r.name, r.value, r.detail) for r in ev.results if not r.passed]
    names = {r.name for r in ev.results}
    assert {"actuator forces vs RobotModel.inverse_dynamics", "ground forces N, T per foot vs "
            "RobotModel.inverse_dynamics", "joint reaction forces vs RobotModel.inverse_dynamics"} <= names
    d = robot_arrays(out)
    # the follower moves: its length is not held
    assert np.ptp(d["lengths"][:, 3]) > 1e-3
    # the ground forces, the load and the weight balance the momentum rate: on average over
    # the run the tangential forces carry the load
    assert np.all(d["normal"] > 0) and list(d["state"][-1]) == ["stuck", "stuck"]


@pytest.mark.parametrize("load", [(40.0, -150.0, 12.0), (-90.0, 30.0, -25.0)])
def test_box_load_statics_through_legsim_cli_matches_robot_model(load, tmp_path):
    _cli()
    p = tmp_path / "load.toml"
    p.write_text(f'model = "{ROOT / "models" / "robot.toml"}"\nanalysis = "statics"\n'
                 f'box_load = [{load[0]}, {load[1]}, {load[2]}]\n')
    r = subprocess.run([str(_cli()), str(p)], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    d = robot_arrays(json.loads(r.stdout))
    sc = load_scene(p, ROOT)
    assert sc.box_load == load
    _, st = robot_statics_reference(sc)
    assert d["forces"][0] == pytest.approx(st.actuator_forces, abs=1e-6)
    assert d["normal"][0] == pytest.approx(st.normal, abs=1e-6)
    assert d["tangential"][0] == pytest.approx(st.tangential, abs=1e-6)
    W = 2 * 158.922   # the weight: the feet carry it and the load
    assert np.sum(d["tangential"][0]) == pytest.approx(-load[0], abs=1e-9)
    assert np.sum(d["normal"][0]) == pytest.approx(W - load[1], abs=1e-3)


def test_box_load_dynamics_through_legsim_cli_matches_robot_model(tmp_path):
    """The servo stand with 60 N sideways and 5 N m on the box, 0.1 s, RK4: the box moves,
    as RobotModel.simulate has it with the same load."""
    _cli()
    text = (ROOT / "scenes" / "robot_fig7.toml").read_text()
    text = text.replace('model = "../models/robot.toml"', f'model = "{ROOT / "models" / "robot.toml"}"')
    text = text.replace("value = 185.55456926620968", "value = 135.55456926620968")
    text = text.replace('record_every = 1\n', 'record_every = 10\nbox_load = [60.0, 0.0, 5.0]\n')
    p = tmp_path / "load_dyn.toml"
    p.write_text(text)
    sc = load_scene(p, ROOT)
    r = subprocess.run([str(_cli()), str(p)], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    d = robot_arrays(json.loads(r.stdout))
    _, ref = robot_reference(sc, d["t"], ROOT)
    assert np.max(np.abs(d["q"] - ref.q)) < 1e-9
    assert d["q"][-1, 0] - d["q"][0, 0] > 1e-3          # pushed sideways


def test_robot_swing_scene_passes_its_checks():
    """The left foot lifts off at 0.051 s and touches down stuck at 0.103 s (its impulse inside
    the static cone), the right foot stays stuck, RobotModel agrees until the lift-off."""
    sc, out, ev = _bench("robot_swing")
    assert sc.checks.lifts == ("left.foot",)
    assert ev.passed, [(r.name, r.value, r.detail) for r in ev.results if not r.passed]
    d = robot_arrays(out)
    t = d["t"]
    free = t[d["state"][:, 1] == "free"]
    assert free[0] == pytest.approx(0.051) and free[-1] == pytest.approx(0.102)
    assert np.all(d["state"][:, 0] == "stuck") and list(d["state"][-1]) == ["stuck", "stuck"]
    i = int(np.argmin(np.abs(t - 0.103)))
    assert "touchdown" in d["events"][i]
    # a swing the bench refuses to compare with the stance: lifts leaves RobotModel
    bad = (ROOT / "scenes" / "robot_swing.toml").read_text().replace("residual = 1e-8", "residual = 1e-8\n"
                                                                     "actuator_force_n = 1.0")
    from legsim_bench.scene import SceneError, parse_scene
    with pytest.raises(SceneError, match="actuator_force_n compare with RobotModel's stance"):
        parse_scene(bad, name="t", root=ROOT, path=ROOT / "scenes" / "robot_swing.toml")
