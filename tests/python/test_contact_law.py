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

from conftest import ROOT

try:
    import legsim_bench.reference  # noqa: F401
except ImportError:  # the bench is not installed: its source tree
    sys.path.insert(0, str(ROOT / "bench"))
from legsim_bench.analyses import robot_reference  # noqa: E402
from legsim_bench.reference import contact_analytic as ca  # noqa: E402
from legsim_bench.scene import load_scene  # noqa: E402

ROBOT = ROOT / "models" / "robot.toml"
FEET = ("right.foot", "left.foot")


def _robot_sim(**kw) -> legsim.Sim:
    lib = legsim.load_library("double")
    if lib.config["LEGSIM_MAX_BODIES"] < 13 or lib.config.get("LEGSIM_MAX_CONTACTS", 0) < 2:
        pytest.skip(f"{lib.path} is built without room for the robot")
    return legsim.Sim(str(ROBOT), **kw)


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
    raises contact_inconsistent (its end let go, as the one-by-one rule does) and goes on
    finite; spinning fast, sliding on is consistent (one of its two solutions): no event;
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
        assert s.contacts()["state"][0] == "free"
    else:
        assert s.contacts()["state"][0] == "sliding" and s.contacts()["normal"][0] > 0
