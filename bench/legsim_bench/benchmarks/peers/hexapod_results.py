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
"""
from __future__ import annotations

import argparse
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


def collect(scenes=mh.SCENES, hs=H, repeats: int = 3, callgrind: bool = True) -> list[dict]:
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


def _count(ir) -> str:
    return "-" if ir is None else f"{ir:,.0f}"


def markdown(rows: list[dict], before: dict, after: dict | None = None) -> str:
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
              "legsim's robot_step (legsim_hexapod_step calls it once a step). Model: bench/legsim_bench/benchmarks/peers/mujoco_hexapod.py.",
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
    return p


def run(a) -> int:
    if a.repeats < 1:
        raise SystemExit("hexapod-peers: --repeats must be at least 1")
    print(write(results.output_dir(a), scenes=tuple(a.scenes), repeats=a.repeats,
                     callgrind=not a.no_callgrind and shutil.which("valgrind") is not None))
    return 0


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description="The hexapod in legsim and MuJoCo: error against the "
                                            "bench's reference and cost per step")
    return run(configure_parser(p).parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
