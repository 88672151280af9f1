"""A belly landing of the hexapod (issue 24): tests/python/fixtures/hexapod_belly.toml is
models/hexapod.toml with three skids under its box ([[box_contact]] at (0.35, -/+0.20, -0.15) and
(-0.35, 0, -0.15) m), its legs raised (each leg's upper actuator 0.42 m, lower 0.66 m: its foot
0.165 m above the skids' plane, 1.34 m out from the box's centre line), held by their servos (the
file's gains) at those lengths and at rowing 0. The references are independent of the spatial engine:

- free fall: the box's height z0 - g t^2 / 2 and velocity -g t until the skids touch down at
  t0 = sqrt(2 d / g), in the step holding t0; the servos' forces zero over the fall (the legs,
  at their set-points at rest, fall with the box: the robot falls as one rigid body);
- energy: kinetic + gravity's potential + the servos' springs (kp (l_cmd - l)^2 / 2, the rowing's
  alike) less the feed-forward's work (a constant force: F_ff (l - l_switch)) never rises beyond
  round-off: the servos' dampers and the impact only take energy out;
- at rest: the servos' feed-forward is the planar leg's statics at the raised lengths
  (legsim.Sim on the leg file alone: the leg's weight held from its frame), so each leg settles
  on its set-point, and the skids' normal forces are the rigid body's on three points, the
  centre of mass over the box's centre line at x = 0 by the legs' symmetry: m g (1/4, 1/4, 1/2);
  the same drop on four skids (one normal row redundant: the least-norm split) a quarter each;
- a tilted plane below the static limit (tan alpha < mu_static): the skids stay stuck, the box
  does not move, every skid inside its cone; above it (mu_static < tan alpha) they slide;
- a slide launched at v0 on level ground (mu_kinetic 0.5), and a landing moving at v0: the whole
  robot's momentum against the ground's impulses and forces, through its centre of mass c (only
  they and gravity act on it; on sliding skids the friction is mu_k N against the slip, along
  -x): c_x + mu_k c_z = c_x(0) + mu_k c_z(0) + v0 t - mu_k g t^2 / 2 while no skid sticks, the
  impact's impulses included, whatever the normal impulse and forces are. A rigid body on its
  skids stops at T = v0 / (mu_k g); the legs sway on their servos (not rigid), so the stop and
  its distance are compared to the rigid body's within the sway's share, and the slide's energy
  loss is the friction's work plus the servos' dampers' (both by the trapezoid rule).
- a rigid block on the belly's skids, unequally loaded, on a slope below the static limit: it
  must stay stuck; from 0.38 rad (tan 0.40 < mu_static 0.6) the engine refuses or slips (xfail).

What the hexapod's API cannot show (no impact impulses in legsim_hexapod_state, no bodies'
velocities): the impact's normal impulses themselves, each never pulling, and their sum; the
skids' normal forces never pulling is checked at every step's end instead, and the momentum
balance through the centre of mass above.
"""
from __future__ import annotations

import numpy as np
import pytest

legsim = pytest.importorskip("legsim")

from conftest import ROOT  # noqa: E402

BELLY = ROOT / "tests" / "python" / "fixtures" / "hexapod_belly.toml"
G = 9.81
RAISED = (0.42, 0.66)  # m: upper, lower of every leg


@pytest.fixture(scope="module")
def belly():
    return legsim.Hexapod.from_toml(BELLY)


def hold_forces(h) -> np.ndarray:
    """Each leg's actuator forces (N, 6 x 2) holding it at RAISED against its weight from its
    frame: the planar leg's statics (its file alone, assembled there from its stand in small
    steps: a dead centre lies on the straight way)."""
    out = []
    for k in range(6):
        s = legsim.Sim(h.leg_model(k))
        s.assemble_pose(0)
        l0 = s.actuator_lengths()[0]
        for a in np.linspace(0.0, 1.0, 41)[1:]:
            s.assemble(list((1 - a) * l0 + a * np.array(RAISED)))
        s.set_force("foot_load", [0.0, 0.0])
        out.append(s.statics())
    return np.array(out)


