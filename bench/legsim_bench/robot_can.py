"""The two-leg robot driven over CAN (``hil_sim --robot``), checked against the bench's own
robot model (:class:`legsim_bench.reference.robot.RobotModel`).

    from legsim_bench.can_link import HilLink
    from legsim_bench.robot_can import run_scene_a

    with HilLink() as hil:
        res = run_scene_a(hil)
        print(res.report())
        assert res.ok, res.failures

Scene A is the paper's Fig. 7 as docs/design/robot-on-ground.md section 7 sets it: from the
servo stand equilibrium at rest, the right upper actuator (leg 0's upper) switches to force
mode at its hold force + 50 N for 0.1 s, the other three stay on their servos; RK4, h = 1 ms.
It is built here in code (the robot's scene files come separately).

How the run is made to start where the reference starts: the CAN frames carry float32, so
every number the bench sends is rounded to float32 first and the reference gets the same
rounded number. The servo stand equilibrium's actuator lengths (from
``RobotModel.equilibrium``) are sent in the RESET (all four, Ctrl_UseLengths), so hil_sim
assembles the robot on the ground at them, and the reference starts from its own assembly
at the same lengths; the servos' set points are the stand lengths and the push is
float32(hold + 50 N), in both.

Tolerances follow from the signal types: a float32 signal is the solver's double rounded
to nearest, within 2^-24 |x| of it; the time is float64, an exact copy. On top of that comes
the core's own agreement with the reference for RK4 at h = 1 ms (measured in
tests/python/test_robot.py: box 1e-10 m, angles 2e-11 rad, ground forces 1.5e-7 N), bounded
here by SOLVER_POS and SOLVER_FORCE with a margin of about ten.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .can_link import ActMode, ContactState, HilLink, State

ROBOT_TOML = Path(__file__).resolve().parents[2] / "models" / "robot.toml"

F32_REL = 2.0 ** -24   # float32 round to nearest: |fl(x) - x| <= 2^-24 |x|
SOLVER_POS = 1e-9      # m, rad: RK4 (h = 1 ms) against the reference's DOP853, with margin
SOLVER_FORCE = 1e-6    # N: ground forces, the same


def f32(x: float) -> float:
    """x as the CAN frame carries it (float32), back in a double."""
    return float(np.float32(x))


def tolerance(expected, solver: float) -> np.ndarray:
    """|got - expected| allowed for a float32 signal: its rounding plus the solver's bound."""
    return np.abs(np.asarray(expected, float)) * F32_REL + solver


@dataclass
class SceneAReference:
    """What the run starts from and what it must reach (the reference's numbers)."""
    lengths: np.ndarray       # (4,) float32-exact start lengths (the servo stand equilibrium)
    servo: np.ndarray         # (4,) float32-exact servo set points (the stand lengths)
    push: float               # N, float32-exact: leg 0's upper, hold force + 50 N
    hold: float               # N, the hold force at the start
    t: float                  # s
    q: np.ndarray             # (39,) at t
    normal: np.ndarray        # (2,) N at t
    tangential: np.ndarray    # (2,) N at t
    q0: np.ndarray            # (39,) at 0
    feet: np.ndarray          # (2, 2) m, where the feet are stuck


def scene_a_reference(duration: float = 0.1, model=None, rtol: float = 1e-9,
                      atol: float = 1e-10) -> SceneAReference:
    """The reference's Scene A, with every number the bench sends rounded as CAN carries it.
    rtol/atol of the reference's DOP853: 1e-9/1e-10 is within 3e-13 m, rad and 5e-9 N of its
    1e-11/1e-12 default here (measured), far below float32, at 60 % of the cost."""
    from .reference import ForceCommand, LengthCommand
    from .reference.robot import RobotModel

    ref = model if model is not None else RobotModel.from_toml(ROBOT_TOML)
    servo = np.array([f32(x) for x in ref.stand_lengths()])
    servo_cmds = [LengthCommand(float(x)) for x in servo]
    z_eq = ref.equilibrium(servo_cmds)
    lengths = np.array([f32(x) for x in ref.lengths(z_eq)])
    start = ref.assemble(lengths, feet_mid=0.0)   # where hil_sim's RESET puts the robot
    at0 = ref.simulate(0.0, t_eval=[0.0], actuators=servo_cmds, start=start)
    hold = float(at0.actuator_forces[0, 0])
    push = f32(hold + 50.0)
    r = ref.simulate(duration, t_eval=[0.0, duration],
                     actuators=[ForceCommand(push)] + servo_cmds[1:], start=start, rtol=rtol,
                     atol=atol)
    return SceneAReference(lengths=lengths, servo=servo, push=push, hold=hold, t=float(r.t[-1]),
                           q=r.q[-1].copy(), normal=r.normal[-1].copy(),
                           tangential=r.tangential[-1].copy(), q0=r.q[0].copy(),
                           feet=np.asarray(r.feet, float).copy())


