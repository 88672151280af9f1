#!/usr/bin/env python3
"""No OK step creates energy beyond the work of the applied loads: a seeded hostile campaign
on the two-leg robot (models/robot.toml) with both integrators, and the per-step energy
balance of every step that returns OK.

    LEGSIM_ROOT=$PWD PYTHONPATH=$PWD/python:$PWD/bench python firmware_core/benchmarks/energy_balance.py
        [--runs 400] [--steps 40] [--seed 1] [--integrators rk4,galpha] [--h 2e-3,1e-3,5e-4,2.5e-4]
        [--order]     # the worst per-step gain against h (docs/design/energy.md's table)

The balance of one step (docs/design/energy.md). The robot's actuators are force-commanded
(constant forces F_a, so no servo stores or dissipates energy) and its loads are constant
point forces F_k at the feet; with gravity, all are conservative over a step, so

    H = kinetic + gravity's potential - sum_k F_k . p_k - sum_a F_a L_a

(p_k the load's point, L_a the actuator's length) changes over an exact step only by the
work of the contacts and stops: friction's (<= 0 when it acts against the slip with N >= 0)
and the inelastic impacts' (<= 0). A step creates energy when

    dH = H_end - H_start > tol,  tol = RTOL * moved + ATOL_REL * size + newton_tol * F,

moved = |dT| + |dV_g| + sum |F_k . dp_k| + sum |F_a dL_a| (the energy the step moved between
its forms), size = |T| + |V_g| + sum |F_k . p_k| + sum |F_a L_a| at both ends (the
round-off of forming H), F = sum |F_k| + sum |F_a| + the weight (what the forces do through
a projection held to newton_tol, m). RTOL and ATOL_REL are the module's constants below; a gain above
them is classified by the step's events and measured against h (--order).
"""
from __future__ import annotations

import argparse
import dataclasses
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path[:0] = [str(ROOT / "python")]

import legsim  # noqa: E402

ROBOT = ROOT / "models" / "robot.toml"
RTOL = 1e-6        # of the energy moved in the step
ATOL_REL = 1e-12   # of the energies' size (round-off of the sums)
STEPS = (2e-3, 1e-3, 5e-4, 2.5e-4)
MAX_LOAD_N = 1e6   # the API's range for a point load (LEGSIM_MAX_FORCE_N)


@dataclasses.dataclass
class Case:
    """One run of the campaign: the ground, the start, the loads (all SI)."""
    seed: int
    integrator: str
    h: float
    slope: float
    mu_s: float
    mu_k: float
    start: str                      # "stand", "slide", "throw"
    lengths: tuple | None           # actuator lengths of the stance (m), None: the stand's
    feet_mid: float
    velocity: tuple                 # (vx, vy, omega) of the start (rigid motion about the box)
    lift: float                     # m along the normal (throw)
    loads: tuple                    # ((Fx, Fy) right, (Fx, Fy) left), N
    forces: tuple                   # actuator forces, N
    switch_at: int = -1             # step at which the loads switch to loads2 (a push)
    loads2: tuple = ((0.0, 0.0), (0.0, 0.0))
    steps: int = 40

    def label(self) -> str:
        return (f"seed {self.seed} {self.integrator} h={self.h:g} {self.start} slope={self.slope:.3f} "
                f"mu=({self.mu_s:.3f},{self.mu_k:.3f})")


@dataclasses.dataclass
class StepBalance:
    """One OK step's balance (J) and what happened in it."""
    case: Case
    step: int
    t: float
    dH: float
    tol: float
    moved: float
    events: list
    states_before: tuple
    states_after: tuple
    normals: tuple
    slips: tuple

    @property
    def creates(self) -> bool:
        return self.dH > self.tol

    def pulling(self, force_scale: float) -> list[int]:
        """The closed feet (stuck or sliding) whose normal force pulls at the step's end
        (below -1e-9 of force_scale, N): a foot that would pull must have lifted off."""
        return [k for k, (st, n) in enumerate(zip(self.states_after, self.normals))
                if st != "free" and n < -1e-9 * force_scale]