def raised_pose(h, box_m, quat=(1.0, 0.0, 0.0, 0.0)) -> dict:
    pose = h.stand_pose(1.0)
    pose.update(box_m=list(box_m), box_quat=list(quat), length_m=[list(RAISED)] * 6)
    return pose


class Energy:
    """The robot's mechanical energy with the servos' springs, less the feed-forward's work
    (gravity's potential from the bodies' centres of mass, body_poses' centres, as legsim_cli's)."""

    def __init__(self, h, m, pose):
        self.m, self.masses = m, h.body_masses()
        self.lc = np.array(pose["length_m"])
        self.rc = np.array(pose["rowing_rad"])
        leg = h.desc.leg[0].leg
        self.kp = np.array([leg.actuator[j].servo_kp_n_per_m for j in range(2)])
        self.kd = np.array([leg.actuator[j].servo_kd_ns_per_m for j in range(2)])
        self.kpr, self.kdr = h.desc.rowing_servo_kp_nm_per_rad, h.desc.rowing_servo_kd_nms_per_rad
        self.ff, self.l_ff = np.zeros((6, 2)), self.lc.copy()
        self.ffr, self.r_ff = np.zeros(6), self.rc.copy()

    def feedforward(self, ff, st, ff_rowing=None):
        """A constant feed-forward from now on: its work counts from the lengths and angles now."""
        self.ff, self.l_ff = np.array(ff), st["length_m"].copy()
        self.ffr = np.zeros(6) if ff_rowing is None else np.array(ff_rowing)
        self.r_ff = st["rowing_rad"].copy()

    def __call__(self, st) -> float:
        dl, dr = st["length_m"] - self.lc, st["rowing_rad"] - self.rc
        spring = 0.5 * (self.kp * dl ** 2).sum() + 0.5 * self.kpr * (dr ** 2).sum()
        work_ff = (self.ff * (st["length_m"] - self.l_ff)).sum() + self.ffr @ (st["rowing_rad"] - self.r_ff)
        return st["kinetic_energy_j"] + G * self.masses @ self.m.body_poses()[:, 2] + spring - work_ff

    def damping_power(self, st) -> float:
        return (self.kd * st["length_rate_mps"] ** 2).sum() + self.kdr * (st["rowing_rate_radps"] ** 2).sum()


DROP_M, H_S = 0.02, 1e-3


def run_drop(h, integrator="rk4"):
    """The drop: skids DROP_M over level ground, every foot and skid free, the servos at the
    raised pose with no feed-forward over the fall (at rest at their set-points their forces
    are zero), the hold forces as feed-forward from the step after the touchdown's; RK4 at 1
    ms (or generalized-alpha), each step's state for 0.6 s, then every 0.1 s to 4.5 s."""
    pose = raised_pose(h, (0.0, 0.0, 0.15 + DROP_M))
    m = h.sim(pose, stuck=(), integrator=integrator)
    m.command_pose(pose["length_m"], pose["rowing_rad"])
    energy = Energy(h, m, pose)
    ff = hold_forces(h)
    st = m.state()
    run = {"st": [st], "E": [energy(st)], "switched_at": None}
    for _ in range(600):
        m.step(1, h_s=H_S)
        st = m.state()
        if st["impacts"] and run["switched_at"] is None:
            m.command_pose(pose["length_m"], pose["rowing_rad"], ff, np.zeros(6))
            energy.feedforward(ff, st)
            run["switched_at"] = len(run["st"])
        run["st"].append(st)
        run["E"].append(energy(st))
    while run["st"][-1]["t_s"] < 4.5 - H_S / 2:
        m.step(100, h_s=H_S)
        st = m.state()
        run["st"].append(st)
        run["E"].append(energy(st))
    run.update(M=h.body_masses().sum(), ff=ff, pose=pose, n=h.desc.n_box_contacts)
    return run


