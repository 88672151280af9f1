"""The hexapod in space (``legsim/hexapod.h``): its file, and the robot standing at a pose.

    >>> h = legsim.Hexapod.from_toml(legsim.data_path("models/hexapod.toml"))
    >>> pose = h.stand_pose(box_height=1.0)
    >>> s = h.statics(pose, stance=(0, 2, 4))          # a tripod
    >>> s["foot_force_n"][0]                           # N, world: the ground on the right front foot
    >>> m = h.sim(pose, stuck=(0, 2, 4))               # moving, the tripod's feet held
    >>> m.command(s["actuator_force_n"], s["rowing_torque_nm"])
    >>> m.step(100, h_s=1e-3); m.state()["box_m"]
    >>> slope = dict(slope_rad=0.26, uphill_rad=0.0)       # 15 degrees, rising along x
    >>> w = h.walk(period_s=1.2, duty=0.6, step_length_m=0.12, step_height_m=0.05,
    ...            box_height_m=1.0, t_end_s=2.4, ground=slope)   # up the fall line, the box level

Units SI, the world's z up. What the file holds and its ranges: firmware_core/include/legsim/hexapod.h;
the formulation and the rule statics takes for what it leaves free: docs/design/spatial.md.
"""
from __future__ import annotations

import ctypes as C
import os

import numpy as np

from ._lib import STORAGE_ALIGN, Library, load_library
from .model import Model

_MSG_LEN = 512
LEGS = 6
_FOOT_STATES = ("free", "stuck", "sliding")  # legsim_contact_state


