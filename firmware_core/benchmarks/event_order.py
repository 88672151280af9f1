#!/usr/bin/env python3
"""The core's accuracy through contact events: the two-leg robot through a touchdown, a
lift-off, a slip onset and a stroke stop's arrival, and a run without events (the control), with RK4 and
generalized-alpha over h = 2e-3 ... 1.25e-4 s, against the bench's event-locating reference
(legsim_bench.reference.robot_events: each event located on DOP853's dense output, the drop's
touchdown to 1e-13 s of sqrt(2 d / g)).

    LEGSIM_ROOT=$PWD PYTHONPATH=$PWD/python:$PWD/bench python firmware_core/benchmarks/event_order.py
        [--cases touchdown,liftoff,slip,stop,none] [--integrators rk4,galpha] [--steps 2e-3,1e-3,...]

Per case, integrator and h it prints: the error at the case's fixed time after the event
(max over the 39 coordinates, m and rad), the whole run's max error on the 2 ms grid, the
observed order log2(e(2h) / e(h)) (and, after the table, the least-squares order over the
step sizes whose error is above the reference's own tolerance), and the step at whose end the core reports each event
(the core reports no event time: the event lies in the step that ends there, so its delay
is in [0, h)) beside the reference's event time, and the error over the first event's delay
and its square (constant when the error is first or second order in the delay: an event
taken at the step's end). For the touchdown and the stop, the energy the impact
takes at h = 1 ms against the exact one. A Markdown table on stdout; results.md keeps it.

Cases (all the robot of models/robot.toml, its stand assembled on the ground):
- touchdown: the stand lifted 1 cm, the servos holding the stand lengths, both feet free.
  It falls rigidly (the servos exert nothing at their set-points) and lands on both feet at
  t = sqrt(2 d / g); fixed time 0.1 s.
- liftoff: the ground at mu_static = mu_kinetic = 0.6 (the friction force continuous at a
  slip onset), constant actuator forces (the stand's statics), the right thigh started at
  -2.5 rad/s with the feet stuck (a consistent velocity): the robot pitches, the left foot's
  |T|/N grows without bound as N falls, so it slips at 96.32 ms and lifts off 23 us later;
  fixed time 0.12 s.
- slip: the ground at mu_static = mu_kinetic = 0.1, the right upper actuator at 185.55 N
  (the Fig. 7 push), the other three servos at the stand lengths: the left foot starts to
  slide at 13.48 ms (the friction force is continuous there); fixed time 0.04 s.
- stop: the right upper actuator's stroke [0.645, 0.80] m (the leg file's upper stroke
  with its minimum raised from 0.40, in a copy of the model files: both legs'; the stand's
  0.6614 m inside it), constant actuator forces = the stand's statics except the right
  upper's, 300 N less: both feet stay stuck (the robot's ground), the right upper shortens
  and arrives at its minimum at 41.54 ms at -0.807 m/s (an inelastic stop: its length rate
  removed with the stuck feet held, Carnot's loss 4.676 J), then rests on it (the reference:
  robot_events with stroke_stops); fixed time 0.08 s. The energy the stop takes at
  h = 1 ms, two ways: the kinetic energy at the end of the step holding the arrival of a
  twin run without stroke stops (legsim.DISABLE["stroke_limits"]; the same steps until
  then) less the run's (kinetic energy in absolute coordinates does not depend on q: for a
  stop taken at the step's end, what its impact removes; for a located one it also holds the
  rest of the step's motion after the arrival, so it is not the impact's alone), and the
  balance E(before) - E(after) of that step, E = kinetic + gravity's potential - sum F l
  (constant forces: E is conserved but for the stop).
- none: the same push on the robot's own ground (0.6 / 0.5): both feet stay stuck, no
  event; fixed time 0.1 s.
"""
from __future__ import annotations

import argparse
import atexit
import copy
import math
import os
import re
import shutil
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path[:0] = [str(ROOT / "python"), str(ROOT / "bench")]

