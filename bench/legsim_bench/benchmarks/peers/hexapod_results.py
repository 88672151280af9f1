"""The hexapod in MuJoCo and legsim: error against the bench's reference and cost per step.

    legsim-bench hexapod-peers --update-results
    python -m legsim_bench.benchmarks.peers.hexapod_results -o DIR        # from bench/

writes ``hexapod_peers.md`` (default out/bench-results/): the machine section, then per
scene (mujoco_hexapod.SCENES), engine and step h the errors at t = 0.2 s against the reference
(HexapodModel.simulate, DOP853 at rtol 1e-12): the box's place (m) and rotation (rad), the
rowing angles (rad), the actuator lengths (m), the held feet's ground forces (N); and the
cost per step and per simulated second, each the smallest over ``--repeats`` runs with the
set-up outside the clock: MuJoCo, ``mujoco.rollout`` (compiled mj_step loop, one thread);
legsim, one ``HexapodSim.step(n)`` call (compiled loop); both through Python, each divided by
the steps.

Then the walking scene (hexapod_walk.py, ``--no-walk`` leaves it out): legsim and MuJoCo walking
two periods on the same commands at several steps, their box and feet errors against the rigid
reference (legsim at WALK_REF_H) and against each one's own finest run, MuJoCo's cone margins, the
costs, and legsim's cost at the errors MuJoCo reaches (equal_error).
"""
from __future__ import annotations

import argparse
import math
import shutil
import sys
from pathlib import Path

import numpy as np

from .. import results
from . import peer_tables
from . import mujoco_hexapod as mh

H = (4e-3, 2e-3, 1e-3, 5e-4, 2.5e-4, 1.25e-4)
ERRS = ("box", "rot", "rowing", "lengths", "force")
CALLGRIND_H = 1e-3
COMMAND = "legsim-bench hexapod-peers --update-results"
MODULE_COMMAND = ("LEGSIM_ROOT=$PWD PYTHONPATH=$PWD/python:$PWD/bench "
                  "python -m legsim_bench.benchmarks.peers.hexapod_results --update-results")


def collect(scenes=mh.SCENES, hs=H, repeats: int = 3, callgrind: bool = True, walk: bool = True) -> dict:
    """{"held": the held-feet scenes' rows, "walk": collect_walk's (None: not run or no liblegsim)}."""
    held = collect_held(scenes, hs, repeats, callgrind)
    w = None
    if walk and mh.available():
        try:
            import legsim
            if legsim.library_available("double"):
                w = collect_walk(callgrind=callgrind)
        except ImportError:
            pass
    return {"held": held, "walk": w}


def collect_held(scenes=mh.SCENES, hs=H, repeats: int = 3, callgrind: bool = True) -> list[dict]:
    from ...reference.hexapod import HexapodModel
    ref = HexapodModel.from_toml(mh.default_path())
    rows = []
    try:
        import legsim
        hexapod = legsim.Hexapod.from_toml(legsim.data_path("models/hexapod.toml")) \
            if legsim.library_available("double") else None
    except ImportError:
        hexapod = None
    for name in scenes:
        sc = mh.setup(name, ref)
        res = mh.reference(sc, ref)
        for engine in ("legsim", "mujoco"):
            if engine == "legsim" and hexapod is None:
                rows.append({"engine": "legsim", "scene": name, "method": "-", "h": float("nan"), "ok": False,
                             "note": "liblegsim.so not found (build the target legsim)"})
                continue
            for h in hs:
                c = mh.compare(sc, ref, h, res, engine=engine, repeats=repeats, hexapod=hexapod)
                ir = mh.instructions_per_step(engine, name, h) if callgrind and h == CALLGRIND_H else None
                rows.append({"engine": c["engine"], "scene": name, "method": c["method"], "h": h, "ok": c["ok"],
                             "per_step_s": c["per_step_s"], "instructions": ir, **c["err"]})
    return rows


WALK_LEGSIM_H = (4e-3, 2e-3, 1e-3, 5e-4, 2.5e-4, 1.25e-4)
WALK_MUJOCO_H = (4e-3, 2e-3, 1e-3, 5e-4, 2.5e-4, 1.25e-4)
WALK_REF_H = 6.25e-5          # legsim's finest run: the rigid model's reference; MuJoCo's own finest
# callgrind over the whole walk at these steps (a finer step's count per step taken as 1 ms's: legsim's
# per-step work falls with h, fewer events a step, so that overstates its cost there)
WALK_CALLGRIND_H = (4e-3, 2e-3, 1e-3)


