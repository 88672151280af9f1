"""Verdicts on the analyses that have no CAN frames: statics, statics_sweep, inverse_dynamics,
assembly, and a robot's runs in legsim_cli (legsim_bench.hil.cli_run).

Their numbers are checked against the bench's reference model exactly as hil_sim's are: the
reference's closed-form pose, its Newton-Euler statics and inverse dynamics, its statics sweep,
leg.toml's joint equations and the free-body balance (legsim_bench.verdict.leg).
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from scipy.optimize import curve_fit

from ..reference import ForceCommand, LegModel, LengthCommand
from ..reference.commands import Sinusoid, Staircase, Step
from ..reference.model_file import read_model_file
from ..reference.robot import RobotModel
from ..reference.robot_events import simulate_events
from ..scene import ACTUATORS, Scene, find_root
from .leg import Leg, constraint_residual, slot_s, static_balance
from .result import CheckResult, Evaluation

__all__ = ["evaluate_analysis", "evaluate_robot", "robot_reference", "robot_model", "robot_events_reference",
           "off_stance", "needs_stance_reference",
           "robot_arrays", "robot_growth", "robot_statics_reference", "robot_inverse_reference", "robot_slip_starts", "robot_table2", "robot_slip_onset",
           "EVENT_NAMES",
           "CONTACT_EVENTS"]

# legsim.h's event bits as legsim_cli names them in a sample's "events" (JSON) and the CSV's
# ';'-separated `events` column ("none" if none; scene_write.cpp: kEventNames), in bit order.
EVENT_NAMES = ("stroke_min", "stroke_max", "force_saturated", "near_singular", "liftoff", "touchdown",
               "stick_to_slip", "slip_to_stick", "contact_inconsistent", "contact_ambiguous",
               "events_deferred", "event_inexact")
# the contact transitions of a robot (docs/design/robot-on-ground.md section 8)
CONTACT_EVENTS = EVENT_NAMES[4:10]
# an actuator's arrival at its stroke's end
STROKE_EVENTS = EVENT_NAMES[0:2]


# ---- checks -------------------------------------------------------------------------------

def _run_check(rec: dict, results: list, name: str):
    """Appends the check that legsim_cli ran to the end; its JSON output, or None if it did not."""

    out = rec.get("cli_output")
    ok = bool(rec.get("complete")) and out is not None
    n = len(out.get("samples", [])) if out else 0
    results.append(CheckResult(name, ok, float(n), None, "samples", "",
                               "; ".join(e["error"] for e in rec["errors"]) or
                               f"status {out.get('status_code')} ({rec.get('cli')})"))
    return out if ok else None


def _wrap(d):
    return (d + np.pi) % (2 * np.pi) - np.pi


def _arrays(out: dict) -> dict:
    """The CLI's samples as arrays in the model's body, actuator and joint order."""
    bodies, joints, acts = out["bodies"], out["joints"], out["actuators"]
    S = out["samples"]

    def num(v):
        return float("nan") if v is None else float(v)

    q = np.array([[num(s["q"][b][c]) for b in bodies for c in ("x", "y", "phi")] for s in S], float)
    F = np.array([[num(s["actuators"][a]["force"]) for a in acts] for s in S], float)
    L = np.array([[num(s["actuators"][a]["length"]) for a in acts] for s in S], float)
    R = np.array([[[num(s["reactions"][j][k]) for k in ("fx", "fy", "moment")] for j in joints]
                  if s["reactions"] is not None else [[math.nan] * 3] * len(joints) for s in S], float)
    return {"t": np.array([s["t"] for s in S], float), "q": q.reshape(len(S), -1), "forces": F,
            "lengths": L, "reactions": R.reshape(len(S), len(joints), 3)}


def tol_checker(ch, results: list):
    """tol_check(name, key, err, unit, label, detail): appends the check of the largest |err|
    against the scene's [checks] key (none when the scene does not set it); label(row, col)
    says where the largest one is."""

    def tol_check(name, key, err, unit, label, detail=""):
        tol = getattr(ch, key)
        if tol is None:
            return
        v, r, c = _max(err)
        results.append(CheckResult(name, v <= tol, v, tol, unit, label(r, c), detail))
    return tol_check


def _max(err) -> tuple[float, int, int]:
    e = np.abs(np.asarray(err, float))
    e = e.reshape(len(e), -1) if e.ndim > 1 else e.reshape(-1, 1)
    e = np.where(np.isnan(e), np.inf, e)   # a missing number fails, never hides
    i = int(np.argmax(e))
    r, c = divmod(i, e.shape[1])
    return float(e[r, c]), r, c


def evaluate_analysis(rec: dict, scene: Scene, root: Path | None = None):
    """The checks of a legsim_cli run against the reference model (an Evaluation)."""

    if scene.robot:
        return evaluate_robot(rec, scene, root)
    root = root or find_root()
    ch = scene.checks
    model_path = scene.model_path or root / "models" / "leg.toml"
    leg = Leg.from_toml(model_path, scene.variant)
    results: list = []
    ev = Evaluation(scene, rec, results, leg=leg)
    out = _run_check(rec, results, f"run: legsim_cli {scene.analysis}")
    if out is None:
        return ev

    gravity = "gravity" not in scene.disable
    load = (0.0, 0.0) if scene.foot_load is None or "force_elements" in scene.disable else scene.foot_load
    model = LegModel.from_toml(model_path, variant=scene.variant)
    where_t = lambda d, r: f"t={d['t'][r]:.4f}s"  # noqa: E731

    tol_check = tol_checker(ch, results)

    def body_label(r, c):
        return f"{where_t(d, r)} {leg.body_names[c // 3]}.{('x', 'y', 'phi')[c % 3]}"

    def pose_checks(q_ref, note):
        dq = d["q"] - q_ref
        dq[:, 2::3] = _wrap(dq[:, 2::3])
        xy = np.delete(dq, np.s_[2::3], axis=1)
        tol_check("positions x, y vs reference", "position_m", xy, "m",
                  lambda r, c: body_label(r, (c // 2) * 3 + c % 2), note)
        tol_check("angles vs reference", "angle_rad", dq[:, 2::3], "rad",
                  lambda r, c: body_label(r, 3 * c + 2), note)
        if ch.residual is not None:
            res = constraint_residual(leg, d["q"])
            tol_check(f"constraint residual |Phi(q)| ({leg.n_constraints} eqs, {model_path.name})",
                      "residual", res, "m|rad", lambda r, c: where_t(d, r))

    def theta0():
        th = model.stand_theta() if scene.lengths is None else \
            model.theta_from_lengths(scene.lengths, near=model.stand_theta())
        if scene.variant == "slot":   # s is wherever the core's assembly put it (cf. checks)
            th = th.copy()
            th[2] = slot_s(Leg.from_toml(model_path, "slot"), d["q"][0])
        return th

    if scene.analysis == "statics_sweep":
        w = out["worst_case"]
        ref = model.statics_sweep(scene.grid, load, gravity)
        got_R = np.array([w["reactions"][j]["max_force"] for j in leg.joint_names], float)
        got_F = np.array([w["actuators"][a]["max_force"] for a in ACTUATORS], float)
        results.append(CheckResult("sweep: poses evaluated vs reference", w["n_poses"] == ref.n_poses,
                                   float(w["n_poses"]), float(ref.n_poses), "poses", "",
                                   f"{scene.grid} x {scene.grid} grid; failed: legsim {w['n_failed']}, "
                                   f"reference {ref.n_failed}"))
        d = {"t": np.zeros(1)}
        tol_check("sweep: max actuator forces vs reference", "statics_force_n",
                  (got_F - ref.max_actuator_force)[None], "N", lambda r, c: ACTUATORS[c],
                  f"legsim {', '.join(f'{x:.4f}' for x in got_F)} N")
        tol_check("sweep: max reaction forces vs reference", "statics_reaction_n",
                  (got_R - ref.max_reaction)[None], "N", lambda r, c: leg.joint_names[c])
        return ev

    d = _arrays(out)   # not ev.data: the report and the plots are for hil_sim's samples
    if scene.analysis == "assembly":
        pose_checks(model.absolute_q(theta0())[None], f"pose {scene.pose_name}"
                    + ("" if scene.lengths is None else f", lengths {list(scene.lengths)}"))
    elif scene.analysis == "statics":
        th = theta0()
        pose_checks(model.absolute_q(th)[None], f"pose {scene.pose_name}")
        F, R = model.statics(theta=th, foot_load=load, gravity=gravity)
        tol_check("actuator forces vs reference statics", "statics_force_n", d["forces"] - F[None], "N",
                  lambda r, c: ACTUATORS[c], f"reference ({F[0]:.4f}, {F[1]:.4f}) N, load {load} N")
        tol_check("reactions vs reference statics", "statics_reaction_n",
                  (d["reactions"] - R[None])[..., 0:2].reshape(len(d["t"]), -1), "N",
                  lambda r, c: f"{leg.joint_names[c // 2]}.f{'xy'[c % 2]}")
        if ch.balance_n is not None or ch.balance_nm is not None:
            bf, bm = static_balance(leg, d["q"], d["reactions"], d["forces"], load, gravity)
            tol_check("static balance, forces (legsim's numbers)", "balance_n", bf, "N",
                      lambda r, c: "", "sum of forces on each body")
            tol_check("static balance, moments (legsim's numbers)", "balance_nm", bm, "N m",
                      lambda r, c: "", "about each centre of mass")
    elif scene.analysis == "inverse_dynamics":
        th = theta0()
        hold = model.lengths(th)
        t = d["t"]
        L = np.tile(hold, (len(t), 1))
        Ld, Ldd = np.zeros_like(L), np.zeros_like(L)
        for c in scene.commands:
            if c is None:
                continue
            s = c.schedule
            L[:, c.actuator] = [s(x, float(hold[c.actuator])) for x in t]
            if s.kind == "sinusoid":
                w = 2 * math.pi * s.frequency
                Ld[:, c.actuator] = s.amplitude * w * np.cos(w * t + s.phase)
                Ldd[:, c.actuator] = -s.amplitude * w * w * np.sin(w * t + s.phase)
        ref = model.inverse_dynamics(L, Ld, Ldd, foot_load=load, gravity=gravity, near=th)
        pose_checks(ref.q, "the reference's pose at the commanded lengths")
        tol_check("actuator forces vs reference inverse dynamics", "actuator_force_n",
                  d["forces"] - ref.actuator_forces, "N", lambda r, c: f"{where_t(d, r)} {ACTUATORS[c]}")
        dr = d["reactions"] - ref.reactions
        tol_check("reaction forces vs reference (Newton-Euler)", "reaction_n",
                  dr[..., 0:2].reshape(len(t), -1), "N",
                  lambda r, c: f"{where_t(d, r)} {leg.joint_names[c // 2]}.f{'xy'[c % 2]}")
        tol_check("reaction moments vs reference", "moment_nm", dr[..., 2], "N m",
                  lambda r, c: f"{where_t(d, r)} {leg.joint_names[c]}.m")
    return ev


# ---- the robot (a model with contacts): legsim_cli against RobotModel ---------------------------

def _robot_schedule(s, initial: float, h: float, t_end: float):
    """A scene schedule as the reference's (legsim_bench.reference.commands). A sinusoid as
    legsim_cli applies it: evaluated before every step of h and held over the step (a
    staircase on the step grid up to t_end)."""
    if s.kind == "hold":
        return float(s.value)
    if s.kind == "initial":
        return float(initial)
    if s.kind == "step":
        return Step(float(s.before), float(s.after), float(s.t0))
    sin = Sinusoid(float(s.offset), float(s.amplitude), float(s.frequency), float(s.phase))
    grid = np.arange(int(round(t_end / h)) + 1) * h
    return Staircase(grid, [sin(x) for x in grid])


def robot_reference(scene: Scene, times, root: Path | None = None):
    """(RobotModel, RobotResult) of a robot dynamics scene at the given times: the scene's
    stand (at its `lengths`), both feet stuck, its commands (uncommanded actuators as `init`
    says). The reference has both feet stuck throughout: a scene with a free foot is refused
    (ValueError)."""
    if any(v != "stuck" for v in scene.contacts.values()):
        raise ValueError("RobotModel has both feet stuck; this scene frees a foot")
    model = robot_model(scene)
    start = model.assemble(None if scene.lengths is None else np.asarray(scene.lengths, float))
    cmds = []
    for a in range(model.na):
        c = scene.commands[a]
        if c is None:
            cmds.append(LengthCommand(float(start.lengths[a])) if scene.init == "hold_length"
                        else ForceCommand(0.0))
            continue
        sch = _robot_schedule(c.schedule, float(start.lengths[a]), scene.step_s, float(times[-1]))
        cmds.append(ForceCommand(sch) if c.mode == "force" else LengthCommand(sch))
    # on the step grid k h, the staircases' own times (legsim_cli's sample times are sums of h)
    t = np.round(np.asarray(times, float) / scene.step_s) * scene.step_s
    r = model.simulate(float(t[-1]), t_eval=t, actuators=cmds, start=start,
                       gravity="gravity" not in scene.disable, box_load=scene.box_load or (0.0, 0.0, 0.0))
    return model, r


def robot_model(scene: Scene) -> RobotModel:
    """RobotModel of the scene's robot file on the scene's ground (its [ground], if any)."""
    path = Path(scene.model_path)
    if not scene.ground_given:
        return RobotModel.from_toml(path)
    data = read_model_file(path)
    data["ground"] = {**data.get("ground", {}), **{k: float(scene.ground[k])
                                                  for k in ("slope", "mu_static", "mu_kinetic")}}
    return RobotModel(data, path.parent)


def off_stance(scene: Scene) -> bool:
    """The scene starts off RobotModel's stance on stuck feet ([start], or a foot not stuck)."""
    return scene.start is not None or any(v != "stuck" for v in scene.contacts.values())


