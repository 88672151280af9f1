"""Tests of the two-leg robot reference (legsim_bench.reference.robot) and of the
analytic contact references (legsim_bench.reference.contact_analytic).

Invariants and independent routes: joint equations evaluated from the world
poses alone, force balance per body from the reported reactions, statics
against virtual work by finite differences of the closed-form assembly, mirror
symmetry, energy conservation, linearized modes against the energy Hessian and
against the nonlinear run, friction and impact closed forms against numerical
integration and the matrix formulas.
"""
import copy
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from legsim_bench.reference import ForceCommand, LengthCommand, n, u
from legsim_bench.reference import contact_analytic as ca
from legsim_bench.reference.robot import RobotModel
from model_files import DATA, LEG, ROBOT


def robot_with(**ground):
    data = copy.deepcopy(DATA)
    data["ground"].update(ground)
    return RobotModel(data, ROBOT.parent)


@pytest.fixture(scope="module")
def stand(robot):
    return robot.statics()


@pytest.fixture(scope="module")
def const_cmds(stand):
    return [ForceCommand(float(f)) for f in stand.actuator_forces]


# ------------------------------------------------------------ helpers
def world(q, bi, pt):
    x, y, ph = q[3 * bi:3 * bi + 3]
    return np.array([x, y]) + pt[0] * u(ph) + pt[1] * n(ph)


def joint_residual(robot, q):
    """Max |joint equation| from the world poses alone (revolute: points
    coincide; prismatic: equal angles, rod centre on the cylinder axis)."""
    worst = 0.0
    for j in robot.joints:
        if j.kind == "revolute":
            d = world(q, j.bodies[0], j.points[0]) - world(q, j.bodies[1], j.points[1])
            worst = max(worst, np.max(np.abs(d)))
        elif j.kind == "prismatic":
            a, b = j.bodies
            worst = max(worst, abs(q[3 * a + 2] - q[3 * b + 2]),
                        abs(n(q[3 * a + 2]) @ (q[3 * b:3 * b + 2] - q[3 * a:3 * a + 2])))
    return worst


def body_force_balance(robot, q, qdd, F, R, G, load):
    """Per body: m a - (m g + joint forces + actuator + ground + load) (13, 2)."""
    nb = robot.nb
    m = robot._m
    res = np.zeros((nb, 2))
    for i in range(nb):
        res[i] = m[i] * qdd[3 * i:3 * i + 2] - m[i] * robot.gravity
    res[0] -= np.asarray(load[:2])
    for k, j in enumerate(robot.joints):
        res[j.bodies[0]] -= R[k, :2]
        if len(j.bodies) > 1:
            res[j.bodies[1]] += R[k, :2]
    for a, (cyl, rod) in enumerate(robot._actuator_bodies()):
        uu = u(q[3 * cyl + 2])
        res[cyl] += F[a] * uu
        res[rod] -= F[a] * uu
    for k in range(2):
        res[robot._foot_body[k]] -= G[k]
    return res


def mirror_reaction(R):
    return np.column_stack([-R[..., 0], R[..., 1], -R[..., 2]])


# ------------------------------------------------------------ composition
def test_composition_sizes_and_names(robot):
    assert robot.nb == 13 and robot.na == 4 and robot.nj == 16
    eqs = sum(1 if j.kind == "slot" else 2 for j in robot.joints)
    assert eqs == 32
    assert robot.body_names[0] == "box"
    assert robot.body_names[1] == "right." + LEG["body"][0]["name"]
    assert robot.body_names[7] == "left." + LEG["body"][0]["name"]
    assert robot.actuator_names == ["right.upper", "right.lower", "left.upper", "left.lower"]
    frame_joints = [j["name"] for j in LEG["joint"] if j["kind"] == "revolute_to_frame"]
    for p in ("right.", "left."):
        for name in frame_joints:
            j = robot.joints[robot.joint_names.index(p + name)]
            assert j.kind == "revolute" and j.bodies[1] == 0      # now a revolute to the box


def test_composition_refuses_non_congruent_attach_points():
    data = copy.deepcopy(DATA)
    data["leg"][1]["attach"]["A"] = [-0.21, 0.10]
    with pytest.raises(ValueError, match="congruent"):
        RobotModel(data, ROBOT.parent)