def four_skids(tmp_path_factory):
    """The same robot on four skids, at (+-0.35, +-0.20, -0.15) m: four normal rows on a rigid
    body, one redundant (stuck, the least-norm multipliers: docs/design/spatial.md)."""
    text = BELLY.read_text()
    text = text[:text.index("\n[[box_contact]]")] + "\n" + "".join(
        f"[[box_contact]]\npoint = [{x}, {y}, -0.15]\n\n" for x in (0.35, -0.35) for y in (-0.20, 0.20))
    path = tmp_path_factory.mktemp("four") / "hexapod_belly4.toml"
    path.write_text(text.replace("../../../models/leg.toml", str(ROOT / "models" / "leg.toml")))
    h = legsim.Hexapod.from_toml(path)
    assert h.desc.n_box_contacts == 4
    return h


@pytest.fixture(scope="module", params=["3 skids, rk4", "3 skids, galpha", "4 skids, rk4"])
def drop(request, belly, tmp_path_factory):
    h = four_skids(tmp_path_factory) if request.param.startswith("4") else belly
    integrator = request.param.split(", ")[1]
    return run_drop(h, integrator)


def test_free_fall_touches_down_at_the_closed_form(drop):
    t0 = np.sqrt(2 * DROP_M / G)
    sts = drop["st"]
    k = next(i for i, st in enumerate(sts) if st["impacts"])
    assert (k - 1) * H_S < t0 <= k * H_S, (k, t0)  # the step holding t0
    assert sts[k]["impacts"] == 1 and sts[k]["events"] == 1
    assert sts[-1]["impacts"] == 1  # the legs stay clear: no foot ever lands
    z0 = 0.15 + DROP_M
    z_off = max(abs(st["box_m"][2] - (z0 - 0.5 * G * st["t_s"] ** 2)) for st in sts[:k])
    v_off = max(np.abs(st["box_velocity_mps"] - [0.0, 0.0, -G * st["t_s"]]).max() for st in sts[:k])
    f_off = max(np.abs(st["actuator_force_n"]).max() for st in sts[:k])
    print(f"touchdown in step {k} ({(k - 1) * H_S:.3f}, {k * H_S:.3f}] s, t0 = {t0:.6f} s; free fall: "
          f"height {z_off:.1e} m, velocity {v_off:.1e} m/s, servos' forces {f_off:.1e} N")
    assert z_off < 1e-13 and v_off < 1e-12 and f_off < 1e-9
    for st in sts[:k]:
        assert st["box_contact_state"] == ["free"] * drop["n"] and st["foot_state"] == ["free"] * 6
    # on its skids from the touchdown's step on: stuck, on the ground, the box stopped
    for st in sts[k:]:
        assert st["box_contact_state"] == ["stuck"] * drop["n"]
        assert np.abs(st["box_contact_m"][:, 2]).max() < 1e-12
        assert np.abs(st["box_velocity_mps"]).max() < 1e-12
        assert st["foot_state"] == ["free"] * 6 and st["foot_m"][:, 2].min() > 0.05


def test_no_energy_gained_and_no_pull(drop):
    E, sts, k = np.array(drop["E"]), drop["st"], drop["switched_at"]
    gain = np.diff(E)
    scale = abs(E).max()
    # the impact's step: the skids' inelastic impact stops the box (the legs keep moving), at
    # most the whole kinetic energy at the touchdown, m g d
    lost_at_impact = E[k - 1] - E[k]
    print(f"largest gain a step {gain.max():.1e} J (energies ~{scale:.0f} J); the impact's step loses "
          f"{lost_at_impact:.4f} J; after it the dampers {E[k] - E[-1]:.4f} J; at 4.5 s kinetic "
          f"{sts[-1]['kinetic_energy_j']:.1e} J")
    # round-off: at rest the projections leave the bodies within ~1e-13 m, which moves energies
    # of forces of hundreds of newtons by ~1e-10 J (four skids: 1.4e-10 J in one step at 4.142 s)
    assert gain.max() < 1e-9
    assert 0.1 < lost_at_impact < drop["M"] * G * DROP_M
    # the skids push, never pull, at every step's end
    n = np.array([st["box_contact_force_n"][:, 2] for st in sts])
    assert n.min() >= 0.0
    assert n[k:].min() > 100.0


