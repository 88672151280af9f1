"""The hexapod's scenes (scenes/hexapod_*.toml, scenes/README.md "The hexapod"): legsim_cli runs
them through the hexapod's C API; here its JSON against the Python API run independently
(legsim.Hexapod.statics, .walk, .sim on the scene's ground) and against the gait's plan, and the
bench's handling of them (it lists them as legsim_cli's and refuses to run them: hil_sim has no
hexapod)."""
import json
import math
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

from legsim_bench.scene import SceneError, is_hexapod_scene, load_scene, shipped_scenes  # noqa: E402

SCENES = ROOT / "scenes"
HEXAPOD_SCENES = {"hexapod_stand_tripod", "hexapod_fig7_six", "hexapod_walk", "hexapod_turn", "hexapod_drop",
                  "hexapod_slope_up", "hexapod_slope_across", "hexapod_slope_turn", "hexapod_slip",
                  "hexapod_inverse_walk",
                  "hexapod_section5"}
BLOCK_SCENES = {"block_incline_across", "block_incline_stop"}  # a hexapod file of no legs (test_block_scenes.py)



def _run(name, *args):
    r = subprocess.run([str(legsim_cli()), str(SCENES / f"{name}.toml"), *args], capture_output=True, text=True,
                       timeout=300)
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout)


@pytest.fixture(scope="module")
def hexapod():
    legsim = pytest.importorskip("legsim")
    try:
        return legsim.Hexapod.from_toml(ROOT / "models" / "hexapod.toml")
    except (OSError, RuntimeError) as e:  # no liblegsim built
        pytest.skip(str(e))


def test_the_bench_lists_them_as_legsim_cli_s_and_refuses_to_run_them():
    every = {p.stem for p in shipped_scenes(ROOT, hexapod=True)}
    bench = {p.stem for p in shipped_scenes(ROOT)}
    assert HEXAPOD_SCENES <= every and not HEXAPOD_SCENES & bench
    assert {p.stem for p in SCENES.glob("*.toml") if is_hexapod_scene(p)} == HEXAPOD_SCENES | BLOCK_SCENES
    legsim_cli()
    with pytest.raises(SceneError, match="a hexapod scene: legsim_cli runs it"):
        load_scene(SCENES / "hexapod_walk.toml", ROOT)


def test_the_tripod_stand_is_the_python_api_s_statics(hexapod):
    """legsim_cli's statics of hexapod_stand_tripod against legsim.Hexapod.statics at the pose the
    JSON says it took (1e-12): the same C function through two front ends."""
    d = _run("hexapod_stand_tripod")
    legs = d["legs"]
    p = d["pose"]
    pose = {"box_m": p["box"], "box_quat": p["box_quat"], "rowing_rad": p["rowing"], "length_m": p["lengths"]}
    # the scene's default pose: the legs' stand, the box level with the stand's feet on the ground
    stand = hexapod.stand_pose(box_height=p["box"][2])
    assert np.allclose(p["lengths"], stand["length_m"], rtol=0, atol=1e-15)
    stance = [legs.index(k) for k in d["stance"]]
    assert stance == [0, 2, 4]
    ref = hexapod.statics(pose, stance=stance)
    st = d["statics"]
    got_f = np.array([st["feet"][k]["force"] for k in legs])
    got_x = np.array([st["feet"][k]["x"] for k in legs])
    assert np.abs(got_f - ref["foot_force_n"]).max() <= 1e-12 * np.abs(ref["foot_force_n"]).max()
    assert np.abs(got_x - ref["foot_m"]).max() <= 1e-12
    assert np.abs(got_x[:, 2]).max() <= 1e-12  # on the ground
    assert np.abs(np.array(st["actuator_forces"]) - ref["actuator_force_n"]).max() <= \
        1e-12 * np.abs(ref["actuator_force_n"]).max()
    assert np.abs(np.array(st["rowing_torques"]) - ref["rowing_torque_nm"]).max() <= 1e-12 * 100
    assert abs(st["margin"] - ref["margin_m"]) <= 1e-12 and np.abs(np.array(st["com"]) - ref["com_m"]).max() <= 1e-12
    # the tripod carries the weight: 36 kg of box and yokes plus the legs' bars
    total = got_f[:, 2].sum()
    assert total > 0 and abs(got_f[:, :2]).max() < 1e-9