# ------------------------------------------------------------ assembly
@pytest.mark.parametrize("slope,mid,dl", [(0.0, 0.0, (0, 0, 0, 0)),
                                          (0.15, 0.3, (0.02, -0.03, -0.01, 0.015))])
def test_assembly_feet_on_ground_and_lengths_met(slope, mid, dl):
    r = robot_with(slope=slope)
    L = r.stand_lengths() + np.array(dl)
    a = r.assemble(L, feet_mid=mid)
    g = r.ground
    gaps = (a.feet - g.point) @ g.normal
    along = (a.feet - g.point) @ g.tangent
    assert np.max(np.abs(gaps)) < 1e-14
    assert abs(along.mean() - mid) < 1e-14
    assert along[0] > along[1]                       # the right foot ahead along the line
    assert np.max(np.abs(r.lengths(a.z) - L)) < 1e-13
    assert joint_residual(r, a.q) < 1e-14
    # the foot points of the composed world pose, from the shanks' poses
    for k in range(2):
        assert np.max(np.abs(world(a.q, r._foot_body[k], r._foot_pt[k]) - a.feet[k])) < 1e-14


def test_stand_is_mirror_symmetric_and_at_the_legs_height(robot):
    a = robot.assemble()
    q = a.q.reshape(13, 3)
    # leg.toml's stand: foot 0.85 m below B; B is 0.15 m below the box centre
    B_box = np.array(DATA["leg"][0]["attach"]["B"])
    assert abs(q[0, 1] - (0.85 - B_box[1])) < 1e-9
    assert abs(q[0, 2]) < 1e-15
    right, left = q[1:7], q[7:13]
    assert np.max(np.abs(left[:, 0] + right[:, 0])) < 1e-14
    assert np.max(np.abs(left[:, 1] - right[:, 1])) < 1e-14
    assert np.max(np.abs(left[:, 2] + right[:, 2])) < 1e-14


# ------------------------------------------------------------ statics
@pytest.mark.parametrize("load", [(0.0, 0.0, 0.0), (30.0, -100.0, 5.0)])
def test_statics_balances_every_body_and_the_whole(robot, load):
    st = robot.statics(box_load=load)
    q = st.assembly.q
    res = body_force_balance(robot, q, np.zeros(39), st.actuator_forces, st.reactions, st.ground, load)
    assert np.max(np.abs(res)) < 1e-10
    assert st.residual < 1e-10
    # whole robot: the ground carries weight and load
    W = robot._m.sum() * robot.gravity
    assert np.max(np.abs(st.ground.sum(axis=0) + W + np.asarray(load[:2]))) < 1e-10
    # moment about the origin: ground forces at the feet, gravity at the centres, load on the box
    def cross(a, b):
        return a[0] * b[1] - a[1] * b[0]
    M = sum(cross(st.assembly.feet[k], st.ground[k]) for k in range(2))
    qq = q.reshape(13, 3)
    M += sum(cross(qq[i, :2], robot._m[i] * robot.gravity) for i in range(13))
    M += cross(qq[0, :2], load[:2]) + load[2]
    assert abs(M) < 1e-10


def test_statics_against_virtual_work(robot):
    """F_a = dV/dl_a - sum_i T_i ds_i/dl_a (feet stay on the line and slide
    along it as the lengths change; their midpoint is held)."""
    load = np.array([25.0, -60.0, 4.0])
    L0 = robot.stand_lengths() + np.array([0.01, -0.02, 0.015, 0.005])
    st = robot.statics(L0, box_load=load)
    g = robot.gravity
    t = robot.ground.tangent

    def V_s(L):
        a = robot.assemble(L)
        qq = a.q.reshape(13, 3)
        V = -float(np.sum(robot._m * (qq[:, :2] @ g))) - float(load @ qq[0])
        return V, (a.feet - robot.ground.point) @ t
    h = 1e-6
    F_vw = np.zeros(4)
    for a in range(4):
        e = np.zeros(4)
        e[a] = h
        Vp, sp = V_s(L0 + e)
        Vm, sm = V_s(L0 - e)
        F_vw[a] = (Vp - Vm) / (2 * h) - float(st.tangential @ ((sp - sm) / (2 * h)))
    assert np.max(np.abs(F_vw - st.actuator_forces)) < 1e-5 * max(1.0, np.max(np.abs(st.actuator_forces)))


