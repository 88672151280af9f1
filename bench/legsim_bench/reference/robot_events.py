"""The two-leg robot with its feet's contact modes and events located exactly.

RobotModel (robot.py) integrates the robot with both feet stuck.  This module
integrates it in any contact mode and through the events between modes, each
located to near machine precision, so that a fixed-step solver's error through
an event can be measured against it:

* Coordinates z = (x, y, psi, thetaR (2), thetaL (2)) and their rates, the
  robot's own kinematics (exact jets: qd = J zd, qdd = J zdd + b).
* Per foot a mode: ``free`` (no rows), ``stuck`` (normal and tangential
  acceleration rows), ``sliding`` with direction s = +-1 (the normal row; the
  ground's force on the foot is N (n - s mu_k t)).  Per mode the equations of
  motion with the contact rows are one square linear solve,
  [M -W^T; G 0] [zdd; lambda] = [h; -g_b], with M = J^T M_q J and
  h = J^T (Q - M_q b) + (dl/dz)^T F.
* Event functions (each a smooth function of the state in one mode):
  free foot: its gap n.(p - p0) falling through 0 (touchdown); stuck foot: N
  falling through 0 (lift-off), mu_s N -+ T falling through 0 (stick to slip);
  sliding foot: N falling through 0 (lift-off), its sliding velocity reaching 0
  (slip to stick).  DOP853 integrates one mode; scipy's solve_ivp finds the
  first root of the event functions on the step's 7th-order dense output with
  Brent's method (xtol 4 eps); the state there is the dense output's.
* At a touchdown: an inelastic impact with Coulomb friction in impulses (the
  core's impact law): the landing foot and the stuck feet held,
  [M -G^T; G 0] [zd+; P] = [M zd-; 0]; a landing impulse outside the static
  cone is redone sliding with mu_k against the slip; a foot whose normal
  impulse would pull (P_n < 0) is left free.  The kinetic energy lost is
  Carnot's 1/2 (G zd-)^T (G M^-1 G^T)^-1 (G zd-) for a stuck landing.
* Stroke stops (``stroke_stops=True``; off by default): per actuator its length
  L (the robot's kinematics, exact jets) against its stroke [L_min, L_max] of the
  leg file.  A free actuator's event functions are L - L_min and L_max - L
  (arrival); at an arrival an inelastic impact holds its length rate at 0 with
  the closed feet and the other stops held, [M -G^T; G 0] [zd+; P] = [M zd-; 0]
  (a held stop whose impulse would pull lets go), losing Carnot's energy.  While
  on its stop the length is a row, L_dd = 0, its multiplier S the stop's axial
  force (> 0 extends: a stop at L_min pushes, S >= 0; one at L_max, S <= 0); its
  event function is S (at L_min) or -S (at L_max) falling through 0 (release).
* After each event the modes are made consistent at acceleration level (a stuck
  foot that would pull lifts off, one outside its cone slides against T, a
  sliding one whose velocity reached zero sticks if the cone holds it, else
  slides the other way, a stop whose force would pull lets go), then the
  integration restarts from the event.

Everything else (commands, loads, energy) is RobotModel's.  SI units.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Optional, Sequence

import numpy as np
from scipy.integrate import solve_ivp

from .commands import ForceCommand
from .model import ReferenceError, command_breakpoints
from .robot import RobotModel

__all__ = ["ContactEvent", "EventResult", "simulate_events", "impact", "impact_with_stops",
           "modes_from", "AT_MIN", "AT_MAX", "EVENT_KINDS", "STOP_KINDS"]

FREE, STUCK, SLIDING = "free", "stuck", "sliding"
EVENT_KINDS = ("touchdown", "liftoff", "stick_to_slip", "slip_to_stick")
STOP_KINDS = ("stroke_min", "stroke_max", "stop_release")
AT_MIN, AT_MAX = -1, 1          # a held stop: the end it is on (0: free)


@dataclass
class ContactEvent:
    """One event: time (s), kind (EVENT_KINDS, or STOP_KINDS: an actuator arriving
    at its stroke end, a held stop letting go), foot (0 right, 1 left; -1 for a
    stop's event), the modes before and after (per foot a state name), the
    impulse of a touchdown or a stop's arrival per foot ((normal, tangential) N s;
    zeros else), the kinetic energy it lost (J), and the state there: z, the rates
    before (zd_minus) and after (zd_plus) the impact.  actuator: a stop's event's
    actuator (-1 else); stops: the held stops after it (per actuator AT_MIN,
    AT_MAX or 0); stop_impulse (4,): the stops' axial impulses at an impact (N s,
    > 0 extends)."""
    t: float
    kind: str
    foot: int
    before: tuple
    after: tuple
    impulse: np.ndarray
    kinetic_lost: float = 0.0
    z: Optional[np.ndarray] = None
    zd_minus: Optional[np.ndarray] = None
    zd_plus: Optional[np.ndarray] = None
    actuator: int = -1
    stops: tuple = ()
    stop_impulse: Optional[np.ndarray] = None


@dataclass
class EventResult:
    """Samples at t_eval: z, zd (N, 7); q, qd (N, 39) world; feet (N, 2, 2);
    states (N, 2) mode names; kinetic, potential (gravity and box load) (N,);
    per foot the ground's force along its normal and tangent, normal and tangential
    (N, 2), and the sliding velocity along the tangent, slip (N, 2) (m/s); events in
    time order; nfev the right-hand side's evaluations; per actuator its length
    (N, 4) (m), its held stop (N, 4) (AT_MIN, AT_MAX, 0) and the stop's axial
    force stop_force (N, 4) (N, > 0 extends; 0 when not held)."""
    t: np.ndarray
    z: np.ndarray
    zd: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    feet: np.ndarray
    states: np.ndarray
    kinetic: np.ndarray
    potential: np.ndarray
    normal: np.ndarray
    tangential: np.ndarray
    slip: np.ndarray
    events: list = field(default_factory=list)
    nfev: int = 0
    lengths: Optional[np.ndarray] = None
    stops: Optional[np.ndarray] = None
    stop_force: Optional[np.ndarray] = None

    @property
    def energy(self) -> np.ndarray:
        return self.kinetic + self.potential


@dataclass(frozen=True)
class _Mode:
    state: tuple      # per foot FREE | STUCK | SLIDING
    sign: tuple       # per foot the sliding direction along t (+1, -1; 0 unless sliding)
    stop: tuple = ()  # per actuator its held stop: AT_MIN, AT_MAX or 0 (() none held)


def modes_from(states: Sequence[str], signs: Sequence[int] = (0, 0), stops: Sequence[int] = ()) -> _Mode:
    st = tuple(states)
    if len(st) != 2 or any(s not in (FREE, STUCK, SLIDING) for s in st):
        raise ValueError(f"need two states of {(FREE, STUCK, SLIDING)}, not {states!r}")
    sg = tuple(int(s) if st[k] == SLIDING else 0 for k, s in enumerate(signs))
    if any(st[k] == SLIDING and sg[k] not in (1, -1) for k in range(2)):
        raise ValueError("a sliding foot needs a direction +1 or -1")
    sp = tuple(int(x) for x in stops)
    if any(x not in (AT_MIN, 0, AT_MAX) for x in sp):
        raise ValueError(f"a stop is {AT_MIN} (at the minimum), {AT_MAX} (the maximum) or 0, not {stops!r}")
    if not any(sp):
        sp = ()
    return _Mode(st, sg, sp)


class _Dynamics:
    """The robot's equations in one mode, with the contact forces."""

    def __init__(self, model: RobotModel, cmds, g, box_load):
        self.m = model
        self.cmds = cmds
        self.g = g
        self.box_load = np.asarray(box_load, float)
        self.n = model.ground.normal
        self.tg = model.ground.tangent
        self.p0 = model.ground.point
        self.nfev = 0
        self._cache_key = None
        self._cache = None

    def mass_and_forces(self, z, zd, t):
        m = self.m
        K = m.kinematics(z, zd)
        Jq = K.J.reshape(-1, 7)
        Mz = Jq.T @ (m._Mflat[:, None] * Jq)
        F = m._forces(self.cmds, t, K)
        h = Jq.T @ (m._applied(self.g, self.box_load) - m._Mflat * K.b.reshape(-1)) + K.lz.T @ F
        return K, Mz, h

    def rows(self, K, mode: _Mode):
        """G (r, 7), its bias (r,), the force directions W (r, 7), per foot the
        slice of its multipliers, then per actuator its stop's row (-1: none).  A
        held stop's row is its length's, L_dd = lz zdd + lb = 0; its force acts
        along the actuator as the actuator's own (lz^T S)."""
        G, gb, W, sl = [], [], [], []
        for k in range(2):
            Jf, bf = K.footJ[k], K.footb[k]
            s = mode.state[k]
            start = len(G)
            if s == STUCK:
                for d in (self.n, self.tg):
                    G.append(d @ Jf)
                    gb.append(d @ bf)
                    W.append(d @ Jf)
            elif s == SLIDING:
                G.append(self.n @ Jf)
                gb.append(self.n @ bf)
                W.append((self.n - mode.sign[k] * self.m.ground.mu_kinetic * self.tg) @ Jf)
            sl.append(slice(start, len(G)))
        stop_row = [-1] * self.m.na
        for a, side in enumerate(mode.stop):
            if side:
                stop_row[a] = len(G)
                G.append(K.lz[a])
                gb.append(K.lb[a])
                W.append(K.lz[a])
        G = np.array(G).reshape(-1, 7)
        return G, np.array(gb), np.array(W).reshape(-1, 7), sl + [stop_row]

    def solve(self, t, y, mode: _Mode):
        """zdd (7,), and per foot N and T (the ground's force on it, N), its gap (m)
        and sliding velocity (m/s)."""
        return self.solve_full(t, y, mode)[:5]

    def solve_full(self, t, y, mode: _Mode):
        """solve's, then per actuator its length (m) and its stop's force (N, 0 when
        not held)."""
        key = (t, y.tobytes(), mode)
        if key == self._cache_key:
            return self._cache
        self.nfev += 1
        z, zd = y[:7], y[7:]
        K, Mz, h = self.mass_and_forces(z, zd, t)
        G, gb, W, sl = self.rows(K, mode)
        r = len(gb)
        A = np.zeros((7 + r, 7 + r))
        A[:7, :7] = Mz
        A[:7, 7:] = -W.T
        A[7:, :7] = G
        x = np.linalg.solve(A, np.concatenate([h, -gb]))
        zdd, lam = x[:7], x[7:]
        N, T = np.zeros(2), np.zeros(2)
        for k in range(2):
            lk = lam[sl[k]]
            if mode.state[k] == STUCK:
                N[k], T[k] = lk
            elif mode.state[k] == SLIDING:
                N[k] = lk[0]
                T[k] = -mode.sign[k] * self.m.ground.mu_kinetic * lk[0]
        gap = (K.foot - self.p0) @ self.n
        vt = np.einsum("kij,j->ki", K.footJ, zd) @ self.tg
        S = np.array([lam[r] if r >= 0 else 0.0 for r in sl[2]])
        out = (zdd, N, T, gap, vt, K.l.copy(), S)
        self._cache_key, self._cache = key, out
        return out


