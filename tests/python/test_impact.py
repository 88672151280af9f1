"""The touchdown impact as a linear complementarity problem (docs/design/events.md, "The
impact"): the normal impulses P_n >= 0, the post-impact normal velocities v_n >= 0,
P_n v_n = 0 per contact; a contact whose impulse would pull leaves (free, no impulse).

Checked against independent references: free flight (a foot that leaves gets no impulse, so
the body flies on as v0 + g t, which RK4 and generalized-alpha integrate exactly), and the
closed-form one-contact inelastic impact (contact_analytic.inelastic_impact) when of two
contacts under the line only one approaches it.
"""
from __future__ import annotations

import math
import sys

import numpy as np
import pytest

import legsim

from conftest import ROOT, compass_desc

try:
    import legsim_bench.reference  # noqa: F401
except ImportError:  # the bench is not installed: its source tree
    sys.path.insert(0, str(ROOT / "bench"))
from legsim_bench.reference import contact_analytic as ca  # noqa: E402

G = 9.81


def _lib(n_contacts: int):
    lib = legsim.load_library("double")
    if lib.config.get("LEGSIM_MAX_CONTACTS", 0) < n_contacts:
        pytest.skip(f"{lib.path} is built without {n_contacts} contacts")
    return lib


def _body(lib, d, mass, inertia, length, points, mu_s, mu_k):
    d.gravity_mps2[1] = -G
    d.n_bodies = 1
    d.body[0].name = b"body"
    d.body[0].length_m = length
    d.body[0].mass_kg = mass
    d.body[0].inertia_kgm2 = inertia
    d.foot_body = -1
    d.n_contacts = len(points)
    for i, pt in enumerate(points):
        d.contact[i].name = f"c{i}".encode()
        d.contact[i].body = 0
        d.contact[i].point[0], d.contact[i].point[1] = pt
    d.ground.mu_static = mu_s
    d.ground.mu_kinetic = mu_k


@pytest.mark.parametrize("integrator", ["rk4", "galpha"])
def test_a_foot_under_the_line_moving_up_gets_no_pulling_impulse(integrator):
    """A free foot 1 mm under the line moving up at 1 m/s (its body not spinning): it is put
    on the line, and as it separates its impulse is 0 and it stays free (LCP: P_n = 0,
    v_n > 0). The body then flies: its velocity after one step is v0 + g h exactly."""
    lib = _lib(1)
    d = lib.ModelDesc()
    d.name = b"block"
    # body point (xi, eta) = (0.03, -0.04): at phi = 0 the foot is at (-0.04, y - 0.03)
    _body(lib, d, 2.0, 0.01, 0.1, [(0.03, -0.04)], 0.6, 0.5)
    h = 1e-3
    s = legsim.Sim(legsim.Model(d, lib, "revolute", "block"), integrator=integrator, step=h)
    v0 = np.array([0.2, 1.0, 0.0])
    s.set_state([0.0, 0.03 - 0.001, 0.0], v0)
    s.step(1)
    c = s.contacts()[0]
    print(integrator, s.events(), c)
    assert c["state"] == "free"
    assert c["impulse"][0] >= 0 and np.all(np.asarray(c["impulse"]) == 0)
    assert abs(c["position"][1] - (1.0 * h - 0.5 * G * h * h)) < 1e-12  # from the line
    assert np.max(np.abs(s.qd - (v0 + np.array([0.0, -G * h, 0.0])))) < 1e-12


LEAN = 0.5  # rad, each rod from the vertical


def _perp(r):
    return np.array([-r[1], r[0]])


def _compass_geometry():
    """Hinge, centres and feet (world) of the compass standing on the line: rod A leaning
    to -x, rod B to +x, hinged at their tops (xi = -0.5), feet at xi = 0.5."""
    uA = np.array([math.sin(-LEAN), -math.cos(-LEAN)])
    uB = np.array([math.sin(LEAN), -math.cos(LEAN)])
    hinge = np.array([0.0, math.cos(LEAN)])
    return hinge, (hinge + 0.5 * uA, hinge + 0.5 * uB), (hinge + uA, hinge + uB)


def _point_rows(body: int, r) -> np.ndarray:
    """The velocity rows (x, y) of a point at world offset r from body's centre."""
    R = np.zeros((2, 6))
    R[:, 3 * body:3 * body + 2] = np.eye(2)
    R[:, 3 * body + 2] = _perp(r)
    return R


def _compass(omega: float, vx: float, mu: float, integrator: str, h: float):
    """Two 1 kg, 1 m rods A and B hinged at their tops (a compass, each leaning LEAN from
    the vertical), feet 0.1 mm under the line; the compass falls at 0.5 m/s and turns
    rigidly at omega about the feet's midpoint (B's foot rising), sliding at vx."""
    lib = _lib(2)
    d = compass_desc(lib, mu, G)
    s = legsim.Sim(legsim.Model(d, lib, "revolute", "compass"), integrator=integrator, step=h)
    _, (cA, cB), _ = _compass_geometry()
    V = np.array([vx, -0.5])
    vA, vB = V + omega * _perp(cA), V + omega * _perp(cB)
    s.set_state([cA[0], cA[1] - 1e-4, -LEAN, cB[0], cB[1] - 1e-4, LEAN],
                [vA[0], vA[1], omega, vB[0], vB[1], omega])
    return s, np.array([vA[0], vA[1], omega, vB[0], vB[1], omega])