def needs_stance_reference(scene: Scene) -> bool:
    """Its [checks] compare with RobotModel's stance (else: the run's own invariants only)."""
    ch = scene.checks
    return ch.slips is not None or ch.lifts is not None or any(
        getattr(ch, k) is not None for k in ("position_m", "angle_rad", "actuator_force_n", "reaction_n",
                                             "ground_force_n", "stays_put_m", "growth_rel"))


def _f32(x):
    return np.asarray(x, float).astype(np.float32).astype(float)


def robot_events_reference(scene: Scene, times, sent: bool = False):
    """(model, EventResult, t_switch) of a robot dynamics scene through its contact events
    (robot_events.simulate_events) at `times`: the scene's stance (at `lengths`) moved as its
    [start] says, each foot's state as the scene gives it (else stuck on the ground, free above
    it, sliding along its velocity), its constant commands; a switch holds `before` and
    t_switch is the reference's time of its event (inf: none; the reference is the run's
    until then). sent: the values the DBC carried (float32 start and setpoints; the lengths are
    float64 on the bus, the scene's exactly)."""
    rnd = _f32 if sent else (lambda x: np.asarray(x, float))
    model = robot_model(scene)
    asm = model.assemble(None if scene.lengths is None else np.asarray(scene.lengths, float))
    z0, zd0 = asm.z.copy(), np.zeros(7)
    g = model.ground
    n = np.array([-math.sin(g.slope), math.cos(g.slope)])
    tg = np.array([math.cos(g.slope), math.sin(g.slope)])
    if scene.start is not None:
        s = scene.start
        lift, tilt, spin = (float(rnd(s[k])) for k in ("lift", "tilt", "spin"))
        z0[:2] += lift * n
        z0[2] += tilt
        zd0[:2] = rnd(s["velocity"])
        zd0[2] = spin
    K = model.kinematics(z0, zd0)
    states, signs = [], []
    for k, foot in enumerate(scene.model_info.contacts):
        gap = float(n @ (K.foot[k] - np.asarray(g.point, float)))
        vt = float(tg @ (K.footJ[k] @ zd0))
        st = scene.contacts.get(foot, "stuck" if abs(gap) <= scene.newton_tol else "free")
        states.append(st)
        signs.append((1 if vt > 0 else -1) if st == "sliding" else 0)
    cmds = []
    for a in range(model.na):
        c = scene.commands[a]
        if c is None:
            cmds.append(LengthCommand(float(asm.lengths[a])) if scene.init == "hold_length" else ForceCommand(0.0))
            continue
        v = {"hold": c.schedule.value, "switch": c.schedule.before,
             "initial": float(asm.lengths[a])}.get(c.schedule.kind)
        if v is None:
            raise ValueError(f"{c.name}: the event-locating reference takes constant commands "
                             f"(got {c.schedule.kind})")
        v = float(rnd(v)) if c.schedule.kind != "initial" else v
        cmds.append(ForceCommand(v) if c.mode == "force" else LengthCommand(v))
    t = np.round(np.asarray(times, float) / scene.step_s) * scene.step_s
    r = simulate_events(model, float(t[-1]), t, z0, zd0, tuple(states), tuple(signs), actuators=cmds,
                        box_load=tuple(rnd(scene.box_load)) if scene.box_load else (0.0, 0.0, 0.0),
                        gravity="gravity" not in scene.disable,
                        stroke_stops="stroke_limits" not in scene.disable)
    feet = scene.model_info.contacts
    t_switch = min([e.t for c in scene.commands if c is not None and c.schedule.kind == "switch"
                    for e in r.events if e.foot >= 0 and e.kind == c.schedule.event
                    and feet[e.foot] == c.schedule.contact],
                   default=math.inf)
    return model, r, t_switch


