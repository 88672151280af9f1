#!/usr/bin/env python3
"""The leg alone through a stroke stop's arrival: the core (RK4 and generalized-alpha over
h = 2e-3 ... 2.5e-4 s) against the bench's leg (legsim_bench.reference.leg_stop: minimal
coordinates, the arrival located on DOP853's dense output, the impact and the held motion in
closed form).

    LEGSIM_ROOT=$PWD PYTHONPATH=$PWD/python:$PWD/bench python firmware_core/benchmarks/leg_stop_order.py

The case (tests/bench/test_leg_stops_located.py checks it): models/leg.toml hanging from its
frame, its upper stroke's minimum raised to 0.645 m (a copy), the stand's statics forces but the
upper's 300 N less: the upper arrives on its minimum at 50.4 ms and rests on it. Per integrator
and h: the core's arrival time (legsim_stroke_event_time) less the reference's, in h; the error
at 0.1 s (max over the 18 coordinates, m and rad) and its order log2(e(2h) / e(h)); at
h = 1 ms the energy the arrival's step takes (E = kinetic + gravity's potential - sum F l, conserved
but for the stop) against Carnot's. A Markdown table on stdout; results.md keeps it.
"""
from __future__ import annotations

import math
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path[:0] = [str(ROOT / "python"), str(ROOT / "bench")]

import legsim  # noqa: E402
from legsim_bench.reference.leg_stop import state_energy, stop_case, upper_stop  # noqa: E402

STROKE_MIN, PUSH, T_END = 0.645, -300.0, 0.1
STEPS = (2e-3, 1e-3, 5e-4, 2.5e-4)


def energy(s, ref, forces):
    return state_energy(s.q, s.qd, s.model.masses, s.model.inertias, ref.gravity, forces, s.actuator_lengths()[0])


def main():
    with tempfile.TemporaryDirectory() as tmp:
        path, ref, th0, forces = stop_case(ROOT / "models" / "leg.toml", tmp, STROKE_MIN, PUSH)
        run = upper_stop(ref, th0, forces, STROKE_MIN, T_END)
        model = legsim.Model.from_toml(str(path))
    print(f"reference: arrival at {run.t_arrival!r} s at {run.rate:.6f} m/s, Carnot's loss "
          f"{run.carnot:.12f} J\n")
    print("| integrator | h (s) | arrival - reference's (h) | error at 0.1 s | order | energy the arrival's step takes - Carnot's (relative) |")
    print("|---|---|---|---|---|---|")
    for integrator in ("rk4", "galpha"):
        prev = None
        for h in STEPS:
            s = legsim.Sim(model, integrator=integrator, step=h)
            s.set_state(ref.absolute_q(th0), np.zeros(18))
            for a, f in enumerate(forces):
                s.command_force(a, float(f))
            s.clear_events()
            k_arr = math.floor(run.t_arrival / h)
            s.step(k_arr)
            e_before = energy(s, ref, forces)
            s.step(1)
            lost = e_before - energy(s, ref, forces)
            dt = (s.stroke_event_time(0) - run.t_arrival) / h if s.stroke_event_mask() & 1 else math.nan
            s.step(round(T_END / h) - k_arr - 1)
            err = float(np.max(np.abs(np.asarray(s.q) - run.q_end)))
            order = f"{math.log2(prev / err):.2f}" if prev else ""
            de = f"{(lost - run.carnot) / run.carnot:+.2e}" if h == 1e-3 else ""
            print(f"| {integrator} | {h:g} | {dt:+.1e} | {err:.3e} | {order} | {de} |")
            prev = err


if __name__ == "__main__":
    main()