def collect_walk(legsim_h=WALK_LEGSIM_H, mujoco_h=WALK_MUJOCO_H, ref_h=WALK_REF_H, t_end=None,
                 callgrind: bool = True) -> dict:
    """The walking scene (hexapod_walk): each engine at each h, its errors against the rigid
    reference (legsim at ref_h) and against its own run at ref_h, its cost; the instructions
    per step at CALLGRIND_H over the whole walk."""
    import legsim

    from . import hexapod_walk as hw
    hx = legsim.Hexapod.from_toml(legsim.data_path("models/hexapod.toml"))
    ref, pl = hw.default_setup(t_end, hexapod=hx)
    rigid = hw.legsim_walk(pl, ref_h, hexapod=hx)
    own = {"legsim": rigid, "mujoco": hw.MujocoWalk(pl, ref, ref_h).simulate()}
    mu = hw.mjcf_walk(ref)["mu"]
    rows = []
    for engine, hs in (("legsim", legsim_h), ("mujoco", mujoco_h)):
        for h in hs:
            out = hw.legsim_walk(pl, h, hexapod=hx) if engine == "legsim" else hw.MujocoWalk(pl, ref, h).simulate()
            ir = hw.instructions_per_step(engine, pl, h, pl.t_end) if callgrind and h in WALK_CALLGRIND_H else None
            e, es = hw.errors(out, rigid), hw.errors(out, own[engine])
            rows.append({"engine": out["engine"], "method": out["method"], "h": h, "ok": out["ok"],
                         "box": e["box"], "feet": e["feet"], "box_self": es["box"], "feet_self": es["feet"],
                         "per_step_s": out["per_step_s"], "instructions": ir, "note": out.get("note", ""),
                         "cone": hw.cone_margin(out, mu) if engine == "mujoco" and out["ok"] else None})
    model_err = hw.errors(own["mujoco"], rigid)
    return {"rows": rows, "model_error": model_err, "ref_h": ref_h, "t_end": pl.t_end, "h_plan": pl.h,
            "mu": mu, "impacts": rigid["impacts"], "period": pl.gait["period_s"], "cone": rigid["cone"],
            "walk_mjcf": {k: v for k, v in hw.mjcf_walk(ref).items() if k not in ("actuator", "rowing")}}


def _interp_cost(err, rows, key, cost) -> tuple:
    """legsim's cost at error ``err`` on its (error, cost) points (log-log interpolation): (cost,
    "=" | "<=" (err above its largest error: its coarsest run's cost bounds it) | "n/a" (below
    its smallest))."""
    pts = sorted((r[key], cost(r)) for r in rows if r["ok"] and r[key] > 0)
    if not pts or not math.isfinite(err):
        return float("nan"), "n/a"
    if err >= pts[-1][0]:
        return pts[-1][1], "<="
    if err < pts[0][0]:
        return float("nan"), "n/a"
    for (e0, c0), (e1, c1) in zip(pts, pts[1:]):
        if e0 <= err <= e1:
            w = 0.0 if e1 == e0 else math.log(err / e0) / math.log(e1 / e0)
            return math.exp(math.log(c0) + w * math.log(c1 / c0)), "="
    return float("nan"), "n/a"


def equal_error(walk: dict) -> list[dict]:
    """Per MuJoCo run: legsim's cost at MuJoCo's error (box, against the rigid reference; and each
    against its own finest run), in wall time and in instructions per simulated second (each run's
    instructions per step over h; a run not counted takes its engine's count at CALLGRIND_H)."""
    rows = walk["rows"]
    ls = [r for r in rows if r["engine"].startswith("legsim")]
    mj = [r for r in rows if r["engine"].startswith("mujoco") and r["ok"]]
    ir = {e: next((r["instructions"] for r in rows if r["engine"].startswith(e) and r["instructions"]
                   and r["h"] == CALLGRIND_H), None) for e in ("legsim", "mujoco")}
    wall = lambda r: r["per_step_s"] / r["h"]                                   # noqa: E731
    instr = lambda e: (lambda r: (r["instructions"] or ir[e]) / r["h"]) if ir[e] else None   # noqa: E731
    out = []
    for r in mj:
        o = {"h": r["h"]}
        for key in ("box", "box_self"):
            for what, f_ls, f_mj in (("wall", wall, wall), ("instr", instr("legsim"), instr("mujoco"))):
                if f_ls is None or f_mj is None:
                    o[f"{key}_{what}"] = (float("nan"), "n/a", float("nan"))
                    continue
                c, rel = _interp_cost(r[key], ls, "box" if key == "box" else "box_self", f_ls)
                o[f"{key}_{what}"] = (c, rel, f_mj(r))
        out.append(o)
    return out


def _count(ir) -> str:
    return "-" if ir is None else f"{ir:,.0f}"