def robot_stroke_check(scene: Scene, d: dict, tol_check, where_t):
    """[checks] in_stroke_m: every actuator's length inside its stroke (the stops hold)."""
    lo = np.array([a[1][0] for a in scene.model_info.actuators])
    hi = np.array([a[1][1] for a in scene.model_info.actuators])
    L = d["lengths"]
    out = np.maximum(np.maximum(lo - L, L - hi), 0.0)
    acts = scene.actuator_names
    tol_check("actuator lengths inside their strokes", "in_stroke_m", out, "m",
              lambda r, c: f"{where_t(r)} {acts[c]}",
              f"shortest {', '.join(f'{x:.5f}' for x in L.min(axis=0))} m "
              f"(minima {', '.join(f'{x:g}' for x in lo)})")


def robot_events_checks(ev, scene: Scene, d: dict, feet, bodies, tol_check, where_t, per_foot: bool,
                        sent: bool = False):
    """[checks] events: the run against robot_events_reference, until a switch's event: the
    contact states at every sample, every reference event in the sample whose step holds it
    (its foot's own events per_foot, else the sample's), no other contact event, every stroke
    stop's arrival likewise (_stroke_arrivals_check, from what the source carries), positions,
    angles and ground forces."""
    results, t, h = ev.results, d["t"], scene.step_s
    try:
        model, r, t_sw = robot_events_reference(scene, t, sent)
    except Exception as e:  # noqa: BLE001 - the reference's refusal is the verdict's failure
        results.append(CheckResult("reference: robot_events (contact events located)", False, None, None, "", "",
                                   str(e)))
        return ev
    ev.reference_run = r
    upto = t <= t_sw + h + 1e-12            # the samples the reference is the run's (a switch's event)
    n = int(np.sum(upto))
    kinds = ("touchdown", "liftoff", "stick_to_slip", "slip_to_stick")

    def got(i, k):
        e = d["foot_events"][i][k] if per_foot else d["events"][i]
        return set(e) & set(kinds)

    bad_states = [f"{feet[k]} {d['state'][i, k]} (reference {r.states[i, k]}) at t = {t[i]:g} s"
                  for i in range(n) for k in range(len(feet)) if str(d["state"][i, k]) != str(r.states[i, k])]
    results.append(CheckResult("contact states vs the event-locating reference, every sample", not bad_states,
                               float(len(bad_states)), None, "samples", "",
                               "; ".join(bad_states[:4]) or f"{n} samples agree"))
    missing, extra, found = [], [], []
    in_run = [e for e in r.events if 1e-12 < e.t <= t[n - 1] + 1e-12 and e.t <= t_sw]
    ref_ev = [e for e in in_run if e.foot >= 0]       # the contacts' (a stop's has foot -1)
    results.append(_stroke_arrivals_check(scene, d, [e for e in in_run if e.kind in STROKE_EVENTS], n))
    for e in ref_ev:
        i = int(np.searchsorted(t, e.t - 1e-12))
        if i >= len(t) or e.kind not in got(i, e.foot):
            missing.append(f"{feet[e.foot]} {e.kind} at {e.t:.6f} s not in the sample at "
                           f"{t[min(i, len(t) - 1)]:g} s")
        else:
            found.append(f"{feet[e.foot]} {e.kind} {e.t:.6f} s")
    for i in range(1, n):
        for k in range(len(feet) if per_foot else 1):
            for kind in got(i, k):
                if not any(e.kind == kind and (not per_foot or e.foot == k) and t[i - 1] < e.t + 1e-12 <= t[i] + 2e-12
                           for e in ref_ev):
                    extra.append(f"{feet[k] if per_foot else 'a foot'} {kind} at t = {t[i]:g} s")
    results.append(CheckResult("contact events in the step that holds the reference's", not missing and not extra,
                               float(len(missing) + len(extra)), None, "events", "",
                               "; ".join(missing + [x + " (not in the reference)" for x in extra]) or
                               "; ".join(found) or "no event"))
    dq = d["q"][:n] - r.q[:n]
    dq[:, 2::3] = _wrap(dq[:, 2::3])
    tol_check("positions x, y vs the event-locating reference", "position_m", np.delete(dq, np.s_[2::3], axis=1),
              "m", lambda r_, c: f"{where_t(r_)} {bodies[c // 2]}.{'xy'[c % 2]}",
              f"until {'the switch at ' + format(t_sw, '.6f') + ' s' if math.isfinite(t_sw) else 'the end'}")
    tol_check("angles vs the event-locating reference", "angle_rad", dq[:, 2::3], "rad",
              lambda r_, c: f"{where_t(r_)} {bodies[c]}.phi")
    g = np.concatenate([d["normal"][1:n] - r.normal[1:n], d["tangential"][1:n] - r.tangential[1:n]], axis=1)
    tol_check("ground forces N, T per foot vs the event-locating reference", "ground_force_n", g, "N",
              lambda r_, c: f"{where_t(r_ + 1)} {feet[c % len(feet)]}.{'NT'[c // len(feet)]}")
    return ev