class Robot:
    """The robot's sim with the balance's terms read through the public API."""

    def __init__(self, integrator: str, h: float, slope=0.0, mu_s=0.6, mu_k=0.5):
        model = legsim.Model.from_toml(str(ROBOT))
        g = model.desc.ground
        g.slope_rad, g.mu_static, g.mu_kinetic = slope, mu_s, mu_k
        self.sim = legsim.Sim(model, integrator=integrator, step=h)
        self.model = model
        names = self.sim.model.contact_names
        # which contact's foot carries each load (the load sits on the foot point)
        self.load_contact = [names.index(n.replace("foot_load", "foot"))
                             for n in self.sim.model.force_names]
        self.loads = np.zeros((len(self.load_contact), 2))
        self.forces = np.zeros(self.sim.n_actuators)
        self.masses = self.sim.model.masses
        self.inertias = self.sim.model.inertias
        self.gravity = np.asarray(self.sim.model.gravity, dtype=float)
        self.newton_tol = self.sim.options["newton_tol"]

    def set_loads(self, loads, forces=None) -> None:
        for i, F in enumerate(loads):
            self.sim.set_force(i, F)
            self.loads[i] = F
        if forces is not None:
            for a, f in enumerate(forces):
                self.sim.command_force(a, f)
                self.forces[a] = f

    def force_scale(self) -> float:
        """N: the loads' and actuator forces' sizes and the weight."""
        return float(np.sum(np.linalg.norm(self.loads, axis=1)) + np.sum(np.abs(self.forces)) +
                     np.sum(self.masses) * np.linalg.norm(self.gravity))

    def projection_slack(self) -> float:
        """J: the most the forces can do through a projection held to newton_tol (positions
        are on Phi = 0 only to that): newton_tol (sum |F_k| + sum |F_a| + weight)."""
        return self.newton_tol * self.force_scale()

    def terms(self) -> np.ndarray:
        """(T, V_g, -sum F_k . p_k, -sum F_a L_a) in J at the current state."""
        s = self.sim
        q, v = s.q.reshape(-1, 3), s.qd.reshape(-1, 3)
        ke = 0.5 * np.sum(self.masses * (v[:, 0] ** 2 + v[:, 1] ** 2) + self.inertias * v[:, 2] ** 2)
        vg = -np.sum(self.masses * (q[:, :2] @ self.gravity))
        pos = s.contacts()["position"]
        vl = -sum(float(self.loads[i] @ pos[k]) for i, k in enumerate(self.load_contact))
        va = -float(self.forces @ s.actuator_lengths()[0])
        return np.array([ke, vg, vl, va])


def rigid_velocity(sim: legsim.Sim, v, omega: float) -> np.ndarray:
    """qd of a rigid motion of the whole robot: the box centre at v (m/s), all bodies turning
    at omega (rad/s) about it (the joints' constraints hold: the robot moves as one body)."""
    q = sim.q.reshape(-1, 3)
    c = q[0, :2]
    qd = np.zeros_like(q)
    r = q[:, :2] - c
    qd[:, 0] = v[0] - omega * r[:, 1]
    qd[:, 1] = v[1] + omega * r[:, 0]
    qd[:, 2] = omega
    return qd.reshape(-1)


def make_robot(c: Case) -> Robot:
    """The case's robot at its start, its loads and forces applied (raises if the start is
    refused, e.g. a stance out of reach)."""
    rb = Robot(c.integrator, c.h, c.slope, c.mu_s, c.mu_k)
    s = rb.sim
    s.assemble_on_ground(None if c.lengths is None else list(c.lengths), c.feet_mid)
    rb.set_loads(c.loads, c.forces)
    if c.start == "stand":
        return rb
    t = np.array([math.cos(c.slope), math.sin(c.slope)])
    n = np.array([-t[1], t[0]])
    if c.start == "slide":   # translation along the line: both feet slide
        qd = rigid_velocity(s, c.velocity[0] * t, 0.0)
        s.set_state(s.q, qd)
        for k in range(s.n_contacts):
            s.set_contact(k, "sliding")
        return rb
    # a throw: lifted along the normal, a rigid velocity, both feet free
    q = s.q.reshape(-1, 3).copy()
    q[:, :2] += c.lift * n
    s.set_state(q.reshape(-1), None)
    s.set_state(s.q, rigid_velocity(s, c.velocity[:2], c.velocity[2]))
    return rb