MASS = np.diag([1.0, 1.0, 1.0 / 12.0] * 2)


@pytest.mark.parametrize("integrator", ["rk4", "galpha"])
@pytest.mark.parametrize("vx, mu", [(0.0, 0.6), (0.3, 2.0)])
def test_compass_landing_on_one_foot_leaves_the_rising_foot_free(integrator, vx, mu):
    """Both feet under the line, A's approaching and B's rising: the impact is the
    one-contact inelastic impact at A's foot (closed form, contact_analytic.inelastic_impact
    with the hinge's rows and the foot's two rows: it sticks), after which B's foot still rises, so it stays free with no
    impulse. Taking both feet into the impact (their approach removed together) pulls B's
    foot down. (At mu = 2 a sliding impact of B with its friction also solves the problem:
    the rule picks the candidate closest to the approach, B leaving.)"""
    h = 1e-6
    s, v0 = _compass(4.0, vx, mu, integrator, h)
    hinge, (cA, cB), (fA, fB) = _compass_geometry()
    J = _point_rows(0, hinge - cA) - _point_rows(1, hinge - cB)
    footA, footB_y = _point_rows(0, fA - cA), _point_rows(1, fB - cB)[1]
    assert np.max(np.abs(J @ v0)) < 1e-14 and footA[1] @ v0 < -1 and footB_y @ v0 > 1
    s.step(1)
    c = s.contacts()
    print(integrator, s.events(), c)
    v_plus, impulse, lost = ca.inelastic_impact(MASS, np.vstack([J, footA]), v0)
    p_foot = impulse[2:]
    assert abs(p_foot[0]) <= mu * p_foot[1]   # inside the cone: A's foot sticks
    assert c["state"][0] == "stuck"
    assert c["state"][1] == "free"
    assert np.all(np.asarray(c["impulse"][1]) == 0)
    # level ground: the world impulse (x, y) is (T, N)
    assert p_foot[-1] > 0 and abs(c["impulse"][0][0] - p_foot[-1]) < 1e-9
    assert abs(c["impulse"][0][1] - p_foot[0]) < 1e-9
    # B's foot separates after the reference impact: the LCP's complementarity
    assert footB_y @ v_plus > 0
    # one step of 1 us after it: the velocity within the stance's accelerations times h
    assert np.max(np.abs(s.qd - v_plus)) < 100 * G * h


@pytest.mark.parametrize("integrator", ["rk4", "galpha"])
def test_robot_impacts_keep_the_complementarity(integrator):
    """The robot with both feet 5 mm under the line and random box velocities (seeded; the
    legs' actuators at 0 N): the impact at t = 0 must solve its LCP. After it (one step of
    1 us), per foot: the normal impulse >= 0; a foot that stayed closed has no normal
    velocity, one that left separates (v_n >= 0, impulse 0). The velocities after 1 us are
    the impact's to the stance's accelerations times h."""
    lib = legsim.load_library("double")
    if lib.config["LEGSIM_MAX_BODIES"] < 13 or lib.config.get("LEGSIM_MAX_CONTACTS", 0) < 2:
        pytest.skip("built without room for the robot")
    rng = np.random.default_rng(22)
    h = 1e-6
    left_seen = closed_seen = 0
    for trial in range(10):
        s = legsim.Sim(str(ROOT / "models" / "robot.toml"), integrator=integrator, step=h)
        q = s.assemble_on_ground().reshape(-1, 3)
        for a in range(s.n_actuators):
            s.command_force(a, 0.0)
        q[:, 1] -= 0.005
        vx, vy, w = rng.uniform(-1.0, 1.0), rng.uniform(-1.5, 0.5), rng.uniform(-4.0, 4.0)
        c0 = q[0, :2].copy()
        v = np.zeros_like(q)
        for b in range(len(q)):  # a rigid motion of the whole robot about the box's centre
            r = q[b, :2] - c0
            v[b] = [vx - w * r[1], vy + w * r[0], w]
        s.set_state(q.reshape(-1), v.reshape(-1))
        s.step(1)
        c = s.contacts()
        assert "touchdown" in s.events(), s.events()
        qa, va = s.q.reshape(-1, 3), s.qd.reshape(-1, 3)
        for k in range(2):
            pn = c["impulse"][k][0]
            assert pn >= -1e-12, (trial, k, c)
            b = s.model.desc.contact[k].body
            r = c["position"][k] - qa[b, :2]
            vn = va[b, 1] + va[b, 2] * r[0]   # the foot's velocity, y: level ground's normal
            if c["state"][k] == "free":
                left_seen += 1
                assert pn == 0 and vn >= -G * h * 10, (trial, k, c)
            else:
                closed_seen += 1
                assert abs(vn) < 100 * G * h, (trial, k, c)
    print(f"{integrator}: {closed_seen} feet stayed, {left_seen} left")
    assert left_seen > 0 and closed_seen > 0   # both sides of the complementarity were met