def _stroke_arrivals_check(scene: Scene, d: dict, ref_stops, n: int) -> CheckResult:
    """Every stop arrival of the reference (stroke_min, stroke_max) in the sample whose step
    holds its time, and no arrival in a step that holds none. A sample says what its source
    carries (robot_arrays, robot_can_arrays): the kinds of the arrivals since the previous
    sample, stroke_kinds, and which actuators arrived, stroke_actuators (None: the source does
    not say, legsim_cli's; over CAN St_StrokeMask, whose kinds are the sample's)."""
    t, kinds, acts = d["t"], d["stroke_kinds"], d["stroke_actuators"]
    names = scene.actuator_names
    missing, extra, found = [], [], []
    for e in ref_stops:
        i = min(int(np.searchsorted(t, e.t - 1e-12)), len(t) - 1)
        what = f"{names[e.actuator]} {e.kind} at {e.t:.6f} s"
        if e.kind in kinds[i] and (acts[i] is None or e.actuator in acts[i]):
            found.append(what)
        else:
            missing.append(f"{what} not in the sample at {t[i]:g} s")
    for i in range(1, n):
        here = [e for e in ref_stops if t[i - 1] < e.t + 1e-12 <= t[i] + 2e-12]
        extra += [f"{kind} at t = {t[i]:g} s" for kind in sorted(kinds[i]) if kind not in {e.kind for e in here}]
        extra += [f"{names[a]} at t = {t[i]:g} s" for a in sorted(acts[i] or ())
                  if a not in {e.actuator for e in here}]
    return CheckResult("stroke stop arrivals in the step that holds the reference's", not missing and not extra,
                       float(len(missing) + len(extra)), None, "events", "",
                       "; ".join(missing + [x + " (not in the reference)" for x in extra]) or
                       f"{len(ref_stops)} arrivals" + (": " + "; ".join(found) if found else ""))


def robot_arrays(out: dict) -> dict:
    """The CLI's robot samples as arrays: t, q (N, 3 nb), forces, lengths (N, na), reactions
    (N, nj, 3), normal, tangential (N, nc), state (N, nc) names, feet (N, nc, 2), residual,
    events (N tuples of EVENT_NAMES), impulse (N, nc, 2) the last impact's (normal, tangential)."""
    d = _arrays(out)
    S, names = out["samples"], out.get("contacts", [])

    def num(v):
        return float("nan") if v is None else float(v)

    def per(key):
        return np.array([[num(s["contacts"][c][key]) if s.get("contacts") else math.nan for c in names]
                         for s in S], float)
    d["normal"], d["tangential"] = per("normal"), per("tangential")
    d["feet"] = np.stack([per("x"), per("y")], axis=-1)
    d["state"] = np.array([[s["contacts"][c]["state"] if s.get("contacts") else "" for c in names]
                           for s in S])
    d["residual"] = np.array([num(s["residual"]) for s in S], float)
    d["events"] = [tuple(s.get("events", ())) for s in S]
    d["stroke_kinds"] = [frozenset(e) & frozenset(STROKE_EVENTS) for e in d["events"]]
    d["stroke_actuators"] = [None] * len(S)     # legsim_cli names the kinds, not the actuators
    d["impulse"] = np.stack([per("impulse_n"), per("impulse_t")], axis=-1)
    return d


def _cosh_rate(t, y, rate0, extra=None):
    """The rate l of y = c (cosh(l t) - 1) [+ k extra] fitted over the run (the linear response
    of an unstable mode to a constant push from rest; `extra` absorbs a second-order term)."""
    c0 = y[-1] / (math.cosh(rate0 * t[-1]) - 1.0)
    if extra is None:
        f = lambda tt, c, lam: c * (np.cosh(lam * tt) - 1.0)  # noqa: E731
        p0 = [c0, rate0]
    else:
        f = lambda tt, c, lam, k: c * (np.cosh(lam * tt) - 1.0) + k * extra  # noqa: E731
        p0 = [c0, rate0, 0.0]
    p, _ = curve_fit(f, t, y, p0=p0, maxfev=20000)
    return float(p[1])


