"""The leg of a model file as the verdicts write it: leg.toml's joint equations in absolute
coordinates (as in the paper) and the free-body equations of its bodies, evaluated on received
positions, reactions and actuator forces (the constraint residual, the static balance).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..reference.model import body_point, world_point
from ..reference.model_file import read_model_file

__all__ = ["Joint", "Leg", "u", "nrm", "cross", "constraint_residual", "static_balance",
           "float32_quantum", "slot_s"]


def u(phi):
    """Body axis, leg.toml's convention (phi = 0 hangs down)."""
    return np.stack([np.sin(phi), -np.cos(phi)], axis=-1)


def nrm(phi):
    """Body normal (CCW from the axis)."""
    return np.stack([np.cos(phi), np.sin(phi)], axis=-1)


def cross(a, b):
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


# ---- leg.toml ------------------------------------------------------------------------

@dataclass
class Joint:
    name: str
    kind: str                 # revolute_to_frame | revolute | prismatic | slot
    bodies: tuple[int, ...]   # 0-based
    points: tuple             # body-fixed (xi, eta) per body, None = the axis (slot)
    frame_point: tuple[float, float] | None = None

    @property
    def n_eq(self) -> int:
        return 1 if self.kind == "slot" else 2


@dataclass
class Leg:
    """The leg of models/leg.toml as this module needs it (its own reading of the file)."""
    body_names: list[str]
    lengths: np.ndarray       # (6,)
    masses: np.ndarray
    inertias: np.ndarray
    joints: list[Joint]
    actuators: list[dict]     # name, cylinder, rod, stroke (min, max), max_force
    gravity: np.ndarray
    load_body: int
    load_point: tuple[float, float]
    variant: str
    frame: dict = field(default_factory=dict)   # named frame points (A, B)

    @classmethod
    def from_toml(cls, path, variant: str = "revolute") -> "Leg":
        data = read_model_file(path)
        ids = {int(b["id"]): i for i, b in enumerate(data["body"])}
        L = np.array([float(b["length"]) for b in data["body"]])
        m = np.array([float(b["mass"]) for b in data["body"]])
        J = np.array([float(b.get("inertia", b["mass"] * b["length"] ** 2 / 12.0)) for b in data["body"]])
        frame = {k: tuple(map(float, v)) for k, v in data.get("frame", {}).items()}
        over = data.get("variant", {}).get(variant, {}) if variant != "revolute" else {}
        if variant != "revolute" and not over:
            raise ValueError(f"leg.toml has no variant {variant!r}")

        def point(bi, end, spec):
            return body_point(L[bi], end, spec)

        joints = []
        for jd in data["joint"]:
            spec = dict(over.get(jd["name"], jd), name=jd["name"])
            kind = spec["kind"]
            if kind == "revolute_to_frame":
                bi = ids[int(spec["body"])]
                fp = spec["point"]
                fp = frame[fp] if isinstance(fp, str) else tuple(map(float, fp))
                joints.append(Joint(spec["name"], kind, (bi,), (point(bi, spec["end"], spec),), fp))
            elif kind in ("revolute", "slot"):
                bs = tuple(ids[int(x)] for x in spec["bodies"])
                joints.append(Joint(spec["name"], kind, bs,
                                    tuple(point(b, e, spec) for b, e in zip(bs, spec["ends"]))))
            elif kind == "prismatic":
                bs = tuple(ids[int(x)] for x in spec["bodies"])
                joints.append(Joint(spec["name"], kind, bs, (None, None)))
            else:
                raise ValueError(f"joint {spec['name']}: unknown kind {kind!r}")
        byname = {j.name: j for j in joints}
        acts = []
        for a in data.get("actuator", []):
            j = byname[a["joint"]]
            acts.append({"name": a["name"], "cylinder": j.bodies[0], "rod": j.bodies[1],
                         "stroke": tuple(map(float, a["stroke"])), "max_force": float(a["max_force"])})
        load = next((f for f in data.get("force", []) if f["name"] == "foot_load"), None)
        if load is None:
            foot = data["foot"]
            lb, lp = ids[int(foot["body"])], point(ids[int(foot["body"])], foot["end"], foot)
        else:
            lb = ids[int(load["body"])]
            lp = point(lb, load.get("end", "at"), load)
        return cls([b.get("name", str(b["id"])) for b in data["body"]], L, m, J, joints, acts,
                   np.array(data.get("gravity", [0.0, -9.81]), float), lb, lp, variant, frame)

    @property
    def n_constraints(self) -> int:
        return sum(j.n_eq for j in self.joints)

    @property
    def joint_names(self) -> list[str]:
        return [j.name for j in self.joints]

    def world(self, q, bi, pt):
        """World position (m) of body-fixed point pt = (xi, eta) of body bi in every pose of
        q (..., 3 nb): the reference's world_point, pose by pose."""
        q = np.asarray(q, float)
        poses = q.reshape(-1, q.shape[-1] // 3, 3)
        return np.array([world_point(p, bi, pt) for p in poses]).reshape(q.shape[:-1] + (2,))

    def constraints(self, q) -> np.ndarray:
        """Phi(q) (..., n_constraints): leg.toml's joint equations in absolute coordinates
        (revolute: the two points coincide; revolute_to_frame: the point is on its frame
        point; prismatic (eqs. 12-16): equal angles and the second body's centre on the first
        one's axis; slot (eq. 18): the first body's point on the second body's axis)."""
        q = np.asarray(q, float)
        rows = []
        for j in self.joints:
            if j.kind == "revolute_to_frame":
                d = self.world(q, j.bodies[0], j.points[0]) - np.asarray(j.frame_point)
                rows += [d[..., 0], d[..., 1]]
            elif j.kind == "revolute":
                d = self.world(q, j.bodies[0], j.points[0]) - self.world(q, j.bodies[1], j.points[1])
                rows += [d[..., 0], d[..., 1]]
            elif j.kind == "prismatic":
                i, k = j.bodies
                rows.append(q[..., 3 * i + 2] - q[..., 3 * k + 2])
                rows.append(np.sum(nrm(q[..., 3 * i + 2]) * (q[..., 3 * k:3 * k + 2] - q[..., 3 * i:3 * i + 2]), -1))
            elif j.kind == "slot":
                i, k = j.bodies
                p = self.world(q, i, j.points[0])
                rows.append(np.sum(nrm(q[..., 3 * k + 2]) * (p - q[..., 3 * k:3 * k + 2]), -1))
        return np.stack(rows, axis=-1)

    def actuator_lengths(self, q) -> np.ndarray:
        """Proximal end of the cylinder to the distal end of the rod (..., n_actuators)."""
        out = []
        for a in self.actuators:
            c, r = a["cylinder"], a["rod"]
            p0 = self.world(q, c, (-self.lengths[c] / 2, 0.0))
            p1 = self.world(q, r, (self.lengths[r] / 2, 0.0))
            out.append(np.linalg.norm(p1 - p0, axis=-1))
        return np.stack(out, -1)

    def balance(self, q, reactions, forces, foot_load=(0.0, 0.0), gravity=True, qdd=None) -> np.ndarray:
        """Residual of the free-body equations (..., 6, 3): for every body the sum of the
        forces (N) and of the moments about its centre of mass (N m) of gravity, the foot
        load, the actuators' axial forces (-F u on the cylinder, +F u on the rod) and the joint
        reactions, minus m a (qdd; None = static). A reaction (F, M) acts on the joint's
        first-listed body (M about its centre); the second body gets -F and the moment
        -M + (r2 - r1) x F about its own centre."""
        q = np.asarray(q, float)
        R = np.asarray(reactions, float).reshape(q.shape[:-1] + (len(self.joints), 3))
        Fa = np.asarray(forces, float)
        nb = len(self.lengths)
        res = np.zeros(q.shape[:-1] + (nb, 3))
        g = self.gravity if gravity else np.zeros(2)
        res[..., :, 0:2] += self.masses[:, None] * g
        lb = self.load_body
        F = np.broadcast_to(np.asarray(foot_load, float), q.shape[:-1] + (2,))
        p = self.world(q, lb, self.load_point)
        res[..., lb, 0:2] += F
        res[..., lb, 2] += cross(p - q[..., 3 * lb:3 * lb + 2], F)
        for ai, a in enumerate(self.actuators):
            e = u(q[..., 3 * a["cylinder"] + 2])
            f = Fa[..., ai:ai + 1] * e
            res[..., a["cylinder"], 0:2] -= f
            res[..., a["rod"], 0:2] += f
        for k, j in enumerate(self.joints):
            Fk, Mk = R[..., k, 0:2], R[..., k, 2]
            i = j.bodies[0]
            res[..., i, 0:2] += Fk
            res[..., i, 2] += Mk
            if len(j.bodies) == 2:
                b = j.bodies[1]
                res[..., b, 0:2] -= Fk
                res[..., b, 2] += -Mk + cross(q[..., 3 * b:3 * b + 2] - q[..., 3 * i:3 * i + 2], Fk)
        if qdd is not None:
            a = np.asarray(qdd, float).reshape(q.shape[:-1] + (nb, 3))
            res -= a * np.stack([self.masses, self.masses, self.inertias], -1)
        return res


def constraint_residual(leg: Leg, q) -> np.ndarray:
    """max |Phi(q)| per sample."""
    return np.max(np.abs(leg.constraints(q)), axis=-1)


def static_balance(leg: Leg, q, reactions, forces, foot_load=(0.0, 0.0), gravity=True):
    """(max force residual (N), max moment residual (N m)) per sample."""
    r = leg.balance(q, reactions, forces, foot_load, gravity)
    return np.max(np.abs(r[..., 0:2]), axis=(-1, -2)), np.max(np.abs(r[..., 2]), axis=-1)


def float32_quantum(x) -> float:
    """Spacing of float32 values at the largest |x| (the DBC's resolution there)."""
    m = float(np.max(np.abs(np.asarray(x, float)))) if np.size(x) else 0.0
    if m == 0 or not math.isfinite(m):
        return float(np.finfo(np.float32).tiny)
    return float(np.spacing(np.float32(m)))


def slot_s(leg: Leg, q) -> float:
    """Distance from the shank's proximal end C along its axis to the slot's point D."""
    j = next(j for j in leg.joints if j.kind == "slot")
    rod, shank = j.bodies
    D = leg.world(q, rod, j.points[0])
    C = leg.world(q, shank, (-leg.lengths[shank] / 2, 0.0))
    return float(np.dot(u(q[3 * shank + 2]), D - C))