def test_statics_rules_fix_the_self_stress_and_leave_normals(robot):
    load = (40.0, -50.0, 0.0)
    eq = robot.statics(box_load=load)
    mn = robot.statics(box_load=load, rule="min_tangential")
    assert abs(eq.friction_use[0] - eq.friction_use[1]) < 1e-12
    assert abs(mn.tangential[0] - mn.tangential[1]) < 1e-10
    assert np.max(np.abs(eq.normal - mn.normal)) < 1e-9
    assert abs(eq.tangential.sum() - mn.tangential.sum()) < 1e-10
    assert abs(eq.tangential.sum() + load[0]) < 1e-10
    # the two differ by the self-stress only (its actuator forces and a tangential pair)
    assert np.max(np.abs(eq.actuator_forces - mn.actuator_forces)) > 1e-3


@pytest.mark.parametrize("slope", [0.1, 0.4])
def test_statics_on_a_slope_needs_tan_slope_on_both_feet(slope):
    r = robot_with(slope=slope, mu_static=0.25, mu_kinetic=0.2)
    st = r.statics()
    assert np.max(np.abs(st.friction_use - math.tan(slope))) < 1e-10
    assert list(st.holds) == [0.25 >= math.tan(slope)] * 2


def test_statics_mirror_symmetry(robot):
    sym = robot.statics(box_load=(0.0, -100.0, 0.0))
    Rr, Rl = sym.reactions[:8], sym.reactions[8:]
    assert np.max(np.abs(Rl - mirror_reaction(Rr))) < 1e-9
    assert np.max(np.abs(sym.actuator_forces[:2] - sym.actuator_forces[2:])) < 1e-9
    assert np.max(np.abs(sym.ground[1] - sym.ground[0] * [-1, 1])) < 1e-9
    # a load and its mirror image give mirrored answers
    a = robot.statics(box_load=(35.0, -20.0, 6.0))
    b = robot.statics(box_load=(-35.0, -20.0, -6.0))
    assert np.max(np.abs(b.reactions[8:] - mirror_reaction(a.reactions[:8]))) < 1e-9
    assert np.max(np.abs(b.reactions[:8] - mirror_reaction(a.reactions[8:]))) < 1e-9
    assert np.max(np.abs(b.actuator_forces - a.actuator_forces[[2, 3, 0, 1]])) < 1e-9
    assert np.max(np.abs(b.ground[::-1] * [-1, 1] - a.ground)) < 1e-9


# ------------------------------------------------------------ dynamics
def test_rest_at_the_constant_force_stand_matches_statics(robot, stand, const_cmds):
    r = robot.simulate(0.05, t_eval=[0.0, 0.05], actuators=const_cmds)
    assert np.max(np.abs(r.q[-1] - r.q[0])) < 1e-12
    assert np.max(np.abs(r.reactions[0] - stand.reactions)) < 1e-9
    assert np.max(np.abs(r.ground[0] - stand.ground)) < 1e-9


@pytest.fixture(scope="module")
def pushed(robot, stand, const_cmds):
    cmds = [ForceCommand(float(stand.actuator_forces[0]) + 50.0)] + const_cmds[1:]
    return robot.simulate(0.1, t_eval=np.linspace(0.0, 0.1, 6), actuators=cmds)


def test_dynamics_conserves_energy_without_damping(pushed):
    assert np.ptp(pushed.energy) < 1e-9
    assert np.max(np.abs(pushed.q[-1] - pushed.q[0])) > 1e-3   # it did move


def test_dynamics_feet_stay_and_joints_hold(robot, pushed):
    for q in pushed.q:
        assert joint_residual(robot, q) < 1e-12
        for k in range(2):
            assert np.max(np.abs(world(q, robot._foot_body[k], robot._foot_pt[k]) - pushed.feet[k])) < 1e-12


def test_dynamics_reactions_balance_every_body(robot, pushed):
    assert np.max(pushed.ne_residual) < 1e-9
    for k in range(len(pushed.t)):
        res = body_force_balance(robot, pushed.q[k], pushed.qdd[k], pushed.actuator_forces[k],
                                 pushed.reactions[k], pushed.ground[k], (0.0, 0.0, 0.0))
        assert np.max(np.abs(res)) < 1e-9
    # momentum: the ground forces are the rate of momentum minus the weight
    m = robot._m
    acc = pushed.qdd.reshape(len(pushed.t), 13, 3)[:, :, :2]
    P_dot = np.einsum("i,kij->kj", m, acc)
    assert np.max(np.abs(pushed.ground.sum(axis=1) - (P_dot - m.sum() * robot.gravity))) < 1e-9