def robot_growth(model, d: dict) -> dict:
    """Predicted and measured growth of a constant-force stand that drifts away.

    Predicted: RobotModel.linearize about the stand with the equal_friction statics forces
    (sway, heave: its two real positive eigenvalues). Measured from the run: the box's x
    (the sway mode is antisymmetric, the only unstable one in x; the pitch oscillation is
    fitted with it) and its y (the heave mode, the only symmetric one; the sway's square
    enters y at second order and is fitted with it)."""
    F = model.statics().actuator_forces
    rates = model.linearize([ForceCommand(float(f)) for f in F]).growth_rates
    t = d["t"]
    x, y = d["q"][:, 0] - d["q"][0, 0], d["q"][:, 1] - d["q"][0, 1]
    sway = lambda tt, a, lam, b, w: a * (np.cosh(lam * tt) - 1.0) + b * (1.0 - np.cos(w * tt))  # noqa: E731
    w0 = 11.76   # the pitch oscillation, rad/s (design section 4)
    p, _ = curve_fit(sway, t, x, p0=[x[-1] / (math.cosh(rates[0] * t[-1]) - 1.0), rates[0], 0.0, w0],
                     maxfev=20000)
    return {"predicted": (float(rates[0]), float(rates[1])),
            "measured": (float(p[1]), _cosh_rate(t, y, rates[1], extra=x ** 2))}


def robot_statics_reference(scene: Scene):
    """(RobotModel, RobotStatics) of a robot statics scene: the stance at its `lengths` (the
    stand's by default), both feet stuck, the scene's statics_rule. The reference has no leg
    force elements: a scene that sets one is refused (ValueError)."""
    if any(any(x != 0 for x in v) for v in scene.forces.values()):
        raise ValueError("RobotModel's statics has no leg force elements; this scene sets "
                         + ", ".join(scene.forces))
    model = robot_model(scene)
    st = model.statics(None if scene.lengths is None else np.asarray(scene.lengths, float),
                       gravity="gravity" not in scene.disable, rule=scene.statics_rule,
                       box_load=scene.box_load or (0.0, 0.0, 0.0))
    return model, st


def robot_inverse_reference(scene: Scene, times) -> list:
    """RobotModel.inverse_dynamics of a robot inverse_dynamics scene at the given times: the
    stance at its `lengths`, both feet stuck, the three commanded lengths driving (their
    sinusoids' rates and accelerations exact), the fourth actuator following, the scene's
    statics_rule and box_load. ValueError unless exactly one actuator is uncommanded."""
    if any(any(x != 0 for x in v) for v in scene.forces.values()):
        raise ValueError("RobotModel has no leg force elements; this scene sets " + ", ".join(scene.forces))
    model = robot_model(scene)
    start = model.assemble(None if scene.lengths is None else np.asarray(scene.lengths, float))
    follow = [a for a in range(model.na) if scene.commands[a] is None]
    if len(follow) != 1:
        raise ValueError("on both stuck feet three lengths drive the robot: command three actuators")
    out, guess = [], None
    for t in np.asarray(times, float):
        L, Ld, Ldd = np.zeros(model.na), np.zeros(model.na), np.zeros(model.na)
        for a, c in enumerate(scene.commands):
            if c is None:
                continue
            s = c.schedule
            L[a] = s(t, float(start.lengths[a]))
            if s.kind == "sinusoid":
                w = 2 * math.pi * s.frequency
                Ld[a] = s.amplitude * w * math.cos(w * t + s.phase)
                Ldd[a] = -s.amplitude * w * w * math.sin(w * t + s.phase)
        r = model.inverse_dynamics(L, Ld, Ldd, follow=follow[0], start=start,
                                   box_load=scene.box_load or (0.0, 0.0, 0.0),
                                   gravity="gravity" not in scene.disable, rule=scene.statics_rule, guess=guess)
        guess = r.i
        out.append(r)
    return out


def _robot_inverse_checks(ev, scene: Scene, d: dict, out: dict, tol_check, pose_checks):
    """A robot inverse_dynamics scene against RobotModel.inverse_dynamics at every sample: the
    pose, the actuator forces (the follower's too), the joint reactions, per foot N and T."""
    results = ev.results
    try:
        refs = robot_inverse_reference(scene, d["t"])
    except Exception as e:  # noqa: BLE001 - the reference's own refusal, reported as a check
        results.append(CheckResult("reference: RobotModel.inverse_dynamics", False, None, None, "", "", str(e)))
        return ev
    t, acts, joints, feet = d["t"], out["actuators"], out["joints"], out.get("contacts", [])
    pose_checks(np.array([r.q for r in refs]), f"rule {scene.statics_rule}")
    F = np.array([r.actuator_forces for r in refs])
    tol_check("actuator forces vs RobotModel.inverse_dynamics", "actuator_force_n", d["forces"] - F, "N",
              lambda r, c: f"t={t[r]:.4f}s {acts[c]}",
              "at the end " + ", ".join(f"{a} {f:.3f} N" for a, f in zip(acts, d["forces"][-1])))
    R = np.array([r.reactions for r in refs])
    tol_check("joint reaction forces vs RobotModel.inverse_dynamics", "reaction_n",
              (d["reactions"] - R)[..., 0:2].reshape(len(t), -1), "N",
              lambda r, c: f"t={t[r]:.4f}s {joints[c // 2]}.f{'xy'[c % 2]}")
    ground = np.concatenate([d["normal"] - np.array([r.normal for r in refs]),
                             d["tangential"] - np.array([r.tangential for r in refs])], axis=1)
    tol_check("ground forces N, T per foot vs RobotModel.inverse_dynamics", "ground_force_n", ground, "N",
              lambda r, c: f"t={t[r]:.4f}s {feet[c % len(feet)]}.{'NT'[c // len(feet)]}",
              f"at the end N {', '.join(f'{x:.3f}' for x in d['normal'][-1])}, "
              f"T {', '.join(f'{x:+.3f}' for x in d['tangential'][-1])} N")
    holds = [[s_["contacts"][f]["holds"] for f in feet] for s_ in out["samples"]]
    ref_holds = [[bool(h) for h in r.holds] for r in refs]
    results.append(CheckResult("each foot's static cone holds as RobotModel's (holds), every sample",
                               holds == ref_holds, None, None, "", "",
                               f"legsim at the end {holds[-1]}, RobotModel {ref_holds[-1]}"))
    stuck = bool(np.all(d["state"] == "stuck"))
    results.append(CheckResult("contact states: both feet stuck throughout", stuck, None, None, "", "",
                               f"states at the end: {', '.join(d['state'][-1])}"))
    return ev


