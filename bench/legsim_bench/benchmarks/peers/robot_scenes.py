"""The two-leg robot scenes the peers run, and their reference (no engine here).

Shared by :mod:`.mujoco_robot` and :mod:`.siconos_robot` (the latter runs in
Debian's system Python, so this module needs only numpy, scipy and the bench's
reference, ``legsim_bench.reference.robot.RobotModel``, which it reads and
never changes).

Every scene starts at rest from a pose of the reference with both feet on the
ground at the stand's foot points and gives each of the four actuators (right
upper, right lower, left upper, left lower) a mode: ``"force"`` (a constant
axial force, N, > 0 extends) or ``"servo"`` (leg.toml's servo law
F = kp (l_cmd - l) - kd l_dot, saturated at max_force, to a constant length).

* ``servo_stand``: the servo stand equilibrium (design section 4), all four
  servos at the stand lengths; it stays at rest.
* ``fig7_a``: the design's Fig. 7 Scene A (section 7): from the servo stand,
  the right upper actuator in force mode at its hold force + 50 N, the other
  three on their servos, 0.1 s.
* ``fig7_b``: Scene B: from the rigid stand, all four at their
  equal_friction statics forces, + 50 N on the right upper, 0.1 s.
* ``slope_stand`` / ``slope_slide``: the robot file's robot on a 0.3 rad
  ground line (tan = 0.309), from the servo equilibrium on that slope with
  its feet stuck, all four servos at the stand lengths; ``mu`` (both the
  static and the kinetic coefficient, so that a peer with one coefficient
  meets the same law) is 0.6 (stands: mu > tan) or 0.25 (slides: mu < tan).
  Sliding on both feet, the centre of mass accelerates down the slope at
  g (sin a - mu cos a) once the servos have settled (contact_analytic's
  slide law for the whole robot): that, not the stuck-feet reference, is the
  check of ``slope_slide``.

The reference of the stuck-feet scenes is RobotModel.simulate (DOP853 at
rtol 1e-11) in its coordinates z = (x, y, psi, right (phi3, phi6), left (phi3,
phi6)): box pose (m, rad) and each leg's angles in its own frame (rad).
"""
from __future__ import annotations

import copy
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional

import numpy as np

from ...reference import ForceCommand, LengthCommand
from ...reference.model_file import read_model_file
from ...reference.robot import RobotModel

REPO_ROOT = Path(__file__).resolve().parents[4]
DEFAULT_ROBOT = REPO_ROOT / "models" / "robot.toml"

SCENES = ("servo_stand", "fig7_a", "fig7_b", "slope_stand", "slope_slide")
SLOPE = 0.3                 # rad, the slope scenes' ground line
SLOPE_MU = {"slope_stand": 0.6, "slope_slide": 0.25}
T_END = {"servo_stand": 0.2, "fig7_a": 0.1, "fig7_b": 0.1, "slope_stand": 0.2, "slope_slide": 0.4}


def load_robot(path=None, **ground) -> RobotModel:
    """RobotModel of the robot file (default models/robot.toml), with the
    ``[ground]`` keys in ``ground`` replaced (slope, mu_static, mu_kinetic)."""
    path = Path(path) if path is not None else DEFAULT_ROBOT
    data = copy.deepcopy(read_model_file(path))
    data["ground"].update(ground)
    return RobotModel(data, path.parent)


@dataclass
class Scene:
    name: str
    robot: RobotModel
    z0: np.ndarray               # (7,) start pose, at rest
    modes: tuple                 # 4 x "force" | "servo"
    values: np.ndarray           # (4,) N for force, m (length command) for servo
    t_end: float
    stuck: bool                  # the stuck-feet reference applies
    mu: float                    # the one friction coefficient a peer uses
    robot_path: Path = field(default=DEFAULT_ROBOT)
    slide_accel: Optional[float] = None   # expected CoM acceleration down the slope (m/s^2)

    @property
    def commands(self) -> list:
        return [ForceCommand(float(v)) if m == "force" else LengthCommand(float(v))
                for m, v in zip(self.modes, self.values)]

    @property
    def start(self):
        """The assembly whose feet are the stuck foot points."""
        return self.robot.assemble()

    def to_json(self) -> dict:
        """What a peer in another process needs to rebuild the scene."""
        return {"name": self.name, "robot_path": str(self.robot_path), "z0": self.z0.tolist(),
                "modes": list(self.modes), "values": self.values.tolist(), "t_end": self.t_end,
                "mu": self.mu, "slope": self.robot.ground.slope}