import legsim  # noqa: E402
from legsim_bench.reference import ForceCommand, LengthCommand  # noqa: E402
from legsim_bench.reference.model_file import read_model_file  # noqa: E402
from legsim_bench.reference.robot import RobotModel  # noqa: E402
from legsim_bench.reference.robot_events import simulate_events  # noqa: E402

STEPS = (2e-3, 1e-3, 5e-4, 2.5e-4, 1.25e-4)
GRID = 2e-3                      # the whole-run error's sample grid (s): on every h's grid
ROBOT = ROOT / "models" / "robot.toml"
DROP_M = 0.01
G = 9.81
STOP_STROKE = (0.645, 0.80)      # m: the upper actuators' stroke in the stop case
STOP_PUSH_N = -300.0             # N: the right upper's force less the stand's statics
CONTACT_KINDS = ("touchdown", "liftoff", "stick_to_slip", "slip_to_stick")
STROKE_KINDS = ("stroke_min", "stroke_max")


def robot_with_upper_stroke(stroke) -> Path:
    """A copy of models/robot.toml and its leg file in a temporary folder, the leg file's
    upper actuator's stroke replaced: both the reference and the core read it."""
    leg = (ROBOT.parent / "leg.toml").read_text()
    m = re.search(r'\[\[actuator\]\]\s*\nname = "upper"[^\[]*?\nstroke = \[[^\]]*\]', leg)
    if not m:
        raise SystemExit("models/leg.toml: no upper actuator's stroke line to replace")
    block = re.sub(r"stroke = \[[^\]]*\]", f"stroke = [{stroke[0]!r}, {stroke[1]!r}]", m.group(0))
    d = Path(tempfile.mkdtemp(prefix="event_order_stop_"))
    atexit.register(shutil.rmtree, d, True)
    (d / "leg.toml").write_text(leg[:m.start()] + block + leg[m.end():])
    (d / "robot.toml").write_text(ROBOT.read_text())
    return d / "robot.toml"


def core_stop_time(s, a):
    """The core's time of actuator a's last arrival on a stroke stop (legsim_stroke_event_time)."""
    return s.stroke_event_time(a)


class Case:
    """A scene set up alike in the reference and in the core."""

    def __init__(self, name, t_end, ground=None, text="", robot=ROBOT, stroke_stops=False):
        self.name, self.t_end, self.text = name, t_end, text
        self.robot, self.stroke_stops = Path(robot), stroke_stops
        data = read_model_file(self.robot)
        if ground:
            data = copy.deepcopy(data)
            data["ground"].update(ground)
        self.ground = ground or {}
        self.ref = RobotModel(data, self.robot.parent)
        self.asm = self.ref.assemble()
        self.states = ("stuck", "stuck")
        self.z0, self.zd0 = self.asm.z.copy(), np.zeros(7)
        self.commands = [LengthCommand(float(x)) for x in self.asm.lengths]

    def reference(self):
        t = np.arange(0, round(self.t_end / GRID) + 1) * GRID
        return simulate_events(self.ref, self.t_end, t, self.z0, self.zd0, self.states,
                               actuators=self.commands, stroke_stops=self.stroke_stops)

    def sim(self, integrator, h, disable=0):
        model = legsim.Model.from_toml(str(self.robot))
        for k, v in self.ground.items():
            setattr(model.desc.ground, k, v)
        s = legsim.Sim(model, integrator=integrator, step=h, disable=disable)
        s.assemble_on_ground()
        # the reference's start exactly (the core's assembly is within its Newton tolerance)
        K = self.ref.kinematics(self.z0, self.zd0)
        s.set_state(K.P.reshape(-1), K.J.reshape(-1, 7) @ self.zd0)
        for k, st in enumerate(self.states):
            s.set_contact(k, st)
        for a, c in enumerate(self.commands):
            if isinstance(c, ForceCommand):
                s.command_force(a, c.force)
            else:
                s.command_length(a, c.length)
        s.clear_events()
        return s