def _robot_statics_checks(ev, scene: Scene, d: dict, out: dict, tol_check, pose_checks):
    """A robot statics scene's one sample against RobotModel.statics: the pose, the actuator
    forces, the joint reactions, per foot N and T, and whether each foot's cone holds."""
    results = ev.results
    try:
        _, st = robot_statics_reference(scene)
    except Exception as e:  # noqa: BLE001 - the reference's own refusal, reported as a check
        results.append(CheckResult("reference: RobotModel.statics", False, None, None, "", "", str(e)))
        return ev
    acts, joints, feet = out["actuators"], out["joints"], out.get("contacts", [])
    pose_checks(st.assembly.q[None], f"rule {scene.statics_rule}")
    tol_check("actuator forces vs RobotModel.statics", "statics_force_n", d["forces"] - st.actuator_forces[None],
              "N", lambda r, c: acts[c],
              ", ".join(f"{a} {f:.3f} N" for a, f in zip(acts, d["forces"][0])))
    dr = (d["reactions"] - st.reactions[None])[..., 0:2].reshape(1, -1)
    tol_check("joint reaction forces vs RobotModel.statics", "statics_reaction_n", dr, "N",
              lambda r, c: f"{joints[c // 2]}.f{'xy'[c % 2]}")
    ground = np.concatenate([d["normal"] - st.normal[None], d["tangential"] - st.tangential[None]], axis=1)
    tol_check("ground forces N, T per foot vs RobotModel.statics", "ground_force_n", ground, "N",
              lambda r, c: f"{feet[c % len(feet)]}.{'NT'[c // len(feet)]}",
              f"N {', '.join(f'{x:.3f}' for x in d['normal'][0])}, "
              f"T {', '.join(f'{x:+.3f}' for x in d['tangential'][0])} N")
    holds = [s_["holds"] for s_ in (out["samples"][0]["contacts"][f] for f in feet)]
    results.append(CheckResult("each foot's static cone holds as RobotModel's (holds)",
                               holds == [bool(h) for h in st.holds], None, None, "", "",
                               f"legsim {holds}, RobotModel {[bool(h) for h in st.holds]}"))
    return ev


def robot_slip_starts(d: dict, k: int, per_foot: bool = False) -> list[float]:
    """The times of the samples at which contact k went from stuck to sliding with the
    core's stick_to_slip event among the sample's events (robot_arrays' d) or, per_foot,
    among contact k's own events (robot_can_arrays' foot_events, Ct_Events over CAN). The
    first sample counts when it is sliding with the event: a foot started stuck whose cone
    cannot hold slips at t = 0 (legsim_contacts_check), before any step."""
    st = d["state"][:, k]
    events = (lambda i: d["foot_events"][i][k]) if per_foot else (lambda i: d["events"][i])
    return [float(d["t"][i]) for i in range(len(st))
            if (i == 0 or st[i - 1] == "stuck") and st[i] == "sliding" and "stick_to_slip" in events(i)]


def _robot_slip_checks(ev, slips, d: dict, feet, per_foot: bool = False):
    """[checks] slips: each listed foot goes from stuck to sliding with STICK_TO_SLIP (per_foot:
    its own, as in robot_slip_starts); the others stay stuck throughout."""
    its = "its " if per_foot else ""
    for k, f in enumerate(feet):
        if f in slips:
            starts = robot_slip_starts(d, k, per_foot)
            ev.results.append(CheckResult(f"{f} slips: stuck to sliding with {its}stick_to_slip", bool(starts),
                                          float(len(starts)), None, "times", "",
                                          f"at t = {', '.join(f'{x:g}' for x in starts) or 'never'} s; "
                                          f"state at the end {d['state'][-1, k]}"))
        else:
            stuck = bool(np.all(d["state"][:, k] == "stuck"))
            ev.results.append(CheckResult(f"{f} stays stuck throughout", stuck, None, None, "", "",
                                          f"states: {', '.join(sorted(set(d['state'][:, k])))}"))
    return ev


# a contact's state change and the event the core must raise with it (section 8)
_CHANGE_EVENTS = {("stuck", "sliding"): "stick_to_slip", ("sliding", "stuck"): "slip_to_stick",
                  ("stuck", "free"): "liftoff", ("sliding", "free"): "liftoff",
                  ("free", "stuck"): "touchdown", ("free", "sliding"): "touchdown"}


def robot_table2(d: dict) -> str:
    """Table II of the paper from a robot run's arrays (robot_arrays' or robot_can_arrays' d):
    the right leg's phi3 (thigh) and phi6 (shank) at the end, and the box's travel."""
    q, t = d["q"], d["t"]
    k3, k6 = 3 * 3 + 2, 3 * 6 + 2
    return (f"at t = {t[-1]:g} s right phi3 = {q[-1, k3]:.5f} rad ({math.degrees(q[-1, k3]):.3f} deg), "
            f"phi6 = {q[-1, k6]:.5f} rad ({math.degrees(q[-1, k6]):.3f} deg); box "
            f"({1e3 * (q[-1, 0] - q[0, 0]):+.2f}, {1e3 * (q[-1, 1] - q[0, 1]):+.2f}) mm, "
            f"{q[-1, 2] - q[0, 2]:+.5f} rad")


def _robot_sequence_check(ev, d: dict, feet):
    """The contact-state sequence against the events: every change of a foot's state between
    two samples comes with its event in the later sample's events."""
    bad, seq = [], []
    for k, f in enumerate(feet):
        st = d["state"][:, k]
        for i in range(1, len(st)):
            if st[i] == st[i - 1]:
                continue
            want = _CHANGE_EVENTS.get((str(st[i - 1]), str(st[i])))
            seq.append(f"{f} {st[i - 1]}->{st[i]} at {d['t'][i]:g} s")
            if want is None or want not in d["events"][i]:
                bad.append(f"{f} {st[i - 1]}->{st[i]} at t = {d['t'][i]:g} s without {want}")
    ev.results.append(CheckResult("contact-state sequence against the events", not bad, float(len(bad)), None,
                                  "changes", "", "; ".join(bad or seq) or "no change"))


def robot_slip_onset(scene: Scene, d: dict, root: Path | None = None, reference=None) -> dict:
    """The first stick_to_slip of a robot dynamics run (robot_arrays' d) against RobotModel's
    stance on stuck feet along the scene's commands up to it: where |T|/N of a foot first
    reaches mu_static (the crossing, interpolated between samples), and which foot the scene's
    contact law must release there (lcp: the one that crossed; paper: the smaller |T|)."""
    feet = range(d["state"].shape[1])
    starts = [(x, k) for k in feet for x in robot_slip_starts(d, k)]
    if not starts:
        return {"event_t": None}
    t_e, k_e = min(starts)
    i_e = int(np.argmin(np.abs(d["t"] - t_e)))
    released = [k for k in feet if d["state"][i_e, k] == "sliding" and d["state"][i_e - 1, k] == "stuck"]
    # reference(scene, times, root): robot_reference, or over CAN the one of what was sent
    model, r = (reference or robot_reference)(scene, d["t"][:i_e + 1], root)
    mu = model.ground.mu_static
    use = np.abs(r.tangential) / r.normal
    out = {"event_t": t_e, "released": released, "model": model, "ref": r, "i_event": i_e,
           "use_at_event": use[-1], "T_at_event": r.tangential[-1], "N_at_event": r.normal[-1]}
    over = np.nonzero(np.any(use > mu, axis=1))[0]
    if over.size == 0 or over[0] == 0:
        out["crossing_t"] = None
        return out
    j = int(over[0])
    cross = []
    for k in feet:  # linear interpolation of use - mu between samples j-1 and j
        a, b = use[j - 1, k] - mu, use[j, k] - mu
        if b > 0:
            cross.append((r.t[j - 1] + (r.t[j] - r.t[j - 1]) * (-a) / (b - a) if a < 0 else r.t[j - 1], k))
    t_c, k_c = min(cross)
    out.update(crossing_t=float(t_c), crossing_foot=k_c, crossing_sample_t=float(r.t[j]),
               smaller_T_foot=int(np.argmin(np.abs(r.tangential[j]))))
    out["expected"] = out["smaller_T_foot"] if scene.contact_law == "paper" else k_c
    return out