def test_dynamics_accelerations_consistent_with_velocities(robot, pushed):
    """qdd of the reduced model against the slope of the integrated qd."""
    r = robot.simulate(0.06, t_eval=[0.05 - 1e-4, 0.05, 0.05 + 1e-4],
                       actuators=[ForceCommand(float(f)) for f in pushed.actuator_forces[0]])
    fd = (r.qd[2] - r.qd[0]) / 2e-4
    assert np.max(np.abs(fd - r.qdd[1])) < 1e-5 * max(1.0, np.max(np.abs(r.qdd[1])))


# ------------------------------------------------------------ modes
@pytest.fixture(scope="module")
def modes(robot, const_cmds):
    return robot.linearize(const_cmds)


def test_constant_force_stand_is_a_saddle_with_sway_and_heave(modes):
    g = modes.growth_rates
    assert len(g) == 2
    # the independent linearization (20 kg box): sway about 4 /s, heave about 0.8 /s
    assert 3.0 < g[0] < 5.0 and 0.5 < g[1] < 1.2
    sway, heave = modes.box_shapes[0].real, modes.box_shapes[1].real
    assert abs(sway[0]) > 10 * abs(sway[1])            # sideways, no heave
    assert abs(heave[1]) > 1e3 * max(abs(heave[0]), abs(heave[2]))   # straight up/down


def test_modes_against_the_energy_hessian(robot, stand, modes):
    """lambda^2 = eig(-M_r^-1 H), H the Hessian of gravity - sum F l over the
    independent coordinates on the stuck-feet manifold (finite differences of
    the potential, not of the forces)."""
    a = robot.assemble()
    feet = a.feet
    F = stand.actuator_forces
    i0 = a.z[[2, 3, 4]]

    def V(i):
        z = robot._solve_dependent(i, feet, a.z[5:7])
        return robot.energy(z, np.zeros(7), actuator_forces=F)[1]
    h = 1e-4
    H = np.zeros((3, 3))
    for p in range(3):
        for q in range(3):
            ep, eq = np.eye(3)[p] * h, np.eye(3)[q] * h
            H[p, q] = (V(i0 + ep + eq) - V(i0 + ep - eq) - V(i0 - ep + eq) + V(i0 - ep - eq)) / (4 * h * h)
    K = robot.kinematics(a.z, np.zeros(7))
    T, _ = robot._partition(K)
    A = K.J.reshape(-1, 7) @ T
    Mr = A.T @ (robot._Mflat[:, None] * A)
    lam2 = np.sort(np.linalg.eigvals(-np.linalg.solve(Mr, H)).real)[::-1]
    lin = np.sort((modes.eigenvalues ** 2).real)[::-1]
    lin = lin[[0, 2, 4]]                                # each lambda^2 appears twice (+-lambda)
    assert np.max(np.abs(lam2 - lin) / np.abs(lin)) < 1e-5


@pytest.mark.parametrize("k", [0, 1])
def test_constant_force_stand_drifts_at_the_predicted_rate(robot, const_cmds, modes, k):
    lam = modes.eigenvalues[k].real
    v = modes.eigenvectors[:, k].real
    v = v / np.max(np.abs(v[:3]))
    eps = 1e-6
    a = robot.assemble()
    i0 = a.z[[2, 3, 4]]
    r = robot.simulate(0.5, t_eval=[0.0, 0.25, 0.5], actuators=const_cmds,
                       i0=i0 + eps * v[:3], id0=eps * v[3:])
    d = np.abs(r.i - i0).max(axis=1)
    rate = math.log(d[2] / d[1]) / 0.25
    assert abs(rate - lam) < 1e-4 * lam
    assert abs(d[2] / d[0] - math.exp(lam * 0.5)) < 1e-4 * math.exp(lam * 0.5)