class Hexapod:
    """A hexapod file's description (``legsim_hexapod_desc``)."""

    def __init__(self, desc, library: Library, source: str):
        self.desc, self.library, self.source = desc, library, source
        size = int(library.cdll.legsim_hexapod_storage_size())
        self._storage = C.create_string_buffer(size + STORAGE_ALIGN)
        base = C.addressof(self._storage)
        self._addr, self._size = base + (-base) % STORAGE_ALIGN, size

    @classmethod
    def from_toml(cls, path, *, precision: str | None = None, lib_path=None) -> "Hexapod":
        """Loads the hexapod file at ``path`` (its legs' files relative to it)."""
        lib = load_library(precision, lib_path)
        if not lib.has_toml_loader:
            raise RuntimeError(f"{lib.path}: this library has no TOML loader")
        desc = lib.HexapodDesc()
        msg = C.create_string_buffer(_MSG_LEN)
        path = os.fspath(path)
        st = lib.cdll.legsim_hexapod_load_toml(path.encode(), C.byref(desc), msg, _MSG_LEN)
        lib.check(st, "legsim_hexapod_load_toml", msg.value.decode(errors="replace"))
        return cls(desc, lib, path)

    @property
    def leg_names(self) -> list[str]:
        return [self.desc.leg[k].name.decode() for k in range(LEGS)]

    def leg_model(self, k: int) -> Model:
        """Leg k's planar model (its file, as the planar core reads it)."""
        d = self.library.ModelDesc()
        C.memmove(C.byref(d), C.byref(self.desc.leg[k].leg), C.sizeof(d))
        return Model(d, self.library, "revolute", self.source)

    def stand_pose(self, box_height: float, rowing=(0.0,) * LEGS) -> dict:
        """A pose with the box level at (0, 0, box_height) m and every leg at its file's stand
        lengths; rowing angles (rad) as given."""
        from .sim import Sim
        lengths = []
        for k in range(LEGS):
            s = Sim(self.leg_model(k))
            s.assemble_pose(0)
            lengths.append(list(s.actuator_lengths()[0]))
        return {"box_m": [0.0, 0.0, float(box_height)], "box_quat": [1.0, 0.0, 0.0, 0.0],
                "rowing_rad": list(rowing), "length_m": lengths}

    def ground_stand_pose(self, box_height: float) -> dict:
        """The stand on the ground plane (level or not): the box level box_height over the ground
        below the origin, each foot where the stand puts it seen from above, on the plane (the
        gait's set-points standing still; legsim_cli's pose on a sloped ground)."""
        sp = self.gait_setpoints(0.0, period_s=1.0, duty=0.75, step_length_m=0.0, step_height_m=0.0,
                                 box_height_m=box_height)
        return {"box_m": list(sp["box_m"]), "box_quat": [1.0, 0.0, 0.0, 0.0], "rowing_rad": list(sp["rowing_rad"]),
                "length_m": sp["length_m"].tolist()}

    @property
    def ground(self) -> dict:
        """The file's ground plane: point (m), upward unit normal, mu_static, mu_kinetic."""
        d = self.desc
        return {"point": list(d.ground_point_m), "normal": list(d.ground_normal),
                "mu_static": d.mu_static, "mu_kinetic": d.mu_kinetic}

    def on_ground(self, *, slope_rad: float | None = None, uphill_rad: float = 0.0, normal=None, point=None,
                  mu_static: float | None = None, mu_kinetic: float | None = None) -> "Hexapod":
        """This hexapod over another ground plane (each value left out keeps the file's): tilted by
        slope_rad from level, rising toward the heading uphill_rad (about the world's z from its x:
        0 rises along x, pi/2 along y), or with the upward unit ``normal`` itself; through
        ``point`` (m). Its gait, statics and sims are on that plane."""
        if slope_rad is not None and normal is not None:
            raise ValueError("give slope_rad (with uphill_rad) or normal, not both")
        h = Hexapod(type(self.desc).from_buffer_copy(self.desc), self.library, self.source)
        d = h.desc
        if slope_rad is not None:
            s = float(slope_rad)
            normal = (-np.sin(s) * np.cos(uphill_rad), -np.sin(s) * np.sin(uphill_rad), np.cos(s))
        if normal is not None:
            for i in range(3):
                d.ground_normal[i] = float(normal[i])
        if point is not None:
            for i in range(3):
                d.ground_point_m[i] = float(point[i])
        if mu_static is not None:
            d.mu_static = float(mu_static)
        if mu_kinetic is not None:
            d.mu_kinetic = float(mu_kinetic)
        return h

    def _on(self, ground) -> "Hexapod":
        """self, or self on_ground(**ground) (a dict of on_ground's keywords)."""
        return self if ground is None else self.on_ground(**ground)

    def gait_setpoints(self, t_s: float, *, period_s: float, duty: float, step_length_m: float,
                       step_height_m: float, turn_rad: float = 0.0, box_height_m: float, ground=None) -> dict:
        """The tripod gait's set-points at ``t_s`` (legsim_hexapod_gait_setpoints) on the file's ground
        (or ``ground``: a dict of on_ground's keywords): each foot's target in the box's frame
        (foot_box_m, 6 x 3), whether it stands (stance, 6 bools), the rowing angles (rowing_rad)
        and actuator lengths (length_m, 6 x 2) that put it there, and the box's planned pose
        (box_m, box_quat: world; on a slope the box stays level, box_height_m over the ground
        below it). Raises OutOfStrokeError (or UnreachableError, ...) for a target the leg cannot
        reach."""
        if ground is not None:
            return self._on(ground).gait_setpoints(t_s, period_s=period_s, duty=duty, step_length_m=step_length_m,
                                                   step_height_m=step_height_m, turn_rad=turn_rad,
                                                   box_height_m=box_height_m)
        lib = self.library
        g = lib.HexapodGait(float(period_s), float(duty), float(step_length_m), float(step_height_m),
                            float(turn_rad), float(box_height_m))
        out = lib.HexapodSetpoint()
        st = lib.cdll.legsim_hexapod_gait_setpoints(C.byref(self.desc), C.byref(g), float(t_s),
                                                    C.c_void_p(self._addr), self._size, C.byref(out))
        lib.check(st, "legsim_hexapod_gait_setpoints")
        return {"foot_box_m": np.array([out.foot_box_m[k][:] for k in range(LEGS)]),
                "stance": np.array([bool(out.stance[k]) for k in range(LEGS)]),
                "rowing_rad": np.array(out.rowing_rad[:]),
                "length_m": np.array([out.length_m[k][:] for k in range(LEGS)]),
                "box_m": np.array(out.box_m[:]), "box_quat": np.array(out.box_quat[:])}

    def body_masses(self) -> np.ndarray:
        """Every body's mass (kg) in body_poses' order: the box, then per leg its yoke and its bars."""
        d = self.desc
        m = [d.box_mass_kg]
        for k in range(LEGS):
            leg = d.leg[k].leg
            m += [d.yoke_mass_kg] + [leg.body[b].mass_kg for b in range(leg.n_bodies)]
        return np.array(m)

    def support_margin(self, foot_m, com_m) -> float:
        """The static stability margin (m) of the feet at foot_m (n x 3, world) about com_m:
        legsim_hexapod_support_margin (both projected along gravity; -inf for fewer than three
        feet or feet on one line)."""
        f = np.asarray(foot_m, dtype=float).reshape(-1, 3)
        arr = (C.c_double * 3 * LEGS)(*[(C.c_double * 3)(*row) for row in f.tolist()])
        com = (C.c_double * 3)(*[float(x) for x in com_m])
        out = C.c_double()
        self.library.check(self.library.cdll.legsim_hexapod_support_margin(arr, len(f), com, C.byref(out)),
                           "legsim_hexapod_support_margin")
        return out.value

    def _pose(self, pose: dict):
        p = self.library.HexapodPose()
        for i in range(3):
            p.box_m[i] = float(pose["box_m"][i])
        for i in range(4):
            p.box_quat[i] = float(pose["box_quat"][i])
        for k in range(LEGS):
            p.rowing_rad[k] = float(pose["rowing_rad"][k])
            for a in range(2):
                p.length_m[k][a] = float(pose["length_m"][k][a])
        return p

    def walk(self, *, period_s: float, duty: float, step_length_m: float, step_height_m: float,
             box_height_m: float, turn_rad: float = 0.0, t_end_s: float, h_s: float = 1e-3,
             every: int = 10, feedforward: bool = True, integrator: str = "rk4", ground=None) -> dict:
        """The robot walking on the tripod gait over the file's ground (or ``ground``: a dict of
        on_ground's keywords): it starts at rest at the gait's pose at t = 0 (the box level
        box_height_m over the ground below the origin, the standing feet stuck on the ground, the
        others free), and before every step of h_s its servos get the gait's set-points at the
        step's end (HexapodSim.command_pose) with, by default, the statics of the planned pose on
        its planned stance as feed-forward (the load the servos' gains alone would sag under); the
        feet touch down, stick, slip and lift off as the ground's cones decide. Returns numpy
        arrays sampled every `every` steps (the start included): t_s, box_m (n, 3), box_quat (n,
        4), foot_m (n, 6, 3), foot_force_n (n, 6, 3), foot_state (n, 6: 0 free, 1 stuck, 2
        sliding), set_foot_box_m (n, 6, 3: the gait's targets in the box's frame), set_box_m (n,
        3: the box's planned centre), com_m (n, 3: the centre of mass), margin_m (n: the static
        stability margin of the gait's stance feet, where they are, about it: support_margin),
        plan_margin_m (n: the planned pose's, its statics'), body_pose (n, bodies, 7), events (each sample's count
        since the last), impacts (touchdowns so far), kinetic_energy_j. ``integrator``: as
        HexapodSim.set_integrator."""
        if ground is not None:
            return self._on(ground).walk(period_s=period_s, duty=duty, step_length_m=step_length_m,
                                         step_height_m=step_height_m, box_height_m=box_height_m, turn_rad=turn_rad,
                                         t_end_s=t_end_s, h_s=h_s, every=every, feedforward=feedforward,
                                         integrator=integrator)
        gait = dict(period_s=period_s, duty=duty, step_length_m=step_length_m, step_height_m=step_height_m,
                    turn_rad=turn_rad, box_height_m=box_height_m)
        sp = self.gait_setpoints(0.0, **gait)
        # the box level over the origin: gravity acts along its z at every planned pose, so the
        # statics there are the planned pose's (its place and heading change none of them)
        pose = {"box_m": list(sp["box_m"]), "box_quat": [1.0, 0.0, 0.0, 0.0],
                "rowing_rad": list(sp["rowing_rad"]), "length_m": sp["length_m"].tolist()}
        m = self.sim(pose, stuck=[k for k in range(LEGS) if sp["stance"][k]], integrator=integrator)
        masses = self.body_masses()
        plan_margin = [np.nan]

        def command(sp):
            ff = fm = None
            if feedforward:
                at = dict(pose, rowing_rad=list(sp["rowing_rad"]), length_m=sp["length_m"].tolist())
                s = self.statics(at, stance=[k for k in range(LEGS) if sp["stance"][k]])
                ff, fm = s["actuator_force_n"], s["rowing_torque_nm"]
                plan_margin[0] = s["margin_m"]
            m.command_pose(sp["length_m"], sp["rowing_rad"], ff, fm)

        # before every step the set-points at its end: the first's before the start's sample (as
        # legsim_cli; a second command would restart generalized-alpha's history once more)
        first = self.gait_setpoints(float(h_s), **gait)
        command(first)
        n = int(round(float(t_end_s) / float(h_s)))
        out = {k: [] for k in ("t_s", "box_m", "box_quat", "foot_m", "foot_force_n", "foot_state",
                               "set_foot_box_m", "set_box_m", "com_m", "margin_m", "plan_margin_m", "body_pose",
                               "events", "impacts", "kinetic_energy_j")}
        events = 0

        def sample(st, sp):
            out["t_s"].append(st["t_s"])
            for k in ("box_m", "box_quat", "foot_m", "foot_force_n", "impacts", "kinetic_energy_j"):
                out[k].append(st[k])
            out["foot_state"].append([_FOOT_STATES.index(x) for x in st["foot_state"]])
            out["set_foot_box_m"].append(sp["foot_box_m"])
            out["set_box_m"].append(sp["box_m"])
            bodies = m.body_poses()
            com = masses @ bodies[:, :3] / masses.sum()
            out["com_m"].append(com)
            # the feet the gait stands on, where they are (a foot bouncing inside a step is no
            # less the stance's)
            on = [k for k in range(LEGS) if sp["stance"][k]]
            out["margin_m"].append(self.support_margin(st["foot_m"][on], com))
            out["plan_margin_m"].append(plan_margin[0])
            out["body_pose"].append(bodies)
            out["events"].append(events)

        st = m.state()
        sample(st, sp)
        for i in range(n):
            sp = self.gait_setpoints((i + 1) * float(h_s), **gait) if i else first
            if i:
                command(sp)
            m.step(1, h_s=h_s)
            st = m.state()
            events += st["events"]
            if (i + 1) % every == 0 or i + 1 == n:
                sample(st, sp)
                events = 0
        res = {k: np.array(v) for k, v in out.items()}
        res["cone"] = st["cone"]
        return res

    def sim(self, pose: dict, stuck=None, integrator: str = "rk4", *, box_stuck=()) -> "HexapodSim":
        """The robot moving from ``pose`` (as statics'), at rest, the feet of ``stuck`` (leg
        indices; every leg the file has by default) and the box's own contact points of
        ``box_stuck`` (indices of the file's [[box_contact]]s) held where the pose puts them, the
        commands zero (legsim_hexapod_sim_init), stepped by ``integrator``
        (HexapodSim.set_integrator). A block (a file of no legs) has no feet: its points are
        ``box_stuck``."""
        legs = range(self.desc.n_legs) if stuck is None else stuck
        mask = _mask(legs, "stuck")
        for k in box_stuck:
            if not 0 <= int(k) < self.desc.n_box_contacts:
                raise ValueError(f"box_stuck: the file has no box contact point {k} "
                                 f"(0..{self.desc.n_box_contacts - 1})")
            mask |= 1 << (LEGS + int(k))
        m = HexapodSim(self, pose, mask)
        m.set_integrator(integrator)
        return m

    def statics(self, pose: dict, stance=range(LEGS), box_force_n=None) -> dict:
        """The robot standing at ``pose`` (keys box_m, box_quat (w, x, y, z), rowing_rad,
        length_m: each leg's two lengths) on the feet of ``stance`` (leg indices), a force
        ``box_force_n`` (N, world) at the box's centre. Returns numpy arrays: com_m (3), foot_m
        (6, 3), foot_force_n (6, 3), actuator_force_n (6, 2), rowing_torque_nm (6), and
        margin_m. Raises NoEquilibriumError when the stance cannot hold the loads."""
        lib = self.library
        p = self._pose(pose)
        mask = _mask(stance, "stance")
        force = None if box_force_n is None else (C.c_double * 3)(*[float(x) for x in box_force_n])
        out = lib.HexapodStanding()
        st = lib.cdll.legsim_hexapod_statics(C.byref(self.desc), C.byref(p), mask, force,
                                             C.c_void_p(self._addr), self._size, C.byref(out))
        lib.check(st, "legsim_hexapod_statics")
        return {"com_m": np.array(out.com_m[:]), "foot_m": np.array([out.foot_m[k][:] for k in range(LEGS)]),
                "foot_force_n": np.array([out.foot_force_n[k][:] for k in range(LEGS)]),
                "actuator_force_n": np.array([out.actuator_force_n[k][:] for k in range(LEGS)]),
                "rowing_torque_nm": np.array(out.rowing_torque_nm[:]), "margin_m": float(out.margin_m)}

    def inverse_dynamics(self, t_s, *, period_s: float, duty: float, step_length_m: float,
                         step_height_m: float, turn_rad: float = 0.0, box_height_m: float) -> dict:
        """The forces that make the robot follow the tripod gait exactly, at each time of ``t_s``
        (s, a number or a sequence; legsim_hexapod_inverse_dynamics): the robot where the gait's
        set-points put it, the box on its plan (level at box_height_m, over the origin at t = 0,
        at the gait's constant twist), the standing feet stuck, the swinging ones on their curves;
        the stance feet take the loads and the inertial forces with the least sum of squares of
        their forces (statics' rule). Returns numpy arrays, one row per time: t_s (n),
        actuator_force_n (n, 6, 2), rowing_torque_nm (n, 6), foot_force_n (n, 6, 3: the ground's
        on each foot, world; 0 swinging), cone_ratio (n, 6: |F_t| / N on the file's ground, 0
        swinging; compare with desc.mu_static), stance (n, 6 bools), foot_m, foot_velocity_mps,
        foot_acceleration_mps2 (n, 6, 3, world; a swinging foot's rates by five-point differences
        of its curve), box_m (n, 3), box_quat (n, 4), joint_force_n and joint_moment_nm (n, 6, 11, 3: per leg its hip's
        reaction on its yoke, then its file's joints' on their first bodies; the force in the
        world, the moment about the joint's point; n_joints (6) of each leg's rows are used)."""
        lib = self.library
        g = lib.HexapodGait(float(period_s), float(duty), float(step_length_m), float(step_height_m),
                            float(turn_rad), float(box_height_m))
        size = int(lib.cdll.legsim_hexapod_inverse_storage_size())
        buf = C.create_string_buffer(size + STORAGE_ALIGN)
        addr = C.addressof(buf) + (-C.addressof(buf)) % STORAGE_ALIGN
        keys = ("t_s", "actuator_force_n", "rowing_torque_nm", "foot_force_n", "cone_ratio", "stance",
                "foot_m", "foot_velocity_mps", "foot_acceleration_mps2", "box_m", "box_quat", "joint_force_n",
                "joint_moment_nm")
        out = {k: [] for k in keys}
        r = lib.HexapodInverse()
        n_joints = None
        for t in np.atleast_1d(np.asarray(t_s, dtype=float)):
            st = lib.cdll.legsim_hexapod_inverse_dynamics(C.byref(self.desc), C.byref(g), float(t),
                                                          C.c_void_p(addr), size, C.byref(r))
            lib.check(st, "legsim_hexapod_inverse_dynamics")
            out["t_s"].append(r.t_s)
            for k in keys[1:]:
                out[k].append(np.ctypeslib.as_array(getattr(r, k)).copy())
            n_joints = np.array(r.n_joints[:])
        res = {k: np.array(v) for k, v in out.items()}
        res["stance"] = res["stance"].astype(bool)
        res["n_joints"] = n_joints
        return res

    def gait_state(self, t_s: float, *, period_s: float, duty: float, step_length_m: float,
                   step_height_m: float, turn_rad: float = 0.0, box_height_m: float) -> dict:
        """The plan's state that inverse_dynamics solves at (legsim_hexapod_gait_state): every
        body's pose q (bodies x 7: centre, quaternion w, x, y, z), velocity v and acceleration a
        (bodies x 6: world, then angular in the body's frame), bodies as HexapodSim.body_poses'."""
        lib = self.library
        g = lib.HexapodGait(float(period_s), float(duty), float(step_length_m), float(step_height_m),
                            float(turn_rad), float(box_height_m))
        size = int(lib.cdll.legsim_hexapod_inverse_storage_size())
        buf = C.create_string_buffer(size + STORAGE_ALIGN)
        addr = C.addressof(buf) + (-C.addressof(buf)) % STORAGE_ALIGN
        cap = 1 + LEGS * (1 + 8)
        q, v, a = (C.c_double * (7 * cap))(), (C.c_double * (6 * cap))(), (C.c_double * (6 * cap))()
        n = C.c_int32()
        st = lib.cdll.legsim_hexapod_gait_state(C.byref(self.desc), C.byref(g), float(t_s), C.c_void_p(addr),
                                                size, q, v, a, cap, C.byref(n))
        lib.check(st, "legsim_hexapod_gait_state")
        nb = n.value
        return {"q": np.array(q[:7 * nb]).reshape(nb, 7), "v": np.array(v[:6 * nb]).reshape(nb, 6),
                "a": np.array(a[:6 * nb]).reshape(nb, 6)}



    def leg_reach(self, leg: int, foot_box_m) -> tuple[float, np.ndarray]:
        """Leg ``leg``'s rowing angle (rad) and two actuator lengths (m) that put its foot at
        ``foot_box_m`` (m, the box's frame), from its file's stand (legsim_hexapod_leg_reach).
        Raises OutOfStrokeError / UnreachableError (LegsimError) for a point it cannot reach."""
        lib = self.library
        foot = np.asarray(foot_box_m, dtype=float)
        if foot.shape != (3,):
            raise ValueError(f"foot_box_m: 3 values, got shape {foot.shape}")
        psi, length = C.c_double(), (C.c_double * 2)()
        st = lib.cdll.legsim_hexapod_leg_reach(C.byref(self.desc), int(leg), (C.c_double * 3)(*foot.tolist()),
                                               C.c_void_p(self._addr), self._size, C.byref(psi), length)
        lib.check(st, "legsim_hexapod_leg_reach")
        return psi.value, np.array(length[:])

    def reaction_sweep(self, *, leg: int = 0, stance=(0, 2, 4), box_height_m: float = 1.0,
                       distance_m=(0.40, 0.62), n_distance: int = 23, heading_rad=(0.0, 0.0), n_heading: int = 1,
                       first: int = 0, count: int | None = None) -> dict:
        """The paper's Section V (legsim_hexapod_reaction_sweep): the robot on ``stance`` with its
        box level ``box_height_m`` above the stance feet's plane, leg ``leg``'s foot moved about
        its hip over distance x direction (from the leg's heading) grids; the points ``first`` ..
        ``first + count - 1`` (all by default), so that parts run anywhere concatenate. Returns
        numpy arrays per point: index, status (0: LEGSIM_OK), distance_m, heading_rad, rowing_rad,
        length_m (n, 2), foot_force_n (n, 6, 3), actuator_force_n (n, 6, 2), rowing_torque_nm
        (n, 6), margin_m, com_m (n, 3), foot_m (n, 6, 3); a point without statics has NaN values."""
        lib = self.library
        total = int(n_distance) * int(n_heading)
        count = max(total - int(first), 1) if count is None else int(count)  # (the library refuses an empty grid)
        sw = lib.HexapodSweep(leg=int(leg), stance_mask=_mask(stance, "stance"), box_height_m=float(box_height_m),
                              distance_m=(C.c_double * 2)(*[float(x) for x in distance_m]),
                              n_distance=int(n_distance),
                              heading_rad=(C.c_double * 2)(*[float(x) for x in heading_rad]),
                              n_heading=int(n_heading))
        if count < 1:
            raise ValueError(f"count: at least one point (first {first} of {total})")
        out = (lib.HexapodSweepPoint * count)()
        st = lib.cdll.legsim_hexapod_reaction_sweep(C.byref(self.desc), C.byref(sw), int(first), count,
                                                    C.c_void_p(self._addr), self._size, out)
        lib.check(st, "legsim_hexapod_reaction_sweep")
        def table(get, shape):
            a = np.full((count,) + shape, np.nan)
            for k, p in enumerate(out):
                if p.status == 0:
                    a[k] = np.array(get(p), dtype=float).reshape(shape)
            return a

        def rows(x):
            return [r[:] for r in x]
        return {"index": np.array([p.index for p in out]), "status": np.array([p.status for p in out]),
                "distance_m": np.array([p.distance_m for p in out]),
                "heading_rad": np.array([p.heading_rad for p in out]),
                "rowing_rad": table(lambda p: p.rowing_rad, ()), "length_m": table(lambda p: p.length_m[:], (2,)),
                "foot_force_n": table(lambda p: rows(p.standing.foot_force_n), (LEGS, 3)),
                "actuator_force_n": table(lambda p: rows(p.standing.actuator_force_n), (LEGS, 2)),
                "rowing_torque_nm": table(lambda p: p.standing.rowing_torque_nm[:], (LEGS,)),
                "margin_m": table(lambda p: p.standing.margin_m, ()),
                "com_m": table(lambda p: p.standing.com_m[:], (3,)),
                "foot_m": table(lambda p: rows(p.standing.foot_m), (LEGS, 3))}