def impact(model: RobotModel, z, zd_minus, mode: _Mode, landing: Sequence[int]):
    """The inelastic touchdown of the feet ``landing`` at pose z (on the ground)
    with approach rates zd_minus, the other closed feet of ``mode`` held as they
    are.  Returns (zd_plus, new mode, impulses (2, 2) (P_n, P_t) per foot)."""
    zdp, cur, imp, _ = impact_with_stops(model, z, zd_minus, mode, landing)
    return zdp, cur, imp


def impact_with_stops(model: RobotModel, z, zd_minus, mode: _Mode, landing: Sequence[int],
                      arriving: Sequence[tuple] = ()):
    """The inelastic impact of the feet ``landing`` (on the ground) and of the
    actuators ``arriving`` at their stroke ends ((actuator, AT_MIN | AT_MAX) each)
    at pose z with approach rates zd_minus, the other closed feet and held stops of
    ``mode`` held as they are: [M -W^T; G 0] [zd+; P] = [M zd-; 0].  A landing foot
    outside the static cone slides with mu_k, one whose normal impulse would pull
    is left free; a stop whose impulse would pull lets go.  Returns (zd_plus, new
    mode, impulses (2, 2) per foot, stop impulses (na,) (N s, > 0 extends))."""
    dyn = _Dynamics(model, [None] * model.na, np.zeros(2), (0.0, 0.0, 0.0))
    K = model.kinematics(z, zd_minus)
    Jq = K.J.reshape(-1, 7)
    Mz = Jq.T @ (model._Mflat[:, None] * Jq)
    mu_s, mu_k = model.ground.mu_static, model.ground.mu_kinetic
    vt = np.einsum("kij,j->ki", K.footJ, zd_minus) @ dyn.tg
    state = list(mode.state)
    sign = list(mode.sign)
    stop = list(mode.stop) if mode.stop else [0] * model.na
    for k in landing:
        state[k] = STUCK
    for a, side in arriving:
        stop[a] = side
    tried = set()
    for _ in range(8 + model.na):
        cur = modes_from(state, sign, stop)
        if cur in tried:
            break
        tried.add(cur)
        G, _, W, sl = dyn.rows(K, cur)
        r = G.shape[0]
        A = np.zeros((7 + r, 7 + r))
        A[:7, :7] = Mz
        A[:7, 7:] = -W.T
        A[7:, :7] = G
        x = np.linalg.solve(A, np.concatenate([Mz @ zd_minus, np.zeros(r)]))
        zdp, P = x[:7], x[7:]
        imp = np.zeros((2, 2))
        changed = False
        for k in range(2):
            pk = P[sl[k]]
            if cur.state[k] == STUCK:
                imp[k] = pk
            elif cur.state[k] == SLIDING:
                imp[k] = (pk[0], -cur.sign[k] * mu_k * pk[0])
            if cur.state[k] != FREE and imp[k, 0] < 0 and k in landing:
                state[k], sign[k], changed = FREE, 0, True           # it would pull: it leaves
            elif cur.state[k] == STUCK and k in landing and abs(imp[k, 1]) > mu_s * imp[k, 0]:
                # outside the static cone: it slides against the tangential impulse
                s = -int(np.sign(imp[k, 1])) or (1 if vt[k] > 0 else -1)
                state[k], sign[k], changed = SLIDING, s, True
        Ps = np.array([P[row] if row >= 0 else 0.0 for row in sl[2]])
        if not changed:
            for a in range(model.na):
                # a stop only pushes: its impulse pulling, it lets go (one at a time)
                if stop[a] and stop[a] * Ps[a] > 0:
                    stop[a], changed = 0, True
                    break
        if not changed:
            return zdp, cur, imp, Ps
    raise ReferenceError(f"the impact has no consistent mode (tried {sorted(map(str, tried))})")


