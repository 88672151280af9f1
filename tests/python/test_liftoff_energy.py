"""A sliding foot that would pull lifts off, and no run creates energy (issue 22 section 2):
the robot's right foot pushed by a 30 kN load (inside the API's 1e6 N range) down and to
the left slides, its normal force falls through zero within a step, and it lifts off. While
it slid with N > 0 its friction mu_k N took energy out; had it kept sliding with N < 0, the
friction would have pushed along the slip and made energy.

Invariants checked against the physics, not against the code's own numbers:
- the energy balance: kinetic + gravity's potential at the end <= at the start + the work of
  the applied loads (the actuators are force-commanded at 0 N, so the load is the only
  source; a constant point force's work is F . (p_end - p_start) of its point, exact) +
  a stated tolerance for the integrators' own error;
- at every step's end a closed foot's normal force is >= 0 (a foot that would pull has
  left), and the right foot has lifted off.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import legsim

from conftest import ROOT

LOAD_N = 30e3
LOAD_ANGLE = -5 * math.pi / 6   # rad: down and to the left


def _energy(s: legsim.Sim) -> float:
    """Kinetic + gravity's potential energy of the robot (J)."""
    m = s.model
    q, v = s.q.reshape(-1, 3), s.qd.reshape(-1, 3)
    ke = 0.5 * np.sum(m.masses * (v[:, 0] ** 2 + v[:, 1] ** 2) + m.inertias * v[:, 2] ** 2)
    return float(ke - np.sum(m.masses * (q[:, :2] @ m.gravity)))


@pytest.mark.parametrize("integrator", ["rk4", "galpha"])
def test_sliding_foot_under_30_kN_lifts_off_without_making_energy(integrator):
    lib = legsim.load_library("double")
    if lib.config["LEGSIM_MAX_BODIES"] < 13 or lib.config.get("LEGSIM_MAX_CONTACTS", 0) < 2:
        pytest.skip("built without room for the robot")
    h = 1e-3
    s = legsim.Sim(str(ROOT / "models" / "robot.toml"), integrator=integrator, step=h)
    s.assemble_on_ground()
    for a in range(s.n_actuators):
        s.command_force(a, 0.0)
    F = LOAD_N * np.array([math.cos(LOAD_ANGLE), math.sin(LOAD_ANGLE)])
    s.set_force("right.foot_load", F)
    e0, work, seen = _energy(s), 0.0, set()
    lifted_at = None
    for i in range(50):
        p = s.contacts()["position"][0].copy()
        s.step(1)
        c = s.contacts()
        work += float(F @ (c["position"][0] - p))
        seen |= set(s.events())
        s.clear_events()
        closed = c["state"] != "free"
        # a foot that would pull has left (round-off allowance 1e-9 of the load)
        assert np.all(c["normal"][closed] >= -1e-9 * LOAD_N), (i, c)
        if lifted_at is None and c["state"][0] == "free":
            lifted_at = i
        if lifted_at is not None and i >= lifted_at + 2:   # 2 ms of flight after it
            break
    balance = _energy(s) - e0 - work
    # the integrators' own energy error over these few steps: 1e-3 of the energy moved
    tol = 1e-3 * (abs(e0) + abs(work))
    print(f"{integrator}: lift-off in step {lifted_at} at t = {s.contact_event_time(0):.7f} s, "
          f"E0 {e0:.3f} J, work {work:.3f} J, E1 - E0 - W = {balance:.3f} J (tol {tol:.3f} J), "
          f"events {sorted(seen)}")
    assert lifted_at is not None and {"stick_to_slip", "liftoff"} <= seen
    assert balance <= tol