def test_at_rest_the_skids_carry_the_weight(drop):
    st, M = drop["st"][-1], drop["M"]
    f = st["box_contact_force_n"]
    w = M * G
    ratio = f[:, 2] / w
    print(f"at {st['t_s']:.1f} s: sum N / m g - 1 = {f[:, 2].sum() / w - 1:.1e}, N / m g = {ratio}, tangential "
          f"{np.abs(f[:, :2]).max():.1e} N, lengths off the set-points {np.abs(st['length_m'] - RAISED).max():.1e} m")
    assert abs(f[:, 2].sum() / w - 1) < 1e-9
    # three skids: the rigid body's; four: by symmetry (and the least-norm rule) a quarter each
    assert np.abs(ratio - ([0.25, 0.25, 0.5] if drop["n"] == 3 else [0.25] * 4)).max() < 1e-9
    assert np.abs(f[:, :2]).max() < 1e-9 * w
    # each leg on its set-point: the planar statics' hold forces are the spatial leg's
    assert np.abs(st["length_m"] - RAISED).max() < 1e-10
    assert np.abs(st["actuator_force_n"] - drop["ff"]).max() < 1e-5


def on_slope(h, alpha, **friction):
    """h over the plane through the origin rising along x at alpha, and the raised pose with its
    skids on it (the box turned by -alpha about y, its centre 0.15 m along the plane's normal)."""
    g = h.on_ground(slope_rad=alpha, **friction)
    n = np.array([-np.sin(alpha), 0.0, np.cos(alpha)])
    return g, n, raised_pose(g, 0.15 * n, (np.cos(alpha / 2), 0.0, -np.sin(alpha / 2), 0.0))


def test_on_a_slope_below_the_static_limit_it_stays_stuck(belly):
    """0.3 rad (tan 0.309 < mu_static 0.6), set on its skids stuck, the legs' servos as on level
    ground (the hold forces for level ground: the legs sway to their slope's equilibrium): no
    skid slips, the box does not move, each skid inside its cone at every step's end; at rest the
    skids' forces sum to the weight and, the stated rule of stuck box points (least-norm
    multipliers, docs/design/spatial.md), share the tangential load evenly."""
    alpha = 0.3
    h, n, pose = on_slope(belly, alpha)
    m = h.sim(pose, stuck=(), box_stuck=(0, 1, 2))
    m.command_pose(pose["length_m"], pose["rowing_rad"], hold_forces(belly), np.zeros(6))
    st0 = m.state()
    w = h.body_masses().sum() * G
    use, drift, turn = 0.0, 0.0, 0.0
    for _ in range(1500):
        m.step(3, h_s=H_S)
        st = m.state()
        assert st["box_contact_state"] == ["stuck"] * 3 and st["foot_state"] == ["free"] * 6
        f = st["box_contact_force_n"]
        nn = f @ n
        assert nn.min() > 0.0
        use = max(use, (np.linalg.norm(f - np.outer(nn, n), axis=1) / nn).max())
        drift = max(drift, np.abs(st["box_m"] - st0["box_m"]).max())
        turn = max(turn, np.abs(st["box_quat"] - st0["box_quat"]).max())
    f = st["box_contact_force_n"]
    ft = np.linalg.norm(f - np.outer(f @ n, n), axis=1)
    off = np.abs(f.sum(0) - [0.0, 0.0, w]).max() / w
    print(f"slope {alpha} rad, {st['t_s']:.1f} s: box moved {drift:.1e} m, turned {turn:.1e}; friction use at most "
          f"{use:.4f} (mu_static {h.desc.mu_static}); at rest sum F off the weight {off:.1e} of m g, each skid's "
          f"tangential / (m g sin alpha / 3) - 1 = {np.abs(ft / (w * np.sin(alpha) / 3) - 1).max():.1e}")
    assert drift < 1e-12 and turn < 1e-12
    assert use < h.desc.mu_static
    assert off < 1e-9
    assert np.abs(ft / (w * np.sin(alpha) / 3) - 1).max() < 1e-9


