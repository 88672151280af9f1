"""The leg of models/leg.toml as plain data, shared by the peer models.

Nothing here depends on an engine. It provides

* :func:`load` -- the bodies, joints, actuators and stand pose read from the
  model file (``legsim_bench.reference.model_file``), every joint point resolved to body-fixed
  ``(xi, eta)`` coordinates;
* :func:`stand_q0` -- the stand pose in absolute coordinates (18 values, bodies
  in leg.toml order, ``x, y`` of the centre and ``phi``), computed in closed
  form from the stand-pose facts (thigh angle, shank angle, frame points);
* :func:`constraints`, :func:`energy` -- our constraint equations and the total
  energy, used to check the peers independently of any reference model;
* :func:`actuator_forces_q` -- the generalized forces of the actuators in the
  convention of the brief (+F u(phi_cyl) on the rod centre, -F u(phi_cyl) on
  the cylinder centre).

Conventions (leg.toml, eq. (1) of the paper): u(phi) = (sin phi, -cos phi),
n(phi) = (cos phi, sin phi); the body-fixed point (xi, eta) sits at
r + xi u + eta n.  The proximal end is xi = -L/2, the distal end xi = +L/2.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ...reference.model_file import read_model_file

REPO_ROOT = Path(__file__).resolve().parents[4]
DEFAULT_MODEL = REPO_ROOT / "models" / "leg.toml"

#: The scenes every peer knows. ``upper_force`` / ``lower_force`` are the axial
#: actuator forces (N, > 0 extends), constant from t = 0.
SCENES = {
    "free_fall": {"upper_force": 0.0, "lower_force": 0.0},
    "upper_step_50N": {"upper_force": 50.0, "lower_force": 0.0},
}

VARIANTS = ("revolute", "slot")


def u(phi: float) -> np.ndarray:
    return np.array([math.sin(phi), -math.cos(phi)])


def n(phi: float) -> np.ndarray:
    return np.array([math.cos(phi), math.sin(phi)])


@dataclass
class Body:
    name: str
    length: float
    mass: float
    inertia: float  # about the centre of mass


@dataclass
class Joint:
    name: str
    kind: str  # revolute_to_frame | revolute | prismatic | slot
    bodies: tuple  # 0-based indices; (i,) for revolute_to_frame
    points: tuple  # body-fixed (xi, eta) per body (revolute*), or world point
    frame_point: tuple | None = None  # revolute_to_frame: world (x, y)


@dataclass
class Actuator:
    name: str
    joint: int  # index into joints (a prismatic joint: cylinder, rod)
    cylinder: int
    rod: int
    stroke: tuple
    max_force: float


@dataclass
class LegModel:
    name: str
    gravity: np.ndarray
    frame: dict
    bodies: list
    joints: list
    actuators: list
    stand: dict
    variant: str = "revolute"
    raw: dict = field(default_factory=dict, repr=False)

    @property
    def n_bodies(self) -> int:
        return len(self.bodies)

    def body_index(self, one_based_id: int) -> int:
        return one_based_id - 1

    def masses(self) -> np.ndarray:
        """Diagonal of the mass matrix, 3 per body (m, m, J)."""
        return np.concatenate([[b.mass, b.mass, b.inertia] for b in self.bodies])


def _end_xi(end: str, length: float, spec: dict) -> tuple:
    if end == "proximal":
        return (-0.5 * length, 0.0)
    if end == "distal":
        return (0.5 * length, 0.0)
    if end == "at":
        at = spec["at"]
        return (float(at[0]), float(at[1]))
    if end == "axis":
        return None  # slot: the axis of the body
    raise ValueError(f"unknown end {end!r}")


def load(path: str | Path | None = None, variant: str = "revolute") -> LegModel:
    """Reads leg.toml; ``variant`` is ``"revolute"`` (D pinned) or ``"slot"``."""
    if variant not in VARIANTS:
        raise ValueError(f"variant must be one of {VARIANTS}, not {variant!r}")
    path = Path(path) if path is not None else DEFAULT_MODEL
    raw = read_model_file(path)
    bodies = []
    for b in raw["body"]:
        L, m = float(b["length"]), float(b["mass"])
        J = float(b.get("inertia", m * L * L / 12.0))
        bodies.append(Body(b["name"], L, m, J))
    frame = {k: tuple(map(float, v)) for k, v in raw["frame"].items()}
    overrides = raw.get("variant", {}).get(variant, {}) if variant != "revolute" else {}
    joints = []
    for j in raw["joint"]:
        spec = dict(j)
        if j["name"] in overrides:
            spec.update(overrides[j["name"]])
        kind = spec["kind"]
        if kind == "revolute_to_frame":
            i = spec["body"] - 1
            p = _end_xi(spec["end"], bodies[i].length, spec)
            joints.append(Joint(spec["name"], kind, (i,), (p,), frame[spec["point"]]))
        elif kind == "revolute":
            i, k = (b - 1 for b in spec["bodies"])
            ends = spec["ends"]
            p0 = _end_xi(ends[0], bodies[i].length, spec)
            p1 = _end_xi(ends[1], bodies[k].length, spec)
            joints.append(Joint(spec["name"], kind, (i, k), (p0, p1)))
        elif kind == "prismatic":
            i, k = (b - 1 for b in spec["bodies"])
            joints.append(Joint(spec["name"], kind, (i, k), ()))
        elif kind == "slot":
            i, k = (b - 1 for b in spec["bodies"])
            p0 = _end_xi(spec["ends"][0], bodies[i].length, spec)
            joints.append(Joint(spec["name"], kind, (i, k), (p0,)))
        else:
            raise ValueError(f"joint {spec['name']!r}: unknown kind {kind!r}")
    jnames = [j.name for j in joints]
    actuators = []
    for a in raw["actuator"]:
        ji = jnames.index(a["joint"])
        cyl, rod = joints[ji].bodies
        actuators.append(Actuator(a["name"], ji, cyl, rod, tuple(a["stroke"]), float(a["max_force"])))
    return LegModel(raw["name"], np.array(raw["gravity"], float), frame, bodies, joints,
                    actuators, dict(raw["pose"]["stand"]), variant, raw)


def point(q: np.ndarray, body: int, xi: float, eta: float = 0.0) -> np.ndarray:
    x, y, phi = q[3 * body: 3 * body + 3]
    return np.array([x, y]) + xi * u(phi) + eta * n(phi)


def stand_q0(model: LegModel) -> np.ndarray:
    """The stand pose in absolute coordinates, in closed form.

    Thigh (3) at phi3 from B, shank (6) at phi6 with its proximal end at C (the
    thigh's distal end), D at the shank point of joint D (xi = -0.10) -- for the
    slot variant D is the same material point of the shank as in the pinned
    variant; the upper actuator (1, 2) runs from A to C, the lower one (4, 5)
    from B to D, each cylinder's proximal end at its frame pivot and each rod's
    distal end at C or D.
    """
    base = model if model is not None else load()
    B = np.array(base.frame["B"])
    A = np.array(base.frame["A"])
    L = [b.length for b in base.bodies]
    phi3 = float(base.stand["phi3"])
    phi6 = float(base.stand["phi6"])
    q = np.zeros(18)
    C = B + L[2] * u(phi3)
    q[6:9] = [*(B + 0.5 * L[2] * u(phi3)), phi3]
    q[15:18] = [*(C + 0.5 * L[5] * u(phi6)), phi6]
    # D: the shank point of the pinned joint D (revolute variant), read from the file
    d_spec = next(j for j in base.raw["joint"] if j["name"] == "D")
    xi_d, eta_d = (float(v) for v in d_spec["at"])
    D = point(q, 5, xi_d, eta_d)
    for (cyl, rod, P, Q) in ((0, 1, A, C), (3, 4, B, D)):
        d = Q - P
        phi = math.atan2(d[0], -d[1])  # u(phi) = d / |d|
        e = u(phi)
        q[3 * cyl: 3 * cyl + 3] = [*(P + 0.5 * L[cyl] * e), phi]
        q[3 * rod: 3 * rod + 3] = [*(Q - 0.5 * L[rod] * e), phi]
    return q


def constraints(model: LegModel, q: np.ndarray) -> np.ndarray:
    """Our joint equations Phi(q) (16 for the pinned knee, 15 for the slot)."""
    out = []
    for j in model.joints:
        if j.kind == "revolute_to_frame":
            (i,), (p,) = j.bodies, j.points
            out.extend(point(q, i, *p) - np.array(j.frame_point))
        elif j.kind == "revolute":
            (i, k), (p0, p1) = j.bodies, j.points
            out.extend(point(q, i, *p0) - point(q, k, *p1))
        elif j.kind == "prismatic":
            i, k = j.bodies
            out.append(q[3 * k + 2] - q[3 * i + 2])
            out.append((q[3 * k: 3 * k + 2] - q[3 * i: 3 * i + 2]) @ n(q[3 * i + 2]))
        elif j.kind == "slot":
            (i, k), (p0,) = j.bodies, j.points
            out.append((point(q, i, *p0) - q[3 * k: 3 * k + 2]) @ n(q[3 * k + 2]))
    return np.array(out)


def energy(model: LegModel, q: np.ndarray, qd: np.ndarray) -> float:
    """Kinetic + gravitational potential energy (J); actuator work not included."""
    M = model.masses()
    T = 0.5 * float(np.sum(M * qd * qd))
    g = model.gravity
    V = -sum(b.mass * (g[0] * q[3 * i] + g[1] * q[3 * i + 1]) for i, b in enumerate(model.bodies))
    return T + V


def actuator_forces_q(model: LegModel, q: np.ndarray, forces) -> np.ndarray:
    """Generalized forces (18) of axial actuator forces (N, > 0 extends).

    +F u(phi_cyl) on the rod's centre, -F u(phi_cyl) on the cylinder's centre:
    both centres are on the cylinder axis, so no moments.
    """
    Q = np.zeros(3 * model.n_bodies)
    for a, F in zip(model.actuators, forces):
        if F == 0.0:
            continue
        e = u(q[3 * a.cylinder + 2])
        Q[3 * a.rod: 3 * a.rod + 2] += F * e
        Q[3 * a.cylinder: 3 * a.cylinder + 2] -= F * e
    return Q


def actuator_lengths(model: LegModel, q: np.ndarray) -> np.ndarray:
    """Cylinder proximal end to rod distal end, per actuator (m)."""
    out = []
    for a in model.actuators:
        Lc, Lr = model.bodies[a.cylinder].length, model.bodies[a.rod].length
        out.append(np.linalg.norm(point(q, a.rod, 0.5 * Lr) - point(q, a.cylinder, -0.5 * Lc)))
    return np.array(out)


def scene_forces(model: LegModel, scene: str) -> list:
    if scene not in SCENES:
        raise ValueError(f"unknown scene {scene!r}; known: {sorted(SCENES)}")
    s = SCENES[scene]
    return [s["upper_force"], s["lower_force"]][: len(model.actuators)]
