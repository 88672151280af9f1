"""Actuator commands and time schedules for the reference model.

A *schedule* is a callable ``s(t) -> float`` with optional ``rate(t)`` and
``accel(t)`` (first and second time derivatives, used by inverse dynamics) and
an optional ``breakpoints`` tuple: times where the schedule is discontinuous.
The integrator stops and restarts exactly at breakpoints so that steps do not
cost accuracy.  Plain floats and plain callables are accepted wherever a
schedule is (a plain callable has no derivatives and no breakpoints).

Commands (one per actuator, in leg.toml's actuator order):

* ``ForceCommand(force)``: the actuator applies the axial force ``force``
  (N, > 0 extends: +F u on the rod, -F u on the cylinder).  No saturation and
  no stroke stops (the core refuses |F| > max_force; so does the constructor
  for a constant force when ``max_force`` is given).
* ``LengthCommand(length)``: the servo of legsim.h,
  ``F = kp (l_cmd - l) - kd l_dot`` saturated at +-max_force, with kp, kd and
  max_force from the model file.  Evaluated continuously (inside every right-
  hand-side evaluation), not sampled.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Union

import numpy as np

Schedule = Union[float, Callable[[float], float]]

__all__ = ["Hold", "Step", "Sinusoid", "Staircase", "ForceCommand", "LengthCommand",
           "evaluate", "rate", "accel", "breakpoints"]


@dataclass(frozen=True)
class Hold:
    """A constant value."""
    value: float

    def __call__(self, t: float) -> float:
        return float(self.value)

    def rate(self, t: float) -> float:
        return 0.0

    def accel(self, t: float) -> float:
        return 0.0

    breakpoints = ()


@dataclass(frozen=True)
class Step:
    """``before`` for t < t0, ``after`` for t >= t0."""
    before: float
    after: float
    t0: float

    def __call__(self, t: float) -> float:
        return float(self.after if t >= self.t0 else self.before)

    def rate(self, t: float) -> float:
        return 0.0

    def accel(self, t: float) -> float:
        return 0.0

    @property
    def breakpoints(self):
        return (float(self.t0),)


@dataclass(frozen=True)
class Sinusoid:
    """``l0 + a sin(2 pi f t + phase)``."""
    l0: float
    a: float
    f: float
    phase: float = 0.0

    def __call__(self, t: float) -> float:
        return self.l0 + self.a * math.sin(2.0 * math.pi * self.f * t + self.phase)

    def rate(self, t: float) -> float:
        w = 2.0 * math.pi * self.f
        return self.a * w * math.cos(w * t + self.phase)

    def accel(self, t: float) -> float:
        w = 2.0 * math.pi * self.f
        return -self.a * w * w * math.sin(w * t + self.phase)

    breakpoints = ()


def evaluate(s: Schedule, t: float) -> float:
    return float(s(t)) if callable(s) else float(s)


def rate(s: Schedule, t: float) -> float:
    if not callable(s):
        return 0.0
    if hasattr(s, "rate"):
        return float(s.rate(t))
    raise TypeError("this schedule has no rate(t); use Hold/Step/Sinusoid")


def accel(s: Schedule, t: float) -> float:
    if not callable(s):
        return 0.0
    if hasattr(s, "accel"):
        return float(s.accel(t))
    raise TypeError("this schedule has no accel(t); use Hold/Step/Sinusoid")


class Staircase:
    """What hil_sim holds: value v[i] after t[i] (left-continuous: at t[i] itself the previous
    value, which is what a sample taken at t[i], before the new setpoint arrives, reflects).
    A schedule of the reference model (callable, breakpoints: its integrator restarts there)."""

    def __init__(self, times, values):
        self.times = np.asarray(times, float)
        self.values = np.asarray(values, float)
        self.breakpoints = tuple(float(t) for t in self.times[1:])

    def __call__(self, t: float) -> float:
        i = int(np.searchsorted(self.times, t, side="left")) - 1
        return float(self.values[max(i, 0)])

    def rate(self, t: float) -> float:
        return 0.0

    def accel(self, t: float) -> float:
        return 0.0


def breakpoints(s) -> tuple:
    return tuple(getattr(s, "breakpoints", ()) or ())


@dataclass(frozen=True)
class ForceCommand:
    """Apply an axial force (N, > 0 extends); a float or a schedule of t."""
    force: Schedule = 0.0

    def __post_init__(self):
        if not callable(self.force) and not math.isfinite(float(self.force)):
            raise ValueError("force must be finite")


@dataclass(frozen=True)
class LengthCommand:
    """Servo to a length (m); a float or a schedule of t."""
    length: Schedule