def test_on_a_slope_above_the_static_limit_it_slides(belly):
    """mu_static 0.3 < tan 0.4 = 0.423 (mu_kinetic 0.25): every skid slides from the first step
    and the box goes downhill (-x)."""
    h, n, pose = on_slope(belly, 0.4, mu_static=0.3, mu_kinetic=0.25)
    m = h.sim(pose, stuck=(), box_stuck=(0, 1, 2))
    m.command_pose(pose["length_m"], pose["rowing_rad"], hold_forces(belly), np.zeros(6))
    x0 = m.state()["box_m"]
    m.step(1, h_s=H_S)
    assert m.state()["box_contact_state"] == ["sliding"] * 3
    m.step(99, h_s=H_S)
    st = m.state()
    assert st["box_contact_state"] == ["sliding"] * 3
    assert st["box_m"][0] - x0[0] < -1e-3


V0 = 1.0  # m/s


def com(m, masses) -> np.ndarray:
    return masses @ m.body_poses()[:, :3] / masses.sum()


# the legs at rowing 0 on their servos; swept forward 0.6 rad onto their rowing stops (the right
# legs' max, the left legs' min) with 20 N m into them, where the slide's deceleration presses them
ROWING_ON_STOPS = np.array([0.6, 0.6, 0.6, -0.6, -0.6, -0.6])


@pytest.mark.parametrize("on_stops", [False, True], ids=["rowing servo", "rowing on its stops"])
def test_a_slide_on_the_skids_stops_as_friction_takes_the_energy(belly, on_stops):
    """Set on its skids on level ground (mu_kinetic 0.5), launched along x at V0 (every body with
    the box: set_velocity), RK4 at 1 ms for 0.6 s: the skids slide, then stick together. A rigid
    body would stop at T = V0 / (mu_k g) after X = V0^2 / (2 mu_k g). At rowing 0 the legs sway
    on their rowing servos (2000 N m/rad about the hips' vertical axes): the box stops within a
    step of T (0.2035 to 0.20375 s at h = 0.25 ms), 1.5 % short of X (below). On their rowing
    stops the legs sway only on their linear actuators' servos: in the step holding T, 0.07 % past
    X. Exact:
    the whole robot's momentum against the ground's forces (its centre of mass c, on which only
    they and gravity act, the friction mu_k N against the slip along x: c_x + mu_k c_z = c_x(0)
    + mu_k c_z(0) + V0 t - mu_k g t^2 / 2 while every skid slides, whatever the normal forces);
    and the energy lost (kinetic, gravity's, the servos' springs, less the feed-forward's work)
    is the friction's work (F_t . the skid's displacement) plus the servos' dampers' (kd rate^2),
    both by the trapezoid rule over the steps from the first step's end (off by 2.0e-7 of the
    loss on the rowing servos, 1.6e-6 on the stops, at h = 1 ms; the trapezoid's error, falling
    as h^2)."""
    h = belly
    mu = h.desc.mu_kinetic
    pose = raised_pose(h, (0.0, 0.0, 0.15))
    ff, ff_rowing = hold_forces(h), np.zeros(6)
    if on_stops:
        pose["rowing_rad"] = list(ROWING_ON_STOPS)
        ff_rowing = 20.0 * np.sign(ROWING_ON_STOPS)
    m = h.sim(pose, stuck=(), box_stuck=(0, 1, 2))
    m.command_pose(pose["length_m"], pose["rowing_rad"], ff, ff_rowing)
    m.set_velocity([V0, 0.0, 0.0])
    energy = Energy(h, m, pose)
    energy.feedforward(ff, m.state(), ff_rowing)
    masses = h.body_masses()
    T, X = V0 / (mu * G), V0 ** 2 / (2 * mu * G)
    st = m.state()
    x0, c0 = st["box_m"][0], com(m, masses)
    assert st["box_contact_state"] == ["sliding"] * 3
    friction = damped = 0.0
    com_off, stop = 0.0, None
    for i in range(int(round(0.6 / H_S))):
        prev = st
        m.step(1, h_s=H_S)
        st = m.state()
        if i == 0:
            # the works from the first step's end: on their stops the rowing angles are seated by
            # the first step (six arrivals at zero speed), which moves the skids' forces at once
            E0 = energy(st)
            continue
        # the stop's step: the displacement all before the stop, under the sliding force
        stuck = st["box_contact_state"] == ["stuck"] * 3
        for a, b, fa, fb in zip(prev["box_contact_m"], st["box_contact_m"], prev["box_contact_force_n"],
                                st["box_contact_force_n"]):
            friction += (fa[:2] if stuck else 0.5 * (fa[:2] + fb[:2])) @ (b - a)[:2]
        damped += 0.5 * (energy.damping_power(prev) + energy.damping_power(st)) * H_S
        assert st["foot_state"] == ["free"] * 6
        if st["box_contact_state"] == ["sliding"] * 3:
            t = st["t_s"]
            c = com(m, masses) - c0
            com_off = max(com_off, abs(c[0] + mu * c[2] - (V0 * t - 0.5 * mu * G * t ** 2)), abs(c[1]))
        elif stop is None:
            stop = i + 1
            assert st["box_contact_state"] == ["stuck"] * 3  # together
            x_stop = st["box_m"][0] - x0
    lost = E0 - energy(st)
    print(f"stops in step {stop} ({(stop - 1) * H_S:.5f}, {stop * H_S:.5f}] s, T = {T:.6f} s; distance "
          f"{x_stop:.6f} m, closed form {X:.6f} m ({x_stop / X - 1:+.2%}); centre of mass off its closed form "
          f"{com_off:.1e} m while sliding; energy lost {lost:.6f} J, friction {-friction:.6f} J + dampers "
          f"{damped:.6f} J: off by {abs(lost + friction - damped) / lost:.1e}")
    if on_stops:
        assert (stop - 1) * H_S < T <= stop * H_S
        assert np.abs(st["rowing_rad"] - ROWING_ON_STOPS).max() < 1e-12  # held on the stops throughout
        assert abs(x_stop / X - 1) < 1e-3
    else:
        assert abs(stop * H_S - T) < 1e-3
        assert abs(x_stop / X - 1) < 0.02
    assert st["box_contact_state"] == ["stuck"] * 3  # stays
    assert abs(st["box_m"][0] - x0 - x_stop) < 1e-12
    assert com_off < 1e-10
    assert abs(lost + friction - damped) < (1e-5 if on_stops else 1e-6) * lost