def setup(name: str, robot_path=None) -> Scene:
    """The scene ``name`` (see SCENES) on the robot file ``robot_path``."""
    if name not in SCENES:
        raise ValueError(f"unknown scene {name!r}; known: {SCENES}")
    path = Path(robot_path) if robot_path is not None else DEFAULT_ROBOT
    if name.startswith("slope"):
        mu = SLOPE_MU[name]
        robot = load_robot(path, slope=SLOPE, mu_static=mu, mu_kinetic=mu)
    else:
        robot = load_robot(path)
        mu = robot.ground.mu_static
    Ls = robot.stand_lengths()
    servo = [LengthCommand(float(x)) for x in Ls]
    t_end = T_END[name]
    if name == "fig7_b":
        F = robot.statics().actuator_forces.copy()
        F[0] += 50.0
        return Scene(name, robot, robot.assemble().z.copy(), ("force",) * 4, F, t_end, True, mu, path)
    z_eq = robot.equilibrium(servo)
    modes, values = ["servo"] * 4, Ls.copy()
    if name == "fig7_a":
        hold = robot.simulate(1e-6, t_eval=[0.0], actuators=servo, i0=z_eq[[2, 3, 4]]).actuator_forces[0]
        modes[0], values[0] = "force", float(hold[0]) + 50.0
    sc = Scene(name, robot, z_eq, tuple(modes), values, t_end, name != "slope_slide", mu, path)
    if name == "slope_slide":
        g = float(np.linalg.norm(robot.gravity))
        sc.slide_accel = g * (math.sin(SLOPE) - mu * math.cos(SLOPE))
    return sc


def reference(scene: Scene, t_eval) -> dict:
    """The stuck-feet reference at the times ``t_eval``: z (N, 7), the ground
    forces N, T (N, 2) per foot (right, left)."""
    if not scene.stuck:
        raise ValueError(f"{scene.name}: the feet slide; the stuck-feet reference does not apply")
    r = scene.robot.simulate(scene.t_end, t_eval=np.asarray(t_eval, float), actuators=scene.commands,
                             i0=scene.z0[[2, 3, 4]], start=scene.start)
    return {"t": r.t, "z": r.z, "normal": r.normal, "tangential": r.tangential,
            "actuator_forces": r.actuator_forces}


def angle_bodies(robot: RobotModel) -> list:
    """Per leg the global indices of the bodies whose world angle is
    psi + sign phi3 and psi + sign phi6 (found from the reference's
    Jacobians: d angle / d theta = sign (1, 0) and sign (0, 1))."""
    K = robot.kinematics(robot.assemble().z, np.zeros(7))
    out = []
    for leg in robot.legs:
        c, picks = leg.col, []
        for e in ((1.0, 0.0), (0.0, 1.0)):
            hit = [leg.body0 + i for i in range(leg.model.nb)
                   if np.allclose(K.J[leg.body0 + i, 2, c:c + 2], leg.sign * np.array(e), atol=1e-12)]
            if len(hit) != 1:
                raise ValueError(f"leg {leg.name}: no unique body carries its angle {e}")
            picks.append(hit[0])
        out.append(picks)
    return out


def z_of_q(robot: RobotModel, q, bodies=None) -> np.ndarray:
    """The reference's z (7,) from world poses q (39,) of the 13 bodies."""
    q = np.asarray(q, float).reshape(-1, 3)
    bodies = angle_bodies(robot) if bodies is None else bodies
    z = np.empty(7)
    z[:3] = q[0]
    for leg, (b3, b6) in zip(robot.legs, bodies):
        z[leg.col] = leg.sign * (q[b3, 2] - q[0, 2])
        z[leg.col + 1] = leg.sign * (q[b6, 2] - q[0, 2])
    return z


def trajectory_error(z, z_ref) -> float:
    """Max over samples and the 7 coordinates of |z - z_ref| (m or rad)."""
    return float(np.max(np.abs(np.asarray(z) - np.asarray(z_ref))))


def centre_of_mass(robot: RobotModel, q) -> np.ndarray:
    """World centre of mass (2,) of the 13 bodies for world poses q (39,)."""
    q = np.asarray(q, float).reshape(-1, 3)
    m = robot._m
    return (m[:, None] * q[:, :2]).sum(axis=0) / m.sum()