def cases():
    td = Case("touchdown", 0.1, text="1 cm level drop, servos")
    td.z0[1] += DROP_M
    td.states = ("free", "free")

    lo = Case("liftoff", 0.12, ground={"mu_static": 0.6, "mu_kinetic": 0.6},
              text="pitching on stuck feet, constant forces")
    lo.commands = [ForceCommand(float(f)) for f in lo.ref.statics().actuator_forces]
    T, _ = lo.ref._partition(lo.ref.kinematics(lo.z0, np.zeros(7)))
    lo.zd0 = T @ np.array([0.0, -2.5, 0.0])

    sl = Case("slip", 0.04, ground={"mu_static": 0.1, "mu_kinetic": 0.1},
              text="push on mu = 0.1, left foot slides")
    sl.commands[0] = ForceCommand(185.55)

    st = Case("stop", 0.08, text="right upper onto its raised stroke minimum, feet stuck",
              robot=robot_with_upper_stroke(STOP_STROKE), stroke_stops=True)
    st.commands = [ForceCommand(float(f)) for f in st.ref.statics().actuator_forces]
    st.commands[0] = ForceCommand(st.commands[0].force + STOP_PUSH_N)

    no = Case("none", 0.1, text="push on mu 0.6/0.5, feet stuck (control)")
    no.commands[0] = ForceCommand(185.55)
    return {c.name: c for c in (td, lo, sl, st, no)}


def q_error(qa, qb):
    """max |difference| over the 39 coordinates (m, rad; angles wrapped)."""
    d = (np.asarray(qa) - np.asarray(qb)).reshape(-1, 3)
    d[:, 2] = (d[:, 2] + math.pi) % (2 * math.pi) - math.pi
    return float(np.max(np.abs(d)))


def kinetic(s, qd):
    v = np.asarray(qd).reshape(-1, 3)
    return 0.5 * float(np.sum(s.model.masses * (v[:, 0] ** 2 + v[:, 1] ** 2))
                       + np.sum(s.model.inertias * v[:, 2] ** 2))


def potential(s, q):
    return float(np.sum(s.model.masses * G * np.asarray(q).reshape(-1, 3)[:, 1]))


def force_potential(s, case):
    """-sum F l of the constant (force-mode) actuator commands (J)."""
    forces = [c.force if isinstance(c, ForceCommand) else 0.0 for c in case.commands]
    return -float(np.dot(forces, s.actuator_lengths()[0]))