def test_a_landing_with_horizontal_velocity_slides_and_stops(belly):
    """Dropped DROP_M onto its skids moving along x at V0 (mu_kinetic 0.5), the servos as in the
    drop: one impact of the three skids on their cones at t0 = sqrt(2 d / g) (in the step holding
    it), sliding from it, stuck together at the stop. The whole robot's momentum against the
    ground's impulses and forces, the impact's included (the friction's impulse mu_k times the
    normal one, against the slip): c_x + mu_k c_z = c_x(0) + mu_k c_z(0) + V0 t - mu_k g t^2 / 2
    from the release to the stop, whatever the normal impulse and forces (the fall's part: c_x
    = V0 t, c_z = -g t^2 / 2). A rigid body would stop at V0 / (mu_k g) after V0 t0 + (V0 -
    mu_k g t0)^2 / (2 mu_k g); the legs sway (3 % sooner, 1 % shorter: below). No step gains
    energy."""
    h = belly
    mu = h.desc.mu_kinetic
    pose = raised_pose(h, (0.0, 0.0, 0.15 + DROP_M))
    m = h.sim(pose, stuck=())
    m.command_pose(pose["length_m"], pose["rowing_rad"])
    m.set_velocity([V0, 0.0, 0.0])
    energy = Energy(h, m, pose)
    ff = hold_forces(h)
    masses = h.body_masses()
    t0 = np.sqrt(2 * DROP_M / G)
    T, X = V0 / (mu * G), V0 * t0 + (V0 - mu * G * t0) ** 2 / (2 * mu * G)
    st = m.state()
    x0, c0, E = st["box_m"][0], com(m, masses), energy(st)
    com_off, gain, touch, stop = 0.0, -np.inf, None, None
    for i in range(400):
        m.step(1, h_s=H_S)
        st = m.state()
        if st["impacts"] and touch is None:
            touch = i + 1
            assert st["impacts"] == 1 and st["box_contact_state"] == ["sliding"] * 3
            m.command_pose(pose["length_m"], pose["rowing_rad"], ff, np.zeros(6))
            energy.feedforward(ff, st)
        gain, E = max(gain, energy(st) - E), energy(st)
        assert st["foot_state"] == ["free"] * 6
        if stop is None and "stuck" in st["box_contact_state"]:
            stop = i + 1
            assert st["box_contact_state"] == ["stuck"] * 3
            x_stop = st["box_m"][0] - x0
        if stop is None:
            t = st["t_s"]
            c = com(m, masses) - c0
            com_off = max(com_off, abs(c[0] + mu * c[2] - (V0 * t - 0.5 * mu * G * t ** 2)), abs(c[1]))
    print(f"touchdown in step {touch}, t0 = {t0:.6f} s; stops in step {stop}, a rigid body's T = {T:.6f} s; "
          f"distance {x_stop:.6f} m, a rigid body's {X:.6f} m ({x_stop / X - 1:+.2%}); centre of mass off its "
          f"closed form {com_off:.1e} m; largest gain a step {gain:.1e} J")
    assert (touch - 1) * H_S < t0 <= touch * H_S
    assert com_off < 1e-10
    assert abs(stop * H_S - T) < 0.01 and abs(x_stop / X - 1) < 0.02
    assert st["box_contact_state"] == ["stuck"] * 3 and abs(st["box_m"][0] - x0 - x_stop) < 1e-12
    assert gain < 1e-9


