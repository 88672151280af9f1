"""Foot contact transitions in the core (docs/design/robot-on-ground.md section 2) through
the Python API, against the analytic cases of legsim_bench.reference.contact_analytic:
a block on a slope sticks for mu_s >= tan(slope) and slips below it, a slider decelerates
at g (mu_k cos - sin) and loses exactly the friction work, a touchdown loses exactly
Carnot's energy; and the robot's feet lift off and touch down with their events.

The block is a model made here: one body with its contact point at its centre of mass
(a particle on the line: the friction has no moment about the centre, so the motion is
the analytic one), or off it for the touchdown (an impact that also spins it).
"""
from __future__ import annotations

import math
import sys

import numpy as np
import pytest

import legsim

from conftest import ROOT

try:
    import legsim_bench.reference  # noqa: F401
except ImportError:  # the bench is not installed: its source tree
    sys.path.insert(0, str(ROOT / "bench"))
from legsim_bench.reference import contact_analytic as ca  # noqa: E402

G = 9.81
MASS = 2.0
INERTIA = 0.01


def _lib():
    lib = legsim.load_library("double")
    if lib.config.get("LEGSIM_MAX_CONTACTS", 0) < 1:
        pytest.skip(f"{lib.path} is built without contacts")
    return lib


def block(slope: float, mu_s: float, mu_k: float, point=(0.0, 0.0), gravity=G, **kw) -> legsim.Sim:
    """One body (2 kg, 0.01 kg m^2) with a contact at body point ``point``; the ground line
    through the origin at ``slope``."""
    lib = _lib()
    d = lib.ModelDesc()
    d.name = b"block"
    d.gravity_mps2[1] = -gravity
    d.n_bodies = 1
    d.body[0].name = b"block"
    d.body[0].length_m = 0.1
    d.body[0].mass_kg = MASS
    d.body[0].inertia_kgm2 = INERTIA
    d.foot_body = -1
    d.n_contacts = 1
    d.contact[0].name = b"foot"
    d.contact[0].body = 0
    d.contact[0].point[0], d.contact[0].point[1] = point
    d.ground.slope_rad = slope
    d.ground.mu_static = mu_s
    d.ground.mu_kinetic = mu_k
    return legsim.Sim(legsim.Model(d, lib, "revolute", "block"), **kw)


def _along(s: legsim.Sim, slope: float) -> tuple[float, float]:
    """Position and velocity of the block along the downhill direction -t (m, m/s)."""
    t = np.array([math.cos(slope), math.sin(slope)])
    return -float(s.q[:2] @ t), -float(s.qd[:2] @ t)


@pytest.mark.parametrize("integrator", ["rk4", "galpha"])
@pytest.mark.parametrize("slope", [0.2, 0.5, 1.0])
@pytest.mark.parametrize("rel", [1e-9, -1e-9])
def test_block_on_slope_sticks_or_slips_exactly_at_tan(integrator, slope, rel):
    mu_s = math.tan(slope) * (1 + rel)
    s = block(slope, mu_s, 0.8 * mu_s, integrator=integrator)
    s.set_state([0.0, 0.0, 0.0])
    s.set_contact("foot", "stuck")
    s.step(20)
    c = s.contacts()[0]
    sticks = ca.slope_sticks(mu_s, slope)
    assert sticks == (rel > 0)
    assert c["state"] == ("stuck" if sticks else "sliding")
    assert ("stick_to_slip" in s.events()) == (not sticks)
    assert abs(c["normal"] - MASS * G * math.cos(slope)) < 1e-9
    if sticks:
        assert abs(c["tangential"] - MASS * G * math.sin(slope)) < 1e-9 and c["holds"]
        assert np.max(np.abs(s.q)) < 1e-15
    else:
        assert abs(c["tangential"] - 0.8 * mu_s * c["normal"]) < 1e-9   # mu_k N, uphill
        assert c["slip"] < 0                                          # sliding downhill