def run_core(case, integrator, h, ref):
    s = case.sim(integrator, h)
    n = round(case.t_end / h)
    every = round(GRID / h)
    errs, events = [], []
    lost = None
    e0 = kinetic(s, s.qd) + potential(s, s.q)
    e_prev = e0 + force_potential(s, case)
    # the stop case at h = 1 ms: a twin without stroke stops, in step with it until the arrival
    twin = (case.sim(integrator, h, legsim.DISABLE["stroke_limits"])
            if case.stroke_stops and h == 1e-3 else None)
    for k in range(1, n + 1):
        qd_before = s.qd
        s.step(1)
        if twin is not None:
            twin.step(1)
        ev = [e for e in s.events() if e in CONTACT_KINDS + STROKE_KINDS]
        if ev:
            # the core's event time (legsim_contact_event_time; a stop's, if the API has it):
            # the earliest of this step's
            times = [s.contact_event_time(c) for c in range(2)]
            if any(e in STROKE_KINDS for e in ev):
                mask = s.stroke_event_mask()
                times += [core_stop_time(s, a) for a in range(s.n_actuators) if mask >> a & 1]
            times = [t for t in times if t is not None and (k - 1) * h - 1e-12 <= t <= k * h + 1e-12]
            events.append((min(times) if times else k * h, ev))
            if lost is None and any(e in STROKE_KINDS for e in ev):
                # constant forces: E = kinetic + gravity's potential - sum F l is conserved
                # but for the stop, which takes E(before) - E(after) of this step
                e_now = kinetic(s, s.qd) + potential(s, s.q) + force_potential(s, case)
                lost = {"stop": e_prev - e_now,
                        "twin": None if twin is None else kinetic(twin, twin.qd) - kinetic(s, s.qd)}
                twin = None
            if "touchdown" in ev and lost is None:
                # the fall is rigid (every body at one velocity, no spin), so the feet
                # approach at g t_e (t_e: the core's touchdown time) and stop: by Carnot's
                # theorem the impulse takes 1/2 sum_k P_n,k g t_e (the impulses the core
                # reports, legsim_contact.impulse_ns)
                v = qd_before.reshape(-1, 3)
                rigid = np.max(np.abs(v - v[0])) < 1e-9 and np.max(np.abs(v[:, 2])) < 1e-9
                t_e = events[-1][0]
                pn = sum(float(c["impulse"][0]) for c in s.contacts())
                lost = {"rigid": rigid, "impulse": 0.5 * pn * G * t_e,
                        "balance": e0 - kinetic(s, s.qd) - potential(s, s.q)}
        s.clear_events()
        e_prev = kinetic(s, s.qd) + potential(s, s.q) + force_potential(s, case)
        if k % every == 0:
            errs.append(q_error(s.q, ref.q[k // every]))
    return errs[-1], max(errs), events, lost


FIT_FLOOR = 1e-13  # m, rad: the reference's atol


def order_fits(rows):
    """[(case, integrator, points, least-squares order, smallest pairwise order)] over the
    rows' step sizes whose error at the fixed time is at least FIT_FLOOR (at least 3 of them)."""
    out = []
    for key in dict.fromkeys((r[0], r[1]) for r in rows):
        pts = [(math.log(r[2]), math.log(r[3])) for r in rows if (r[0], r[1]) == key and r[3] >= FIT_FLOOR]
        if len(pts) < 3:
            continue
        mx = sum(x for x, _ in pts) / len(pts)
        my = sum(y for _, y in pts) / len(pts)
        slope = sum((x - mx) * (y - my) for x, y in pts) / sum((x - mx) ** 2 for x, _ in pts)
        worst = min((b[1] - a[1]) / (b[0] - a[0]) for a, b in zip(pts, pts[1:]))
        out.append((key[0], key[1], len(pts), slope, worst))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cases", default="touchdown,liftoff,slip,stop,none")
    ap.add_argument("--integrators", default="rk4,galpha")
    ap.add_argument("--steps", default=",".join(f"{h:g}" for h in STEPS),
                    help="step sizes (s), largest first")
    a = ap.parse_args()
    all_cases = cases()
    rows, energy, stop_energy, ref_table = [], [], [], []
    for name in a.cases.split(","):
        case = all_cases[name]
        ref = case.reference()
        ref_events = [(e.t, e.kind, e.foot if e.foot >= 0 else e.actuator) for e in ref.events]
        ref_table.append((name, ref_events))
        print(f"{name}: reference events {ref_events}", file=sys.stderr)
        for integ in a.integrators.split(","):
            prev = None
            for h in (float(x) for x in a.steps.split(",")):
                e_end, e_max, events, lost = run_core(case, integ, h, ref)
                order = "" if prev is None else f"{math.log2(prev / e_end):.2f}"
                prev = e_end
                first = events[0] if events else None
                dt = None if not (first and ref.events) else first[0] - ref.events[0].t
                delay = "" if dt is None else f"{dt:.3e} ({dt / h:+.1e} h)"
                ratio = "" if not dt else f"{e_end / dt:.3g} | {e_end / dt ** 2:.3g}"
                ratio = ratio or " | "
                core_ev = "; ".join(f"{t * 1e3:.7f} ms {'+'.join(ev)}" for t, ev in events[:3]) or "none"
                if len(events) > 3:
                    core_ev += f"; ... ({len(events)} steps with events)"
                rows.append((name, integ, h, e_end, e_max, order, core_ev, delay, ratio))
                print(f"  {integ} h={h:g}: err {e_end:.3e} max {e_max:.3e} order {order} events {core_ev}",
                      file=sys.stderr)
                if name == "touchdown" and h == 1e-3 and lost:
                    energy.append((integ, lost, ref.events[0].kinetic_lost))
                if name == "stop" and h == 1e-3 and lost:
                    stop_energy.append((integ, lost, ref.events[0].kinetic_lost))
    cmd = "firmware_core/benchmarks/event_order.py" + ("" if len(sys.argv) < 2 else " " + " ".join(sys.argv[1:]))
    print(f"`{cmd}` (reference: RobotModel + robot_events, DOP853 rtol 1e-12, atol 1e-13)\n")
    print("Reference events (s):\n")
    for name, evs in ref_table:
        print(f"- {name}: " + (", ".join(f"{kind} {'actuator' if kind in STROKE_KINDS + ('stop_release',) else 'foot'} {k} at {t:.12f}"
                                         for t, kind, k in evs) or "none"))
    print()
    print("| case | integrator | h (s) | error at the fixed time | max error on the 2 ms grid | "
          "order (fixed time) | steps at whose end the core reports an event | first event's delay (s) | "
          "error / delay | error / delay^2 |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for name, integ, h, e_end, e_max, order, core_ev, delay, ratio in rows:
        print(f"| {name} | {integ} | {h:g} | {e_end:.3e} | {e_max:.3e} | {order} | {core_ev} | {delay} | {ratio} |")
    fits = order_fits(rows)
    if fits:
        print(f"\nOrder over the range: the least-squares slope of log(error at the fixed time) on log(h), "
              f"over the step sizes whose error is at least {FIT_FLOOR:g} (the reference's own absolute "
              "tolerance: below it the difference is the reference's):\n")
        print("| case | integrator | step sizes fitted | order (fit) | smallest pairwise order |")
        print("|---|---|---|---|---|")
        for name, integ, n, slope, worst in fits:
            print(f"| {name} | {integ} | {n} | {slope:.2f} | {worst:.2f} |")
    if energy:
        print("\nTouchdown energy, 1 cm level drop, h = 1 ms:\n")
        print("| integrator | kinetic energy the impulse takes (J) | energy lost, E(0) - E(after) (J) | "
              "exact (J) | impulse's error | balance's error |")
        print("|---|---|---|---|---|---|")
        for integ, lost, exact in energy:
            if not lost["rigid"]:
                print(f"| {integ} | (the fall was not rigid) | {lost['balance']:.10f} | {exact:.10f} | | "
                      f"{(lost['balance'] - exact) / exact:+.3e} |")
                continue
            print(f"| {integ} | {lost['impulse']:.10f} | {lost['balance']:.10f} | {exact:.10f} | "
                  f"{(lost['impulse'] - exact) / exact:+.3e} | {(lost['balance'] - exact) / exact:+.3e} |")
    if stop_energy:
        print("\nStop energy, the right upper onto its stroke minimum, h = 1 ms (E = kinetic + gravity's "
              "potential - sum F l; constant forces):\n")
        print("| integrator | kinetic energy the stop takes at the step's end (J) | "
              "E(before) - E(after) of the step holding the arrival (J) | exact (J) | "
              "at the step's end: error | E balance: error |")
        print("|---|---|---|---|---|---|")
        for integ, lost, exact in stop_energy:
            tw = lost["twin"]
            print(f"| {integ} | {tw:.10f} | {lost['stop']:.10f} | {exact:.10f} | "
                  f"{(tw - exact) / exact:+.3e} | {(lost['stop'] - exact) / exact:+.3e} |")
    return 0


if __name__ == "__main__":
    os.environ.setdefault("LEGSIM_ROOT", str(ROOT))
    sys.exit(main())
