"""The hexapod's inverse dynamics along its gait through legsim_cli (scenes/hexapod_inverse_walk.toml,
scenes/README.md "Inverse dynamics along the gait"): its JSON against the Python API run
independently (legsim.Hexapod.inverse_dynamics at the same times), its summary against its
samples, the ground forces against the weight, and bad scenes refused."""
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from built import legsim_cli

ROOT = Path(__file__).resolve().parents[2]
try:
    import legsim_bench.scene  # noqa: F401
except ImportError:  # the bench is not installed: use the source tree
    sys.path.insert(0, str(ROOT / "bench"))


SCENE = ROOT / "scenes" / "hexapod_inverse_walk.toml"



def _run(scene, *args):
    return subprocess.run([str(legsim_cli()), str(scene), *args], capture_output=True, text=True, timeout=300)


@pytest.fixture(scope="module")
def hexapod():
    legsim = pytest.importorskip("legsim")
    try:
        return legsim.Hexapod.from_toml(ROOT / "models" / "hexapod.toml")
    except (OSError, RuntimeError) as e:  # no liblegsim built
        pytest.skip(str(e))


@pytest.fixture(scope="module")
def walk():
    r = _run(SCENE)
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout)


def test_the_scene_is_the_python_api_s_inverse_dynamics(walk, hexapod):
    assert walk["kind"] == "hexapod" and walk["analysis"] == "inverse_gait" and walk["status"] == "ok"
    s = walk["samples"]
    assert len(s) == walk["n_steps"] + 1 == 61
    t = np.array([x["t"] for x in s])
    assert np.allclose(t, np.arange(61) * 0.02, rtol=0, atol=1e-12)
    r = hexapod.inverse_dynamics(t, **walk["gait"])
    legs = walk["legs"]
    force = np.array([[x["feet"][k]["force"] for k in legs] for x in s])
    ratio = np.array([[x["feet"][k]["cone_ratio"] for k in legs] for x in s])
    stance = np.array([[x["feet"][k]["state"] == "stuck" for k in legs] for x in s])
    scale = np.abs(r["foot_force_n"]).max()
    assert (stance == r["stance"]).all()
    assert np.abs(force - r["foot_force_n"]).max() <= 1e-12 * scale
    assert np.abs(np.array([x["actuator_forces"] for x in s]) - r["actuator_force_n"]).max() <= 1e-12 * scale
    assert np.abs(np.array([x["rowing_torques"] for x in s]) - r["rowing_torque_nm"]).max() <= 1e-12 * scale
    assert np.abs(ratio - r["cone_ratio"]).max() <= 1e-14
    hip = np.array([[x["reactions"][k][0]["force"] for k in legs] for x in s])
    assert np.abs(hip - r["joint_force_n"][:, :, 0]).max() <= 1e-12 * scale
    names = [j["joint"] for j in s[0]["reactions"][legs[0]]]
    assert names[0] == "hip" and len(names) == r["n_joints"][0]


def test_the_summary_and_the_weight(walk, hexapod):
    s, legs = walk["samples"], walk["legs"]
    ratio = max(x["feet"][k]["cone_ratio"] for x in s for k in legs)
    summary = walk["summary"]
    assert summary["max_cone_ratio"] == ratio
    assert summary["friction_enough"] == (ratio <= walk["ground"]["mu_static"])
    assert summary["max_actuator_force"][0] == max(abs(x["actuator_forces"][i][0]) for x in s for i in range(6))
    # straight on, the box at a constant velocity: the ground carries the weight and the legs'
    # inertia; the swinging feet's rise starts and ends with a vertical acceleration (a cosine:
    # 2 pi^2 step_height / T_swing^2 = 4.3 m/s^2), 6 % of the weight more at lift-off and touchdown
    d = hexapod.desc
    mass = d.box_mass_kg + 6 * (d.yoke_mass_kg + sum(d.leg[0].leg.body[b].mass_kg for b in range(d.leg[0].leg.n_bodies)))
    weight = -mass * d.gravity_mps2[2]
    fz = np.array([sum(x["feet"][k]["force"][2] for k in legs) for x in s])
    print(f"the ground's vertical forces over the period: {fz.min():.2f} .. {fz.max():.2f} N (weight {weight:.2f} N); "
          f"largest cone ratio {ratio:.4f} (mu_static {walk['ground']['mu_static']})")
    assert np.abs(fz / weight - 1).max() < 0.08
    for x in s:
        for k in legs:
            f = x["feet"][k]
            if f["state"] == "free":
                assert f["force"] == [0, 0, 0] and f["cone_ratio"] == 0
            else:
                assert abs(f["x"][2]) < 1e-9 and f["velocity"] == [0, 0, 0] and f["force"][2] > 0


def test_check_csv_and_bad_scenes(tmp_path):
    r = _run(SCENE, "--check")
    assert r.returncode == 0 and "samples" not in json.loads(r.stdout)
    r = _run(SCENE, "--format", "csv")
    assert r.returncode == 2 and "JSON only" in r.stderr
    text = SCENE.read_text().replace("../models/hexapod.toml", str(ROOT / "models" / "hexapod.toml"))
    bad = {"step_s = 0.02": ("step_s = 0.07", "not a whole number of samples"),
           "duration = 1.2": ("duration = 1.2\nstuck = [0]", "unknown key"),
           "step_height_m = 0.05": ("step_height_m = 0.05, turn_rad = 2.0", "'turn_rad' must be in"),
           "box_height_m = 1.0": ("box_height_m = 3.0", "gait: its inverse dynamics at t = 0")}
    for i, (old, (new, message)) in enumerate(bad.items()):
        p = tmp_path / f"bad{i}.toml"
        p.write_text(text.replace(old, new))
        r = _run(p)
        assert r.returncode == 2 and r.stderr.startswith("legsim_cli: error: ") and message in r.stderr, r.stderr
