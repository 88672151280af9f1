"""The two-leg robot's dynamics scenes over CAN (``hil_sim --robot``, or ``--model ROBOT.toml``),
checked against the bench's own robot model (:class:`legsim_bench.reference.robot.RobotModel`).

``legsim-bench run robot_fig7`` records the scene on hil_sim (legsim_bench.hil.runner.record: each
leg's ACT_CMD, LOAD_CMD, the RESET's lengths, contact law and free feet) and
:func:`evaluate_robot_can` checks the recording with the checks the scene's ``[checks]`` names,
as legsim_cli's run is checked (legsim_bench.verdict.analyses.evaluate_robot), with two differences
that follow from the bus:

* The reference replays what was sent, not the scene's doubles: the RESET's lengths and every
  setpoint as the float32 the DBC carries, each held from the exchange that sent it to the next
  (a left-continuous staircase: a sample at an exchange reflects the step that ended there).
  A sinusoid is therefore a staircase over CAN (on the exchange grid, record_every steps).
* Every received number is float32: within 2^-24 |x| of the core's double (round to nearest).
  The tolerance of a check is the scene's (the solver's agreement with the reference, as in
  legsim_cli) plus 2^-24 times the largest |value| of its kind (positions, angles, forces); a
  displacement or drift, the difference of two rounded values, gets twice that.

Stroke stops' arrivals come per actuator (St_StrokeMask) with the kinds of the sample's arrivals
(St_Status STROKE_MIN, STROKE_MAX): each must be in the sample whose step holds the reference's
arrival of that actuator, as legsim_cli's (which names the kinds alone).

Contact events come per foot (Ct_Events: the core's legsim_contact_event_mask of that foot over
every step since the previous sample), so the contact-state sequence is checked foot by foot:
every change of a foot's state between two samples comes with that foot's event, and a foot
whose state is the same but that raised events must have gone there and back (stick to slip
and slip to stick, lift-off and touchdown) or be inconsistent.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..reference import ForceCommand, LengthCommand, Staircase
from ..reference.robot import RobotModel
from . import analyses as an
from .result import CheckResult, Evaluation

F32_REL = 2.0 ** -24   # float32 round to nearest: |fl(x) - x| <= 2^-24 |x|
STROKE_STATUS = {"stroke_min": 1 << 3, "stroke_max": 1 << 4}   # St_Status bits (can/README.md)

__all__ = ["evaluate_robot_can", "robot_can_arrays", "can_reference", "float32_allowance", "F32_REL",
           "CHANGE_EVENTS"]

# a foot's state change and the event that must come with it (docs/design/robot-on-ground.md 8)
CHANGE_EVENTS = {("stuck", "sliding"): "stick_to_slip", ("sliding", "stuck"): "slip_to_stick",
                 ("stuck", "free"): "liftoff", ("sliding", "free"): "liftoff",
                 ("free", "stuck"): "touchdown", ("free", "sliding"): "touchdown"}
# events of a foot whose state is the same at both samples: it went there and back
ROUND_TRIPS = ({"stick_to_slip", "slip_to_stick"}, {"liftoff", "touchdown"})


def float32_allowance(values) -> float:
    """What float32 rounding adds at most to an error in these values: 2^-24 max |x|."""
    v = np.abs(np.asarray(values, float))
    v = v[np.isfinite(v)]
    return float(v.max()) * F32_REL if v.size else 0.0


def robot_can_arrays(rec: dict) -> dict:
    """The recording's robot samples as arrays in the core's order (robot_arrays' layout):
    t, step, q (N, 39), forces, lengths (N, 4), reactions (N, 16, 3), normal, tangential (N, 2),
    state (N, 2) names, feet (N, 2, 2), impulse (N, 2, 2) the last impact's (normal, tangential),
    residual, foot_events (N, 2) sets of names, events
    (N tuples: both feet's, as legsim_cli's one list per sample), the stroke stops' arrivals
    since the previous sample: stroke_kinds (N sets of stroke_min, stroke_max) and
    stroke_actuators (N sets of actuator indices)."""
    S = rec["samples"]
    n = len(S)
    C = [s.get("contacts") or [] for s in S]
    nc = max((len(c) for c in C), default=0)
    d = {"t": np.array([s["t"] for s in S], float), "step": np.array([s["step"] for s in S], int),
         "q": np.array([s["q"] for s in S], float).reshape(n, -1),
         "forces": np.array([s["forces"] for s in S], float).reshape(n, -1),
         "lengths": np.array([s["lengths"] for s in S], float).reshape(n, -1),
         "reactions": np.array([s["reactions"] for s in S], float).reshape(n, -1, 3),
         "residual": np.array([s["residual"] for s in S], float)}
    d["normal"] = np.array([[c[k]["normal"] for k in range(nc)] for c in C], float).reshape(n, nc)
    d["tangential"] = np.array([[c[k]["tangential"] for k in range(nc)] for c in C], float).reshape(n, nc)
    d["feet"] = np.array([[[c[k]["x"], c[k]["y"]] for k in range(nc)] for c in C], float).reshape(n, nc, 2)
    d["impulse"] = np.array([[[c[k]["impulse_n"], c[k]["impulse_t"]] for k in range(nc)] for c in C],
                            float).reshape(n, nc, 2)
    d["state"] = np.array([[c[k]["state"] for k in range(nc)] for c in C]).reshape(n, nc)
    d["foot_events"] = [[frozenset(c[k]["events"]) for k in range(nc)] for c in C]
    d["events"] = [tuple(sorted(set().union(*fe))) if fe else () for fe in d["foot_events"]]
    # the stops' arrivals: St_Status' STROKE_MIN / STROKE_MAX are the robot's (both legs send the
    # same bits), St_StrokeMask each leg's actuators (the bench puts leg k's at bits 2k, 2k + 1)
    d["stroke_kinds"] = [frozenset(k for k, bit in STROKE_STATUS.items() if s["status"] & bit) for s in S]
    d["stroke_actuators"] = [frozenset(a for a in range(d["lengths"].shape[1]) if s["stroke_mask"] >> a & 1)
                             for s in S]
    return d


def can_reference(scene, rec: dict, times, root: Path | None = None):
    """(RobotModel, RobotResult) of what hil_sim was sent, at `times`: the stand assembled at the
    RESET's lengths (the scene's, float64 on the bus: exact; else the pose's), both feet stuck, each commanded
    actuator on the staircase of its sent setpoints, the others as `init` says, the box load
    as sent (leg 0's LOAD_CMD 2 and 3). RobotModel has
    both feet stuck: a scene with a free foot is refused (ValueError)."""
    if any(v != "stuck" for v in scene.contacts.values()):
        raise ValueError("RobotModel has both feet stuck; this scene frees a foot")
    model = an.robot_model(scene)
    lengths = None if scene.lengths is None else np.asarray(scene.lengths, float)   # Ctrl_Length_*: float64
    start = model.assemble(lengths)
    names = rec.get("actuators") or list(scene.actuator_names)
    h = scene.step_s
    cmds = []
    for a, name in enumerate(names):
        sent = [(c["step"] * h, c[name]) for c in rec["commands"] if name in c]
        if not sent:
            cmds.append(LengthCommand(float(start.lengths[a])) if scene.init == "hold_length"
                        else ForceCommand(0.0))
            continue
        modes = {m for _, (m, _v) in sent}
        if len(modes) != 1:
            raise ValueError(f"{name}: both force and length commands; the reference holds one mode")
        # a setpoint sent again unchanged is no breakpoint (the integrator restarts at each)
        kept = [x for i, x in enumerate(sent) if i == 0 or x[1][1] != sent[i - 1][1][1]]
        stair = Staircase([t for t, _ in kept], [v for _, (_m, v) in kept])
        cmds.append(ForceCommand(stair) if modes == {"force"} else LengthCommand(stair))
    t = np.round(np.asarray(times, float) / h) * h
    box = {x["name"]: x["value"] for x in rec.get("loads", []) if x.get("box")}   # float32, as sent
    box_load = (*box["box.load"], box["box.moment"][0]) if box else (0.0, 0.0, 0.0)
    r = model.simulate(float(t[-1]), t_eval=t, actuators=cmds, start=start,
                       gravity="gravity" not in scene.disable, box_load=box_load)
    return model, r


def _sequence_check(ev, d: dict, feet) -> list[str]:
    """Each foot's state sequence against its own events over CAN (Ct_Events)."""
    bad, seq = [], []
    for k, f in enumerate(feet):
        st = d["state"][:, k]
        for i in range(1, len(st)):
            got = d["foot_events"][i][k] - {"contact_inconsistent", "contact_ambiguous"}
            if st[i] != st[i - 1]:
                want = CHANGE_EVENTS.get((str(st[i - 1]), str(st[i])))
                seq.append(f"{f} {st[i - 1]}->{st[i]} at {d['t'][i]:g} s ({', '.join(sorted(got))})")
                if want is None or want not in got:
                    bad.append(f"{f} {st[i - 1]}->{st[i]} at t = {d['t'][i]:g} s without {want} "
                               f"(its events: {', '.join(sorted(got)) or 'none'})")
            elif got and not any(rt <= got for rt in ROUND_TRIPS) \
                    and "contact_inconsistent" not in d["foot_events"][i][k]:
                bad.append(f"{f} stays {st[i]} at t = {d['t'][i]:g} s but raised {', '.join(sorted(got))}")
    ev.results.append(CheckResult("contact-state sequence against each foot's events over CAN (Ct_Events)",
                                  not bad, float(len(bad)), None, "changes", "",
                                  "; ".join(bad or seq) or "no change, no event"))
    return seq


def _switch_check(ev, scene, rec: dict, d: dict, feet):
    """A command switched on an event: its first setpoint `after` goes in the exchange right
    after the sample in which its foot raised the event (Ct_Events), never before."""
    for c in scene.commands:
        if c is None or c.schedule.kind != "switch":
            continue
        s = c.schedule
        k = feet.index(s.contact)
        hit = [int(d["step"][i]) for i in range(len(d["t"])) if s.event in d["foot_events"][i][k]]
        sent = [x["step"] for x in rec["commands"] if c.name in x and x[c.name][1] == np.float32(s.after)]
        want = hit[0] if hit else None
        ok = (sent[0] if sent else None) == want
        ev.results.append(CheckResult(f"{c.name} switched at {s.contact}'s {s.event}", ok, None, None, "", "",
                                      f"event in the sample at step {want}, 'after' sent from step "
                                      f"{sent[0] if sent else None}"))


def evaluate_robot_can(rec: dict, scene, root: Path | None = None):
    """The checks of a robot scene run on hil_sim over CAN (an Evaluation)."""

    ch = scene.checks
    results: list = []
    ev = Evaluation(scene, rec, results)
    S = rec["samples"]
    expected = len(scene.boundaries()) + 1
    problems = [e["error"] for e in rec["errors"]]
    if not rec.get("complete"):
        problems.append("run not complete")
    if len(S) != expected:
        problems.append(f"{len(S)} samples, expected {expected}")
    halted = [s for s in S if s["state"] == "HALTED" or s["legsim_status"] != 0]
    if halted:
        problems.append(f"HALTED / legsim_status {halted[0]['legsim_status']} at t={halted[0]['t']:.4f}")
    faults = [f for s in S for f in s["faults"]] + rec.get("late_faults", [])
    if faults:
        problems.append(f"{len(faults)} FAULT(s): {faults[0]['code']}")
    if S and any(s.get("legs") != 2 for s in S):
        problems.append("a sample that is not the robot's (hil_sim --robot)")
    results.append(CheckResult("run: hil_sim --robot over CAN, all exchanges answered", not problems,
                               float(len(S)), float(expected), "samples",
                               f"to t={S[-1]['t']:.4f}s" if S else "", "; ".join(problems) or
                               f"steps 0..{S[-1]['step']}, {rec.get('wall_time_s', 0):.1f} s wall"))
    if problems and (not S or halted or len(S) != expected):
        return ev
    d = robot_can_arrays(rec)
    t = d["t"]
    grid = float(np.max(np.abs(t - d["step"] * scene.step_s)))
    if grid > 1e-9:
        results.append(CheckResult("St_Time on the step grid", False, grid, 1e-9, "s"))
    feet = list(scene.model_info.contacts)
    bodies = ["box"] + [f"body{i}" for i in range(1, d["q"].shape[1] // 3)]
    acts = list(scene.actuator_names)
    xy = np.delete(d["q"], np.s_[2::3], axis=1)
    allow = {"position_m": float32_allowance(xy), "angle_rad": float32_allowance(d["q"][:, 2::3]),
             "actuator_force_n": float32_allowance(d["forces"]),
             "ground_force_n": float32_allowance(np.concatenate([d["normal"], d["tangential"]], axis=1)),
             "reaction_n": float32_allowance(d["reactions"][..., 0:2]),
             "stays_put_m": 2 * float32_allowance(xy), "residual": float32_allowance(d["residual"]),
             "in_stroke_m": float32_allowance(d["lengths"])}
    where_t = lambda r: f"t={t[r]:.4f}s"  # noqa: E731

    def tol_check(name, key, err, unit, label, detail=""):
        tol = getattr(ch, key)
        if tol is None:
            return
        v, r, c = an._max(err)
        tol_can = tol + allow.get(key, 0.0)
        results.append(CheckResult(name + " (float32 over CAN)", v <= tol_can, v, tol_can, unit, label(r, c),
                                   (detail + "; " if detail else "") +
                                   f"scene's {tol:g} + float32 {allow.get(key, 0.0):.2g}"))

    def pose_checks(q_ref, detail=""):
        dq = d["q"] - q_ref
        dq[:, 2::3] = an._wrap(dq[:, 2::3])
        tol_check("positions x, y vs RobotModel", "position_m", np.delete(dq, np.s_[2::3], axis=1), "m",
                  lambda r, c: f"{where_t(r)} {bodies[c // 2]}.{'xy'[c % 2]}")
        tol_check("angles vs RobotModel", "angle_rad", dq[:, 2::3], "rad",
                  lambda r, c: f"{where_t(r)} {bodies[c]}.phi", detail)

    tol_check("constraint residual |Phi(q)| (legsim's, St_Residual)", "residual", d["residual"], "m|rad",
              lambda r, c: where_t(r))
    seq = _sequence_check(ev, d, feet)
    an.robot_stroke_check(scene, d, tol_check, where_t)
    if scene.switches:
        _switch_check(ev, scene, rec, d, feet)
    if ch.events:   # the event-locating reference, of what was sent (float32)
        return an.robot_events_checks(ev, scene, d, feet, bodies, tol_check, where_t, per_foot=True, sent=True)
    if an.off_stance(scene) or not an.needs_stance_reference(scene):
        return ev
    reference = lambda sc, times, rt: can_reference(sc, rec, times, rt)  # noqa: E731
    if getattr(ch, "lifts", None) is not None:   # a swing: lift-off, touchdown (analyses' checks)
        mu_s = an.robot_model(scene).ground.mu_static
        return an._robot_lift_checks(ev, scene, d, feet, bodies, float(mu_s), root, tol_check,
                                     reference=reference)
    if ch.slips is not None:
        if ch.slip_onset_steps is not None:
            an._robot_slip_onset_checks(ev, scene, d, feet, root, tol_check, reference=reference)
        return an._robot_slip_checks(ev, ch.slips, d, feet, per_foot=True)   # each foot by its own events
    try:
        model, r = can_reference(scene, rec, t, root)
    except ValueError as e:
        results.append(CheckResult("reference: RobotModel", False, None, None, "", "", str(e)))
        return ev
    ev.reference_run = r   # the report's reference curves
    pose_checks(r.q, an.robot_table2(d))   # Table II of the paper
    box = np.abs(d["q"][:, :3] - r.q[:, :3])
    results.append(CheckResult("box pose (ST_BOX) vs RobotModel (float32 over CAN)",
                               ch.position_m is None or bool(np.all(box[:, :2] <= ch.position_m + allow["position_m"])
                                                             and np.all(box[:, 2] <= (ch.angle_rad or math.inf)
                                                                        + allow["angle_rad"])),
                               float(box.max()), None, "m|rad", where_t(int(np.argmax(box.max(axis=1)))),
                               f"max |dx|, |dy| {box[:, :2].max():.2g} m, |dphi| {box[:, 2].max():.2g} rad"))
    solved = np.ones(len(t), bool)
    solved[0] = False   # the RESET's sample: no forces solved yet
    joints = [f"joint {j}" for j in range(d["reactions"].shape[1])]
    an._robot_stance_checks(ev, model, r, d, solved, acts, feet, joints, bodies, tol_check, " (ST_CONTACT)")
    stuck = bool(np.all(d["state"] == "stuck"))
    results.append(CheckResult("contact states (Ct_State): both feet stuck throughout (RobotModel's stance)",
                               stuck and not seq, None, None, "", "",
                               f"states at the end: {', '.join(d['state'][-1])}; changes: {len(seq)}"))
    return ev