def _consistent(dyn: _Dynamics, t, y, mode: _Mode, max_passes=8):
    """The mode made consistent at acceleration level (see the module doc); returns
    (mode, [(kind, foot, actuator), ...]) (-1: none)."""
    mu_s = dyn.m.ground.mu_static
    changes = []
    seen = {mode}
    for _ in range(max_passes + dyn.m.na):
        _, N, T, _, vt, _, S = dyn.solve_full(t, y, mode)
        state, sign = list(mode.state), list(mode.sign)
        stop = list(mode.stop)
        for k in range(2):
            if mode.state[k] != FREE and N[k] < 0:
                state[k], sign[k] = FREE, 0
                changes.append(("liftoff", k, -1))
            elif mode.state[k] == STUCK and abs(T[k]) > mu_s * N[k]:
                state[k], sign[k] = SLIDING, -int(np.sign(T[k]))
                changes.append(("stick_to_slip", k, -1))
        if stop and state == list(mode.state):
            # a stop whose force would pull lets go (the feet first, one stop a pass)
            for a, side in enumerate(stop):
                if side and side * S[a] > 0:
                    stop[a] = 0
                    changes.append(("stop_release", -1, a))
                    break
        new = modes_from(state, sign, stop)
        if new == mode:
            return mode, changes
        if new in seen:
            raise ReferenceError(f"contact modes cycle at t = {t!r}: {sorted(map(str, seen))}")
        seen.add(new)
        mode = new
    raise ReferenceError(f"no consistent contact mode at t = {t!r}")


