"""The contact law option (legsim_options.contact_law, docs/design/robot-on-ground.md
section 2): "lcp", each foot leaves its Coulomb cone by itself; "paper", the paper's rule
while both feet are on the ground (when a foot's |T| exceeds mu_static N, the foot with the
SMALLER |T| is released and slides with mu_kinetic N, the other stays stuck).

The sliding configuration of scenes/robot_sliding.toml (uppers held, the right one 20 mm
longer; both lower servos ramped out together) is run here through the Python API under
both laws and checked against the bench's independent reference on stuck feet
(legsim_bench.reference.robot.RobotModel): the event comes within one step after the
reference's |T|/N reaches mu_static, and the released foot is the law's.
"""
from __future__ import annotations

import ctypes as C
import functools
import math
import sys

import numpy as np
import pytest

import legsim

from conftest import ROOT, compass_desc, robot_sim as _robot_sim

try:
    import legsim_bench.reference  # noqa: F401
except ImportError:  # the bench is not installed: its source tree
    sys.path.insert(0, str(ROOT / "bench"))
from legsim_bench.verdict.analyses import robot_reference  # noqa: E402
from legsim_bench.reference import contact_analytic as ca  # noqa: E402
from legsim_bench.scene import load_scene  # noqa: E402

ROBOT = ROOT / "models" / "robot.toml"
FEET = ("right.foot", "left.foot")


def test_contact_law_option_is_checked():
    s = _robot_sim()
    assert s.options["contact_law"] == "lcp"
    assert int(s.library.default_options().contact_law) == 0
    with pytest.raises(ValueError, match="contact_law must be one of"):
        s.set_options(contact_law="coulomb")
    # a value outside the enum, as a C caller could store it: refused, nothing changed
    bad = type(s._options).from_buffer_copy(s._options)
    bad.contact_law = 2
    st = s.library.cdll.legsim_set_options(s.handle, C.byref(bad))
    assert legsim.status_name(st) == "LEGSIM_ERR_BAD_INPUT"
    assert s.options["contact_law"] == "lcp"
    s.set_options(contact_law="paper")
    assert s.options["contact_law"] == "paper"
    assert _robot_sim(contact_law="paper").options["contact_law"] == "paper"


def _run_sliding(law: str, scene: str = "robot_sliding"):
    """scenes/robot_sliding.toml through the Python API under `law`: per step the states, N, T
    and the events, the commands applied before every step as legsim_cli does."""
    sc = load_scene(scene, ROOT)
    s = _robot_sim(contact_law=law, integrator=sc.integrator, step=sc.step_s)
    s.assemble_on_ground(np.asarray(sc.lengths), feet_mid=0.0)
    h = sc.step_s
    states, normal, tangential, events = [], [], [], []
    for k in range(sc.n_steps):
        t = k * h
        for a, c in enumerate(sc.commands):
            v = c.schedule
            if v.kind == "hold":
                s.command_length(a, float(v.value))
            else:
                s.command_length(a, v.offset + v.amplitude * math.sin(2 * math.pi * v.frequency * t + v.phase))
        s.clear_events()
        s.step(1)
        c = s.contacts()
        states.append(tuple(c["state"]))
        normal.append(c["normal"].copy())
        tangential.append(c["tangential"].copy())
        events.append(tuple(s.events()))
    t = (np.arange(sc.n_steps) + 1) * h
    return sc, t, states, np.array(normal), np.array(tangential), events


@functools.lru_cache(maxsize=None)
def _reference(first: int):
    """RobotModel on stuck feet along robot_sliding's commands, at t = 0 and after each step up
    to step `first` (both laws run the same stuck-stuck stance up to their event)."""
    sc = load_scene("robot_sliding", ROOT)
    return robot_reference(sc, np.arange(first + 2) * sc.step_s, ROOT)


