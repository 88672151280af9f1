"""Contact events located inside the step (docs/design/events.md), checked against the
bench's event-locating reference (legsim_bench.reference.robot_events: DOP853's dense output,
the drop's touchdown at sqrt(2 d / g) to 1e-13 s) and against exact results:
- the 1 cm level drop lands at sqrt(2 d / g) to 1e-3 h for every h, and its impulse takes
  Carnot's energy to 1e-6 relative (the core took the touchdown at the step's end: 3.7 % more);
- a slip onset is located to 1e-3 h of the reference's;
- stuck feet on a slope steeper than the friction allows slip at the start time, not after
  the first step.
The core's event time is read through the C API (legsim_contact_event_time)."""
from __future__ import annotations

import ctypes as C
import math

import numpy as np
import pytest

legsim = pytest.importorskip("legsim")

from legsim_bench.reference import LengthCommand  # noqa: E402
from legsim_bench.reference.model_file import read_model_file  # noqa: E402
from legsim_bench.reference.robot import RobotModel  # noqa: E402
from legsim_bench.reference.robot_events import simulate_events  # noqa: E402
from model_files import ROBOT  # noqa: E402

G = 9.81
DROP = 0.01


def event_time(s, k):
    f = s.library.cdll.legsim_contact_event_time
    f.restype = C.c_int
    f.argtypes = [C.c_void_p, C.c_int32, C.POINTER(C.c_double)]
    t = C.c_double()
    assert f(s.handle, k, C.byref(t)) == 0
    return t.value


def robot_sim(ref, z0, zd0, states, h, ground=None, commands=None):
    model = legsim.Model.from_toml(str(ROBOT))
    for k, v in (ground or {}).items():
        setattr(model.desc.ground, k, v)
    s = legsim.Sim(model, integrator="rk4", step=h)
    s.assemble_on_ground()
    K = ref.kinematics(z0, zd0)
    s.set_state(K.P.reshape(-1), K.J.reshape(-1, 7) @ zd0)
    for k, st in enumerate(states):
        s.set_contact(k, st)
    for a, c in enumerate(commands):
        s.command_length(a, float(c))
    s.clear_events()
    return s


@pytest.fixture(scope="module")
def drop():
    ref = RobotModel(read_model_file(ROBOT), ROBOT.parent)
    asm = ref.assemble()
    z0 = asm.z.copy()
    z0[1] += DROP
    t = np.array([0.0, 0.05])
    run = simulate_events(ref, 0.05, t, z0, np.zeros(7), ("free", "free"),
                          actuators=[LengthCommand(float(x)) for x in asm.lengths])
    return ref, asm, z0, run


@pytest.mark.parametrize("h", [2e-3, 1e-3, 5e-4, 2.5e-4])
def test_touchdown_located_and_its_energy_exact(drop, h):
    ref, asm, z0, run = drop
    t_exact = math.sqrt(2 * DROP / G)
    assert run.events[0].t == pytest.approx(t_exact, abs=1e-12)
    s = robot_sim(ref, z0, np.zeros(7), ("free", "free"), h, commands=asm.lengths)
    for _ in range(int(0.05 / h)):
        s.step(1)
        if "touchdown" in s.events():
            break
    assert "touchdown" in s.events()
    for k in range(2):
        assert abs(event_time(s, k) - t_exact) <= 1e-3 * h
    # Carnot: the feet approach at g t_e and stop, the impulse takes 1/2 sum P_n g t_e
    pn = sum(float(c["impulse"][0]) for c in s.contacts())
    lost = 0.5 * pn * G * event_time(s, 0)
    assert lost == pytest.approx(run.events[0].kinetic_lost, rel=1e-6)


@pytest.mark.parametrize("h", [1e-3, 2.5e-4])
def test_slip_onset_located(h):
    ground = {"mu_static": 0.1, "mu_kinetic": 0.1}
    data = read_model_file(ROBOT)
    data["ground"].update(ground)
    ref = RobotModel(data, ROBOT.parent)
    asm = ref.assemble()
    t = np.array([0.0, 0.02])
    run = simulate_events(ref, 0.02, t, asm.z.copy(), np.zeros(7), ("stuck", "stuck"),
                          actuators=[legsim_bench_force(185.55)] + [LengthCommand(float(x)) for x in asm.lengths[1:]])
    t_ref = run.events[0].t
    s = robot_sim(ref, asm.z.copy(), np.zeros(7), ("stuck", "stuck"), h, ground, asm.lengths)
    s.command_force(0, 185.55)
    s.clear_events()
    for _ in range(int(0.02 / h)):
        s.step(1)
        if "stick_to_slip" in s.events():
            break
    assert "stick_to_slip" in s.events()
    k = run.events[0].foot
    assert abs(event_time(s, k) - t_ref) <= 1e-3 * h


