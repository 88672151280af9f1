"""The sim's time is its origin (the last set time, or where the step size last changed) plus
the steps since then times h: exact multiples of h, not a running sum whose round-off grows."""
from __future__ import annotations

import legsim


def test_time_is_the_origin_plus_steps_times_h():
    s = legsim.Sim(integrator="rk4", step=1e-3)  # the compiled-in leg
    s.assemble_pose(0)
    s.step(1000)
    running_sum = 0.0
    for _ in range(1000):
        running_sum += 1e-3
    assert running_sum != 1.0                     # what a sum of h gives: 1.0000000000000007
    assert s.time == 1000 * 1e-3 == 1.0 and s.step_count == 1000

    s.set_state(s.q, s.qd, t=0.25)                # a set time is the new origin
    s.step(300)
    assert s.time == 0.25 + 300 * 1e-3

    origin = s.time                               # so is the time where h changes
    s.set_options(step=5e-4)
    s.step(7)
    assert s.time == origin + 7 * 5e-4 and s.step_count == 1307