@pytest.mark.parametrize("law, released, kept", [("lcp", 1, 0), ("paper", 0, 1)])
def test_sliding_configuration_releases_the_law_s_foot(law, released, kept):
    sc, t, states, N, T, events = _run_sliding(law)
    first = next(i for i, e in enumerate(events) if "stick_to_slip" in e)
    # the same stuck-stuck run up to the event under both laws: the event at t = 0.344 s
    assert t[first] == pytest.approx(0.344, abs=1e-12)
    assert states[first - 1] == ("stuck", "stuck")
    assert states[first][released] == "sliding" and states[first][kept] == "stuck"
    # after it the kept foot stays stuck to the end (0.37 s) and the released one slides,
    # with |T| = mu_kinetic N against the slip
    assert all(st[kept] == "stuck" for st in states)
    assert all(st[released] == "sliding" for st in states[first:])
    sl = np.arange(len(t)) >= first
    assert np.abs(T[sl, released]) == pytest.approx(0.5 * N[sl, released], rel=1e-12)

    # the reference on stuck feet up to the event (the staircase of the commands, as here)
    model, r = _reference(first)
    use = np.abs(r.tangential) / r.normal
    mu = model.ground.mu_static
    assert mu == 0.6
    # legsim's forces before the event are the reference's (round-off of the integrations)
    assert np.max(np.abs(N[:first] - r.normal[1:-1])) < 1e-5
    assert np.max(np.abs(T[:first] - r.tangential[1:-1])) < 1e-5
    # the left foot's |T|/N reaches mu_static in the last step before the event, the
    # right one's is still inside its cone (0.5615)
    assert use[-2, 1] < mu < use[-1, 1]
    assert use[-1, 0] == pytest.approx(0.5615, abs=1e-4)
    # the right foot has the smaller |T| (84.47 N against 88.75 N): the paper releases it,
    # Coulomb lets the left one go
    assert abs(r.tangential[-1, 0]) == pytest.approx(84.47, abs=0.01)
    assert abs(r.tangential[-1, 1]) == pytest.approx(88.75, abs=0.01)
    expected = int(np.argmin(np.abs(r.tangential[-1]))) if law == "paper" else int(np.argmax(use[-1]))
    assert expected == released


def test_the_paper_law_changes_nothing_without_a_slip():
    """Touchdown, a stance and lift-off are the default's under the paper's law: the robot
    dropped 3 mm, standing 0.2 s, then the uppers pulled in (test_contact.py's run) give the
    same states and forces bit for bit."""
    runs = []
    for law in ("lcp", "paper"):
        s = _robot_sim(contact_law=law)
        q = s.assemble_on_ground()
        for a, L in enumerate(s.actuator_lengths()[0]):
            s.command_length(a, L)
        drop = q.copy().reshape(-1, 3)
        drop[:, 1] += 0.003
        s.set_state(drop.reshape(-1))
        out, seen = [], set()
        for k in range(400):
            if k == 250:
                for a in (1, 3):
                    s.command_length(a, float(s.model.strokes[a, 0]) + 0.002)
            s.step(1)
            seen |= set(s.events())
            out.append(np.concatenate([s.q, s.contacts()["normal"], s.contacts()["tangential"]]))
        runs.append((np.array(out), seen))
    assert {"touchdown", "liftoff"} <= runs[0][1] and runs[0][1] == runs[1][1]
    assert np.array_equal(runs[0][0], runs[1][0])


def _rod(mu: float, omega: float, **kw) -> legsim.Sim:
    """legsim_bench's Painleve rod (test_robot_reference.py): 1 kg, 1 m, at 60 deg above the
    ground, its lower end on the line sliding to -x at 1 m/s, spinning at omega; mu_s = mu_k."""
    lib = legsim.load_library("double")
    if lib.config.get("LEGSIM_MAX_CONTACTS", 0) < 1:
        pytest.skip(f"{lib.path} is built without contacts")
    d = lib.ModelDesc()
    d.name = b"rod"
    d.gravity_mps2[1] = -9.81
    d.n_bodies = 1
    d.body[0].name = b"rod"
    d.body[0].length_m = 1.0
    d.body[0].mass_kg = 1.0
    d.body[0].inertia_kgm2 = 1.0 / 12.0
    d.foot_body = -1
    d.n_contacts = 1
    d.contact[0].name = b"end"
    d.contact[0].body = 0
    d.contact[0].point[0], d.contact[0].point[1] = 0.5, 0.0  # 0.5 m along u(phi) = (sin, -cos)
    d.ground.mu_static = mu
    d.ground.mu_kinetic = mu
    s = legsim.Sim(legsim.Model(d, lib, "revolute", "rod"), **kw)
    th = math.radians(60)
    e = -0.5 * np.array([math.cos(th), math.sin(th)])          # end - centre
    vc = np.array([-1.0, 0.0]) - omega * np.array([-e[1], e[0]])  # the end moves at (-1, 0)
    s.set_state([-e[0], -e[1], th - math.pi / 2], [vc[0], vc[1], omega])
    s.set_contact("end", "sliding")
    return s


