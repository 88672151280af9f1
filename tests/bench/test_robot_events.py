"""The robot reference's event location (legsim_bench.reference.robot_events) against
closed forms and the stuck-feet reference (RobotModel.simulate, another formulation):

- a level drop falls rigidly and lands both feet at t = sqrt(2 d / g), located to 1e-13 s;
- its touchdown loses exactly Carnot's energy, computed independently from the 39 absolute
  coordinates and the Newton-Euler columns of the joints and ground rows (ca.inelastic_impact);
  and E(0) - E(after) is the same (the fall does no other work);
- after the landing, the motion on the stuck feet is RobotModel.simulate's from the post-impact
  state (coordinate partitioning vs the contact rows);
- a slip onset is located where the stuck-feet reference's |T| crosses mu_s N, and the
  sliding loses exactly the friction work;
- a lift-off where the normal force is zero, a slip to stick where the sliding velocity is;
- a landing outside the static cone slides with mu_k and loses less than a stuck one;
- without events, the run is RobotModel.simulate's to 1e-11.
"""
from __future__ import annotations

import copy
import math

import numpy as np
import pytest

from legsim_bench.reference import ForceCommand, LengthCommand
from legsim_bench.reference import contact_analytic as ca
from legsim_bench.reference.robot import Assembly, RobotModel, _IND
from legsim_bench.reference.robot_events import simulate_events
from model_files import DATA, ROBOT

G = 9.81


def drop(robot, d, t_end, t_eval):
    a = robot.assemble()
    z0 = a.z.copy()
    z0[1] += d
    cmds = [LengthCommand(float(x)) for x in a.lengths]   # the servos hold: nothing in the fall
    return a, cmds, simulate_events(robot, t_end, t_eval, z0, np.zeros(7), ("free", "free"),
                                    actuators=cmds)


def carnot_absolute(robot, q, v_minus):
    """Carnot's loss of the stance at q (39 absolute coordinates): the constraint rows are
    the Newton-Euler columns of the 32 joint reactions and the 2 x 2 ground forces."""
    A, _, _, _ = robot._ne_system(q, np.zeros_like(q), np.zeros(robot.na), (0.0, 0.0, 0.0), np.zeros(2))
    return ca.inelastic_impact(np.diag(robot._Mflat), A.T, v_minus)


@pytest.mark.parametrize("d", [0.01, 0.003])
def test_level_drop_lands_at_the_free_fall_time_and_loses_carnots_energy(robot, d):
    t_td = math.sqrt(2 * d / G)
    a, _, res = drop(robot, d, t_td + 0.002, [0.0, t_td + 0.002])
    ev = res.events
    assert [(e.kind, e.foot) for e in ev] == [("touchdown", 0), ("touchdown", 1)]
    print(f"d = {d}: touchdown at {ev[0].t!r} s, free fall {t_td!r} s "
          f"({ev[0].t - t_td:+.2e} s); kinetic energy lost {ev[0].kinetic_lost:.12f} J")
    assert abs(ev[0].t - t_td) < 1e-13 and ev[1].t == ev[0].t
    assert ev[0].after == ("stuck", "stuck")
    # the impact's closed form, in the absolute coordinates of the landed pose
    v_minus = np.zeros(3 * robot.nb)
    v_minus[1::3] = -math.sqrt(2 * G * d)
    v_plus, _, lost = carnot_absolute(robot, a.q, v_minus)
    assert abs(ev[0].kinetic_lost - lost) < 1e-12 * lost
    K = robot.kinematics(ev[0].z, ev[0].zd_plus)
    assert np.max(np.abs(K.J.reshape(-1, 7) @ ev[0].zd_minus - v_minus)) < 1e-12
    assert np.max(np.abs(K.J.reshape(-1, 7) @ ev[0].zd_plus - v_plus)) < 1e-12
    assert np.max(np.abs(K.foot - a.feet)) < 1e-12 and np.max(np.abs(K.P.reshape(-1) - a.q)) < 1e-12
    # the energy balance: the drop's potential energy less the post-impact kinetic energy
    e_after = sum(robot.energy(ev[0].z, ev[0].zd_plus))
    assert abs((res.energy[0] - e_after) - lost) < 1e-11
    # impulses: inside the cone, mirror images, together the momentum removed (vertical)
    P = ev[0].impulse
    assert np.all(P[:, 0] > 0) and np.all(np.abs(P[:, 1]) <= robot.ground.mu_static * P[:, 0])
    assert P[0, 0] == pytest.approx(P[1, 0], rel=1e-12) and P[0, 1] == pytest.approx(-P[1, 1], rel=1e-9)