BLOCK = """name = "belly-block"
gravity = [0.0, 0.0, -9.81]
[box]
mass = 30.0
size = [0.90, 0.50, 0.30]
inertia = [0.85, 2.25, 2.65]
[[box_contact]]
point = [0.35, -0.20, -0.15]
[[box_contact]]
point = [0.35, 0.20, -0.15]
[[box_contact]]
point = [-0.35, 0.0, -0.15]
[ground]
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
mu_static = 0.6
mu_kinetic = 0.5
"""


@pytest.mark.parametrize("alpha", [
    0.30,
    pytest.param(0.40, marks=pytest.mark.xfail(strict=True, raises=legsim.ContactError, reason=(
        "the stuck skids share the tangential load evenly (least-norm multipliers), which puts the "
        "front skids (the least loaded) past mu_static from about 0.38 rad (|F_t| / N = 0.64 there) "
        "though a split in proportion to the normal loads holds each at tan(alpha): from 0.38 to "
        "0.46 rad the first step fails with LEGSIM_ERR_CONTACT"))),
    pytest.param(0.52, marks=pytest.mark.xfail(strict=True, reason=(
        "as 0.40; from 0.48 rad the front skids slip (0.48, 0.50: the rear one stuck, the box still; "
        "0.52, 0.54: all three slide, the box 2.7, 3.6 mm downhill in 0.1 s) though tan(alpha) < "
        "mu_static")))])
def test_a_rigid_body_on_unequally_loaded_skids_sticks_below_the_static_limit(tmp_path, alpha):
    """The box alone on the belly's skids (a block: the hexapod file's box, its three skids, no
    legs), its centre of mass over x = 0: the front skids carry 1/4 of the normal load each, the
    rear one 1/2 on level ground. Set stuck on a plane at alpha with tan(alpha) < mu_static = 0.6
    (0.30, 0.40, 0.52 rad: tan 0.309, 0.423, 0.573), a rigid body must stay: its skids' forces in
    proportion to their normal loads (each at tan(alpha)) are inside every cone."""
    path = tmp_path / "block.toml"
    path.write_text(BLOCK)
    h = legsim.Hexapod.from_toml(path).on_ground(slope_rad=alpha)
    n = np.array([-np.sin(alpha), 0.0, np.cos(alpha)])
    pose = {"box_m": list(0.15 * n), "box_quat": [np.cos(alpha / 2), 0.0, -np.sin(alpha / 2), 0.0],
            "rowing_rad": [0.0] * 6, "length_m": [[0.0, 0.0]] * 6}
    m = h.sim(pose, stuck=(), box_stuck=(0, 1, 2))
    m.step(100, h_s=H_S)
    st = m.state()
    assert st["box_contact_state"] == ["stuck"] * 3
    assert np.abs(st["box_m"] - pose["box_m"]).max() < 1e-12