@pytest.mark.parametrize("mu, omega, inconsistent", [(0.5, 0.0, False), (2.0, 0.0, True), (2.0, 12.0, False)])
def test_painleve_rod_is_reported_never_nan(mu, omega, inconsistent):
    """Beyond the critical friction (1.347 at 60 deg) a rod sliding on its end has no
    consistent mode when not spinning (the reference's contact_modes finds none): the step
    raises contact_inconsistent (its end let go, as the one-by-one rule does, and lands stuck)
    and goes on finite; spinning fast, sliding on is consistent (one of its two solutions): no event;
    below the critical friction, sliding holds."""
    # the bench's enumeration on the same rod (test_robot_reference.py's W and b)
    m_, l, th = 1.0, 0.5, math.radians(60)
    M = np.diag([m_, m_, m_ * l * l / 3.0])
    e = -l * np.array([math.cos(th), math.sin(th)])
    Gm = np.array([[0.0, 1.0, e[0]], [1.0, 0.0, -e[1]]])
    W = Gm @ np.linalg.solve(M, Gm.T)
    b = np.array([-9.81 + omega ** 2 * l * math.sin(th), omega ** 2 * l * math.cos(th)])
    sols = ca.contact_modes(W, b, mu, mu, [-1])
    assert (len(sols) == 0) == inconsistent
    s = _rod(mu, omega)
    s.clear_events()
    s.step(1)
    ev = s.events()
    assert ("contact_inconsistent" in ev) == inconsistent, ev
    assert np.all(np.isfinite(s.q)) and np.all(np.isfinite(s.qd))
    if inconsistent:
        # let go, its end (at the ground, accelerating into it) lands again in the same step,
        # stuck: the impulse inside the cone, pushing
        c = s.contacts()
        assert "liftoff" in ev and "touchdown" in ev and c["state"][0] == "stuck"
        N, T = c["impulse"][0]
        assert N > 0 and abs(T) <= mu * N
    else:
        assert s.contacts()["state"][0] == "sliding" and s.contacts()["normal"][0] > 0


def _compass_reference(q, qd, mu, g=9.81):
    """The bench's enumeration (contact_analytic.contact_modes) for the compass of
    _compass at (q, qd): W = G (M^-1 - M^-1 J^T (J M^-1 J^T)^-1 J M^-1) G^T over the hinge
    J, b the feet's (normal, tangential) accelerations with no contact force; returns the
    consistent solutions and the sign of foot A's sliding velocity (along +x)."""
    def perp(r):
        return np.array([-r[1], r[0]])

    c = [q[3 * i:3 * i + 2] for i in (0, 1)]
    w = [qd[3 * i + 2] for i in (0, 1)]
    u = [np.array([math.sin(q[3 * i + 2]), -math.cos(q[3 * i + 2])]) for i in (0, 1)]
    top = [-0.5 * u[i] for i in (0, 1)]   # hinge - centre, per rod
    foot = [0.5 * u[i] for i in (0, 1)]   # foot - centre

    def rows(r, i):  # a point's acceleration rows (x, y) on rod i
        R = np.zeros((2, 6))
        R[:, 3 * i:3 * i + 2] = np.eye(2)
        R[:, 3 * i + 2] = perp(r)
        return R

    M = np.diag([1.0, 1.0, 1.0 / 12.0] * 2)
    J = rows(top[0], 0) - rows(top[1], 1)
    gam = -w[0] ** 2 * top[0] + w[1] ** 2 * top[1]
    G = np.vstack([rows(foot[0], 0)[[1, 0]], rows(foot[1], 1)[[1, 0]]])
    gG = np.concatenate([(-w[0] ** 2 * foot[0])[[1, 0]], (-w[1] ** 2 * foot[1])[[1, 0]]])
    F = np.array([0.0, -g, 0.0, 0.0, -g, 0.0])
    Mi = np.linalg.inv(M)
    S = J @ Mi @ J.T
    W = G @ (Mi - Mi @ J.T @ np.linalg.solve(S, J @ Mi)) @ G.T
    b = G @ (Mi @ (F + J.T @ np.linalg.solve(S, -gam - J @ Mi @ F))) + gG
    vA = (qd[0:2] + w[0] * perp(foot[0]))[0]
    return ca.contact_modes(W, b, mu, mu, [int(np.sign(vA)), 0]), np.sign(vA)