def test_servo_stand_is_stable_and_stays(robot):
    servo = [LengthCommand(float(x)) for x in robot.stand_lengths()]
    z = robot.equilibrium(servo)
    m = robot.linearize(servo, z)
    assert np.all(m.eigenvalues.real < 0)
    # the servos carry the weight with a sag of F/kp
    assert z[1] < robot.assemble().z[1]
    i0 = z[[2, 3, 4]]
    r = robot.simulate(0.2, t_eval=[0.0, 0.2], actuators=servo, i0=i0)
    assert np.max(np.abs(r.z[-1] - z)) < 1e-10
    # at rest the ground carries the whole weight
    W = robot._m.sum() * robot.gravity
    assert np.max(np.abs(r.ground[-1].sum(axis=0) + W)) < 1e-9


# ------------------------------------------------------------ friction, analytic
@pytest.mark.parametrize("slope", [0.1, 0.35, 0.6])
def test_slope_sticks_or_slips_exactly_at_tan(slope):
    tn = math.tan(slope)
    assert ca.slope_sticks(tn, slope)
    assert ca.slope_sticks(tn * (1 + 1e-12), slope)
    assert not ca.slope_sticks(tn * (1 - 1e-12), slope)
    stuck = ca.slide(0.0, 1.0, tn * (1 + 1e-9), tn * 0.9, slope)
    slid = ca.slide(0.0, 1.0, tn * (1 - 1e-9), tn * 0.9, slope)
    assert not stuck.sliding and stuck.position == 0.0
    assert slid.sliding and slid.position > 0.0
    # the acceleration-level contact problem of a point mass on the slope agrees
    m, g = 2.0, ca.G0
    W = np.eye(2) / m
    b = np.array([-g * math.cos(slope), -g * math.sin(slope)])     # (normal, uphill tangent)
    for mu_s, expect in ((tn * (1 + 1e-9), "stick"), (tn * (1 - 1e-9), "slip-")):
        sols = ca.contact_modes(W, b, mu_s, 0.9 * tn, [0])
        assert [s.modes for s in sols] == [(expect,)]
    # at the onset the static cone acts; sliding, the kinetic one
    sol = ca.contact_modes(W, b, 0.5 * tn, 0.4 * tn, [0])
    assert len(sol) == 1
    assert abs(sol[0].accel[1] + g * (math.sin(slope) - 0.5 * tn * math.cos(slope))) < 1e-12
    sol = ca.contact_modes(W, b, 0.5 * tn, 0.4 * tn, [-1])
    assert [s.modes for s in sol] == [("slide",)]
    assert abs(sol[0].accel[1] + g * (math.sin(slope) - 0.4 * tn * math.cos(slope))) < 1e-12
    assert abs(-sol[0].accel[1] - ca.slide_acceleration(0.4 * tn, slope)) < 1e-12


def slide_numeric(v0, t_end, mu_k, slope, g=ca.G0):
    """m x'' = m g sin - mu_k m g cos sign(x') until x' = 0 (integrated)."""
    def rhs(t, y):
        return [y[1], g * math.sin(slope) - mu_k * g * math.cos(slope) * math.copysign(1.0, y[1])]

    def stop(t, y):
        return y[1]
    stop.terminal = True
    sol = solve_ivp(rhs, (0, t_end), [0.0, v0], method="DOP853", rtol=1e-12, atol=1e-14, events=stop)
    return sol.y[0, -1], sol.y[1, -1], sol.t[-1]


@pytest.mark.parametrize("v0,mu_k,slope", [(2.0, 0.5, 0.1), (1.5, 0.3, 0.0), (3.0, 0.2, 0.3)])
def test_slider_decelerates_at_g_mu_cos_minus_sin(v0, mu_k, slope):
    g = ca.G0
    decel = g * (mu_k * math.cos(slope) - math.sin(slope))
    assert abs(-ca.slide_acceleration(mu_k, slope) - decel) < 1e-15
    s = ca.slide(v0, 0.1, 0.6, mu_k, slope)
    x, v, _ = slide_numeric(v0, 0.1, mu_k, slope)
    assert abs(s.velocity - (v0 - decel * 0.1)) < 1e-12
    assert abs(s.velocity - v) < 1e-10 and abs(s.position - x) < 1e-10
    # to a stop (when it decelerates), then it sticks (mu_s >= mu_k > tan)
    if decel > 0:
        ts = v0 / decel
        end = ca.slide(v0, ts + 1.0, 0.6, mu_k, slope)
        x, v, tstop = slide_numeric(v0, ts + 1.0, mu_k, slope)
        assert abs(end.stop_time - ts) < 1e-12 and abs(tstop - ts) < 1e-9
        assert not end.sliding and abs(end.position - v0 * v0 / (2 * decel)) < 1e-12
        assert abs(end.position - x) < 1e-9