def _pairs(x, what: str):
    """A 6 x 2 table as ctypes (ValueError for another shape: ctypes would fill it with zeros)."""
    a = np.asarray(x, dtype=float)
    if a.shape != (LEGS, 2):
        raise ValueError(f"{what}: 6 x 2 values (one pair per leg), got shape {a.shape}")
    return ((C.c_double * 2) * LEGS)(*[(C.c_double * 2)(*row) for row in a.tolist()])


def _six(x, what: str):
    a = np.asarray(x, dtype=float)
    if a.shape != (LEGS,):
        raise ValueError(f"{what}: 6 values (one per leg), got shape {a.shape}")
    return (C.c_double * LEGS)(*a.tolist())


def _mask(legs, what: str) -> int:
    mask = 0
    for k in legs:
        if not 0 <= int(k) < LEGS:
            raise ValueError(f"{what}: leg {k} does not exist (0..5)")
        mask |= 1 << int(k)
    return mask


class HexapodSim:
    """The hexapod moving (``legsim_hexapod_sim``): RK4 (or generalized-alpha) on the rotation group, the stuck feet
    held; each linear actuator's force and each rowing torque held as commanded."""

    def __init__(self, hexapod: Hexapod, pose: dict, mask: int):
        lib = self.library = hexapod.library
        size = int(lib.cdll.legsim_hexapod_sim_size())
        self._storage = C.create_string_buffer(size + STORAGE_ALIGN)
        base = C.addressof(self._storage)
        addr = base + (-base) % STORAGE_ALIGN
        self._sim = C.c_void_p()
        st = lib.cdll.legsim_hexapod_sim_init(C.c_void_p(addr), size, C.byref(hexapod.desc),
                                              C.byref(hexapod._pose(pose)), mask, C.byref(self._sim))
        lib.check(st, "legsim_hexapod_sim_init")

    def command(self, actuator_force_n, rowing_torque_nm) -> None:
        """Each leg's two actuators' axial forces (N, 6 x 2) and rowing torques (N m, 6)."""
        f, t = _pairs(actuator_force_n, "actuator_force_n"), _six(rowing_torque_nm, "rowing_torque_nm")
        self.library.check(self.library.cdll.legsim_hexapod_command(self._sim, f, t), "legsim_hexapod_command")

    def command_pose(self, length_m, rowing_rad, feedforward_n=None, feedforward_nm=None) -> None:
        """The servos' set-points: each leg's two actuator lengths (m, 6 x 2) and rowing angles
        (rad, 6), e.g. a gait's (Hexapod.gait_setpoints), with feed-forward forces (N, 6 x 2) and
        torques (N m, 6) added to the servos' (None: 0). Raises OutOfStrokeError past a stroke."""
        f, t = _pairs(length_m, "length_m"), _six(rowing_rad, "rowing_rad")
        ff = None if feedforward_n is None else _pairs(feedforward_n, "feedforward_n")
        fm = None if feedforward_nm is None else _six(feedforward_nm, "feedforward_nm")
        self.library.check(self.library.cdll.legsim_hexapod_command_pose(self._sim, f, t, ff, fm),
                           "legsim_hexapod_command_pose")

    def command_each(self, mode, value, feedforward=None) -> None:
        """Each command slot on its own (legsim_hexapod_command_each): per leg (6 rows) its upper
        and lower actuators and its rowing motor (3 columns), mode "keep" (unchanged), "force"
        (value: N or N m) or "servo" (value: the set-point, m or rad; feedforward: N or N m, None:
        0). Raises OutOfStrokeError past a stroke, BadInputError for a value out of range; all
        or nothing."""
        modes = {"keep": 0, "force": 1, "servo": 2}
        m = np.asarray(mode, dtype=object)
        v = np.asarray(value, dtype=float)
        f = np.zeros((LEGS, 3)) if feedforward is None else np.asarray(feedforward, dtype=float)
        for name, a in (("mode", m), ("value", v), ("feedforward", f)):
            if a.shape != (LEGS, 3):
                raise ValueError(f"{name}: 6 x 3 values (per leg: upper, lower, rowing), got shape {a.shape}")
        bad = [x for x in m.ravel() if x not in modes]
        if bad:
            raise ValueError(f"mode: each one of {sorted(modes)}, got {bad[0]!r}")
        lib = self.library
        c = lib.HexapodCommands()
        for k in range(LEGS):
            for j in range(3):
                c.mode[k][j], c.value[k][j], c.feedforward[k][j] = modes[m[k, j]], v[k, j], f[k, j]
        lib.check(lib.cdll.legsim_hexapod_command_each(self._sim, C.byref(c)), "legsim_hexapod_command_each")

    def body_poses(self) -> np.ndarray:
        """Every body's pose (bodies x 7: centre, unit quaternion w, x, y, z; world): the box,
        then per leg its yoke and its bars in its file's order (a bar's axis is its frame's x)."""
        cap = 1 + LEGS * (1 + 8)
        buf = (C.c_double * (7 * cap))()
        n = C.c_int32()
        self.library.check(self.library.cdll.legsim_hexapod_body_poses(self._sim, buf, cap, C.byref(n)),
                           "legsim_hexapod_body_poses")
        return np.array(buf[:7 * n.value]).reshape(n.value, 7)

    def set_integrator(self, integrator: str) -> None:
        """The steps' integrator from the next on: "rk4" (order 4) or "galpha" (generalized-alpha,
        order 2, numerically damped: legsim_hexapod_set_integrator)."""
        codes = {"rk4": 0, "galpha": 1}
        if integrator not in codes:
            raise ValueError(f"integrator: {integrator!r} is not one of {sorted(codes)}")
        self.library.check(self.library.cdll.legsim_hexapod_set_integrator(self._sim, codes[integrator]),
                           "legsim_hexapod_set_integrator")

    def set_velocity(self, velocity_mps, omega_radps=(0.0, 0.0, 0.0)) -> None:
        """A launch before the first step: the box's velocity (m/s, world) and angular velocity
        (rad/s, its frame), every body carried with it; a point stuck at the start that this moves
        along the ground slides (legsim_hexapod_set_velocity)."""
        v = (C.c_double * 3)(*[float(x) for x in velocity_mps])
        w = (C.c_double * 3)(*[float(x) for x in omega_radps])
        self.library.check(self.library.cdll.legsim_hexapod_set_velocity(self._sim, v, w),
                           "legsim_hexapod_set_velocity")

    def step(self, n: int = 1, *, h_s: float = 1e-3) -> None:
        self.library.check(self.library.cdll.legsim_hexapod_step(self._sim, float(h_s), int(n)),
                           "legsim_hexapod_step")

    def state(self) -> dict:
        """t_s, box_m, box_quat (w, x, y, z), box_velocity_mps (world), box_omega_radps (box frame),
        rowing_rad (6), length_m (6 x 2), foot_m (6 x 3, world), foot_force_n (6 x 3: the ground's
        on each foot), actuator_force_n (6 x 2), rowing_torque_nm (6), foot_state (6: "free", "stuck"
        or "sliding"), kinetic_energy_j, events (located
        in the last step), impacts (touchdowns since the start), cone (the contact problems on the
        cones since the start: solved, by_sweeps, max_iterations, max_residual), actuator_stop (6 x
        2) and rowing_stop (6): -1 on the stroke's min stop, 1 on its max, 0 inside; stop_impacts
        (arrivals on a stop since the start); length_rate_mps (6 x 2) and rowing_rate_radps (6);
        the box's own contact points (the file's [[box_contact]], n of them) as the feet:
        box_contact_m (n x 3, world), box_contact_force_n (n x 3), box_contact_state (n)."""
        out = self.library.HexapodState()
        self.library.check(self.library.cdll.legsim_hexapod_get_state(self._sim, C.byref(out)),
                           "legsim_hexapod_get_state")
        return {"t_s": out.t_s, "box_m": np.array(out.box_m[:]), "box_quat": np.array(out.box_quat[:]),
                "box_velocity_mps": np.array(out.box_velocity_mps[:]),
                "box_omega_radps": np.array(out.box_omega_radps[:]), "rowing_rad": np.array(out.rowing_rad[:]),
                "length_m": np.array([out.length_m[k][:] for k in range(LEGS)]),
                "foot_m": np.array([out.foot_m[k][:] for k in range(LEGS)]),
                "foot_force_n": np.array([out.foot_force_n[k][:] for k in range(LEGS)]),
                "actuator_force_n": np.array([out.actuator_force_n[k][:] for k in range(LEGS)]),
                "rowing_torque_nm": np.array(out.rowing_torque_nm[:]),
                "foot_state": [_FOOT_STATES[out.foot_state[k]] for k in range(LEGS)],
                "kinetic_energy_j": out.kinetic_energy_j, "events": out.events, "impacts": out.impacts,
                "cone": {"solved": out.cone_solved, "by_sweeps": out.cone_by_sweeps,
                         "max_iterations": out.cone_max_iterations, "max_residual": out.cone_max_residual},
                "actuator_stop": np.array([out.actuator_stop[k][:] for k in range(LEGS)]),
                "rowing_stop": np.array(out.rowing_stop[:]), "stop_impacts": out.stop_impacts,
                "length_rate_mps": np.array([out.length_rate_mps[k][:] for k in range(LEGS)]),
                "rowing_rate_radps": np.array(out.rowing_rate_radps[:]),
                "box_contact_m": np.array([out.box_contact_m[k][:] for k in range(out.n_box_contacts)]).reshape(-1, 3),
                "box_contact_force_n": np.array([out.box_contact_force_n[k][:]
                                                 for k in range(out.n_box_contacts)]).reshape(-1, 3),
                "box_contact_state": [_FOOT_STATES[out.box_contact_state[k]] for k in range(out.n_box_contacts)]}