@pytest.mark.parametrize("slope", [0.3, 0.6])
def test_block_slides_from_rest_at_g_sin_minus_mu_cos(slope):
    """A stuck start that cannot hold slides from t = 0 (the modes are checked at the step's
    start after an outside change), uniformly accelerated: RK4 integrates the quadratic
    exactly."""
    mu_s, mu_k, h, n = math.tan(slope) * 0.9, math.tan(slope) * 0.6, 1e-3, 400
    s = block(slope, mu_s, mu_k, step=h)
    s.set_state([0.0, 0.0, 0.0])
    s.set_contact("foot", "stuck")
    s.step(n)
    a = ca.slide_acceleration(mu_k, slope)
    t = n * h
    x, v = _along(s, slope)
    err_x, err_v = abs(x - 0.5 * a * t * t), abs(v - a * t)
    print(f"slope {slope}: a = {a:.6f} m/s^2, x = {x:.9f} m, error x {err_x:.2e} m, v {err_v:.2e} m/s")
    assert err_x < 1e-13 and err_v < 1e-12
    assert s.events() == ["stick_to_slip"]
    assert s.contact_event_time(0) == 0.0
    # legsim_contacts_check: the same change at t = 0 before any step, and once only
    s2 = block(slope, mu_s, mu_k, step=h)
    s2.set_state([0.0, 0.0, 0.0])
    s2.set_contact("foot", "stuck")
    s2.contacts_check()
    c = s2.contacts()[0]
    assert s2.events() == ["stick_to_slip"] and c["state"] == "sliding" and s2.time == 0.0
    assert abs(c["tangential"] - mu_k * MASS * G * math.cos(slope)) < 1e-9   # mu_k N, uphill
    s2.clear_events()
    s2.contacts_check()
    s2.step(n)
    assert s2.events() == [] and np.max(np.abs(s2.q - s.q)) < 1e-15


@pytest.mark.parametrize("integrator", ["rk4", "galpha"])
def test_slider_decelerates_stops_and_loses_the_friction_work(integrator):
    """Downhill at 1.5 m/s on a 0.15 rad slope with mu_k = 0.45 (> tan): it decelerates at
    g (mu_k cos - sin) until it stops (slip to stick, within one step), then stays
    (mu_s >= tan). Energy lost = mu_k N x path, to round-off while it slides."""
    slope, mu_s, mu_k, v0, h = 0.15, 0.6, 0.45, 1.5, 1e-3
    s = block(slope, mu_s, mu_k, step=h, integrator=integrator)
    t = np.array([math.cos(slope), math.sin(slope)])
    s.set_state([0.0, 0.0, 0.0], [*(-v0 * t), 0.0])
    s.set_contact("foot", "sliding")
    N = MASS * G * math.cos(slope)

    def energy():
        return 0.5 * MASS * float(s.qd[:2] @ s.qd[:2]) + MASS * G * s.q[1]

    e0 = energy()
    ref_stop = ca.slide(v0, 10.0, mu_s, mu_k, slope, MASS).stop_time
    worst_x = worst_e = 0.0
    k = 0
    while s.contacts()[0]["state"] == "sliding":
        s.step(1)
        k += 1
        if s.contacts()[0]["state"] != "sliding":
            break
        r = ca.slide(v0, k * h, mu_s, mu_k, slope, MASS)
        x, v = _along(s, slope)
        worst_x = max(worst_x, abs(x - r.position), abs(v - r.velocity))
        worst_e = max(worst_e, abs((e0 - energy()) - mu_k * N * r.path))
    t_stop = k * h
    print(f"{integrator}: stop at {t_stop:.4f} s (analytic {ref_stop:.6f}), worst error x/v "
          f"{worst_x:.2e}, energy vs friction work {worst_e:.2e} J")
    assert "slip_to_stick" in s.events()
    assert ref_stop <= t_stop < ref_stop + h
    tol = 1e-12 if integrator == "rk4" else 2e-6   # generalized-alpha: second order
    assert worst_x < tol and worst_e < tol * 100
    x_stop = ca.slide(v0, 10.0, mu_s, mu_k, slope, MASS).position
    s.step(50)
    x, v = _along(s, slope)
    a = ca.slide_acceleration(mu_k, slope)
    assert abs(x - x_stop) < abs(a) * h * h and abs(v) < 1e-12
    assert s.contacts()[0]["state"] == "stuck"


