"""The two-leg robot in the peers (MuJoCo, Siconos) against the bench's reference.

MuJoCo: built from robot.toml (a heavier box in a copy of the file makes a
heavier model), the servo stand stays at rest, Fig. 7 Scene A converges to
the reference as h decreases (to the floor its soft contacts allow), the slope
stands for mu > tan and slides for mu < tan. Siconos (Debian's python3-siconos
in the system Python, a separate process): the same model follows the file,
and Fig. 7 Scene A agrees with the reference at its first-order level.
"""
import math
import shutil
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
try:
    import legsim_bench  # noqa: F401
except ImportError:  # the bench is not installed: use the source tree
    sys.path.insert(0, str(ROOT / "bench"))

from legsim_bench.benchmarks.peers import mujoco_robot as mr  # noqa: E402
from legsim_bench.benchmarks.peers import robot_scenes as rs  # noqa: E402
from legsim_bench.benchmarks.peers import siconos_robot as sr  # noqa: E402


@pytest.fixture(scope="module")
def fig7():
    s = rs.setup("fig7_a")
    return s, rs.reference(s, np.arange(0, 101) * 1e-3)


def heavier_robot(tmp_path, extra):
    """A copy of robot.toml (and the leg file it names) with a heavier box."""
    shutil.copy(ROOT / "models" / "leg.toml", tmp_path / "leg.toml")
    text = (ROOT / "models" / "robot.toml").read_text()
    mass = rs.load_robot().box_mass
    new = text.replace(f"mass = {mass}", f"mass = {mass + extra}", 1)
    assert new != text
    path = tmp_path / "robot.toml"
    path.write_text(new)
    return path


def test_mujoco_model_follows_the_robot_file(tmp_path):
    base = mr.MujocoRobot("servo_stand", 1e-3)
    total = float(np.sum(base.scene.robot._m))
    assert abs(base.m.body_mass.sum() - total) < 1e-12
    # 13 bodies + the world; 3 box dofs + 2 legs x 6 tree joints; 2 x 2 loop closures; 4 actuators
    assert (base.m.nbody, base.m.nv, base.m.neq, base.m.nu) == (14, 15, 4, 4)
    heavy = mr.MujocoRobot("servo_stand", 1e-3, robot_path=heavier_robot(tmp_path, 5.0))
    assert abs(heavy.m.body_mass.sum() - (total + 5.0)) < 1e-12
    # the start pose of MuJoCo's tree is the reference's pose
    q = base.q_of(np.zeros(base.m.nq))
    assert np.max(np.abs(q - base.scene.robot.absolute_q(base.scene.z0))) < 1e-14


def test_mujoco_servo_stand_stays_at_rest():
    s = rs.setup("servo_stand")
    c = mr.compare(s, 5e-4)
    assert c["ok"]
    assert c["err_z"] < 5e-5                     # m or rad, over 0.2 s
    W = float(np.sum(s.robot._m)) * float(np.linalg.norm(s.robot.gravity))
    assert abs(c["normal"].sum() - W) < 1e-3 * W
    assert c["err_NT"] < 0.05                    # N: incl. the servo thrust T = -/+36.35 N


def test_mujoco_fig7_converges_to_the_reference(fig7):
    s, ref = fig7
    errs = [mr.compare(s, h, ref=ref) for h in (1e-3, 5e-4, 2e-4)]
    e = [c["err_z"] for c in errs]
    assert all(c["ok"] for c in errs)
    assert e[0] > e[1] > e[2]
    assert e[0] / e[2] > 8.0                     # at least first order over a factor 5 in h
    assert e[2] < 2e-5                           # the soft-contact floor is a few 1e-6
    assert errs[2]["err_NT"] < 0.02              # N, both feet, at t = 0.1 s
    # the box moved as the design's section 7 says (+0.58 mm, +4.05 mm, +0.01634 rad)
    dz = errs[2]["z"][-1] - s.z0
    assert np.max(np.abs(dz[:3] - (5.756e-4, 4.046e-3, 1.6341e-2))) < 2e-5


def test_mujoco_slope_stands_above_tan_and_slides_below():
    stand = mr.compare(rs.setup("slope_stand"), 5e-4)
    assert stand["ok"] and stand["err_z"] < 1e-4
    s = rs.setup("slope_slide")
    r = mr.run(s, 5e-4, every=2)
    assert r["ok"]
    g = s.robot.ground
    x = np.array([rs.centre_of_mass(s.robot, q) for q in r["q"]]) @ g.tangent
    t = r["t"]
    sel = t >= 0.2
    accel = -2.0 * np.polyfit(t[sel], x[sel], 2)[0]
    assert x[0] - x[-1] > 0.02                   # slid down the slope
    free = float(np.linalg.norm(s.robot.gravity)) * math.sin(rs.SLOPE)
    assert s.slide_accel < accel < free           # friction acts, but no more than mu N
    assert abs(accel - s.slide_accel) < 0.2 * s.slide_accel


def test_siconos_is_available():
    ok, why = sr.probe()
    assert ok, why


def test_siconos_model_follows_the_robot_file(tmp_path):
    total = float(np.sum(rs.load_robot()._m))
    r = sr.run("servo_stand", 1e-3, t_end=2e-3)
    assert r["ok"] and abs(r["mass"] - total) < 1e-12
    r = sr.run("servo_stand", 1e-3, t_end=2e-3, robot_path=heavier_robot(tmp_path, 5.0))
    assert abs(r["mass"] - (total + 5.0)) < 1e-12


def test_siconos_fig7_agrees_at_first_order(fig7):
    s, ref = fig7
    c1 = sr.compare("fig7_a", 1e-3, ref=ref)
    c2 = sr.compare("fig7_a", 5e-4, ref=ref)
    assert c1["ok"] and c2["ok"]
    assert c1["err_z"] > 1.8 * c2["err_z"]      # first order or better
    assert c2["err_z"] < 1.5e-4
    assert c2["err_NT"] < 0.3                    # N, from the step's impulse / h