def refine(rb: Robot, before: bytes, h: float, ns=(1, 2, 4, 8, 16)) -> list[float]:
    """The gain dH (J) over one step of h taken from the saved state `before` as n steps of
    h / n, per n (NaN where a part fails): a gain the integrator's truncation error makes
    shrinks like n^-p (p its order: 4 for RK4, 2 for generalized-alpha); one a law makes
    (a force where it must not act) stays. The sim is left as it was."""
    s = rb.sim
    opts = type(s._options).from_buffer_copy(s._options)
    now = s._save()
    out = []
    for n in ns:
        s._restore(before)
        s._options = type(opts).from_buffer_copy(opts)
        h0 = rb.terms()
        try:
            if n > 1:
                s.set_options(step=h / n)
            s.step(n)
            out.append(float(np.sum(rb.terms() - h0)))
        except legsim.LegsimError:
            out.append(float("nan"))
    s._restore(now)
    s._options = opts
    return out


def run_case(c: Case, on_step=None) -> tuple[list[StepBalance], str | None]:
    """Steps the case; the balance of every OK step, and the error that ended it (None).
    on_step(robot, balance, state_before) is called after each OK step."""
    try:
        rb = make_robot(c)
    except legsim.LegsimError as e:
        return [], f"start refused: {e.status_name}"
    s = rb.sim
    out = []
    s.clear_events()
    h0 = rb.terms()
    c0 = s.contacts()
    for i in range(c.steps):
        if i == c.switch_at:
            rb.set_loads(c.loads2)
            h0 = rb.terms()
        before = s._save() if on_step else None
        try:
            s.step(1)
        except legsim.LegsimError as e:
            return out, e.status_name
        h1 = rb.terms()
        c1 = s.contacts()
        d = h1 - h0
        moved = float(np.sum(np.abs(d)))
        size = float(np.sum(np.abs(h0)) + np.sum(np.abs(h1)))
        tol = RTOL * moved + ATOL_REL * size + rb.projection_slack()
        b = StepBalance(c, i, s.time, float(np.sum(d)), tol, moved, s.events(),
                        tuple(c0["state"]), tuple(c1["state"]), tuple(c1["normal"]), tuple(c1["slip"]))
        s.clear_events()
        out.append(b)
        if on_step:
            on_step(rb, b, before)
        h0, c0 = h1, c1
    return out, None


def random_case(seed: int, integrator: str, h: float, steps: int = 40, scale: float = 1.0) -> Case:
    """A hostile case drawn from seed: any slope up to 1 rad, friction 0 .. 2 (rarely up to
    10), loads log-uniform up to the API's 1e6 N in any direction, actuator forces anywhere
    in +-1500 N, slides up to 50 m/s, throws up to 30 m/s and 20 rad/s, pushes switched on
    mid-run. scale < 1 shrinks the loads' top (to MAX_LOAD_N scale^3) and the speeds (by
    scale): the same draws, a milder robot."""
    rng = np.random.default_rng(seed)
    slope = float(rng.choice([0.0, rng.uniform(-1.0, 1.0)]))
    mu_s = float(rng.choice([rng.uniform(0, 2), rng.uniform(0, 10), 0.0], p=[0.8, 0.1, 0.1]))
    mu_k = float(mu_s * rng.choice([1.0, rng.uniform(0, 1)]))
    start = str(rng.choice(["stand", "slide", "throw"]))
    lengths = None
    if rng.uniform() < 0.5:
        lengths = (rng.uniform(0.45, 0.75), rng.uniform(0.40, 0.65), rng.uniform(0.45, 0.75),
                   rng.uniform(0.40, 0.65))

    def load():
        if rng.uniform() < 0.3:
            return (0.0, 0.0)
        mag = 10 ** rng.uniform(0, math.log10(MAX_LOAD_N * scale ** 3))
        a = rng.uniform(-math.pi, math.pi)
        return (mag * math.cos(a), mag * math.sin(a))

    loads = (load(), load())
    forces = tuple(float(x) for x in rng.uniform(-1500, 1500, 4) * rng.choice([0, 1, 1]))
    v = (float(rng.uniform(-50, 50)) * scale, 0.0, 0.0) if start == "slide" else \
        (float(rng.uniform(-30, 30)) * scale, float(rng.uniform(-30, 30)) * scale, float(rng.uniform(-20, 20)) * scale)
    lift = float(rng.uniform(0, 1.0)) if start == "throw" else 0.0
    switch_at = int(rng.integers(1, steps)) if rng.uniform() < 0.3 else -1
    return Case(seed, integrator, h, slope, mu_s, mu_k, start, lengths, float(rng.uniform(-1, 1)),
                v, lift, loads, forces, switch_at, (load(), load()), steps)


