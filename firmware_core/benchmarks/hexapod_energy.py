#!/usr/bin/env python3
"""No OK step of the hexapod creates energy: a seeded campaign of drops onto the ground (legsim.
HexapodSim, models/hexapod.toml) under constant force commands, and the energy balance of every
step that returns OK.

    LEGSIM_ROOT=$PWD PYTHONPATH=$PWD/python:$PWD/bench python firmware_core/benchmarks/hexapod_energy.py
        [--runs 40] [--steps 300] [--seed 1] [--h 1e-3] [--past]

Each run: the legs at random lengths (within 2 cm of the stand's, inside their strokes) and
rowing angles (+-0.3 rad), the box tilted by up to 3 degrees, the lowest foot up to 3 cm above the
ground, at rest; every actuator commanded the six feet's statics force at that pose plus up to
+-40 N, every rowing motor its statics torque plus up to +-2 N m. The commands are constant, so
with gravity they are conservative and

    H = kinetic + gravity's potential - sum_a F_a L_a - sum_l tau_l psi_l

changes over an exact step only by the contacts' work: friction's (<= 0) and the impacts'
(<= 0). A step creates energy when H_end - H_start > tol, tol = 1e-10 * size + 1e-12 J (size:
|T| + |V_g| + sum |F_a L_a| + sum |tau psi| at the step's start: H's round-off), the
integrator's own error (about 1e-10 J a step at 1 ms where nothing happens) included.
Prints the runs' statuses, the OK steps, events and impacts, and the largest gain per step.

--past: the commands drive past the strokes: in each run four actuators get 300 to 800 N more
(either way) and two rowing motors 10 to 20 N m more, so that their lengths and angles reach their
strokes' ends (stops: an inelastic impact, then held while they push); every OK step is also
checked to leave every length and rowing angle inside its stroke (to 1e-12 m, rad), and the
arrivals on a stop are counted.
"""
from __future__ import annotations

import argparse
import sys

import numpy as np


def bodies_mass(h) -> np.ndarray:
    """Each body's mass in the order of HexapodSim.body_poses (the box, per leg its yoke and bars)."""
    d = h.desc
    m = [d.box_mass_kg]
    for k in range(6):
        m.append(d.yoke_mass_kg)
        m.extend(d.leg[k].leg.body[b].mass_kg for b in range(d.leg[k].leg.n_bodies))
    return np.array(m)


def energy(sim, mass, g, F, tau):
    st = sim.state()
    z = sim.body_poses()[:, 2]
    parts = np.array([st["kinetic_energy_j"], g * float(mass @ z), -float(np.sum(F * st["length_m"])),
                      -float(np.sum(tau * st["rowing_rad"]))])
    return parts.sum(), np.abs(parts).sum()


def strokes(h) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each leg's actuators' strokes (6 x 2 x [min, max], m) and the rowing stroke (rad)."""
    d = h.desc
    act = np.array([[[d.leg[k].leg.actuator[a].stroke_min_m, d.leg[k].leg.actuator[a].stroke_max_m]
                     for a in range(2)] for k in range(6)])
    return act[..., 0], act[..., 1], np.array(d.rowing_stroke_rad[:])


def past_stroke(st, lo, hi, row) -> float:
    """How far the furthest length or rowing angle is past its stroke (negative: all inside)."""
    L, psi = st["length_m"], st["rowing_rad"]
    return float(max(np.max(lo - L), np.max(L - hi), np.max(row[0] - psi), np.max(psi - row[1])))


def off_its_stop(st, lo, hi, row) -> float:
    """How far the furthest stroke the state reports on a stop is from that stop's end (0: none)."""
    a, r = st["actuator_stop"], st["rowing_stop"]
    L, psi = st["length_m"], st["rowing_rad"]
    off = [np.abs(np.where(a < 0, L - lo, L - hi))[a != 0], np.abs(np.where(r < 0, psi - row[0], psi - row[1]))[r != 0]]
    return float(max([0.0] + [float(x.max()) for x in off if x.size]))