def _compass(mu, a, wB, **kw):
    """Two 1 kg, 1 m rods hinged at their tops (xi = -0.5), feet (xi = 0.5) on the ground
    line, each leaning a from the vertical (A to -x, B to +x); B's foot stuck, the compass
    turning about it at wB, so A's foot slides along the line. mu_s = mu_k = mu."""
    lib = legsim.load_library("double")
    d = compass_desc(lib, mu)

    def perp(r):
        return np.array([-r[1], r[0]])

    uA = np.array([math.sin(-a), -math.cos(-a)])
    uB = np.array([math.sin(a), -math.cos(a)])
    hinge = np.array([0.0, math.cos(a)])
    cA, cB = hinge + 0.5 * uA, hinge + 0.5 * uB
    vh = wB * perp(hinge - (hinge + uB))                 # B turns about its foot
    wA = -vh[1] / perp(uA)[1]                            # A's foot keeps on the line
    vcA, vcB = vh + wA * perp(cA - hinge), wB * perp(cB - (hinge + uB))
    s = legsim.Sim(legsim.Model(d, lib, "revolute", "compass"), **kw)
    s.set_state([cA[0], cA[1], -a, cB[0], cB[1], a], [vcA[0], vcA[1], wA, vcB[0], vcB[1], wB])
    s.set_contact("footA", "sliding")
    s.set_contact("footB", "stuck")
    return s


@pytest.mark.parametrize("mu, expected", [(2.0, ("slide", "slip-")), (4.0, ("slide", "free"))])
def test_several_consistent_modes_raise_contact_ambiguous(mu, expected):
    """A compass (two rods hinged at the top) at 50 deg a side, turning at 6 rad/s about its
    stuck foot B while foot A slides to -x: B's stuck mode fails, and the reference's
    enumeration finds two consistent modes, both feet lifting off and `expected` (mu = 2:
    A slides on, B starts to slip to -x; mu = 4: A slides on, B lifts off). The step raises
    contact_ambiguous and takes the first in the documented priority (current, stick, slip,
    lift-off), which is `expected`, and stays finite."""
    a = math.radians(50)
    s = _compass(mu, a, 6.0, step=1e-4)
    # before the step, as the reference sees it: the current mode (slide, stick) fails
    sols, dirA = _compass_reference(s.q, s.qd, mu)
    assert dirA < 0 and sorted(x.modes for x in sols) == sorted([("free", "free"), expected])
    s.clear_events()
    s.step(1)
    ev = s.events()
    # the reference at the state where the core enumerated (the step's end; a slip onset or
    # a lift-off changes no coordinate or velocity): still the same two
    modes = [x.modes for x in _compass_reference(s.q, s.qd, mu)[0]]
    assert sorted(modes) == sorted([("free", "free"), expected]), modes
    rank = {"slide": 0, "stick": 0, "slip+": 2, "slip-": 2, "free": 3}  # current, stick, slip, free
    assert min(modes, key=lambda md: sum(rank[x] for x in md)) == expected
    assert "contact_ambiguous" in ev and "contact_inconsistent" not in ev, ev
    assert ("stick_to_slip" in ev) == (expected[1] == "slip-"), ev
    assert ("liftoff" in ev) == (expected[1] == "free"), ev
    c = s.contacts()
    assert tuple(c["state"]) == ("sliding", "sliding" if expected[1] == "slip-" else "free")
    assert np.all(np.isfinite(s.q)) and np.all(np.isfinite(s.qd))
    assert c["normal"][0] > 0
    # the sliding feet slide to -x: friction along +x, T = mu N
    sl = c["state"] == "sliding"
    assert c["tangential"][sl] == pytest.approx(mu * c["normal"][sl], rel=1e-12)
    assert np.all(c["normal"][sl] > 0)
