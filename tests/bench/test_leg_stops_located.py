"""The leg alone's stroke stop arrival located inside the step (docs/design/events.md), against
the bench's independent model of the leg (legsim_bench.reference.leg_stop on LegModel: minimal
coordinates (phi3, phi6), closed-form poses, the arrival located on DOP853's dense output, the
impact and the held motion in closed form):

- the leg of models/leg.toml hanging from its frame (no ground), the stand's statics forces but
  the upper actuator's 300 N less, its stroke minimum raised to 0.645 m (a copy of the file): it
  shortens and arrives there at 50.4 ms at -0.67 m/s;
- the core reports the arrival's time (legsim_stroke_event_time) within 1e-3 h of the
  reference's, with both integrators and at every h;
- the stop takes Carnot's energy, 1/2 ldot^2 / (g M^-1 g) with g = dl/dtheta (the reference's
  closed form), to 1e-6 relative at h = 1 ms;
- after it the trajectory keeps RK4's order: the error at 0.1 s (50 ms on) falls by >= 2^3.5
  per halving of h; the reference's stop keeps pushing over that time (checked).
(An arrival taken at the step's end fails all three: firmware_core/benchmarks/results.md.)

A build without the event code (LEGSIM_MAX_CONTACTS = 0, the Cortex-M4F leg image) takes the
arrival at the step's end; this library is the host's.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

legsim = pytest.importorskip("legsim")

from legsim_bench.reference.leg_stop import state_energy, stop_case, upper_stop  # noqa: E402
from model_files import LEG_TOML  # noqa: E402

STROKE_MIN = 0.645      # m: the upper actuator's raised minimum
PUSH = -300.0           # N: the upper's force less the stand's statics
T_END = 0.1             # s: the order is measured there, 50 ms after the arrival
STEPS = (2e-3, 1e-3, 5e-4, 2.5e-4)


@pytest.fixture(scope="module")
def case(tmp_path_factory):
    path, ref, th0, forces = stop_case(LEG_TOML, tmp_path_factory.mktemp("leg_stop"), STROKE_MIN, PUSH)
    run = upper_stop(ref, th0, forces, STROKE_MIN, T_END)
    assert run.stop_force.min() * run.stop_force.max() > 0, "the reference's stop lets go"
    return path, ref, th0, forces, run.t_arrival, run.rate, run.carnot, run.q_end


def core_run(case, integrator, h):
    path, ref, th0, forces, *_ = case
    s = legsim.Sim(legsim.Model.from_toml(str(path)), integrator=integrator, step=h)
    s.set_state(ref.absolute_q(th0), np.zeros(18))
    for a, f in enumerate(forces):
        s.command_force(a, float(f))
    s.clear_events()
    return s


def energy(s, ref, forces):
    return state_energy(s.q, s.qd, s.model.masses, s.model.inertias, ref.gravity, forces, s.actuator_lengths()[0])


@pytest.mark.parametrize("integrator", ["rk4", "galpha"])
@pytest.mark.parametrize("h", STEPS)
def test_arrival_time_is_located(case, integrator, h):
    t_ref = case[4]
    s = core_run(case, integrator, h)
    s.step(math.floor(t_ref / h) + 1)
    assert s.stroke_event_mask() == 1, s.events()
    t = s.stroke_event_time(0)
    print(f"{integrator} h {h:g}: arrival at {t!r} s, the reference's {t_ref!r} s ({(t - t_ref) / h:+.1e} h)")
    assert abs(t - t_ref) <= 1e-3 * h
    assert abs(s.actuator_lengths()[0][0] - STROKE_MIN) < 1e-9


def test_stop_takes_carnots_energy(case):
    _, ref, _, forces, t_ref, rate, carnot, _ = case
    h = 1e-3
    s = core_run(case, "rk4", h)
    s.step(math.floor(t_ref / h))
    e_before = energy(s, ref, forces)
    s.step(1)
    assert s.stroke_event_mask() == 1
    lost = e_before - energy(s, ref, forces)
    print(f"arrival at {rate:.6f} m/s: the stop takes {lost:.12f} J, Carnot's {carnot:.12f} J "
          f"({(lost - carnot) / carnot:+.2e})")
    assert abs(lost - carnot) <= 1e-6 * carnot


def test_rk4_keeps_its_order_through_the_stop(case):
    q_ref = case[7]
    errs = []
    for h in STEPS:
        s = core_run(case, "rk4", h)
        s.step(round(T_END / h))
        assert s.stroke_event_mask() == 1 and abs(s.actuator_lengths()[0][0] - STROKE_MIN) < 1e-9
        errs.append(float(np.max(np.abs(np.asarray(s.q) - q_ref))))
    orders = [math.log2(a / b) for a, b in zip(errs, errs[1:])]
    print("errors", ", ".join(f"{e:.3e}" for e in errs), "orders", ", ".join(f"{o:.2f}" for o in orders))
    assert all(o >= 3.5 for o, b in zip(orders, errs[1:]) if b > 1e-12), orders