def _robot_slip_onset_checks(ev, scene: Scene, d: dict, feet, root, tol_check, reference=None):
    """[checks] slip_onset_steps: legsim's first stick_to_slip within that many steps after
    RobotModel's stuck-stuck |T|/N reaches mu_static, the released foot the contact law's, and
    the stance before it (position_m, angle_rad, ground_force_n) against the reference."""
    o = robot_slip_onset(scene, d, root, reference)
    if o["event_t"] is None or o.get("crossing_t") is None:
        ev.results.append(CheckResult("slip onset vs RobotModel's stance", False, None, None, "", "",
                                      "no stick_to_slip in the run" if o["event_t"] is None else
                                      f"RobotModel's |T|/N never reaches mu_static by t = {o['event_t']:g} s"))
        return
    h = scene.step_s
    lag = (o["event_t"] - o["crossing_t"]) / h
    ok = -1e-9 <= lag <= scene.checks.slip_onset_steps
    ev.results.append(CheckResult(
        "slip onset: stick_to_slip after RobotModel's |T|/N reaches mu_static", ok, lag,
        scene.checks.slip_onset_steps, "steps", "",
        f"legsim's event at t = {o['event_t']:.4f} s, the reference's crossing at {o['crossing_t']:.6f} s "
        f"({feet[o['crossing_foot']]}); at the event |T|/N = "
        f"{', '.join(f'{x:.4f}' for x in o['use_at_event'])}, |T| = "
        f"{', '.join(f'{abs(x):.2f}' for x in o['T_at_event'])} N"))
    rule = ("the smaller |T| (paper)" if scene.contact_law == "paper" else "the one leaving its cone (lcp)")
    want = feet[o["expected"]]
    got = [feet[k] for k in o["released"]]
    ev.results.append(CheckResult(f"released foot: {rule}", got == [want], None, None, "", "",
                                  f"legsim released {', '.join(got) or 'none'}, the reference says {want}",
                                  got=", ".join(got), want=want))
    # the stance holds up to the sample before the event's; forces are solved from sample 1 on
    i_e, r = o["i_event"], o["ref"]
    dq = d["q"][:i_e] - r.q[:i_e]
    dq[:, 2::3] = _wrap(dq[:, 2::3])
    xy = np.delete(dq, np.s_[2::3], axis=1)
    tt = d["t"]
    tol_check("positions x, y vs RobotModel before the slip", "position_m", xy, "m",
              lambda r_, c: f"t={tt[r_]:.4f}s")
    tol_check("angles vs RobotModel before the slip", "angle_rad", dq[:, 2::3], "rad",
              lambda r_, c: f"t={tt[r_]:.4f}s")
    g = np.concatenate([d["normal"][1:i_e] - r.normal[1:i_e], d["tangential"][1:i_e] - r.tangential[1:i_e]],
                       axis=1)
    tg = tt[1:i_e]
    tol_check("ground forces N, T per foot vs RobotModel before the slip", "ground_force_n", g, "N",
              lambda r_, c: f"t={tg[r_]:.4f}s {feet[c % len(feet)]}.{'NT'[c // len(feet)]}")


def _robot_lift_checks(ev, scene: Scene, d: dict, feet, bodies, mu_s: float, root, tol_check,
                       reference=None):
    """A swing ([checks] lifts): each foot of lifts goes stuck -> free (liftoff) -> stuck
    (touchdown, its reported impulse inside the static cone), once; the other feet stay stuck;
    every state change comes with its event; until the first lift-off the run is RobotModel's
    stance on both stuck feet (positions and angles). d: robot_arrays' layout (impulse
    optional); reference(scene, times, root) -> (model, result), robot_reference by default
    (a run over CAN passes its own)."""
    results, lifts, t = ev.results, scene.checks.lifts, d["t"]
    reference = reference or robot_reference
    _robot_sequence_check(ev, d, feet)
    first = len(t)
    for k, f in enumerate(feet):
        st = [str(x) for x in d["state"][:, k]]
        changes = [(i, st[i - 1], st[i]) for i in range(1, len(st)) if st[i] != st[i - 1]]
        detail = ", ".join(f"{a}->{b} at {t[i]:g} s" for i, a, b in changes) or "no change"
        if f not in lifts:
            results.append(CheckResult(f"{f}: stays stuck", not changes, None, None, "", "", detail))
            continue
        ok = [(a, b) for _, a, b in changes] == [("stuck", "free"), ("free", "stuck")]
        results.append(CheckResult(f"{f}: lifts off, then touches down stuck", ok, None, None, "", "", detail))
        if changes:
            first = min(first, changes[0][0])
        if ok and "impulse" in d:
            i = changes[1][0]
            pn, pt = float(d["impulse"][i, k, 0]), float(d["impulse"][i, k, 1])
            results.append(CheckResult(f"{f}: touchdown impulse inside the static cone", pn > 0 and abs(pt) <= mu_s * pn,
                                       None, None, "", f"t={t[i]:.4f}s",
                                       f"P_n {pn:.4f} N s, P_t {pt:+.4f} N s (|P_t|/P_n {abs(pt) / pn:.3f}, "
                                       f"mu_static {mu_s:g})" if pn > 0 else f"P_n {pn:.4g} N s"))
    tol_check("constraint residual |Phi(q)| (legsim's)", "residual", d["residual"], "m|rad", lambda r, c: f"t={t[r]:.4f}s")
    if first > 1 and (scene.checks.position_m is not None or scene.checks.angle_rad is not None):
        try:
            _, r = reference(scene, t[:first], root)
        except ValueError as e:
            results.append(CheckResult("reference: RobotModel", False, None, None, "", "", str(e)))
            return ev
        ev.reference_run = r   # the report's reference curves (until the lift-off)
        dq = d["q"][:first] - r.q
        dq[:, 2::3] = _wrap(dq[:, 2::3])
        tol_check("positions x, y vs RobotModel until the lift-off", "position_m", np.delete(dq, np.s_[2::3], axis=1),
                  "m", lambda r_, c: f"t={t[r_]:.4f}s {bodies[c // 2]}.{'xy'[c % 2]}")
        tol_check("angles vs RobotModel until the lift-off", "angle_rad", dq[:, 2::3], "rad",
                  lambda r_, c: f"t={t[r_]:.4f}s {bodies[c]}.phi", f"{first} samples, up to t = {t[first - 1]:g} s")
    return ev