def test_the_walk_advances_as_the_gait_plans(hexapod):
    """hexapod_walk: two periods straight, the box's final x the plan's 2 step_length / duty to
    10 %; its height within 2 cm of the gait's, its heading and side drift small; and the run is
    legsim.Hexapod.walk's (the same driving through the Python API), sample for sample."""
    d = _run("hexapod_walk")
    g = d["gait"]
    plan = 2 * g["step_length_m"] / g["duty"]
    last = d["samples"][-1]
    assert last["t"] == pytest.approx(2 * g["period_s"], abs=1e-9)
    assert abs(last["box"][0] - plan) <= 0.1 * plan, (last["box"][0], plan)
    assert max(abs(s["box"][2] - g["box_height_m"]) for s in d["samples"]) < 0.02
    q = last["box_quat"]
    assert abs(2 * math.atan2(q[3], q[0])) < math.radians(1)
    assert last["impacts"] >= 6  # each foot touched down at least once a period
    w = hexapod.walk(**{k: g[k] for k in g}, t_end_s=d["duration"], h_s=d["step_s"], every=d["record_every"])
    assert np.array_equal(np.array([s["box"] for s in d["samples"]]), w["box_m"])
    assert np.array_equal(np.array([[s["feet"][k]["x"] for k in d["legs"]] for s in d["samples"]]), w["foot_m"])
    assert [s["impacts"] for s in d["samples"]] == list(w["impacts"])


def test_the_turn_turns_as_the_gait_plans():
    d = _run("hexapod_turn")
    g = d["gait"]
    plan = 2 * g["turn_rad"] / g["duty"]
    q = d["samples"][-1]["box_quat"]
    yaw = 2 * math.atan2(q[3], q[0])
    assert abs(yaw - plan) <= 0.1 * plan, (yaw, plan)
    assert max(math.hypot(*s["box"][:2]) for s in d["samples"]) < 0.05  # on the spot


def _ground(d):
    """The scene's [ground] as Hexapod.on_ground's keywords (the header's resolved plane)."""
    g = d["ground"]
    return dict(normal=g["normal"], point=g["point"], mu_static=g["mu_static"], mu_kinetic=g["mu_kinetic"])


def _scene_checks(d):
    sys.path.insert(0, str(ROOT / "tests" / "model"))
    import check_cli_output
    return {k: check_cli_output.hexapod_check(d, k, w) for k, w in d["checks"].items()}


@pytest.mark.parametrize("name, degrees", [("hexapod_slope_up", 15), ("hexapod_slope_across", 15),
                                           ("hexapod_slope_turn", 10)])
def test_the_slope_walks_are_the_python_api_s(hexapod, name, degrees):
    """hexapod_slope_up / _across (15 degrees, up the fall line and across it) and _turn (on the
    spot on 10 degrees, generalized-alpha): the scene's checks pass (progress or yaw against the
    plan, height over the ground below the box, tilt, the stuck feet inside their cones, the
    stance's margin), and the run is legsim.Hexapod.walk's on the scene's ground, sample for
    sample."""
    d = _run(name)
    got = _scene_checks(d)
    print(name, {k: v[0] for k, v in got.items()})
    assert all(ok for _, ok in got.values()), got
    g = d["gait"]
    n = d["ground"]["normal"]
    assert abs(math.acos(n[2]) - math.radians(degrees)) < 1e-12
    w = hexapod.walk(**g, t_end_s=d["duration"], h_s=d["step_s"], every=d["record_every"], ground=_ground(d),
                     integrator=d["integrator"].replace("generalized_alpha", "galpha"))
    assert np.array_equal(np.array([s["box"] for s in d["samples"]]), w["box_m"])
    assert np.array_equal(np.array([[s["feet"][k]["x"] for k in d["legs"]] for s in d["samples"]]), w["foot_m"])
    assert np.allclose(np.array([s["com"] for s in d["samples"]]), w["com_m"], rtol=0, atol=1e-12)
    assert np.allclose(np.array([s["margin"] for s in d["samples"]]), w["margin_m"], rtol=0, atol=1e-12)


def test_the_slip_is_the_python_api_s(hexapod):
    """hexapod_slip: its checks pass (|F_t| = mu_k N, the friction against the slip, its work the
    energy lost), and the run is the Python API's: the stand on the scene's ground, the servos
    holding it with its six feet's statics as feed-forward, step for step."""
    d = _run("hexapod_slip")
    got = _scene_checks(d)
    print("hexapod_slip", {k: v[0] for k, v in got.items()})
    assert all(ok for _, ok in got.values()), got
    assert all(f["state"] == "sliding" for s in d["samples"][1:] for f in s["feet"].values())
    h = hexapod.on_ground(**_ground(d))
    p = d["pose"]
    pose = {"box_m": p["box"], "box_quat": p["box_quat"], "rowing_rad": p["rowing"], "length_m": p["lengths"]}
    ref = h.ground_stand_pose(p["box"][2] - h.ground["point"][2])
    assert np.abs(np.array(p["lengths"]) - ref["length_m"]).max() < 1e-12
    s = h.statics(pose)
    m = h.sim(pose)
    m.command_pose(pose["length_m"], pose["rowing_rad"], s["actuator_force_n"], s["rowing_torque_nm"])
    for k, sample in enumerate(d["samples"][1:]):
        m.step(1, h_s=d["step_s"])
        st = m.state()
        assert np.array_equal(st["box_m"], sample["box"]), k
    assert np.array_equal(st["foot_m"], [sample["feet"][k]["x"] for k in d["legs"]])