ORDER = {"rk4": 4, "galpha": 2}


def classify(gains: list[float], integrator: str, tol: float) -> str:
    """What a gain is, from the gains of the same step taken as n = 1, 2, 4, ... part steps:
    "truncation" when they fall at the integrator's order (within half an order) over the
    last two halvings, or are below tol from n = 4 on (the step was not resolved: the
    integrator's error, gone once it is); "law" when the finest keeps more than half the
    first (it does not shrink with h: a force or impulse where it must not act); else "slow"
    (it shrinks below the order)."""
    g = np.asarray(gains)
    if not np.all(np.isfinite(g)):
        return "failed-refinement"
    if np.all(g[2:] <= tol):
        return "truncation"
    p = ORDER[integrator]
    rates = [math.log2(max(g[i], 1e-300) / max(g[i + 1], 1e-300)) for i in range(len(g) - 3, len(g) - 1)]
    if min(rates) >= p - 0.5:
        return "truncation"
    if g[-1] > 0.5 * g[0]:
        return "law"
    return "slow"


FURTHER = (32, 64, 128, 256)


def refine_further(rb: Robot, b: StepBalance, before: bytes) -> None:
    """A gain that does not shrink by 16 parts (or whose refinement failed), taken again in
    32 .. 256 parts and classified on those: an RK4 step whose event location cut it into
    part steps has taken them in up to 16 sub-steps each (step.cpp, part_integrate), so its
    16-part refinement repeats it. b.gains becomes those of 1, 32, 64, 128, 256 parts when they
    all succeed."""
    fine = refine(rb, before, b.case.h, FURTHER)
    if all(np.isfinite(fine)):
        b.gains = b.gains[:1] + fine
        b.kind = classify(b.gains, b.case.integrator, b.tol)
        b.further = True


def campaign(runs: int, seed0: int, integrators, hs, steps: int, verbose=False):
    """Runs the cases of seeds seed0 .. seed0 + runs - 1."""
    """All the cases' OK steps that create energy, with counts."""
    found, pulling, n_ok, n_fail, n_refused = [], [], 0, 0, 0
    for r in range(runs):
        for integ in integrators:
            for h in hs:
                c = random_case(seed0 + r, integ, h, steps)
                kept = []

                def on_step(rb, b, before):
                    if b.pulling(rb.force_scale()):
                        pulling.append(b)
                    if b.creates:
                        b.gains = refine(rb, before, b.case.h)
                        b.kind = classify(b.gains, b.case.integrator, b.tol)
                        if b.kind in ("law", "failed-refinement"):
                            refine_further(rb, b, before)
                bal, err = run_case(c, on_step)
                n_ok += len(bal)
                if err is not None:
                    if err.startswith("start refused"):
                        n_refused += 1
                    else:
                        n_fail += 1
                for b in bal:
                    if b.creates:
                        found.append(b)
                        if verbose:
                            print(describe(b))
    for b in pulling:
        print("a closed foot pulls:", describe(b))
    return found, dict(ok_steps=n_ok, failed_runs=n_fail, refused_starts=n_refused,
                       steps_with_a_pulling_closed_foot=len(pulling))


