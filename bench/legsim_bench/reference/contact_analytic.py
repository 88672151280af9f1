"""Analytic references for planar contact with Coulomb friction.

Closed-form answers that any contact implementation must reproduce (the core's
foot contact, issue 9, is to be tested against them), plus a brute-force
enumeration of the planar contact problem at acceleration level, which shows
when it has no solution or several (Painleve).  Pure Python + numpy, SI units.

* A block on a slope of angle theta (rad, > 0 downhill along +s): at rest it
  needs the friction use |T|/N = tan(theta), so it sticks for
  mu_static >= tan(theta) and slides for mu_static < tan(theta).  Sliding
  downhill it accelerates at g (sin - mu_k cos), i.e. decelerates at
  g (mu_k cos - sin); sliding uphill it decelerates at g (sin + mu_k cos).
  The energy lost is the friction work mu_k m g cos(theta) x path length.
* A perfectly inelastic impact that removes the velocity along the rows G
  (normal only: frictionless touchdown; normal and tangential: the foot sticks)
  changes the velocity by dv = -M^-1 G^T (G M^-1 G^T)^-1 G v-, and loses
  exactly the kinetic energy of that jump, 1/2 dv^T M dv (Carnot), which is
  1/2 (G v-)^T (G M^-1 G^T)^-1 (G v-): the kinetic energy of the constrained
  approach velocity.
* A rod touching down on one end, translating without spin: closed forms of
  the same impact (angular momentum about the contact point, or the normal
  impulse), an independent check of the matrix formula.
"""
from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

__all__ = ["G0", "slope_friction_use", "slope_sticks", "slide_acceleration", "SlideState", "slide",
           "inelastic_impact", "rod_touchdown", "ContactSolution", "contact_modes"]

G0 = 9.81  # m/s^2, the models' gravity


def slope_friction_use(slope: float) -> float:
    """|T|/N a body at rest on the slope needs: tan(slope)."""
    return abs(math.tan(slope))


def slope_sticks(mu_static: float, slope: float) -> bool:
    """A body at rest on the slope stays: mu_static >= tan(slope) (at
    equality the needed force lies on the cone's edge and still holds)."""
    return mu_static >= slope_friction_use(slope)


def slide_acceleration(mu_kinetic: float, slope: float, downhill: bool = True, g: float = G0) -> float:
    """Acceleration along the downhill direction (m/s^2) of a block sliding
    downhill (friction uphill: g (sin - mu cos)) or uphill (friction downhill:
    g (sin + mu cos)).  A slider downhill decelerates at g (mu cos - sin)."""
    s, c = math.sin(slope), math.cos(slope)
    return g * (s - mu_kinetic * c) if downhill else g * (s + mu_kinetic * c)


@dataclass(frozen=True)
class SlideState:
    position: float        # m, downhill positive, from the start
    velocity: float        # m/s, downhill positive
    sliding: bool
    path: float            # m, distance slid (for the friction work)
    friction_work: float   # J dissipated: mu_k m g cos(theta) * path
    stop_time: float       # s when the slide stopped (inf: it does not stop before t)


def slide(v0: float, t: float, mu_static: float, mu_kinetic: float, slope: float = 0.0,
          mass: float = 1.0, g: float = G0) -> SlideState:
    """State at time t of a block on a slope started with velocity v0
    (downhill positive; slope >= 0) under Coulomb friction, static/kinetic.

    Phases: slide with constant acceleration until the velocity vanishes;
    then it sticks if mu_static >= tan(slope), else it slides downhill from
    rest with mu_kinetic.
    """
    if not (mu_kinetic <= mu_static and slope >= 0 and t >= 0):
        raise ValueError("need mu_kinetic <= mu_static, slope >= 0, t >= 0")
    N = mass * g * math.cos(slope)
    x, v, path, tt, t_stop = 0.0, float(v0), 0.0, 0.0, math.inf
    for _ in range(3):                 # at most: slide, stop, slide downhill
        if v == 0.0:
            if slope_sticks(mu_static, slope):
                t_stop = min(t_stop, tt)
                return SlideState(x, 0.0, False, path, mu_kinetic * N * path, t_stop)
            a = slide_acceleration(mu_kinetic, slope, True, g)      # > 0: from rest downhill
            d = t - tt
            return _moved(x, v, a, d, path, mu_kinetic * N, t_stop)
        a = slide_acceleration(mu_kinetic, slope, v > 0, g)
        if v * a >= 0:                 # speeds up (or keeps) in its direction: never stops
            return _moved(x, v, a, t - tt, path, mu_kinetic * N, t_stop)
        ts = -v / a                    # time to stop
        if tt + ts >= t:
            return _moved(x, v, a, t - tt, path, mu_kinetic * N, t_stop)
        x += v * ts + 0.5 * a * ts * ts
        path += abs(v * ts + 0.5 * a * ts * ts)
        tt += ts
        v = 0.0
        t_stop = tt
    raise AssertionError("unreachable")


def _moved(x, v, a, d, path, fric, t_stop):
    dx = v * d + 0.5 * a * d * d
    return SlideState(x + dx, v + a * d, True, path + abs(dx), fric * (path + abs(dx)),
                      t_stop if math.isfinite(t_stop) else math.inf)


