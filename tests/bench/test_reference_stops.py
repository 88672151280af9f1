"""The robot reference's stroke stops (legsim_bench.reference.robot_events, stroke_stops=True)
checked on their own, against closed forms and the reference without stops:

- an arrival is located with the length on its end to 1e-12 m and its rate removed; the
  impact loses exactly Carnot's energy, computed independently from the 39 absolute
  coordinates with the Newton-Euler columns of the joints, the ground rows and the actuator's
  axial force (ca.inelastic_impact), to 1e-10 relative, and v+ is that impact's;
- held, the length stays on its end, the stop pushes, and the energy with the constant forces'
  potential (-F l) stays constant (the stop does no work);
- a held stop lets go where its force reaches zero, and the length leaves its end;
- with the stops disabled, or far, the run is the reference's without stops (and the
  stuck-feet RobotModel.simulate's, another formulation), and before an arrival it is too.

The case is event_order.py's `stop`: the robot on its stand, both feet stuck, the stand's
statics forces but the right upper's 300 N less; the upper strokes' minimum raised to 0.645 m
(a copy of the model files) so that the right upper arrives at it at 41.5 ms at -0.81 m/s.
"""
from __future__ import annotations

import numpy as np
import pytest

from legsim_bench.reference import ForceCommand
from legsim_bench.reference import contact_analytic as ca
from legsim_bench.reference.robot import RobotModel
from legsim_bench.reference.robot_events import AT_MIN, simulate_events
from model_files import LEG_TOML, ROBOT

STROKE_MIN = 0.645      # m: the upper actuators' raised minimum
PUSH = -300.0           # N: the right upper's force less the stand's statics


def robot_with_upper_stroke(folder, lo, hi) -> RobotModel:
    """The robot of models/robot.toml, its legs' upper stroke [lo, hi] (a copy of the files)."""
    leg = LEG_TOML.read_text()
    old = "stroke = [0.40, 0.80]"
    assert leg.count(old) == 1, "models/leg.toml: the upper actuator's stroke line changed"
    (folder / "leg.toml").write_text(leg.replace(old, f"stroke = [{float(lo)!r}, {float(hi)!r}]"))
    (folder / "robot.toml").write_text(ROBOT.read_text())
    return RobotModel.from_toml(folder / "robot.toml")


def push_commands(robot):
    cmds = [ForceCommand(float(f)) for f in robot.statics().actuator_forces]
    cmds[0] = ForceCommand(cmds[0].force + PUSH)
    return cmds


def total_energy(robot, z, zd, cmds):
    """kinetic + gravity's potential - sum F l (constant forces): conserved but for impacts."""
    return sum(robot.energy(z, zd, actuator_forces=[c.force for c in cmds]))


@pytest.fixture(scope="module")
def stop_run(tmp_path_factory):
    r = robot_with_upper_stroke(tmp_path_factory.mktemp("stop"), STROKE_MIN, 0.80)
    a = r.assemble()
    cmds = push_commands(r)
    t = np.linspace(0.0, 0.08, 41)
    res = simulate_events(r, 0.08, t, a.z, np.zeros(7), actuators=cmds, stroke_stops=True)
    return r, a, cmds, t, res


def carnot_absolute(robot, q, v_minus, actuator):
    """Carnot's loss at q (39 absolute coordinates) with the joints, both feet (ground rows)
    and the actuator's length held: the rows are the Newton-Euler columns of the 32 joint
    reactions, the 2 x 2 ground forces and the actuator's axial force."""
    A, _, _, gcol = robot._ne_system(q, np.zeros_like(q), None, (0.0, 0.0, 0.0), np.zeros(2))
    cols = np.concatenate([A[:, :gcol + 4], A[:, gcol + 4 + actuator:gcol + 5 + actuator]], axis=1)
    return ca.inelastic_impact(np.diag(robot._Mflat), cols.T, v_minus)


