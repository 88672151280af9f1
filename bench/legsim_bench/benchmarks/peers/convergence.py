"""Work-precision of the peer engines on the leg: error at t_end vs h, timing.

    python -m legsim_bench.benchmarks.peers.convergence            # from bench/, markdown table
    python -m legsim_bench.benchmarks.peers.convergence --json out.json --h 1e-3 1e-4 1e-5

For each peer (Exudyn, MuJoCo), method, variant and scene, every step h is
run from the stand pose to t_end (0.1 s) and compared with the reference
(:mod:`.reference`: the bench's reference model, else the peers' selfref) on
the same error measure:

* pos_err: max over the six bodies of |r_i - r_i,ref| (m, centres);
* ang_err: max over the bodies of |phi_i - phi_i,ref| (rad);

plus two checks that need no reference: the largest joint residual of *our*
constraint equations in the peer's final state (m or rad), and the energy
balance E(t) - E(0) - sum_a F_a (l_a(t) - l_a(0)) (J; zero for the exact
solution: constant actuator forces do work F dl, nothing dissipates).

Timing: wall_s is the engine's integration only (time.perf_counter around
Exudyn's SolveDynamic / mujoco.rollout, model building and output mapping
excluded), best of ``--repeats`` runs; per_sim_s = wall_s / t_end.
"""
from __future__ import annotations

import argparse
import json
import math
import sys

import numpy as np

from . import exudyn_leg, leg_model as lm, mujoco_leg
from .reference import reference

PEERS = {
    "exudyn": (exudyn_leg, exudyn_leg.METHODS),
    "mujoco": (mujoco_leg, ("rk4", "euler")),
}
DEFAULT_H = (1e-3, 5e-4, 2e-4, 1e-4, 5e-5, 2e-5, 1e-5)


def errors(q: np.ndarray, q_ref: np.ndarray) -> tuple:
    d = (np.asarray(q) - np.asarray(q_ref)).reshape(-1, 3)
    return float(np.max(np.hypot(d[:, 0], d[:, 1]))), float(np.max(np.abs(d[:, 2])))


def energy_balance(model: lm.LegModel, scene: str, q0, q, qd) -> float:
    forces = np.array(lm.scene_forces(model, scene))
    work = float(forces @ (lm.actuator_lengths(model, q) - lm.actuator_lengths(model, q0)))
    return lm.energy(model, q, qd) - lm.energy(model, q0, np.zeros_like(q0)) - work


def run_one(peer: str, method: str, scene: str, variant: str, h: float, t_end: float,
            q_ref: np.ndarray, repeats: int = 1, **kw) -> dict:
    mod = PEERS[peer][0]
    model = lm.load(None, variant)
    q0 = lm.stand_q0(model)
    best = None
    for _ in range(max(1, repeats)):
        r = mod.run(scene, t_end, h, method, variant=variant, every=0, **kw)
        if best is None or r["wall_s"] < best["wall_s"]:
            best = r
    r = best
    pos, ang = errors(r["q_end"], q_ref)
    return {
        "peer": peer, "engine": r["engine"], "method": method, "variant": variant,
        "scene": scene, "h": h, "n_steps": r["n_steps"], "ok": r["ok"],
        "pos_err": pos, "ang_err": ang,
        "constraint": float(np.max(np.abs(lm.constraints(model, r["q_end"])))),
        "energy_err": float(energy_balance(model, scene, q0, r["q_end"], r["qd_end"])),
        "wall_s": r["wall_s"], "us_per_step": 1e6 * r["wall_s"] / r["n_steps"],
        "per_sim_s": r["wall_s"] / t_end,
    }


def study(scenes=("free_fall", "upper_step_50N"), variants=("revolute", "slot"),
          hs=DEFAULT_H, t_end: float = 0.1, peers=None, repeats: int = 1, log=None):
    rows, refs = [], {}
    for variant in variants:
        for scene in scenes:
            ref = reference(scene, t_end, variant=variant)
            refs[(variant, scene)] = ref["engine"]
            for peer, (mod, methods) in PEERS.items():
                if peers and peer not in peers:
                    continue
                if not mod.available():
                    if log:
                        log(f"# {peer}: not importable, skipped")
                    continue
                for method in methods:
                    for h in hs:
                        row = run_one(peer, method, scene, variant, h, t_end, ref["q"][-1],
                                      repeats)
                        row["reference"] = ref["engine"]
                        rows.append(row)
                        if log:
                            log(_fmt(row))
    return rows, refs


def _fmt(r: dict) -> str:
    return (f"| {r['peer']} | {r['method']} | {r['variant']} | {r['scene']} | {r['h']:.0e} | "
            f"{r['pos_err']:.2e} | {r['ang_err']:.2e} | {r['constraint']:.1e} | "
            f"{r['energy_err']:.1e} | {r['us_per_step']:.1f} | {r['per_sim_s']:.3f} |"
            + ("" if r["ok"] else " FAILED |"))


HEADER = ("| peer | method | variant | scene | h (s) | pos err (m) | ang err (rad) | "
          "max abs Phi | energy err (J) | us/step | wall s per sim s |\n"
          "|---|---|---|---|---|---|---|---|---|---|---|")


def versions() -> dict:
    return {"exudyn": exudyn_leg.VERSION, "mujoco": mujoco_leg.VERSION,
            "numpy": np.__version__, "python": sys.version.split()[0]}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--h", type=float, nargs="+", default=list(DEFAULT_H))
    ap.add_argument("--t-end", type=float, default=0.1)
    ap.add_argument("--scenes", nargs="+", default=list(lm.SCENES))
    ap.add_argument("--variants", nargs="+", default=list(lm.VARIANTS))
    ap.add_argument("--peers", nargs="+", default=None)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--json", default=None, help="write the rows to this file")
    a = ap.parse_args(argv)
    print(f"# versions: {versions()}")
    print(HEADER)
    rows, refs = study(a.scenes, a.variants, a.h, a.t_end, a.peers, a.repeats,
                       log=lambda s: print(s, flush=True))
    print(f"# references: { {f'{k[0]}/{k[1]}': v for k, v in refs.items()} }")
    if a.json:
        with open(a.json, "w") as f:
            json.dump({"versions": versions(), "t_end": a.t_end, "rows": rows}, f, indent=1)
    bad = [r for r in rows if not r["ok"] or not math.isfinite(r["pos_err"])]
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