def inelastic_impact(M, G, v_minus):
    """Perfectly inelastic impact removing G v: returns (v_plus, impulse,
    energy_lost), where M (v+ - v-) = G^T impulse (per row of G).

    v+ = v- - M^-1 G^T (G M^-1 G^T)^-1 G v-; energy lost (Carnot) =
    1/2 (G v-)^T (G M^-1 G^T)^-1 (G v-)."""
    M = np.atleast_2d(np.asarray(M, float))
    G = np.atleast_2d(np.asarray(G, float))
    v = np.asarray(v_minus, float)
    Minv_Gt = np.linalg.solve(M, G.T)
    W = G @ Minv_Gt
    p = np.linalg.solve(W, G @ v)
    v_plus = v - Minv_Gt @ p
    lost = 0.5 * float((G @ v) @ p)
    return v_plus, -p, lost


def rod_touchdown(mass: float, length: float, angle: float, speed: float, stick: bool):
    """A uniform rod (mass, length) at ``angle`` above the horizontal, its
    lower end at the left, translating straight down at ``speed`` without
    spin, touches down on its lower end, perfectly inelastic.

    stick=True (the end stops: normal and tangential): angular momentum about
    the end is kept: omega = -3 v cos(angle) / (2 L), the centre then moves
    on a circle about the end; kinetic energy after (3/8) m v^2 cos^2.
    stick=False (frictionless: the normal velocity of the end stops): a
    vertical impulse P = v / (1/m + c^2/J), c = L/2 cos(angle), J = m L^2/12.
    Returns (v_centre_after (2,), omega_after, energy_lost)."""
    m, L, b, v = mass, length, angle, speed
    J = m * L * L / 12.0
    d = 0.5 * L * np.array([math.cos(b), math.sin(b)])      # centre minus contact end
    T0 = 0.5 * m * v * v
    if stick:
        w = -3.0 * v * math.cos(b) / (2.0 * L)
        vc = w * np.array([-d[1], d[0]])                     # omega x (centre - end)
        T1 = 0.5 * (m * L * L / 3.0) * w * w
    else:
        c = d[0]
        P = v / (1.0 / m + c * c / J)
        w = -c * P / J
        vc = np.array([0.0, -v + P / m])
        T1 = 0.5 * m * float(vc @ vc) + 0.5 * J * w * w
    return vc, w, T0 - T1


@dataclass(frozen=True)
class ContactSolution:
    modes: tuple          # per contact: "free", "stick", "slip+", "slip-", "slide"
    force: np.ndarray     # (2n,) per contact (normal, tangential)
    accel: np.ndarray     # (2n,) contact accelerations (normal, tangential)


def contact_modes(W, b, mu_static, mu_kinetic, slip_sign, tol=1e-12):
    """Every solution of the planar contact problem at acceleration level.

    Contacts are closed (gap and normal velocity zero).  a = W f + b with, per
    contact k, f = (f_n, f_t), a = (a_n, a_t) in its (normal, tangent) axes,
    W = G M^-1 G^T (the Delassus matrix) and b the contact accelerations with
    no contact force.  slip_sign[k]: 0 if the contact is at rest tangentially
    (it may stick, f_n >= 0 and |f_t| <= mu_s f_n with a_t = 0, or start to slip
    with f_t = -/+ mu_s f_n against a_t), +1/-1 if it slides that way (f_t =
    -sign mu_k f_n).  A contact may also leave (f = 0, a_n >= 0).

    A contact at rest has one cone, the static one, for sticking and for the
    onset of slip: with mu_k < mu_s in the onset too, a block that can stick
    could also "start" to slide (two solutions); the kinetic coefficient takes
    over once the sliding velocity is not zero.

    Enumerates the 4^n (or 2^n) mode combinations, each a linear system, and
    returns the list of consistent ones: an empty list is the Painleve
    inconsistency, more than one the indeterminacy.
    """
    W = np.atleast_2d(np.asarray(W, float))
    b = np.asarray(b, float)
    n = b.size // 2
    mu_s = np.broadcast_to(np.asarray(mu_static, float), (n,))
    mu_k = np.broadcast_to(np.asarray(mu_kinetic, float), (n,))
    choices = [("free", "stick", "slip+", "slip-") if s == 0 else ("free", "slide") for s in slip_sign]
    out = []
    for modes in itertools.product(*choices):
        A = np.zeros((2 * n, 2 * n))
        r = np.zeros(2 * n)
        for k, md in enumerate(modes):
            i_n, i_t = 2 * k, 2 * k + 1
            if md == "free":
                A[i_n, i_n] = A[i_t, i_t] = 1.0
                continue
            A[i_n] = W[i_n]
            r[i_n] = -b[i_n]                  # a_n = 0
            if md == "stick":
                A[i_t] = W[i_t]
                r[i_t] = -b[i_t]              # a_t = 0
            else:
                s = {"slip+": 1.0, "slip-": -1.0, "slide": float(slip_sign[k])}[md]
                mu = mu_k[k] if md == "slide" else mu_s[k]
                A[i_t, i_t] = 1.0
                A[i_t, i_n] = s * mu         # f_t = -s mu f_n
        try:
            f = np.linalg.solve(A, r)
        except np.linalg.LinAlgError:
            continue
        a = W @ f + b
        ok = True
        for k, md in enumerate(modes):
            fn, ft, an, at = f[2 * k], f[2 * k + 1], a[2 * k], a[2 * k + 1]
            if md == "free":
                ok &= an >= -tol
            else:
                ok &= fn >= -tol
                if md == "stick":
                    ok &= abs(ft) <= mu_s[k] * fn + tol
                elif md == "slip+":
                    ok &= at > tol
                elif md == "slip-":
                    ok &= at < -tol
        if ok:
            out.append(ContactSolution(tuple(modes), f, a))
    return out