@dataclass
class RobotCanResult:
    reference: SceneAReference
    start: State                       # the RESET's sample
    end: State                         # after the push
    errors: dict[str, float] = field(default_factory=dict)      # max |got - expected|
    allowed: dict[str, float] = field(default_factory=dict)     # the matching max tolerance
    failures: list[str] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return not self.failures

    def report(self) -> str:
        e = self.end
        lines = [f"Scene A over CAN: t = {e.t:.6f} s, {e.step_count} steps; box moved "
                 f"({(e.q[0] - self.start.q[0]) * 1e3:+.3f} mm, {(e.q[1] - self.start.q[1]) * 1e3:+.3f} mm, "
                 f"{e.q[2] - self.start.q[2]:+.5f} rad); right phi3 {e.q[3 * 3 + 2]:.5f} rad, "
                 f"phi6 {e.q[3 * 6 + 2]:.5f} rad"]
        for k, c in enumerate(e.contacts):
            lines.append(f"  foot {k}: {c.state.name}, N = {c.normal:.4f} N, T = {c.tangential:+.4f} N")
        for name, err in self.errors.items():
            lines.append(f"  {name}: max error {err:.3g} (allowed {self.allowed[name]:.3g})")
        lines += [f"  FAILED: {f}" for f in self.failures]
        return "\n".join(lines)


def _compare(res: RobotCanResult, name: str, got, expected, solver: float) -> None:
    got, expected = np.asarray(got, float), np.asarray(expected, float)
    err = np.abs(got - expected)
    tol = tolerance(expected, solver)
    res.errors[name] = float(err.max())
    res.allowed[name] = float(tol.max())
    bad = np.nonzero(err > tol)[0]
    if bad.size:
        i = int(bad[0])
        res.failures.append(f"{name}[{i}] = {got.flat[i]!r}, reference {expected.flat[i]!r} "
                            f"(error {err.flat[i]:.3g} > {tol.flat[i]:.3g})")


def run_scene_a(link: HilLink, duration: float = 0.1, step_s: float = 1e-3,
                reference: SceneAReference | None = None) -> RobotCanResult:
    """Drives Scene A on the robot behind `link` (lockstep, RK4) and checks the box pose, the
    whole q, the contact states and the ground forces against the reference."""
    ref = reference if reference is not None else scene_a_reference(duration)
    n = round(duration / step_s)
    start = link.reset(integrator="rk4", step_s=step_s, lengths=ref.lengths, hold_length=False,
                       cmd_timeout_ms=0)
    if start.legs != 2:
        raise ValueError("the hil_sim on this bus runs the one leg, not the robot (hil_sim --robot)")
    # leg 0: upper pushes, lower on its servo; leg 1: both on their servos (all before a step)
    link.command((ActMode.FORCE, ref.push), (ActMode.LENGTH, ref.servo[1]), leg=0)
    link.command((ActMode.LENGTH, ref.servo[2]), (ActMode.LENGTH, ref.servo[3]), leg=1)
    end = link.step(n)
    res = RobotCanResult(reference=ref, start=start, end=end)

    _compare(res, "start q (m, rad)", start.q, ref.q0, SOLVER_POS)
    _compare(res, "box q (m, rad)", end.q[:3], ref.q[:3], SOLVER_POS)
    _compare(res, "q (m, rad)", end.q, ref.q, SOLVER_POS)
    _compare(res, "ground N (N)", [c.normal for c in end.contacts], ref.normal, SOLVER_FORCE)
    _compare(res, "ground T (N)", [c.tangential for c in end.contacts], ref.tangential, SOLVER_FORCE)
    # the feet stay where they were stuck
    _compare(res, "feet (m)", [[c.x, c.y] for c in end.contacts], ref.feet, SOLVER_POS)
    states = [c.state for c in end.contacts]
    if states != [ContactState.STUCK, ContactState.STUCK]:
        res.failures.append(f"contact states {[s.name for s in states]}, expected both STUCK")
    if abs(end.t - ref.t) > 1e-12 or end.step_count != n:
        res.failures.append(f"t = {end.t!r} after {end.step_count} steps, expected {ref.t!r}, {n}")
    if end.faults:
        res.failures.append("faults: " + "; ".join(str(f) for f in end.faults))
    return res


__all__ = ["run_scene_a", "scene_a_reference", "SceneAReference", "RobotCanResult", "tolerance",
           "F32_REL", "SOLVER_POS", "SOLVER_FORCE", "ROBOT_TOML"]