def _e(x) -> str:
    return "-" if x is None or not math.isfinite(x) else f"{x:.2e}"


def markdown_walk(w: dict) -> list[str]:
    rows = w["rows"]
    mj = w["walk_mjcf"]
    lines = ["", "## The walking scene (scenes/hexapod_walk.toml, issue 24 sections 4 and 5)", "",
             f"{w['t_end']:g} s ({w['t_end'] / w['period']:g} periods) of the tripod gait from walk()'s "
             "start, both engines given "
             f"legsim.Hexapod.walk's commands (the gait's set-points and the planned statics as feed-forward, "
             f"computed by legsim at every {w['h_plan'] * 1e3:g} ms, the scene's step_s: a controller at that "
             "rate; a step h that divides it holds the period's command, a coarser step takes the command at "
             "its end as walk() at step h, which adds that sampling's O(h) to its error). legsim: "
             "HexapodSim.command_pose + step(1) per step, its RK4 on the rotation group with the contact "
             f"events located (reference run: {w['impacts']} touchdowns, {w['cone']['solved']} contact problems, "
             f"at most {w['cone']['max_iterations']} iterations). MuJoCo: the same model and servos "
             f"(`general` actuators: kp, -kp, -kd, the sum with the feed-forward saturated), each foot a "
             f"{mj['foot_radius']:g} m sphere on the ground plane, condim 3, cone elliptic, mu = "
             f"{mj['mu']:g} (the file's mu_static; legsim slides at mu_kinetic {mj['mu_kinetic']:g}; MuJoCo has "
             f"one mu), impratio {mj['impratio']:g}, noslip iterations {mj['noslip_iterations']}, solref "
             f"(2h, 1) for loops and contacts, solimp 0.9999 (loops) / {mj['contact_solimp'][0]:g} (contacts), "
             "RK4, mujoco.rollout. Model: bench/legsim_bench/benchmarks/peers/hexapod_walk.py.", "",
             f"Errors: the largest distance (m) over the samples every {hw_sample() * 1e3:g} ms of the box "
             f"centre (box) and of the six feet (feet), against the rigid reference (legsim at "
             f"{w['ref_h'] * 1e3:g} ms) and against the engine's own run at {w['ref_h'] * 1e3:g} ms "
             "(self). MuJoCo's model error (its run at "
             f"{w['ref_h'] * 1e3:g} ms against the rigid reference): box {_e(w['model_error']['box'])} m, "
             f"feet {_e(w['model_error']['feet'])} m. Cone: min over samples and loaded feet of "
             "mu N - |T| (N, >= 0 inside). Cost: one run's stepping (legsim: the step(1) calls; MuJoCo: "
             "rollout) / steps; instructions per step over the whole walk (callgrind, inside robot_step / "
             "mj_step) at h = 4, 2 and 1 ms.", "",
             "| engine | method | h (s) | box (m) | feet (m) | box, self (m) | feet, self (m) | cone (N) "
             "| cost per step (us) | cost per simulated s (ms) | instructions per step |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        if not r["ok"]:
            lines.append(f"| {r['engine']} | {r['method']} | {r['h']:g} | failed | {r['note'][:80]} "
                         "| | | | | | |")
            continue
        lines.append(f"| {r['engine']} | {r['method']} | {r['h']:g} | {_e(r['box'])} | {_e(r['feet'])} "
                     f"| {_e(r['box_self'])} | {_e(r['feet_self'])} | {_e(r['cone'])} "
                     f"| {r['per_step_s'] * 1e6:.1f} | {r['per_step_s'] / r['h'] * 1e3:.1f} "
                     f"| {_count(r.get('instructions'))} |")
    lines += ["", "Equal error: legsim's cost at each MuJoCo run's box error, interpolated (log-log) on "
              "legsim's (error, cost) points; '<=' where MuJoCo's error is above legsim's largest (legsim's "
              "coarsest run is cheaper and closer), 'n/a' below its smallest. Ratio = legsim / MuJoCo "
              "(target <= 0.1). Instructions per simulated second: the run's count per step / h (a run finer than "
              "1 ms: the count at 1 ms, which overstates legsim's: its wall time per step falls with h).", "",
              "| MuJoCo h (s) | MuJoCo box err (rigid ref) | legsim / MuJoCo, wall | legsim / MuJoCo, "
              "instructions | MuJoCo box err (self) | legsim / MuJoCo at it, wall | ..., instructions |",
              "|---|---|---|---|---|---|---|"]
    mj_rows = {r["h"]: r for r in rows if r["engine"].startswith("mujoco") and r["ok"]}

    def ratio(t):
        c, rel, m = t
        return "n/a" if rel == "n/a" or not math.isfinite(m) else f"{'<= ' if rel == '<=' else ''}{c / m:.2f}"
    for o in equal_error(w):
        r = mj_rows[o["h"]]
        lines.append(f"| {o['h']:g} | {_e(r['box'])} | {ratio(o['box_wall'])} | {ratio(o['box_instr'])} "
                     f"| {_e(r['box_self'])} | {ratio(o['box_self_wall'])} | {ratio(o['box_self_instr'])} |")
    return lines


def hw_sample() -> float:
    from .hexapod_walk import SAMPLE_S
    return SAMPLE_S


def markdown(data: dict, before: dict, after: dict | None = None) -> str:
    rows = data["held"]
    lines = [f"Regenerate: `{COMMAND}` (liblegsim built; or, from the repository, `{MODULE_COMMAND}`)", "",
             "# The hexapod in legsim and MuJoCo: error against the reference and cost per step", ""]
    lines += results.machine_section(before, after)
    lines += ["Reference: the bench's HexapodModel (minimal coordinates, the held feet's legs "
              "eliminated, DOP853 at rtol 1e-12). Errors at t = 0.2 s, max abs over the "
              "entries: box place (m), box rotation (the angle of R_ref^T R, rad), rowing angles "
              "(rad), the 12 actuator lengths (m), the held feet's ground forces (N, world). "
              "Scenes (tests/bench/test_hexapod_reference.py): a_six, the stand at box height "
              "1 m on all six feet held, the statics' forces + 50 N on the right legs' upper "
              "actuators; b_tripod, legs 0, 2, 4 held at unequal rowing angles, 1, 3, 5 free "
              "with their feet lifted, + 50 N on legs 0 and 2's uppers. legsim: "
              "legsim.Hexapod.sim with the stance's feet stuck, its RK4 on the rotation group "
              "(+ projection), one step(n) call. MuJoCo: free box, hinge yokes, the legs' "
              "spanning trees with loops and held feet as `connect` equalities, soft: solref "
              "(2h, 1), solimp 0.9999; RK4, mujoco.rollout. Cost: wall time of the stepping "
              "loop / steps, the smallest of the repeats, set-up excluded; per simulated "
              "second = per step / h. Instructions (at h = 1 ms): valgrind callgrind over one run, "
              "collecting only inside MuJoCo's mj_step (mujoco.rollout calls it once a step) or "
              "legsim's robot_step (legsim_hexapod_step calls it once a step). "
              "Model: bench/legsim_bench/benchmarks/peers/mujoco_hexapod.py.",
              "",
              "| scene | engine | method | h (s) | box (m) | rotation (rad) | rowing (rad) | lengths (m) "
              "| forces (N) | cost per step (us) | cost per simulated s (ms) | instructions per step |",
              "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        if not r["ok"]:
            lines.append(f"| {r['scene']} | {r['engine']} | {r['method']} | {r['h']:g} | failed "
                         f"| {r.get('note', '')} | | | | | | |")
            continue
        errs = " | ".join(f"{r[k]:.2e}" for k in ERRS)
        lines.append(f"| {r['scene']} | {r['engine']} | {r['method']} | {r['h']:g} | {errs} "
                     f"| {r['per_step_s'] * 1e6:.1f} | {r['per_step_s'] / r['h'] * 1e3:.1f} "
                     f"| {_count(r.get('instructions'))} |")
    if data.get("walk"):
        lines += markdown_walk(data["walk"])
    return "\n".join(lines) + "\n"


def write(out: Path, **kw) -> Path:
    return peer_tables.write(out, "hexapod_peers.md", collect, markdown, **kw)


def configure_parser(p: argparse.ArgumentParser) -> argparse.ArgumentParser:
    """The options of `legsim-bench hexapod-peers`."""
    results.add_output_options(p)
    p.add_argument("--repeats", type=int, default=3,
                   help="timing repeats of every engine (the smallest cost is kept)")
    p.add_argument("--scenes", nargs="+", choices=mh.SCENES, default=list(mh.SCENES))
    p.add_argument("--no-callgrind", action="store_true", help="no instruction counts (valgrind)")
    p.add_argument("--no-walk", action="store_true", help="the held-feet scenes only (no walking scene)")
    return p


def run(a) -> int:
    if a.repeats < 1:
        raise SystemExit("hexapod-peers: --repeats must be at least 1")
    print(write(results.output_dir(a), scenes=tuple(a.scenes), repeats=a.repeats,
                     callgrind=not a.no_callgrind and shutil.which("valgrind") is not None,
                     walk=not a.no_walk))
    return 0


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description="The hexapod in legsim and MuJoCo: error against the "
                                            "bench's reference and cost per step")
    return run(configure_parser(p).parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
