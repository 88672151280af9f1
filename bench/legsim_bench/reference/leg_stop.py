"""The leg alone (LegModel, minimal coordinates theta = (phi3, phi6)) through its upper
actuator's arrival on a stroke minimum, for checking the core's located stops: the arrival
located on DOP853's dense output (an event on l_up(theta) - l_min), the plastic impact on the
stop in closed form, and the motion held on it after.

- Carnot's loss of the arrival: 1/2 ldot^2 / (g M^-1 g), g = dl_up/dtheta, M the reduced mass
  matrix; theta' after it: theta' - M^-1 g ldot / (g M^-1 g) (ldot becomes 0).
- Held: the upper length alone sets phi3 (C = B + L3 u(phi3), |C - A| = l_up), so with the
  length on its end phi3 is constant and the shank swings alone, phi6'' = r_6 / M_66 (M theta''
  = r the leg's reduced equations; the stop's force acts on phi3 only). Its force,
  lambda = (r_3 - M_36 phi6'') / g_3, is returned on a grid so that a caller can check it
  keeps pushing (the reference does not model a release).

SI units; constant axial actuator forces.
"""
from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

from .model import LegModel

TOL = dict(method="DOP853", rtol=1e-13, atol=1e-14)
UPPER_STROKE = "stroke = [0.40, 0.80]"  # models/leg.toml's upper actuator line


def stop_case(leg_toml, folder, l_min: float, push: float):
    """The case the core's test and benchmark share: a copy of leg_toml in folder with the upper
    stroke's minimum at l_min (m); the stand pose at rest; constant forces = the stand's statics
    plus push (N) on the upper. Returns (path, LegModel, theta0, forces)."""
    text = Path(leg_toml).read_text()
    if text.count(UPPER_STROKE) != 1:
        raise ValueError(f"{leg_toml}: the upper actuator's stroke line is not {UPPER_STROKE!r}")
    path = Path(folder) / "leg.toml"
    path.write_text(text.replace(UPPER_STROKE, f"stroke = [{float(l_min)!r}, 0.80]"))
    ref = LegModel.from_toml(path)
    th0 = ref.stand_theta()
    forces = np.array(ref.statics(theta=th0)[0], float)
    forces[0] += push
    return path, ref, th0, forces


@dataclasses.dataclass
class StopRun:
    t_arrival: float        # s
    rate: float             # m/s: the upper length's rate at the arrival
    carnot: float           # J: the kinetic energy the plastic stop takes
    theta_arrival: np.ndarray
    stop_force: np.ndarray  # the stop's multiplier on a grid of the held motion (one sign: held)
    q_end: np.ndarray       # (18,) absolute coordinates at t_end


def upper_stop(ref: LegModel, theta0, forces, l_min: float, t_end: float) -> StopRun:
    """From rest at theta0 under constant actuator forces (N) until t_end (s), the upper
    actuator arriving on l_min (m) on the way (ValueError if it does not before t_end)."""
    forces = np.asarray(forces, float)

    def free(t, y):
        return np.concatenate([y[2:], ref.accelerations(y[:2], y[2:], actuator_forces=forces)])

    def arrival(t, y):
        return ref.lengths(y[:2])[0] - l_min
    arrival.terminal, arrival.direction = True, -1
    sol = solve_ivp(free, (0.0, t_end), np.concatenate([np.asarray(theta0, float), [0.0, 0.0]]),
                    events=arrival, **TOL)
    if not len(sol.t_events[0]):
        raise ValueError("the upper actuator does not reach its stroke minimum before t_end")
    t_arr, y_arr = float(sol.t_events[0][0]), sol.y_events[0][0]
    th, thd = y_arr[:2], y_arr[2:]
    g = ref.length_jacobian(th)[0]
    if abs(g[1]) > 1e-12:
        raise ValueError("the upper length depends on phi6: not the leg this reference holds")
    minv_g = np.linalg.solve(ref.mass_matrix(th), g)
    rate = float(g @ thd)
    carnot = 0.5 * rate * rate / float(g @ minv_g)
    thd_plus = thd - minv_g * rate / float(g @ minv_g)

    def shank(p6, w6):
        theta, thetad = np.array([th[0], p6]), np.array([0.0, w6])
        M = ref.mass_matrix(theta)
        r = M @ ref.accelerations(theta, thetad, actuator_forces=forces)
        a6 = r[1] / M[1, 1]
        return a6, (r[0] - M[0, 1] * a6) / g[0]

    held = solve_ivp(lambda t, y: [y[1], shank(y[0], y[1])[0]], (t_arr, t_end),
                     [th[1], thd_plus[1]], dense_output=True, **TOL)
    lam = np.array([shank(*held.sol(t))[1] for t in np.linspace(t_arr, t_end, 41)])
    q_end = ref.absolute_q(np.array([th[0], held.y[0, -1]]))
    return StopRun(t_arr, rate, carnot, th.copy(), lam, q_end)


def state_energy(q, qd, masses, inertias, gravity, forces, lengths) -> float:
    """Kinetic + gravity's potential - sum F l (J) of a planar state in absolute coordinates
    (q, qd: x, y, phi per body; masses, inertias per body; gravity (2,); constant actuator forces
    F at lengths l): conserved but for a stop, so a step's loss of it is the stop's."""
    v = np.asarray(qd).reshape(-1, 3)
    p = np.asarray(q).reshape(-1, 3)
    kin = 0.5 * float(np.sum(masses * (v[:, 0] ** 2 + v[:, 1] ** 2)) + np.sum(inertias * v[:, 2] ** 2))
    pot = -float(np.sum(masses * (p[:, :2] @ np.asarray(gravity))))
    return kin + pot - float(np.dot(forces, lengths))