def one_run(h, rng, steps, dt, mass, past=False, check=None):
    """One drop of `steps` steps (0: only its random draws); check(sim, state, gain), if given, after
    each OK step."""
    import legsim

    base = h.stand_pose(1.0)
    stand = np.array(base["length_m"])
    lengths = stand + rng.uniform(-0.02, 0.02, stand.shape)
    rowing = rng.uniform(-0.3, 0.3, 6)
    axis = rng.normal(size=3)
    axis[2] = 0
    angle = np.radians(rng.uniform(0, 3))
    quat = [np.cos(angle / 2), *(np.sin(angle / 2) * axis / np.linalg.norm(axis))]
    pose = {"box_m": [0.0, 0.0, 2.0], "box_quat": quat, "rowing_rad": list(rowing), "length_m": lengths.tolist()}
    # the lowest foot `lift` above the ground (found with the box well up)
    probe = h.sim(pose, stuck=())
    lift = rng.uniform(0.0, 0.03)
    pose["box_m"][2] += lift - probe.state()["foot_m"][:, 2].min()
    s = h.statics(pose)
    F = np.clip(np.array(s["actuator_force_n"]) + rng.uniform(-40, 40, (6, 2)), -1400, 1400)
    tau = np.clip(np.array(s["rowing_torque_nm"]) + rng.uniform(-2, 2, 6), -29, 29)
    if past:
        drive = rng.choice(12, 4, replace=False)
        F.flat[drive] = np.clip(F.flat[drive] + rng.choice([-1, 1], 4) * rng.uniform(300, 800, 4), -1400, 1400)
        turn = rng.choice(6, 2, replace=False)
        tau[turn] = np.clip(tau[turn] + rng.choice([-1, 1], 2) * rng.uniform(10, 20, 2), -29, 29)
    lo, hi, row = strokes(h)
    sim = h.sim(pose, stuck=())
    sim.command(F, tau)
    g = -h.desc.gravity_mps2[2]
    H, size = energy(sim, mass, g, F, tau)
    out = {"status": "ok", "steps": 0, "events": 0, "gain": 0.0, "over": 0, "past": -1.0, "on_stop": 0,
           "off_stop": 0.0}
    for _ in range(steps):
        try:
            sim.step(1, h_s=dt)
        except legsim.LegsimError as e:
            out["status"] = e.status_name
            break
        H1, size1 = energy(sim, mass, g, F, tau)
        gain = H1 - H
        out["steps"] += 1
        out["events"] += sim.state()["events"]
        out["gain"] = max(out["gain"], gain)
        out["over"] += gain > 1e-10 * size + 1e-12
        H, size = H1, size1
        st = sim.state()
        if check is not None:
            check(sim, st, gain)
        out["past"] = max(out["past"], past_stroke(st, lo, hi, row))
        out["on_stop"] += int(np.any(st["actuator_stop"]) or np.any(st["rowing_stop"]))
        out["off_stop"] = max(out["off_stop"], off_its_stop(st, lo, hi, row))
    out["impacts"] = sim.state()["impacts"]
    out["stop_impacts"] = sim.state()["stop_impacts"]
    return out


def campaign(runs: int, steps: int, seed: int, dt: float, past: bool = False):
    import legsim

    h = legsim.Hexapod.from_toml(legsim.data_path("models/hexapod.toml"))
    mass = bodies_mass(h)
    rng = np.random.default_rng(seed)
    return [one_run(h, rng, steps, dt, mass, past) for _ in range(runs)]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--runs", type=int, default=40)
    ap.add_argument("--steps", type=int, default=300)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--h", type=float, default=1e-3)
    ap.add_argument("--past", action="store_true", help="commands that drive past the strokes")
    a = ap.parse_args(argv)
    res = campaign(a.runs, a.steps, a.seed, a.h, a.past)
    statuses = {}
    for r in res:
        statuses[r["status"]] = statuses.get(r["status"], 0) + 1
    print(f"hexapod energy campaign: {a.runs} runs of {a.steps} steps (h = {a.h:g} s, seed {a.seed}"
          f"{', driven past the strokes' if a.past else ''})")
    print(f"  statuses: {statuses}")
    print(f"  OK steps {sum(r['steps'] for r in res)}, events {sum(r['events'] for r in res)}, "
          f"impacts {sum(r['impacts'] for r in res)}")
    print(f"  largest gain in a step {max(r['gain'] for r in res):.2e} J; steps above tolerance "
          f"{sum(r['over'] for r in res)}")
    worst = max(r["past"] for r in res)
    print(f"  arrivals on a stroke's stop {sum(r['stop_impacts'] for r in res)}, steps ending with one held "
          f"{sum(r['on_stop'] for r in res)} (a held one at most {max(r['off_stop'] for r in res):.1e} off its end); "
          f"furthest past a stroke after an OK step {worst:.1e} (negative: inside)")
    return 0 if all(r["over"] == 0 for r in res) and worst <= 1e-12 else 1


if __name__ == "__main__":
    sys.exit(main())