def test_arrival_is_on_the_stroke_end_and_loses_carnots_energy(stop_run):
    r, a, cmds, t, res = stop_run
    assert [(e.kind, e.actuator, e.foot) for e in res.events] == [("stroke_min", 0, -1)]
    ev = res.events[0]
    assert ev.stops == (AT_MIN, 0, 0, 0) and ev.after == ("stuck", "stuck")
    Km = r.kinematics(ev.z, ev.zd_minus)
    Kp = r.kinematics(ev.z, ev.zd_plus)
    print(f"arrival at {ev.t!r} s: L - L_min {Km.l[0] - STROKE_MIN:+.2e} m, rate {Km.ld[0]:.6f} m/s "
          f"-> {Kp.ld[0]:+.1e}; lost {ev.kinetic_lost:.12f} J; stop impulse {ev.stop_impulse[0]:.6f} N s")
    assert 0.03 < ev.t < 0.05 and Km.ld[0] < -0.5           # a clear arrival speed
    assert abs(Km.l[0] - STROKE_MIN) < 1e-12
    assert abs(Kp.ld[0]) < 1e-12
    v_minus = Km.J.reshape(-1, 7) @ ev.zd_minus
    v_plus, _, lost = carnot_absolute(r, Km.P.reshape(-1), v_minus, 0)
    print(f"Carnot's from the absolute coordinates {lost:.12f} J "
          f"({(ev.kinetic_lost - lost) / lost:+.1e} relative)")
    assert abs(ev.kinetic_lost - lost) < 1e-10 * lost
    assert np.max(np.abs(Kp.J.reshape(-1, 7) @ ev.zd_plus - v_plus)) < 1e-10
    # the stop pushes (at its minimum the axial impulse extends); the feet stay on the ground
    assert ev.stop_impulse[0] > 0 and np.all(ev.stop_impulse[1:] == 0)
    assert np.max(np.abs(Kp.footJ.reshape(4, 7) @ ev.zd_plus)) < 1e-12
    # the run's energy: constant before, drops by the loss at the arrival, constant after
    E = np.array([total_energy(r, z, zd, cmds) for z, zd in zip(res.z, res.zd)])
    before, after = t < ev.t, t > ev.t
    assert np.ptp(E[before]) < 1e-9 and np.ptp(E[after]) < 1e-9
    assert abs((E[0] - E[after][0]) - ev.kinetic_lost) < 1e-9 * ev.kinetic_lost + 1e-9


def test_held_stop_keeps_its_length_and_pushes(stop_run):
    r, a, cmds, t, res = stop_run
    held = t > res.events[0].t
    assert np.all(res.stops[held, 0] == AT_MIN) and np.all(res.stops[~held] == 0)
    assert np.max(np.abs(res.lengths[held, 0] - STROKE_MIN)) < 1e-10
    assert np.all(res.stop_force[held, 0] > 0) and np.all(res.stop_force[~held] == 0)
    assert np.all(res.stop_force[:, 1:] == 0)
    # the stop's force is the length row's multiplier (270 N: it makes up most of the 300 N
    # taken off the right upper's statics force)
    print(f"stop force after the arrival {res.stop_force[held, 0][0]:.3f} N")
    assert np.all(res.normal > 0) and np.all(res.states == "stuck")