def legsim_bench_force(f):
    from legsim_bench.reference import ForceCommand
    return ForceCommand(f)


def test_a_start_that_cannot_hold_is_resolved_at_the_start():
    # stuck feet on a slope whose stance needs more friction (|T|/N 0.15 at the right foot) than mu_s 0.05
    model = legsim.Model.from_toml(str(ROBOT))
    model.desc.ground.slope_rad = 0.5
    model.desc.ground.mu_static = 0.05
    model.desc.ground.mu_kinetic = 0.05
    s = legsim.Sim(model, integrator="rk4", step=1e-3)
    s.assemble_on_ground()
    s.set_contact(0, "stuck")
    s.set_contact(1, "stuck")
    s.clear_events()
    t0 = s.time
    s.step(1)
    assert "stick_to_slip" in s.events()
    sliding = [k for k, c in enumerate(s.contacts()) if c["state"] == "sliding"]
    assert sliding
    assert all(event_time(s, k) == t0 for k in sliding)  # not t0 + h: at the start
    # it slid for the whole step: its sliding velocity is not 0 (about (g sin - mu g cos) h)
    assert all(abs(float(s.contacts()[k]["slip"])) > 1e-4 for k in sliding)


@pytest.fixture(scope="module")
def pitch_liftoff():
    """The robot pitching on stuck feet (mu_s = mu_k = 0.6, constant actuator forces, the
    right thigh started at -2.5 rad/s): the left foot slips at 96.32 ms and lifts off 23 us
    later, its normal force falling to zero so fast that one RK4 step over the slide errs
    by 7e-9 m at any h above 23 us (event_order.py's lift-off case)."""
    data = read_model_file(ROBOT)
    data["ground"].update({"mu_static": 0.6, "mu_kinetic": 0.6})
    ref = RobotModel(data, ROBOT.parent)
    asm = ref.assemble()
    forces = [float(f) for f in ref.statics().actuator_forces]
    T, _ = ref._partition(ref.kinematics(asm.z, np.zeros(7)))
    zd0 = T @ np.array([0.0, -2.5, 0.0])
    run = simulate_events(ref, 0.12, np.array([0.0, 0.12]), asm.z.copy(), zd0, ("stuck", "stuck"),
                          actuators=[legsim_bench_force(f) for f in forces])
    return ref, asm, zd0, forces, run


@pytest.mark.parametrize("h", [1e-3, 5e-4, 2.5e-4])
def test_slip_then_liftoff_within_a_step_keeps_rk4_accurate(pitch_liftoff, h):
    ref, asm, zd0, forces, run = pitch_liftoff
    assert [e.kind for e in run.events] == ["stick_to_slip", "liftoff"]
    t_lift = run.events[1].t
    model = legsim.Model.from_toml(str(ROBOT))
    model.desc.ground.mu_static = model.desc.ground.mu_kinetic = 0.6
    s = legsim.Sim(model, integrator="rk4", step=h)
    s.assemble_on_ground()
    K = ref.kinematics(asm.z, zd0)
    s.set_state(K.P.reshape(-1), K.J.reshape(-1, 7) @ zd0)
    for k in range(2):
        s.set_contact(k, "stuck")
    for a, f in enumerate(forces):
        s.command_force(a, f)
    s.clear_events()
    s.step(round(0.12 / h))
    foot = run.events[1].foot
    assert abs(event_time(s, foot) - t_lift) <= 1e-3 * h
    d = (np.asarray(s.q) - run.q[-1]).reshape(-1, 3)
    d[:, 2] = (d[:, 2] + math.pi) % (2 * math.pi) - math.pi
    # the smooth motion's own error at these h is <= 6e-10 m (event_order.py's "none"); the
    # slide's part step, taken whole, added 7e-9 m at every h
    assert float(np.max(np.abs(d))) <= {1e-3: 3e-9, 5e-4: 2e-10, 2.5e-4: 1e-11}[h]
