"""legsim itself on the two-leg robot scenes, measured the way the peers are.

The same scenes (robot_scenes.setup: start pose, actuator modes and values)
through legsim's Python API (python/legsim, liblegsim.so) on the robot file the
scene names: the state set to the scene's start (RobotModel.absolute_q of z0,
at rest), both feet set stuck where they stand, the four commands given
(force: legsim_command_force; servo: legsim_command_length, whose servo law is
leg.toml's, the reference's), then fixed steps h of RK4 (+ projection) or
generalized-alpha.

Error: as mujoco_robot.compare, err_z along the whole trajectory sampled every
1 ms (z of the 13 bodies' world poses, robot_scenes.z_of_q) and err_NT at the
end (legsim_contacts' N, T per foot; contact 0 is the right foot, as the
reference's column 0).

Cost: the smallest over ``repeats`` of the wall time (time.perf_counter_ns) of
ONE ``legsim_step(sim, n_steps)`` call over the whole scene, divided by the
steps, after a fresh set-up each time (set-up excluded): a compiled loop timed
from Python, as mujoco.rollout is for MuJoCo.
"""
from __future__ import annotations

import numpy as np

from .. import core as lc
from . import robot_scenes as rs

try:
    import legsim
except ImportError:  # the bench without the Python API
    legsim = None

METHODS = ("rk4", "galpha")
METHOD_LABEL = {"rk4": "RK4 + projection", "galpha": "generalized-alpha"}


def available() -> bool:
    return legsim is not None and legsim.library_available("double")


class LegsimRobot:
    """One scene at one step and integrator: ``set_up`` then ``simulate`` / ``time``."""

    def __init__(self, scene, h: float, method: str = "rk4", robot_path=None):
        if legsim is None:
            raise ImportError("the legsim Python API (python/legsim) is not importable")
        if method not in METHODS:
            raise ValueError(f"method must be one of {METHODS}, not {method!r}")
        self.scene = rs.setup(scene, robot_path) if isinstance(scene, str) else scene
        self.h, self.method = float(h), method
        self.sim = legsim.Sim(str(self.scene.robot_path), integrator=method, step=self.h)
        self.q0 = self.scene.robot.absolute_q(self.scene.z0)
        self.bodies = rs.angle_bodies(self.scene.robot)
        self.n_steps = int(round(self.scene.t_end / self.h))
        if self.n_steps < 1 or abs(self.n_steps * self.h - self.scene.t_end) > 1e-9:
            raise ValueError(f"t_end={self.scene.t_end} is not a positive multiple of h={h}")

    def set_up(self) -> None:
        """The scene's start at t = 0: pose z0 at rest, both feet stuck, the commands."""
        s = self.sim
        s.set_state(self.q0, np.zeros_like(self.q0), 0.0)
        for k in range(s.n_contacts):
            s.set_contact(k, "stuck")
        for a, (mode, v) in enumerate(zip(self.scene.modes, self.scene.values)):
            (s.command_force if mode == "force" else s.command_length)(a, float(v))

    def simulate(self, every: int = 1) -> dict:
        """The trajectory, sampled every ``every`` steps, and the ground forces at the end."""
        self.set_up()
        s, robot = self.sim, self.scene.robot
        t, z = [0.0], [rs.z_of_q(robot, s.q, self.bodies)]
        done = 0
        while done < self.n_steps:
            k = min(every, self.n_steps - done)
            s.step(k)
            done += k
            t.append(s.time)
            z.append(rs.z_of_q(robot, s.q, self.bodies))
        c = s.contacts()
        return {"t": np.array(t), "z": np.array(z), "normal": np.array(c["normal"], float),
                "tangential": np.array(c["tangential"], float), "states": list(c["state"])}

    def time(self) -> float:
        """Wall time per step (s) of one legsim_step call over the scene, set-up excluded."""
        self.set_up()
        return lc.timed_step(self.sim, self.n_steps) * 1e-9 / self.n_steps


def compare(scene, h: float, method: str = "rk4", *, sample_dt: float = 1e-3, repeats: int = 1,
            ref=None, robot_path=None) -> dict:
    """err_z, err_NT against the reference (as mujoco_robot.compare) and per_step_s, the
    smallest over ``repeats`` timed runs."""
    peer = LegsimRobot(scene, h, method, robot_path)
    every = int(round(sample_dt / h))
    if every < 1 or abs(every * h - sample_dt) > 1e-9:
        raise ValueError(f"sample_dt={sample_dt} is not a multiple of h={h}")
    r = peer.simulate(every)
    if ref is None:
        ref = rs.reference(peer.scene, r["t"])
    r["err_z"] = rs.trajectory_error(r["z"], ref["z"])
    r["err_NT"] = float(max(np.max(np.abs(r["normal"] - ref["normal"][-1])),
                            np.max(np.abs(r["tangential"] - ref["tangential"][-1]))))
    r["per_step_s"] = min(peer.time() for _ in range(max(1, repeats)))
    r.update(engine=f"legsim {peer.sim.precision}", method=METHOD_LABEL[method], h=peer.h,
             scene=peer.scene.name, n_steps=peer.n_steps,
             ok=bool(np.all(np.isfinite(r["z"]))) and all(st == "stuck" for st in r["states"]),
             ref=ref)
    return r