def order_table(runs: int, seed0: int, integrators, hs, duration: float, scales=(1.0, 0.3, 0.1)) -> str:
    """The worst per-step gain (J) over the same cases at each h (each case run for `duration`
    s), apart for the steps without a contact or stroke event and those with one, and the
    order it shrinks with (log2 of the ratio from the step size before): a Markdown table."""
    lines = ["| cases | integrator | h (s) | OK steps | worst gain, no event (J) | order | "
             "worst gain / moved | worst gain, event steps (J) | order |",
             "|---|---|---|---|---|---|---|---|---|"]
    for scale in scales:
        for integ in integrators:
            prev = None
            for h in hs:
                w = [0.0, 0.0, 0.0]   # no event (J), its relative, event steps (J)
                n = 0
                for r in range(runs):
                    c = random_case(seed0 + r, integ, h, scale=scale)
                    c.steps = int(round(duration / h))
                    if c.switch_at >= 0:   # the push at the same time for every h
                        c.switch_at = int(round(c.switch_at / 40 * duration / h))
                    bal, _ = run_case(c)
                    n += len(bal)
                    for b in bal:
                        ev = [e for e in b.events if e not in ("contact_ambiguous", "force_saturated")]
                        if ev:
                            w[2] = max(w[2], b.dH)
                        else:
                            w[0] = max(w[0], b.dH)
                            w[1] = max(w[1], b.dH / max(b.moved, 1e-300))
                order = ["", ""] if prev is None else [
                    f"{math.log2(a / b):.2f}" if a > 0 and b > 0 else "-" for a, b in ((prev[0], w[0]), (prev[2], w[2]))]
                label = f"loads <= {MAX_LOAD_N * scale ** 3:.0e} N, speeds x {scale:g}"
                lines.append(f"| {label} | {integ} | {h:g} | {n} | {w[0]:.2e} | {order[0]} | {w[1]:.2e} | "
                             f"{w[2]:.2e} | {order[1]} |")
                prev = w
    return "\n".join(lines)


def describe(b: StepBalance) -> str:
    kind = getattr(b, "kind", "")
    gains = " ".join(f"{x:.3g}" for x in getattr(b, "gains", []))
    if getattr(b, "further", False):
        gains = "n = 1, " + ", ".join(map(str, FURTHER)) + ": " + gains
    return (f"[{kind}: {gains}] {b.case.label()} step {b.step}: dH = {b.dH:+.4g} J (tol {b.tol:.3g}, moved {b.moved:.4g}) "
            f"events {b.events} {b.states_before}->{b.states_after} N {np.round(b.normals, 3)} "
            f"slip {np.round(b.slips, 3)}")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--runs", type=int, default=400)
    ap.add_argument("--steps", type=int, default=40)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--integrators", default="rk4,galpha")
    ap.add_argument("--h", default=",".join(f"{h:g}" for h in STEPS))
    ap.add_argument("-v", "--verbose", action="store_true")
    ap.add_argument("--order", action="store_true", help="the worst gain against h (a table)")
    ap.add_argument("--duration", type=float, default=0.02, help="s, each case's run (--order)")
    a = ap.parse_args(argv)
    integrators = a.integrators.split(",")
    hs = [float(x) for x in a.h.split(",")]
    if a.order:
        print(order_table(a.runs, a.seed, integrators, hs, a.duration))
        return 0
    t0 = time.time()
    found, counts = campaign(a.runs, a.seed, integrators, hs, a.steps, a.verbose)
    print(f"{counts}, {len(found)} steps create energy, {time.time() - t0:.1f} s")
    kinds = {}
    for b in found:
        key = (b.case.integrator, b.kind, "+".join(sorted(b.events)) or "-")
        kinds[key] = kinds.get(key, 0) + 1
    for key, n in sorted(kinds.items()):
        print(f"  {n:5d} {key}")
    # every gain that does not shrink with h, then the largest others
    for b in found:
        if b.kind in ("law", "failed-refinement"):
            print(describe(b))
    for b in sorted(found, key=lambda b: -b.dH / max(b.moved, 1e-300))[:20]:
        if b.kind not in ("law", "failed-refinement"):
            print(describe(b))
    return 0 if not any(b.kind == "law" for b in found) and not counts["steps_with_a_pulling_closed_foot"] else 1


if __name__ == "__main__":
    sys.exit(main())