def test_stance_after_the_landing_is_the_stuck_feet_reference(robot):
    d = 0.01
    t_td = math.sqrt(2 * d / G)
    t = np.array([t_td + 0.02, t_td + 0.05])
    a, cmds, res = drop(robot, d, float(t[-1]), t)
    ev = res.events[0]
    z, zd = ev.z, ev.zd_plus
    K = robot.kinematics(z, zd)
    start = Assembly(z.copy(), K.P.reshape(-1), K.foot.copy(), a.lengths.copy())
    t_td = ev.t
    # RobotModel's clock starts at 0: the servo commands are constant, so it may
    ref = robot.simulate(float(t[-1] - t_td), t - t_td, actuators=cmds, start=start,
                         i0=z[_IND], id0=zd[_IND])
    err = np.max(np.abs(ref.q - res.q))
    print(f"after the landing: |q - q_stuck-reference| {err:.2e}")
    assert err < 1e-11
    assert np.all(res.states == "stuck")


def test_slip_onset_is_where_the_stuck_reference_leaves_the_cone():
    data = copy.deepcopy(DATA)
    data["ground"].update(mu_static=0.1, mu_kinetic=0.1)
    r = RobotModel(data, ROBOT.parent)
    a = r.assemble()
    cmds = [ForceCommand(185.55)] + [LengthCommand(float(x)) for x in a.lengths[1:]]
    res = simulate_events(r, 0.02, [0.0, 0.02], a.z, np.zeros(7), actuators=cmds)
    assert [(e.kind, e.foot) for e in res.events] == [("stick_to_slip", 1)]
    t_ev = res.events[0].t
    # the stuck-feet reference's friction use of the left foot crosses mu_s: bracket it
    dt = 1e-6
    st = r.simulate(t_ev + dt, [t_ev - dt, t_ev + dt], actuators=cmds)
    f = np.abs(st.tangential[:, 1]) - 0.1 * st.normal[:, 1]
    assert f[0] < 0 < f[1]
    root = t_ev - dt + 2 * dt * (-f[0]) / (f[1] - f[0])     # secant: error ~ dt^2 f''/f'
    print(f"slip onset {t_ev!r} s, the stuck reference's cone crossing {root!r} s")
    assert abs(root - t_ev) < 1e-10
    assert res.states[-1].tolist() == ["stuck", "sliding"]


def test_no_event_run_is_the_stuck_feet_reference(robot):
    a = robot.assemble()
    cmds = [ForceCommand(185.55)] + [LengthCommand(float(x)) for x in a.lengths[1:]]
    t = np.linspace(0.0, 0.1, 6)
    res = simulate_events(robot, 0.1, t, a.z, np.zeros(7), actuators=cmds)
    ref = robot.simulate(0.1, t, actuators=cmds)
    assert res.events == []
    assert np.max(np.abs(res.q - ref.q)) < 1e-11