@pytest.mark.parametrize("mu_s, stuck", [(2.0, True), (0.1, False)])
def test_touchdown_loses_carnots_energy(mu_s, stuck):
    """A spinning block (contact 0.05 m off its centre) falls onto the ground: in flight
    q(t) = q0 + v0 t + g t^2 / 2 exactly, so the touchdown time t_e (the foot's height 0),
    the pose there and the approach velocity v- = v0 + g t_e are known in closed form;
    the impulse sticks the foot (inside the cone) and the energy lost is exactly Carnot's
    1/2 (G v-)^T W^-1 (G v-) (after it, the stuck block keeps its energy: the rest of the
    step is conservative); outside the cone it slides, losing less."""
    pt = (0.03, -0.04)
    s = block(0.0, mu_s, 0.8 * mu_s, point=pt)
    q0, qd0 = np.array([0.0, 0.0404, 0.1]), np.array([0.4, -1.2, 0.3])
    s.set_state(q0, qd0)
    M = np.diag([MASS, MASS, INERTIA])

    def energy(q, v):
        return 0.5 * v @ M @ v + MASS * G * q[1]

    def foot_offset(phi):   # the contact point's offset from the centre of mass at angle phi
        u, n = np.array([math.sin(phi), -math.cos(phi)]), np.array([math.cos(phi), math.sin(phi)])
        return pt[0] * u + pt[1] * n

    e0 = energy(q0, qd0)
    while "touchdown" not in s.events():
        s.step(1)
    t_e = s.contact_event_time(0)
    gravity = np.array([0.0, -G, 0.0])
    q_e = q0 + qd0 * t_e + 0.5 * gravity * t_e ** 2
    v_minus = qd0 + gravity * t_e
    sp = foot_offset(q_e[2])
    assert abs(q_e[1] + sp[1]) < 1e-9        # the located time puts the foot on the ground
    Gp = np.array([[1.0, 0.0, -sp[1]], [0.0, 1.0, sp[0]]])   # the foot's Jacobian at q_e
    v_plus, impulse, lost = ca.inelastic_impact(M, Gp, v_minus)
    c = s.contacts()[0]
    q, v = s.q, s.qd
    e = energy(q, v)
    print(f"mu_s {mu_s}: t_e {t_e:.12f} s, state {c['state']}, impulse {c['impulse']}, "
          f"lost {e0 - e:.12f} J, Carnot {lost:.12f} J")
    assert abs(c["position"][1]) < 1e-12 and s.events() == ["touchdown"]
    if stuck:
        assert c["state"] == "stuck"
        assert abs((e0 - e) - lost) < 1e-9 * lost
        # level ground: the world impulse (x, y) is (T, N)
        assert np.max(np.abs(np.asarray(c["impulse"])[::-1] - impulse)) < 1e-9
    else:
        assert c["state"] == "sliding"
        assert abs(c["impulse"][1]) == pytest.approx(0.8 * mu_s * c["impulse"][0], rel=1e-12)
        assert 0 < e0 - e < lost
        sp = foot_offset(q[2])
        assert abs(v[1] + sp[0] * v[2]) < 1e-12   # the foot's normal velocity stays 0
        assert c["slip"] * c["impulse"][1] < 0  # friction against the slip


def test_robot_lifts_off_and_touches_down():
    lib = legsim.load_library("double")
    if lib.config["LEGSIM_MAX_BODIES"] < 13 or lib.config.get("LEGSIM_MAX_CONTACTS", 0) < 2:
        pytest.skip("built without room for the robot")
    s = legsim.Sim(str(ROOT / "models" / "robot.toml"))
    q = s.assemble_on_ground()
    lengths = s.actuator_lengths()[0]
    for a, L in enumerate(lengths):
        s.command_length(a, L)
    # dropped from 3 mm: both feet touch down together (the robot is symmetric)
    drop = q.copy().reshape(-1, 3)
    drop[:, 1] += 0.003
    s.set_state(drop.reshape(-1))
    assert list(s.contacts()["state"]) == ["free", "free"]
    for _ in range(100):
        s.step(1)
        if "touchdown" in s.events():
            break
    c = s.contacts()
    assert "touchdown" in s.events() and all(c["state"] != "free")
    v_impact = math.sqrt(2 * G * 0.003)
    assert np.all(c["impulse"][:, 0] > 0)
    # the feet's approach is removed: the impulses carry at most the whole robot's momentum
    assert c["impulse"][:, 0].sum() < s.model.masses.sum() * v_impact * 1.01
    s.clear_events()
    s.step(200)
    c = s.contacts()
    assert all(c["state"] == "stuck") and np.all(c["normal"] > 0)
    # the feet leave when the servos pull them up faster than gravity lets the body follow:
    # shorten the upper actuators quickly (they lift the feet off as the knee folds)
    s.clear_events()
    for a in (1, 3):
        s.command_length(a, float(s.model.strokes[a, 0]) + 0.002)
    s.step(100)
    assert "liftoff" in s.events()
