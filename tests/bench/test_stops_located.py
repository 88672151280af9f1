"""A stroke stop's arrival located inside the step (docs/design/events.md), checked against
the bench's reference with stroke stops (legsim_bench.reference.robot_events,
stroke_stops=True; its own checks in test_reference_stops.py):

- the robot on its stand, both feet stuck, the right upper's force 300 N under the stand's
  statics, its stroke minimum raised to 0.645 m: it arrives there at 41.5 ms at -0.81 m/s;
- the core reports the arrival's time (legsim_stroke_event_time) within 1e-3 h of the
  reference's, at every h;
- the energy the stop takes is Carnot's (the reference's loss) to 1e-6 relative at h = 1 ms
  (taken at the step's end it was 2 % more);
- after it the trajectory keeps RK4's order: the error at 80 ms falls by >= 2^3.5 per halving.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

legsim = pytest.importorskip("legsim")

from legsim_bench.reference import ForceCommand  # noqa: E402
from legsim_bench.reference.robot_events import simulate_events  # noqa: E402
from test_reference_stops import PUSH, STROKE_MIN, robot_with_upper_stroke  # noqa: E402

T_END = 0.08
G = 9.81


@pytest.fixture(scope="module")
def case(tmp_path_factory):
    folder = tmp_path_factory.mktemp("stop_located")
    ref = robot_with_upper_stroke(folder, STROKE_MIN, 0.80)
    asm = ref.assemble()
    forces = [float(f) for f in ref.statics().actuator_forces]
    forces[0] += PUSH
    res = simulate_events(ref, T_END, [0.0, T_END], asm.z, np.zeros(7),
                          actuators=[ForceCommand(f) for f in forces], stroke_stops=True)
    assert [(e.kind, e.actuator) for e in res.events] == [("stroke_min", 0)]
    return folder / "robot.toml", ref, asm, forces, res


def core_run(case, h):
    path, ref, asm, forces, _ = case
    s = legsim.Sim(legsim.Model.from_toml(str(path)), integrator="rk4", step=h)
    s.assemble_on_ground()
    K = ref.kinematics(asm.z, np.zeros(7))    # the reference's start exactly
    s.set_state(K.P.reshape(-1), np.zeros(39))
    for k in range(2):
        s.set_contact(k, "stuck")
    for a, f in enumerate(forces):
        s.command_force(a, f)
    s.clear_events()
    return s


def energy(s, forces):
    """kinetic + gravity's potential - sum F l (constant forces): conserved but for the stop."""
    v = np.asarray(s.qd).reshape(-1, 3)
    q = np.asarray(s.q).reshape(-1, 3)
    kin = 0.5 * float(np.sum(s.model.masses * (v[:, 0] ** 2 + v[:, 1] ** 2))
                      + np.sum(s.model.inertias * v[:, 2] ** 2))
    return kin + float(np.sum(s.model.masses * G * q[:, 1])) - float(np.dot(forces, s.actuator_lengths()[0]))


def q_error(qa, qb):
    d = (np.asarray(qa) - np.asarray(qb)).reshape(-1, 3)
    d[:, 2] = (d[:, 2] + math.pi) % (2 * math.pi) - math.pi
    return float(np.max(np.abs(d)))


@pytest.mark.parametrize("h", [2e-3, 1e-3, 5e-4, 2.5e-4])
def test_arrival_time_is_located(case, h):
    *_, forces, res = case
    t_ref = res.events[0].t
    s = core_run(case, h)
    k_arrival = math.floor(t_ref / h) + 1
    s.step(k_arrival)
    assert s.stroke_event_mask() == 1, s.events()
    t = s.stroke_event_time(0)
    print(f"h {h:g}: arrival at {t!r} s, the reference's {t_ref!r} s ({(t - t_ref) / h:+.1e} h)")
    assert abs(t - t_ref) <= 1e-3 * h
    assert abs(s.actuator_lengths()[0][0] - STROKE_MIN) < 1e-9


def test_stop_takes_carnots_energy(case):
    *_, forces, res = case
    h = 1e-3
    s = core_run(case, h)
    e_prev = energy(s, forces)
    for _ in range(round(T_END / h)):
        s.step(1)
        e_now = energy(s, forces)
        if s.stroke_event_mask():
            break
        e_prev = e_now
    lost, exact = e_prev - e_now, res.events[0].kinetic_lost
    print(f"the stop takes {lost:.10f} J, Carnot's {exact:.10f} J ({(lost - exact) / exact:+.2e})")
    assert abs(lost - exact) <= 1e-6 * exact


def test_rk4_keeps_its_order_through_the_stop(case):
    *_, res = case
    q_ref = res.q[-1]
    errs = []
    for h in (2e-3, 1e-3, 5e-4, 2.5e-4):
        s = core_run(case, h)
        s.step(round(T_END / h))
        errs.append(q_error(s.q, q_ref))
    orders = [math.log2(a / b) for a, b in zip(errs, errs[1:])]
    print("errors", ", ".join(f"{e:.3e}" for e in errs), "orders", ", ".join(f"{o:.2f}" for o in orders))
    assert all(o >= 3.5 for o in orders if errs[-1] > 1e-12), orders
