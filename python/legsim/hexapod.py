"""The hexapod in space (``legsim/hexapod.h``): its file, and the robot standing at a pose.

    >>> h = legsim.Hexapod.from_toml(legsim.data_path("models/hexapod.toml"))
    >>> pose = h.stand_pose(box_height=1.0)
    >>> s = h.statics(pose, stance=(0, 2, 4))          # a tripod
    >>> s["foot_force_n"][0]                           # N, world: the ground on the right front foot
    >>> m = h.sim(pose, stuck=(0, 2, 4))               # moving, the tripod's feet held
    >>> m.command(s["actuator_force_n"], s["rowing_torque_nm"])
    >>> m.step(100, h_s=1e-3); m.state()["box_m"]

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

    def gait_setpoints(self, t_s: float, *, period_s: float, duty: float, step_length_m: float,
                       step_height_m: float, turn_rad: float = 0.0, box_height_m: float) -> dict:
        """The tripod gait's set-points at ``t_s`` (legsim_hexapod_gait_setpoints): each foot's
        target in the box's frame (foot_box_m, 6 x 3), whether it stands (stance, 6 bools), and
        the rowing angles (rowing_rad) and actuator lengths (length_m, 6 x 2) that put it there.
        Raises OutOfStrokeError (or UnreachableError, ...) for a target the leg cannot reach."""
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
                "length_m": np.array([out.length_m[k][:] for k in range(LEGS)])}

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
             every: int = 10, feedforward: bool = True, integrator: str = "rk4") -> dict:
        """The robot walking on the tripod gait: it starts at rest at the gait's pose at t = 0
        (the box level box_height_m over the origin, the standing feet stuck on the ground of the
        file, the others free), and before every step of h_s its servos get the gait's set-points
        at the step's end (HexapodSim.command_pose) with, by default, the statics of the planned
        pose on its planned stance as feed-forward (the load the servos' gains alone would sag
        under); the feet touch down, stick, slip and lift off as the ground's cones decide. Returns numpy arrays sampled every `every` steps (the
        start included): t_s, box_m (n, 3), box_quat (n, 4), foot_m (n, 6, 3), foot_force_n
        (n, 6, 3), foot_state (n, 6: 0 free, 1 stuck, 2 sliding), set_foot_box_m (n, 6, 3: the
        gait's targets in the box's frame), body_pose (n, bodies, 7), events (each sample's
        count since the last), impacts (touchdowns so far), kinetic_energy_j. ``integrator``: as
        HexapodSim.set_integrator."""
        gait = dict(period_s=period_s, duty=duty, step_length_m=step_length_m, step_height_m=step_height_m,
                    turn_rad=turn_rad, box_height_m=box_height_m)
        sp = self.gait_setpoints(0.0, **gait)
        pose = {"box_m": [0.0, 0.0, float(box_height_m)], "box_quat": [1.0, 0.0, 0.0, 0.0],
                "rowing_rad": list(sp["rowing_rad"]), "length_m": sp["length_m"].tolist()}
        m = self.sim(pose, stuck=[k for k in range(LEGS) if sp["stance"][k]], integrator=integrator)

        def command(sp):
            ff = fm = None
            if feedforward:
                at = dict(pose, rowing_rad=list(sp["rowing_rad"]), length_m=sp["length_m"].tolist())
                s = self.statics(at, stance=[k for k in range(LEGS) if sp["stance"][k]])
                ff, fm = s["actuator_force_n"], s["rowing_torque_nm"]
            m.command_pose(sp["length_m"], sp["rowing_rad"], ff, fm)

        command(sp)
        n = int(round(float(t_end_s) / float(h_s)))
        out = {k: [] for k in ("t_s", "box_m", "box_quat", "foot_m", "foot_force_n", "foot_state",
                               "set_foot_box_m", "body_pose", "events", "impacts", "kinetic_energy_j")}
        events = 0

        def sample(st, target):
            out["t_s"].append(st["t_s"])
            for k in ("box_m", "box_quat", "foot_m", "foot_force_n", "impacts", "kinetic_energy_j"):
                out[k].append(st[k])
            out["foot_state"].append([_FOOT_STATES.index(x) for x in st["foot_state"]])
            out["set_foot_box_m"].append(target)
            out["body_pose"].append(m.body_poses())
            out["events"].append(events)

        st = m.state()
        sample(st, sp["foot_box_m"])
        for i in range(n):
            sp = self.gait_setpoints((i + 1) * float(h_s), **gait)
            command(sp)
            m.step(1, h_s=h_s)
            st = m.state()
            events += st["events"]
            if (i + 1) % every == 0 or i + 1 == n:
                sample(st, sp["foot_box_m"])
                events = 0
        res = {k: np.array(v) for k, v in out.items()}
        res["cone"] = st["cone"]
        return res

    def sim(self, pose: dict, stuck=range(LEGS), integrator: str = "rk4") -> "HexapodSim":
        """The robot moving from ``pose`` (as statics'), at rest, the feet of ``stuck`` (leg
        indices) held where the pose puts them, the commands zero (legsim_hexapod_sim_init),
        stepped by ``integrator`` (HexapodSim.set_integrator)."""
        m = HexapodSim(self, pose, _mask(stuck, "stuck"))
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
        (arrivals on a stop since the start)."""
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
                "rowing_stop": np.array(out.rowing_stop[:]), "stop_impacts": out.stop_impacts}