def test_stop_lets_go_where_its_force_reaches_zero(tmp_path):
    """Started on the stop (the upper minimum at the stand length), 10 N short of the
    statics on the right upper, the robot pitching with the length held: the stop's force
    falls through zero and the length leaves its end."""
    r0 = RobotModel.from_toml(ROBOT)
    L0 = float(r0.stand_lengths()[0])
    r = robot_with_upper_stroke(tmp_path, L0, 0.80)
    a = r.assemble()
    cmds = [ForceCommand(float(f)) for f in r.statics().actuator_forces]
    cmds[0] = ForceCommand(cmds[0].force - 10.0)
    K = r.kinematics(a.z, np.zeros(7))
    rows = np.vstack([K.footJ.reshape(4, 7), K.lz[:1]])
    zd0 = np.linalg.svd(rows)[2][5] * 2.0                   # feet and the right upper at rest
    zd0 *= np.sign(K.lz[1] @ zd0)                            # the right lower lengthening
    assert np.max(np.abs(rows @ zd0)) < 1e-12
    t = np.linspace(0.0, 0.06, 31)
    res = simulate_events(r, 0.06, t, a.z, zd0, actuators=cmds, stroke_stops=True,
                          stops=(AT_MIN, 0, 0, 0))
    kinds = [(e.kind, e.actuator) for e in res.events]
    assert ("stop_release", 0) in kinds and all(k[1] != 0 or k[0] == "stop_release" for k in kinds)
    rel = next(e for e in res.events if e.kind == "stop_release")
    assert res.stop_force[0, 0] > 5.0
    # the force there, in the held mode, is zero to the location's precision
    from legsim_bench.reference.robot_events import _Dynamics, modes_from
    dyn = _Dynamics(r, cmds, r.gravity, (0.0, 0.0, 0.0))
    S = dyn.solve_full(rel.t, np.concatenate([rel.z, rel.zd_minus]),
                       modes_from(("stuck", "stuck"), (0, 0), (AT_MIN, 0, 0, 0)))[6][0]
    weight = float(np.sum(r._m)) * 9.81
    print(f"release at {rel.t!r} s, the stop's force there {S:.2e} N")
    assert abs(S) < 1e-9 * weight and 0.0 < rel.t < 0.06
    after = t > rel.t
    assert np.all(res.stops[after, 0] == 0) and np.all(res.stop_force[after, 0] == 0)
    assert np.all(res.lengths[after, 0] > L0) and np.all(np.diff(res.lengths[after, 0]) > 0)


def test_stops_disabled_or_far_reproduce_the_reference_without_stops(stop_run, robot):
    r, a, cmds, t, res = stop_run
    off = simulate_events(r, 0.08, t, a.z, np.zeros(7), actuators=cmds)
    assert off.events == [] and off.lengths[-1, 0] < STROKE_MIN      # it runs past the end
    # the stuck-feet reference (coordinate partitioning, no contact rows) agrees
    st = r.simulate(0.08, t, actuators=cmds)
    err = np.max(np.abs(st.q - off.q))
    print(f"stops disabled vs RobotModel.simulate: {err:.2e}")
    assert err < 1e-11
    # before the arrival, the run with stops is the run without
    before = t < res.events[0].t
    assert np.max(np.abs(res.q[before] - off.q[before])) < 1e-12
    # the robot's own strokes are far: with or without stops, the same run
    ra = robot.assemble()
    cmds0 = push_commands(robot)
    far = simulate_events(robot, 0.08, t, ra.z, np.zeros(7), actuators=cmds0, stroke_stops=True)
    none = simulate_events(robot, 0.08, t, ra.z, np.zeros(7), actuators=cmds0)
    assert far.events == [] and np.max(np.abs(far.q - none.q)) < 1e-13
    assert np.all(far.stops == 0) and np.all(far.stop_force == 0)


def test_start_outside_the_stroke_is_refused(stop_run):
    r, a, cmds, _, _ = stop_run
    r0_lengths = a.lengths.copy()
    r0_lengths[0] = 0.62                                      # below the raised minimum
    bad = r.assemble(r0_lengths)
    with pytest.raises(ValueError, match="outside its stroke"):
        simulate_events(r, 0.01, [0.0], bad.z, np.zeros(7), actuators=cmds, stroke_stops=True)
    with pytest.raises(ValueError, match="held at its stop"):
        simulate_events(r, 0.01, [0.0], a.z, np.zeros(7), actuators=cmds, stroke_stops=True,
                        stops=(AT_MIN, 0, 0, 0))