def test_sliding_loses_exactly_the_friction_work():
    """Through the slip onset and while the left foot slides (the Fig. 7 push on mu 0.1/0.1),
    the kinetic and gravity energy changes by the actuators' power plus the friction's
    (T v_t of the sliding foot; the stuck foot and the normal forces do no work), integrated
    by Simpson's rule on either side of the onset: the sliding mode's force (N, its direction
    against the slip) and the switch at the located onset."""
    from scipy.integrate import simpson
    data = copy.deepcopy(DATA)
    data["ground"].update(mu_static=0.1, mu_kinetic=0.1)
    r = RobotModel(data, ROBOT.parent)
    a = r.assemble()
    cmds = [ForceCommand(185.55)] + [LengthCommand(float(x)) for x in a.lengths[1:]]
    t_end, n1 = 0.04, 201
    t_ev = simulate_events(r, t_end, [0.0], a.z, np.zeros(7), actuators=cmds).events[0].t
    t = np.concatenate([np.linspace(0.0, t_ev, n1), np.linspace(t_ev, t_end, 501)])
    t[n1 - 1] = np.nextafter(t_ev, 0.0)          # the last sample before the onset, in the stuck mode
    res = simulate_events(r, t_end, t, a.z, np.zeros(7), actuators=cmds)
    assert res.states[n1 - 1].tolist() == ["stuck", "stuck"] and res.states[n1].tolist() == ["stuck", "sliding"]
    assert np.all(res.slip[n1:, 1] * res.tangential[n1:, 1] <= 1e-12)  # friction against the slip
    assert np.allclose(np.abs(res.tangential[n1:, 1]), 0.1 * res.normal[n1:, 1], rtol=1e-12)
    power = np.zeros(len(t))
    for i, (tt, z, zd) in enumerate(zip(res.t, res.z, res.zd)):
        K = r.kinematics(z, zd)
        power[i] = r._forces(cmds, tt, K) @ K.ld
    power += np.sum(res.tangential * res.slip, axis=1)
    work = simpson(power[:n1], x=res.t[:n1]) + simpson(power[n1:], x=res.t[n1:])
    friction = simpson(np.sum(res.tangential * res.slip, axis=1)[n1:], x=res.t[n1:])
    change = res.energy[-1] - res.energy[0]
    print(f"energy change {change:.12f} J, work of the actuators and friction {work:.12f} J "
          f"(friction {friction:.6e} J)")
    assert friction < -1e-4
    assert abs(change - work) < 1e-9


def test_liftoff_is_located_where_the_normal_force_reaches_zero():
    """The robot pitching on constant forces (event_order.py's lift-off case, mu 0.6/0.6): the
    left foot's |T|/N grows without bound as N falls, so it slips, then lifts off where its
    sliding-mode N is zero; then it rises off the ground."""
    from legsim_bench.reference.robot_events import _Dynamics, modes_from
    data = copy.deepcopy(DATA)
    data["ground"].update(mu_static=0.6, mu_kinetic=0.6)
    r = RobotModel(data, ROBOT.parent)
    a = r.assemble()
    cmds = [ForceCommand(float(f)) for f in r.statics().actuator_forces]
    T, _ = r._partition(r.kinematics(a.z, np.zeros(7)))
    zd0 = T @ np.array([0.0, -2.5, 0.0])
    t = np.linspace(0.0, 0.12, 61)
    res = simulate_events(r, 0.12, t, a.z, zd0, actuators=cmds)
    assert [(e.kind, e.foot) for e in res.events] == [("stick_to_slip", 1), ("liftoff", 1)]
    slip, lift = res.events
    assert 0 < lift.t - slip.t < 1e-4 and lift.before == ("stuck", "sliding") and lift.after == ("stuck", "free")
    dyn = _Dynamics(r, cmds, r.gravity, (0.0, 0.0, 0.0))
    sign = -int(np.sign(dyn.solve(slip.t, np.concatenate([slip.z, slip.zd_minus]), modes_from(("stuck", "stuck")))[2][1]))
    _, N, _, gap, _ = dyn.solve(lift.t, np.concatenate([lift.z, lift.zd_minus]),
                                modes_from(("stuck", "sliding"), (0, sign)))
    weight = float(np.sum(r._m)) * 9.81
    print(f"slip {slip.t!r} s, lift-off {lift.t!r} s: N there {N[1]:.2e} N, gap {gap[1]:.2e} m")
    assert abs(N[1]) < 1e-9 * weight and abs(gap[1]) < 1e-12
    after = res.t > lift.t
    gaps = res.feet[after, 1] @ r.ground.normal
    assert np.all(gaps > 0) and res.states[-1].tolist() == ["stuck", "free"]
    assert np.all(res.normal[after, 1] == 0.0) and np.all(res.normal[:, 0] > 0)