def simulate_events(model: RobotModel, t_end: float, t_eval, z0, zd0, states=(STUCK, STUCK),
                    signs=(0, 0), actuators: Optional[Sequence] = None, box_load=(0.0, 0.0, 0.0),
                    gravity=True, rtol=1e-12, atol=1e-13, max_events=64, stroke_stops=False,
                    stops: Sequence[int] = ()) -> EventResult:
    """Integrate the robot from (z0, zd0) in the contact modes ``states`` (per foot
    free, stuck, sliding; a sliding foot's direction in ``signs``) to t_end (s),
    locating every contact event (see the module doc).  The start must be
    consistent: closed feet on the ground and not moving into it.  actuators: 4
    commands as RobotModel.simulate (constant schedules only: the integration
    restarts at events, not at command breakpoints).  Samples at t_eval (s).
    stroke_stops: the actuators stop at their stroke ends (arrivals and releases
    located as the contact events); stops: the stops held at the start (per
    actuator AT_MIN, AT_MAX or 0; its length on that end, its rate 0), else every
    length must start inside its stroke."""
    cmds = list(actuators) if actuators is not None else [None] * model.na
    if len(cmds) != model.na:
        raise ValueError(f"need {model.na} actuator commands")
    if any(0.0 < b < t_end for b in command_breakpoints(cmds)):
        raise ValueError("simulate_events takes constant commands only")
    g = model._gravity(gravity)
    dyn = _Dynamics(model, cmds, g, box_load)
    stops = tuple(stops) if stops else ()
    if stops and (len(stops) != model.na or not stroke_stops):
        raise ValueError(f"stops: {model.na} values, and only with stroke_stops")
    mode = modes_from(states, signs, stops)
    y = np.concatenate([np.asarray(z0, float), np.asarray(zd0, float)])
    t = 0.0
    te = np.asarray(t_eval, float)
    if te.ndim != 1 or np.any(np.diff(te) < 0) or te[0] < 0 or te[-1] > t_end:
        raise ValueError("t_eval must be increasing inside [0, t_end]")
    lo = np.array([s_[0] for s_ in model._stroke], float)
    hi = np.array([s_[1] for s_ in model._stroke], float)
    if stroke_stops:
        K0 = model.kinematics(y[:7], y[7:])
        for a in range(model.na):
            side = stops[a] if stops else 0
            end = lo[a] if side == AT_MIN else hi[a]
            if side and (abs(K0.l[a] - end) > 1e-9 or abs(K0.ld[a]) > 1e-9):
                raise ValueError(f"actuator {a}: held at its stop, its length {K0.l[a]!r} m and rate "
                                 f"{K0.ld[a]!r} m/s must be {end!r} and 0")
            if not side and not lo[a] <= K0.l[a] <= hi[a]:
                raise ValueError(f"actuator {a}: its length {K0.l[a]!r} m starts outside its stroke "
                                 f"[{lo[a]}, {hi[a]}]")
    events: list[ContactEvent] = []

    def record(t_ev, kind, foot, act, before, imp=None, lost=0.0, zdm=None, zdp=None, stop_imp=None):
        events.append(ContactEvent(t_ev, kind, foot, before, mode.state,
                                   np.zeros((2, 2)) if imp is None else imp.copy(), lost,
                                   y[:7].copy(), (y[7:] if zdm is None else zdm).copy(),
                                   (y[7:] if zdp is None else zdp).copy(), act,
                                   mode.stop or (0,) * model.na, stop_imp))

    before = tuple(states)
    mode, ch = _consistent(dyn, t, y, mode)
    for kind, k, a in ch:
        record(0.0, kind, k, a, before)
    T_out, Y_out, S_out = [], [], []

    while True:
        mu_s = model.ground.mu_static

        def rhs(tt, yy, mode=mode):
            return np.concatenate([yy[7:], dyn.solve(tt, yy, mode)[0]])

        ev_funcs, ev_info = [], []
        for k in range(2):
            s = mode.state[k]
            if s == FREE:
                ev_funcs.append(lambda tt, yy, k=k, mode=mode: dyn.solve(tt, yy, mode)[3][k])
                ev_info.append(("touchdown", k))
            else:
                ev_funcs.append(lambda tt, yy, k=k, mode=mode: dyn.solve(tt, yy, mode)[1][k])
                ev_info.append(("liftoff", k))
                if s == STUCK:
                    for sg in (1.0, -1.0):
                        ev_funcs.append(lambda tt, yy, k=k, sg=sg, mode=mode:
                                        (lambda r: mu_s * r[1][k] - sg * r[2][k])(dyn.solve(tt, yy, mode)))
                        ev_info.append(("stick_to_slip", k))
                else:
                    ev_funcs.append(lambda tt, yy, k=k, mode=mode:
                                    mode.sign[k] * dyn.solve(tt, yy, mode)[4][k])
                    ev_info.append(("slip_to_stick", k))
        if stroke_stops:
            for a in range(model.na):
                side = mode.stop[a] if mode.stop else 0
                if side:
                    # the stop's force reaching zero: at the minimum S >= 0, at the maximum S <= 0
                    ev_funcs.append(lambda tt, yy, a=a, side=side, mode=mode:
                                    -side * dyn.solve_full(tt, yy, mode)[6][a])
                    ev_info.append(("stop_release", a))
                else:
                    ev_funcs.append(lambda tt, yy, a=a, mode=mode: dyn.solve_full(tt, yy, mode)[5][a] - lo[a])
                    ev_info.append(("stroke_min", a))
                    ev_funcs.append(lambda tt, yy, a=a, mode=mode: hi[a] - dyn.solve_full(tt, yy, mode)[5][a])
                    ev_info.append(("stroke_max", a))
        for f in ev_funcs:
            f.terminal = True
            f.direction = -1.0
        sol = solve_ivp(rhs, (t, t_end), y, method="DOP853", rtol=rtol, atol=atol,
                        events=ev_funcs, dense_output=True)
        if sol.status < 0:
            raise ReferenceError(f"integration failed at t = {sol.t[-1]!r}: {sol.message}")
        t_stop = float(sol.t[-1])
        # samples of this piece: [t, t_stop) (the end's own sample in the last piece)
        last = sol.status == 0
        sel = (te >= t) & ((te < t_stop) | (last & (te <= t_stop)))
        if np.any(sel):
            ys = sol.sol(te[sel]).T
            if last and te[sel][-1] == t_stop:
                ys[-1] = sol.y[:, -1]
            T_out.extend(te[sel])
            Y_out.extend(ys)
            S_out.extend([mode] * int(np.sum(sel)))
        if last:
            break
        # the event: the first one located (several at the same instant: all of them)
        hits = [(float(sol.t_events[i][0]), i) for i in range(len(ev_funcs)) if len(sol.t_events[i])]
        t_ev = min(h[0] for h in hits)
        y = sol.y_events[min(hits)[1]][0].copy()
        before = mode.state
        if len(events) >= max_events:
            raise ReferenceError(f"more than {max_events} events by t = {t_ev!r}")
        kinds = {ev_info[i] for tt, i in hits if tt == t_ev}
        landing = [k for kind, k in kinds if kind == "touchdown"]
        arriving = [a for kind, a in kinds if kind in ("stroke_min", "stroke_max")]
        if landing or arriving:
            # the other free feet touching and actuators arriving at the same instant
            # (a level drop lands both feet)
            _, _, _, gap, _, L, _ = dyn.solve_full(t_ev, y, mode)
            if landing:
                landing = sorted({k for k in range(2) if mode.state[k] == FREE and abs(gap[k]) < 1e-12}
                                 | set(landing))
            held = mode.stop or (0,) * model.na
            if stroke_stops:
                arriving = sorted({a for a in range(model.na) if not held[a]
                                   and min(abs(L[a] - lo[a]), abs(L[a] - hi[a])) < 1e-12} | set(arriving))
            arrive = [(a, AT_MIN if abs(L[a] - lo[a]) < abs(L[a] - hi[a]) else AT_MAX) for a in arriving]
            ke0 = model.energy(y[:7], y[7:], gravity=False)[0]
            zdm = y[7:].copy()
            zdp, mode, imp, pstop = impact_with_stops(model, y[:7], zdm, mode, landing, arrive)
            y[7:] = zdp
            lost = ke0 - model.energy(y[:7], y[7:], gravity=False)[0]
            for k in landing:
                record(t_ev, "touchdown", k, -1, before, imp, lost, zdm, zdp, pstop)
            for a, side in arrive:
                record(t_ev, "stroke_min" if side == AT_MIN else "stroke_max", -1, a, before, imp, lost,
                       zdm, zdp, pstop)
        else:
            state, sign = list(mode.state), list(mode.sign)
            stop = list(mode.stop)
            for kind, k in sorted(kinds):
                if kind == "liftoff":
                    state[k], sign[k] = FREE, 0
                elif kind == "stick_to_slip":
                    _, N, T, _, _ = dyn.solve(t_ev, y, mode)
                    state[k], sign[k] = SLIDING, -int(np.sign(T[k]))
                elif kind == "slip_to_stick":
                    state[k], sign[k] = STUCK, 0
                    # the sliding velocity is zero to the root's precision: hold it there
                    K = model.kinematics(y[:7], y[7:])
                    vt = dyn.tg @ (K.footJ[k] @ y[7:])
                    if abs(vt) > 1e-9:
                        raise ReferenceError(f"slip to stick at v_t = {vt!r} m/s")
                elif kind == "stop_release":
                    stop[k] = 0
                mode = modes_from(state, sign, stop)
                if kind == "stop_release":
                    record(t_ev, kind, -1, k, before)
                else:
                    record(t_ev, kind, k, -1, before)
        mode, ch = _consistent(dyn, t_ev, y, mode)
        for kind, k, a in ch:
            # a foot stuck again that the cone cannot hold slides on the other way
            record(t_ev, kind, k, a, before)
        t = t_ev

    Tn = np.array(T_out)
    Y = np.array(Y_out).reshape(-1, 14)
    n = len(Tn)
    q, qd = np.zeros((n, 3 * model.nb)), np.zeros((n, 3 * model.nb))
    feet = np.zeros((n, 2, 2))
    kin, pot = np.zeros(n), np.zeros(n)
    Nn, Tt, vt = np.zeros((n, 2)), np.zeros((n, 2)), np.zeros((n, 2))
    L, Sf = np.zeros((n, model.na)), np.zeros((n, model.na))
    for i, yy in enumerate(Y):
        _, Nn[i], Tt[i], _, vt[i], L[i], Sf[i] = dyn.solve_full(float(Tn[i]), yy, S_out[i])
        K = model.kinematics(yy[:7], yy[7:])
        q[i] = K.P.reshape(-1)
        qd[i] = K.J.reshape(-1, 7) @ yy[7:]
        feet[i] = K.foot
        kin[i], pot[i] = model.energy(yy[:7], yy[7:], box_load, None, gravity)
    states = np.array([m.state for m in S_out]).reshape(-1, 2)
    held = np.array([m.stop or (0,) * model.na for m in S_out], int).reshape(-1, model.na)
    return EventResult(Tn, Y[:, :7].copy(), Y[:, 7:].copy(), q, qd, feet, states, kin, pot,
                       Nn, Tt, vt, events, dyn.nfev, lengths=L, stops=held, stop_force=Sf)
