"""The robot peers' figures, and legsim's beside them: error against the reference and
cost per step.

    python -m legsim_bench.benchmarks.peers.robot_results -o DIR        # from bench/
    python -m legsim_bench.benchmarks.peers.robot_results --update-results

writes ``robot_peers.md`` (default out/bench-results/): the machine section
(results.machine_section), then per engine (legsim, MuJoCo, Siconos), scene and
step h: err_z (the largest deviation over the whole trajectory, sampled every
1 ms, of the box pose and the four leg angles, m or rad), err_NT (the largest
error of the ground forces N, T of both feet at the end, N) and the cost per
step and per simulated second.

Cost, every engine the smallest over ``--repeats`` runs of the scene, set-up
(model building, start state) outside the clock: legsim, the wall time of one
``legsim_step(sim, n)`` call over the scene through its Python API (compiled
loop; legsim_robot.py); MuJoCo, of ``mujoco.rollout`` (compiled mj_step loop,
one thread, through the Python bindings); Siconos, of its TimeStepping loop
(computeOneStep + nextStep), which includes this peer's Python callbacks
(mass, forces, contact rows); each divided by the steps.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from .. import results
from . import peer_tables
from . import legsim_robot as lr
from . import mujoco_robot as mr
from . import robot_scenes as rs
from . import siconos_robot as sr

SCENES = ("fig7_a", "fig7_b", "servo_stand")
MUJOCO_H = (1e-3, 5e-4, 2e-4, 1e-4)
SICONOS_H = (1e-3, 5e-4, 2e-4)
LEGSIM_H = (1e-3, 5e-4, 2e-4)


def collect(scenes=SCENES, mujoco_h=MUJOCO_H, siconos_h=SICONOS_H, repeats: int = 3,
            legsim_h=LEGSIM_H) -> list[dict]:
    rows = []
    for name in scenes:
        sc = rs.setup(name)
        ref = rs.reference(sc, np.arange(0, int(round(sc.t_end / 1e-3)) + 1) * 1e-3)
        if legsim_h and lr.available():
            for method in lr.METHODS:
                for h in legsim_h:
                    rows.append(_row(lr.compare(sc, h, method, repeats=repeats, ref=ref), name))
        elif legsim_h:
            rows.append({"engine": "legsim", "scene": name, "method": "-", "h": float("nan"),
                         "ok": False, "err_z": float("nan"), "err_NT": float("nan"),
                         "per_step_s": float("nan"),
                         "note": "liblegsim.so not found (build the target legsim; LEGSIM_LIB_DIR)"})
        for h in mujoco_h:
            c = mr.compare(sc, h, repeats=repeats, ref=ref)
            rows.append(_row(c, name))
        if siconos_h and sr.available():
            for h in siconos_h:
                rows.append(_row(siconos_compare(name, h, ref, repeats), name))
        elif siconos_h:
            rows.append({"engine": "siconos", "scene": name, "method": "-", "h": float("nan"),
                         "ok": False, "err_z": float("nan"), "err_NT": float("nan"),
                         "per_step_s": float("nan"), "note": sr.probe()[1]})
    return rows


def siconos_compare(name: str, h: float, ref: dict, repeats: int) -> dict:
    """sr.compare (errors and the first run's cost), its cost then the smallest over
    ``repeats`` runs (each a process of its own; only its stepping loop is timed)."""
    c = sr.compare(name, h, ref=ref)
    for _ in range(max(1, repeats) - 1):
        c["per_step_s"] = min(c["per_step_s"], sr.run(name, h, every=int(round(1e-3 / h)))["per_step_s"])
    return c


def _row(c: dict, scene: str) -> dict:
    return {"engine": c["engine"], "scene": scene, "method": c["method"], "h": c["h"], "ok": c["ok"],
            "err_z": c["err_z"], "err_NT": c["err_NT"], "per_step_s": c["per_step_s"]}


def markdown(rows: list[dict], before: dict, after: dict | None = None) -> str:
    lines = ["# The two-leg robot in legsim and the peers: error against the reference and cost per step", ""]
    lines += results.machine_section(before, after)
    lines += ["Reference: the bench's RobotModel (both feet stuck, DOP853 at rtol 1e-11). "
              "err_z: max over t (every 1 ms) and the 7 coordinates (box x, y, psi; per leg "
              "phi3, phi6 in its frame) of |z - z_ref| (m or rad). err_NT: max over both feet "
              "of |N - N_ref|, |T - T_ref| at the end (N). Cost: wall time of the scene's stepping "
              "loop / steps, the smallest of the repeats, set-up excluded; per simulated second "
              "= per step / h. legsim: its Python API, both feet set stuck at the start pose, "
              "one legsim_step(sim, n) call (compiled loop). MuJoCo: soft contacts and loop "
              "closures, solref (2h, 1), RK4, mujoco.rollout (compiled loop). Siconos: "
              "Moreau-Jean theta 0.5, FrictionContact(2) Lemke, its loop includes the peer's "
              "Python callbacks. Scenes: docs/design/robot-on-ground.md sections 4 and 7, "
              "bench/legsim_bench/benchmarks/peers/robot_scenes.py.", "",
              "| engine | method | scene | h (s) | err_z | err_NT (N) | cost per step (us) "
              "| cost per simulated s (ms) |",
              "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        if not r["ok"]:
            lines.append(f"| {r['engine']} | {r['method']} | {r['scene']} | {r['h']:g} | failed "
                         f"| {r.get('note', '')} | | |")
            continue
        lines.append(f"| {r['engine']} | {r['method']} | {r['scene']} | {r['h']:g} | {r['err_z']:.2e} "
                     f"| {r['err_NT']:.2e} | {r['per_step_s'] * 1e6:.1f} "
                     f"| {r['per_step_s'] / r['h'] * 1e3:.1f} |")
    return "\n".join(lines) + "\n"


def write(out: Path, **kw) -> Path:
    return peer_tables.write(out, "robot_peers.md", collect, markdown, **kw)


def configure_parser(p: argparse.ArgumentParser) -> argparse.ArgumentParser:
    """The options of `legsim-bench robot-peers` (and of python -m legsim_bench.benchmarks.peers.robot_results)."""
    results.add_output_options(p)
    p.add_argument("--repeats", type=int, default=3,
                   help="timing repeats of every engine (the smallest cost is kept)")
    p.add_argument("--scenes", nargs="+", choices=SCENES, default=list(SCENES))
    p.add_argument("--no-siconos", action="store_true", help="legsim and MuJoCo only")
    return p


def run(a) -> int:
    if a.repeats < 1:
        raise SystemExit("robot-peers: --repeats must be at least 1")
    path = write(results.output_dir(a), scenes=tuple(a.scenes), repeats=a.repeats,
                 siconos_h=() if a.no_siconos else SICONOS_H)
    print(path)
    return 0


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description="The two-leg robot in legsim, MuJoCo and Siconos: error "
                                            "against the bench's reference and cost per step")
    return run(configure_parser(p).parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
