"""A body sliding on an inclined plane with Coulomb friction, launched across the fall line: the
closed forms (a particle; a rigid block whose centre of mass is over its contact points' centroid
translates and follows them). Pure Python, SI units.

The plane at alpha, mu_k = k tan(alpha), phi the angle between the velocity and the fall line, v
the speed. Along and across the velocity:
    dv/dt = g sin(alpha) (cos(phi) - k),   v dphi/dt = -g sin(alpha) sin(phi),
so dv/dphi = v (k - cos(phi)) / sin(phi). With u = tan(phi / 2), a launch across the fall line
(phi0 = pi / 2, u0 = 1) at v0, T0 = v0 / (g sin(alpha)) and L0 = v0 T0:
    k = 1: v (1 + cos(phi)) = v0 (1 + cos(phi0)), v = v0 (1 + u^2) / 2 -> v0 / 2;
           t(u) = T0 (1/4 - ln(u) / 2 - u^2 / 4),
           x(u) = L0 ((1 - u) / 2 + (1 - u^3) / 6)             (across),
           y(u) = L0 (-ln(u) / 4 - (1 - u^4) / 16)              (down the fall line);
    k > 1: v = v0 u^(k-1) (1 + u^2) / 2: it stops (u -> 0, heading down the fall line) at
           T = T0 k / (k^2 - 1), x_s = 2 k L0 / (4 k^2 - 1), y_s = L0 / (4 (k^2 - 1)), and with
           tan(alpha) < mu_s stays there; before,
           t(u) = T0 / 2 ((1 - u^(k-1)) / (k-1) + (1 - u^(k+1)) / (k+1)),
           x(u) = L0 / 2 ((1 - u^(2k-1)) / (2k-1) + (1 - u^(2k+1)) / (2k+1)),
           y(u) = L0 / 4 ((1 - u^(2k-2)) / (2k-2) - (1 - u^(2k+2)) / (2k+2)).
tests/model/test_spatial_block.cpp carries the same forms in C++ against the core itself.
"""
from __future__ import annotations

import math

__all__ = ["G0", "plane_axes", "across", "stop"]

G0 = 9.81  # m/s^2, the models' gravity


def plane_axes(normal) -> tuple[float, tuple, tuple]:
    """The incline of upward unit normal n (not level): its angle alpha, its unit fall line (down
    the plane) and the horizontal across it (down x n), world axes."""
    n = [float(x) for x in normal]
    alpha = math.acos(n[2])
    h = math.hypot(n[0], n[1])
    down = (n[0] / h * math.cos(alpha), n[1] / h * math.cos(alpha), -math.sin(alpha))
    across_ = (down[1] * n[2] - down[2] * n[1], down[2] * n[0] - down[0] * n[2], down[0] * n[1] - down[1] * n[0])
    return alpha, down, across_


def across(k: float, alpha: float, v0: float, t: float, g: float = G0) -> tuple[float, float, float]:
    """(x across, y down the fall line, speed) at t >= 0 of the launch across the fall line at v0,
    mu_k = k tan(alpha), k >= 1; after a stop (k > 1, t >= T) the stop's place and 0."""
    if k < 1:
        raise ValueError(f"k = {k}: the closed forms here are for k >= 1")
    s = g * math.sin(alpha)
    T0, L0 = v0 / s, v0 * v0 / s
    if k > 1 and t >= stop(k, alpha, v0, g)[0]:
        _, xs, ys = stop(k, alpha, v0, g)
        return xs, ys, 0.0

    def time(u):
        if k == 1:
            return T0 * (0.25 - 0.5 * math.log(u) - 0.25 * u * u)
        return T0 / 2 * ((1 - u ** (k - 1)) / (k - 1) + (1 - u ** (k + 1)) / (k + 1))

    lo, hi = 0.0, 1.0  # time(hi) <= t < time(lo): time falls with u
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if time(mid) > t else (lo, mid)
    u = 0.5 * (lo + hi)
    if k == 1:
        return (L0 * ((1 - u) / 2 + (1 - u ** 3) / 6), L0 * (-0.25 * math.log(u) - (1 - u ** 4) / 16),
                v0 * (1 + u * u) / 2)
    return (L0 / 2 * ((1 - u ** (2 * k - 1)) / (2 * k - 1) + (1 - u ** (2 * k + 1)) / (2 * k + 1)),
            L0 / 4 * ((1 - u ** (2 * k - 2)) / (2 * k - 2) - (1 - u ** (2 * k + 2)) / (2 * k + 2)),
            v0 * u ** (k - 1) * (1 + u * u) / 2)


def stop(k: float, alpha: float, v0: float, g: float = G0) -> tuple[float, float, float]:
    """(T, x_s, y_s): when and where the launch across the fall line stops (k > 1)."""
    if not k > 1:
        raise ValueError(f"k = {k}: it stops only for k > 1")
    s = g * math.sin(alpha)
    T0, L0 = v0 / s, v0 * v0 / s
    return T0 * k / (k * k - 1), 2 * k * L0 / (4 * k * k - 1), L0 / (4 * (k * k - 1))