def test_a_sliding_foot_sticks_where_its_velocity_reaches_zero(robot):
    """From the servo equilibrium, the left lower set-point 15 mm shorter makes the left foot
    slide at once (resolved at t = 0) and stick again where its sliding velocity is zero."""
    a = robot.assemble()
    cmds = [LengthCommand(float(x)) for x in a.lengths]
    z_eq = robot.equilibrium(cmds)
    cmds[3] = LengthCommand(float(a.lengths[3] - 0.015))
    t = np.linspace(0.0, 0.05, 51)
    res = simulate_events(robot, 0.05, t, z_eq, np.zeros(7), actuators=cmds)
    assert [(e.t == 0.0, e.kind, e.foot) for e in res.events] == [(True, "stick_to_slip", 1),
                                                                  (False, "slip_to_stick", 1)]
    stick = res.events[1]
    vt = robot.ground.tangent @ (robot.kinematics(stick.z, stick.zd_plus).footJ[1] @ stick.zd_plus)
    print(f"slip to stick at {stick.t!r} s, v_t there {vt:.2e} m/s")
    assert abs(vt) < 1e-12
    sliding = (res.t > 0) & (res.t < stick.t)
    assert np.all(res.states[sliding, 1] == "sliding") and len(np.unique(np.sign(res.slip[sliding, 1]))) == 1
    held = res.t > stick.t
    assert np.all(res.states[held, 1] == "stuck")
    assert np.all(np.abs(res.tangential[held, 1]) <= robot.ground.mu_static * res.normal[held, 1])


def test_touchdown_outside_the_cone_slides_with_kinetic_friction():
    """The 1 cm drop moving sideways at 1 m/s onto mu 0.1/0.1: the sticking impulses would
    leave the cone, so both feet land sliding: the normal approach is removed, the tangential
    impulse is mu_k P_n against the slip, and less energy is lost than by a stuck landing."""
    data = copy.deepcopy(DATA)
    data["ground"].update(mu_static=0.1, mu_kinetic=0.1)
    r = RobotModel(data, ROBOT.parent)
    a = r.assemble()
    z0 = a.z.copy()
    z0[1] += 0.01
    zd0 = np.zeros(7)
    zd0[0] = 1.0
    cmds = [LengthCommand(float(x)) for x in a.lengths]
    res = simulate_events(r, 0.05, [0.0, 0.05], z0, zd0, ("free", "free"), actuators=cmds)
    e = res.events[0]
    assert [(x.kind, x.foot) for x in res.events] == [("touchdown", 0), ("touchdown", 1)]
    assert abs(e.t - math.sqrt(2 * 0.01 / G)) < 1e-13 and e.after == ("sliding", "sliding")
    K = r.kinematics(e.z, e.zd_plus)
    vn = [r.ground.normal @ (K.footJ[k] @ e.zd_plus) for k in range(2)]
    vt = np.array([r.ground.tangent @ (K.footJ[k] @ e.zd_plus) for k in range(2)])
    assert np.max(np.abs(vn)) < 1e-12 and np.all(vt > 0)
    assert np.all(e.impulse[:, 0] > 0)
    assert np.allclose(e.impulse[:, 1], -0.1 * e.impulse[:, 0], rtol=1e-12)
    v_minus = (K.J.reshape(-1, 7) @ e.zd_minus)
    _, _, stuck_loss = carnot_absolute(r, K.P.reshape(-1), v_minus)
    print(f"sliding landing loses {e.kinetic_lost:.9f} J, a stuck one {stuck_loss:.9f} J")
    assert 0 < e.kinetic_lost < stuck_loss