def _robot_stance_checks(ev, model, r, d: dict, solved, acts, feet, joints, bodies, tol_check,
                         ground_tag: str = ""):
    """A dynamics run on stuck feet against RobotModel's stance r (of model): actuator, ground
    (name + ground_tag) and joint reaction forces at the samples where solved, then
    [checks] stays_put_m and growth_rel; tol_check as evaluate_robot's or robot_can's."""
    ch, t = ev.scene.checks, d["t"]
    tt = t[solved]
    tol_check("actuator forces vs RobotModel", "actuator_force_n", (d["forces"] - r.actuator_forces)[solved], "N",
              lambda r_, c: f"t={tt[r_]:.4f}s {acts[c]}")
    ground = np.concatenate([d["normal"] - r.normal, d["tangential"] - r.tangential], axis=1)[solved]
    tol_check(f"ground forces N, T per foot{ground_tag} vs RobotModel", "ground_force_n", ground, "N",
              lambda r_, c: f"t={tt[r_]:.4f}s {feet[c % len(feet)]}.{'NT'[c // len(feet)]}",
              f"at t = {t[-1]:g} s N {', '.join(f'{x:.2f}' for x in d['normal'][-1])}, "
              f"T {', '.join(f'{x:+.2f}' for x in d['tangential'][-1])} N")
    if ch.reaction_n is not None:
        dr = (d["reactions"] - r.reactions)[solved]
        tol_check("joint reaction forces vs RobotModel", "reaction_n", dr[..., 0:2].reshape(len(tt), -1), "N",
                  lambda r_, c: f"t={tt[r_]:.4f}s {joints[c // 2]}.f{'xy'[c % 2]}")
    if ch.stays_put_m is not None:
        disp = d["q"] - d["q"][0]
        tol_check("stays put: largest displacement from the first sample", "stays_put_m",
                  np.delete(disp, np.s_[2::3], axis=1), "m", lambda r_, c: f"t={t[r_]:.4f}s {bodies[c // 2]}")
    if ch.growth_rel is not None:
        g = robot_growth(model, d)
        rel = np.array([(m_ - p_) / p_ for m_, p_ in zip(g["measured"], g["predicted"])])
        tol_check("growth rates of the drift vs RobotModel's linearized modes", "growth_rel", rel[None], "",
                  lambda r_, c: ("sway", "heave")[c],
                  f"sway {g['measured'][0]:.4f} /s (predicted {g['predicted'][0]:.4f}), heave "
                  f"{g['measured'][1]:.4f} /s (predicted {g['predicted'][1]:.4f})")


def evaluate_robot(rec: dict, scene: Scene, root: Path | None = None):
    """The checks of a robot scene run in legsim_cli against RobotModel (an Evaluation)."""

    ch = scene.checks
    results: list = []
    ev = Evaluation(scene, rec, results)
    out = _run_check(rec, results, f"run: legsim_cli robot {scene.analysis}")
    if out is None:
        return ev
    d = robot_arrays(out)
    t = d["t"]
    where_t = lambda r: f"t={t[r]:.4f}s"  # noqa: E731
    bodies, acts, joints, feet = out["bodies"], out["actuators"], out["joints"], out.get("contacts", [])

    tol_check = tol_checker(ch, results)

    def pose_checks(q_ref, detail=""):
        dq = d["q"] - q_ref
        dq[:, 2::3] = _wrap(dq[:, 2::3])
        xy = np.delete(dq, np.s_[2::3], axis=1)
        tol_check("positions x, y vs RobotModel", "position_m", xy, "m",
                  lambda r, c: f"{where_t(r)} {bodies[c // 2]}.{'xy'[c % 2]}")
        tol_check("angles vs RobotModel", "angle_rad", dq[:, 2::3], "rad",
                  lambda r, c: f"{where_t(r)} {bodies[c]}.phi", detail)
        tol_check("constraint residual |Phi(q)| (legsim's)", "residual", d["residual"], "m|rad",
                  lambda r, c: where_t(r))

    if scene.analysis == "assembly":
        model = robot_model(scene)
        a = model.assemble(None if scene.lengths is None else np.asarray(scene.lengths, float))
        pose_checks(a.q[None], f"box ({a.q[0]:.6f}, {a.q[1]:.6f}, {a.q[2]:.6f})")
        return ev
    if scene.analysis == "statics":
        return _robot_statics_checks(ev, scene, d, out, tol_check, pose_checks)
    if scene.analysis == "inverse_dynamics":
        return _robot_inverse_checks(ev, scene, d, out, tol_check, pose_checks)
    robot_stroke_check(scene, d, tol_check, where_t)
    if ch.events or off_stance(scene) or not needs_stance_reference(scene):
        # the run's own invariants, and with events = true the event-locating reference
        tol_check("constraint residual |Phi(q)| (legsim's)", "residual", d["residual"], "m|rad",
                  lambda r, c: where_t(r))
        if ch.events:
            robot_events_checks(ev, scene, d, feet, bodies, tol_check, where_t, per_foot=False)
        else:
            _robot_sequence_check(ev, d, feet)
        return ev
    if ch.lifts is not None:
        return _robot_lift_checks(ev, scene, d, feet, bodies, float(out["ground"]["mu_static"]), root,
                                  tol_check)
    if ch.slips is not None:
        tol_check("constraint residual |Phi(q)| (legsim's)", "residual", d["residual"], "m|rad",
                  lambda r, c: where_t(r))
        _robot_sequence_check(ev, d, feet)
        if ch.slip_onset_steps is not None:
            _robot_slip_onset_checks(ev, scene, d, feet, root, tol_check)
        return _robot_slip_checks(ev, ch.slips, d, feet)
    try:
        model, r = robot_reference(scene, t, root)
    except ValueError as e:
        results.append(CheckResult("reference: RobotModel", False, None, None, "", "", str(e)))
        return ev
    ev.reference_run = r   # the report's reference curves
    pose_checks(r.q, robot_table2(d))
    # Forces where the core has solved them: not the first sample (the first step solves
    # them), nor a sample at a command's breakpoint (it holds the forces of the step that
    # ended there, under the command before; the reference's are the new command's).
    bps = {round(b * 1e9) for c in scene.commands if c is not None for b in c.schedule.breakpoints}
    solved = np.array([s["reactions"] is not None and round(s["t"] * 1e9) not in bps for s in out["samples"]])
    solved[0] = False
    _robot_stance_checks(ev, model, r, d, solved, acts, feet, joints, bodies, tol_check)
    stuck = bool(np.all(d["state"] == "stuck"))
    results.append(CheckResult("contact states: both feet stuck throughout (RobotModel's stance)", stuck,
                               None, None, "", "", f"states at the end: {', '.join(d['state'][-1])}"))
    return ev