@pytest.mark.parametrize("v0,mu_s,mu_k,slope,t", [(2.0, 0.6, 0.5, 0.1, 0.3), (2.0, 0.6, 0.5, 0.1, 2.0),
                                                  (-2.0, 0.2, 0.15, 0.3, 1.5)])
def test_energy_lost_equals_friction_work(v0, mu_s, mu_k, slope, t):
    m, g = 3.0, ca.G0
    s = ca.slide(v0, t, mu_s, mu_k, slope, mass=m)
    dE = 0.5 * m * (s.velocity ** 2 - v0 ** 2) - m * g * math.sin(slope) * s.position
    assert abs(dE + s.friction_work) < 1e-12 * max(1.0, s.friction_work)
    assert s.friction_work > 0


@pytest.mark.parametrize("stick", [True, False])
@pytest.mark.parametrize("angle", [0.3, 0.9])
def test_inelastic_touchdown_loses_the_normal_approach_energy(stick, angle):
    """Carnot: the matrix impact law against the rod's closed form."""
    m, L, v = 1.7, 0.6, 1.3
    J = m * L * L / 12
    M = np.diag([m, m, J])
    d = 0.5 * L * np.array([math.cos(angle), math.sin(angle)])       # centre - contact end
    # velocity of the end = v_c + omega perp(-d): rows (d/d(vx, vy, omega))
    G = np.array([[1.0, 0.0, d[1]], [0.0, 1.0, -d[0]]])              # tangential (x), normal (y)
    if not stick:
        G = G[1:]
    vm = np.array([0.0, -v, 0.0])
    vp, P, lost = ca.inelastic_impact(M, G, vm)
    vc, w, lost_rod = ca.rod_touchdown(m, L, angle, v, stick)
    assert np.max(np.abs(vp[:2] - vc)) < 1e-14 and abs(vp[2] - w) < 1e-14
    assert abs(lost - lost_rod) < 1e-14
    T = lambda x: 0.5 * float(x @ M @ x)                              # noqa: E731
    assert abs((T(vm) - T(vp)) - lost) < 1e-14
    assert abs(T(vp - vm) - lost) < 1e-14                             # energy of the velocity jump
    assert np.max(np.abs(G @ vp)) < 1e-15
    assert np.max(np.abs(M @ (vp - vm) - G.T @ P)) < 1e-14
    if stick:
        assert abs(lost - (0.5 * m * v * v - 3.0 / 8.0 * m * v * v * math.cos(angle) ** 2)) < 1e-14


@pytest.mark.parametrize("mu,omega,expect", [(0.5, 0.0, 1), (2.0, 0.0, 0), (2.0, 12.0, 2)])
def test_painleve_rod_has_no_or_two_solutions_beyond_the_critical_friction(mu, omega, expect):
    """A rod (half-length l) at 60 deg sliding on its lower end away from its
    centre: the normal contact 'mass' is (1 + 3 cos^2 - 3 mu sin cos) / m, negative
    for mu > 1.347 at 60 deg (Painleve): with the free normal acceleration
    -g + omega^2 l sin below zero there is no solution, above it two."""
    m, l, th, g = 1.0, 0.5, math.radians(60), ca.G0
    J = m * l * l / 3.0
    M = np.diag([m, m, J])
    d = -l * np.array([math.cos(th), math.sin(th)])                    # end - centre
    Gm = np.array([[0.0, 1.0, d[0]], [1.0, 0.0, -d[1]]])               # normal (y), tangent (x)
    W = Gm @ np.linalg.solve(M, Gm.T)
    b = np.array([-g + omega ** 2 * l * math.sin(th), omega ** 2 * l * math.cos(th)])
    k_hand = (1 + 3 * math.cos(th) ** 2 - 3 * mu * math.sin(th) * math.cos(th)) / m
    assert abs((W[0, 0] + mu * W[0, 1]) - k_hand) < 1e-14     # sliding to -x: f_t = +mu f_n
    sols = ca.contact_modes(W, b, mu, mu, [-1])
    assert len(sols) == expect
    for s in sols:
        assert s.force[0] >= 0 and s.accel[0] >= -1e-12
