"""The leg in Exudyn: 2D rigid bodies and 2D joints, implicit integrators.

Mapping (see README.md):

* body i -> NodeRigidBody2D (coordinates x, y, theta of the centre of mass)
  + ObjectRigidBody2D (mass m, inertia J = m L^2/12 about the centre).
  Exudyn's rotation A(theta) = [[c, -s], [s, c]] maps the local x axis to
  n(theta) and the local -y axis to u(theta), so **theta = our phi** and our
  body-fixed point (xi, eta) is Exudyn's local point (eta, -xi).
  Reference coordinates = the stand pose, initial displacements = 0.
* revolute_to_frame -> RevoluteJoint2D between a ground marker and a body
  marker; revolute -> RevoluteJoint2D between two body markers.
* prismatic (cylinder i, rod k) -> PrismaticJoint2D, marker0 = centre of i
  with axisMarker0 = local u, marker1 = centre of k with normalMarker1 = local
  n: (r_k - r_i).n_k = 0 and u_i.n_k = 0 -- the same manifold as ours
  ((r_k - r_i).n_i = 0, phi_k = phi_i) near the assembled pose.
* slot (point P of body i on the axis of body k) -> PrismaticJoint2D with
  constrainRotation=False, marker0 = P on i, marker1 = centre of k,
  normalMarker1 = local n of k: (r_k - P).n_k = 0, exactly ours.
* gravity -> LoadMassProportional per body.
* actuator force F -> LoadForceVector with bodyFixed=True: local (0, -F) on
  the rod (= +F u(phi_rod)) and local (0, +F) on the cylinder (= -F u(phi_cyl)),
  at the centres; phi_rod = phi_cyl by the prismatic joint.

Methods: "galpha" (Exudyn's GeneralizedAlpha: index-3, Arnold & Bruls,
rho_inf = 0.8 as legsim's default), "trapezoidal_index2" (Exudyn's
TrapezoidalIndex2: trapezoidal rule on index-2 (velocity) constraints; it
gives the same numbers as GeneralizedAlpha with useNewmark=True,
useIndex2Constraints=True, beta = 1/4, gamma = 1/2, the only way Exudyn allows
index-2 constraints in generalized-alpha). Both use Exudyn's modified Newton
(its default; the Jacobian is refreshed when convergence slows) with relative
and absolute tolerances 1e-12 (with Exudyn's defaults, 1e-8 / 1e-10, the
error at h = 1e-5 is 3e-11 m instead of 1.3e-11 m), the dense linear solver, fixed steps, no
adaptive step reduction.

Exudyn's explicit solvers (RK44, ODE23, DOPRI5, ...) refuse joints: Exudyn
1.13.6 aborts with "SolverExplicit: explicit integrator detected object 7
which contains constraints that cannot be solved"; they only take
constraint-free systems (penalty joints) or CoordinateConstraints. So
``run(..., method="rk44")`` raises NotImplementedError.
"""
from __future__ import annotations

import time

import numpy as np

from . import leg_model as lm

METHODS = ("galpha", "trapezoidal_index2")
EXPLICIT_UNSUPPORTED = ("rk44", "ode23", "dopri5", "explicit_euler")
VARIANTS = ("revolute", "slot")

try:  # import lazily-tolerant: the bench runs without the engine installed
    import exudyn as exu
    import exudyn.itemInterface as eii

    VERSION = exu.__version__
except ImportError:  # pragma: no cover - depends on the environment
    exu = None
    eii = None
    VERSION = None


def available() -> bool:
    return exu is not None


def _local(xi: float, eta: float) -> list:
    """Our body-fixed (xi, eta) as Exudyn's local (x, y, 0)."""
    return [eta, -xi, 0.0]


class ExudynLeg:
    """The built system; ``simulate`` may be called once per instance."""

    def __init__(self, scene: str, variant: str = "revolute", model_path=None):
        if exu is None:
            raise ImportError("exudyn is not installed (pip install exudyn)")
        self.model = model = lm.load(model_path, variant)
        self.scene = scene
        forces = lm.scene_forces(model, scene)
        self.q0 = q0 = lm.stand_q0(model)
        self.SC = SC = exu.SystemContainer()
        self.mbs = mbs = SC.AddSystem()
        ground = mbs.AddObject(eii.ObjectGround(referencePosition=[0.0, 0.0, 0.0]))
        self.nodes, self.bodies = [], []
        g3 = [float(model.gravity[0]), float(model.gravity[1]), 0.0]
        for i, b in enumerate(model.bodies):
            nd = mbs.AddNode(eii.NodeRigidBody2D(referenceCoordinates=list(q0[3 * i: 3 * i + 3]),
                                                 initialCoordinates=[0.0, 0.0, 0.0],
                                                 initialVelocities=[0.0, 0.0, 0.0]))
            ob = mbs.AddObject(eii.ObjectRigidBody2D(nodeNumber=nd, mass=b.mass, inertia=b.inertia))
            mm = mbs.AddMarker(eii.MarkerBodyMass(bodyNumber=ob))
            mbs.AddLoad(eii.LoadMassProportional(markerNumber=mm, loadVector=g3))
            self.nodes.append(nd)
            self.bodies.append(ob)

        def rigid_marker(i, xi=0.0, eta=0.0):
            return mbs.AddMarker(eii.MarkerBodyRigid(bodyNumber=self.bodies[i],
                                                     localPosition=_local(xi, eta)))

        for j in model.joints:
            if j.kind == "revolute_to_frame":
                (i,), (p,) = j.bodies, j.points
                mg = mbs.AddMarker(eii.MarkerBodyPosition(
                    bodyNumber=ground, localPosition=[*j.frame_point, 0.0]))
                mb = mbs.AddMarker(eii.MarkerBodyPosition(bodyNumber=self.bodies[i],
                                                          localPosition=_local(*p)))
                mbs.AddObject(eii.ObjectJointRevolute2D(markerNumbers=[mg, mb]))
            elif j.kind == "revolute":
                (i, k), (p0, p1) = j.bodies, j.points
                m0 = mbs.AddMarker(eii.MarkerBodyPosition(bodyNumber=self.bodies[i],
                                                          localPosition=_local(*p0)))
                m1 = mbs.AddMarker(eii.MarkerBodyPosition(bodyNumber=self.bodies[k],
                                                          localPosition=_local(*p1)))
                mbs.AddObject(eii.ObjectJointRevolute2D(markerNumbers=[m0, m1]))
            elif j.kind == "prismatic":
                i, k = j.bodies
                mbs.AddObject(eii.ObjectJointPrismatic2D(
                    markerNumbers=[rigid_marker(i), rigid_marker(k)],
                    axisMarker0=_local(1.0, 0.0), normalMarker1=_local(0.0, 1.0),
                    constrainRotation=True))
            elif j.kind == "slot":
                (i, k), (p0,) = j.bodies, j.points
                mbs.AddObject(eii.ObjectJointPrismatic2D(
                    markerNumbers=[rigid_marker(i, *p0), rigid_marker(k)],
                    axisMarker0=_local(1.0, 0.0), normalMarker1=_local(0.0, 1.0),
                    constrainRotation=False))
            else:  # pragma: no cover
                raise ValueError(j.kind)

        for a, F in zip(model.actuators, forces):
            if F == 0.0:
                continue
            mbs.AddLoad(eii.LoadForceVector(markerNumber=rigid_marker(a.rod),
                                            loadVector=[0.0, -F, 0.0], bodyFixed=True))
            mbs.AddLoad(eii.LoadForceVector(markerNumber=rigid_marker(a.cylinder),
                                            loadVector=[0.0, F, 0.0], bodyFixed=True))
        self.sensors = []
        mbs.Assemble()

    def _settings(self, t_end: float, h: float, method: str, every: int, rho_inf: float,
                  newton_tol: float, modified_newton: bool = True):
        n_steps = int(round(t_end / h))
        if abs(n_steps * h - t_end) > 1e-9 * max(1.0, t_end):
            raise ValueError(f"t_end={t_end} is not a multiple of h={h}")
        s = exu.SimulationSettings()
        s.solution.file.write = False
        s.solution.file.writeInitialValues = False
        s.solution.sensors.writePeriod = 0.5 * h  # every step (subsampled afterwards)
        s.show.computationTime = False
        s.show.statistics = False
        s.linearSolver.solverType = exu.LinearSolverType.EXUdense
        ti = s.timeIntegration
        ti.numberOfSteps = n_steps
        ti.endTime = t_end
        ti.verboseMode = 0
        ti.adaptiveStep = False
        ti.automaticStepSize = False
        ti.newton.relativeTolerance = newton_tol
        ti.newton.absoluteTolerance = newton_tol
        ti.newton.useModifiedNewton = modified_newton
        ti.newton.maxIterations = 25
        ti.generalizedAlpha.spectralRadius = rho_inf
        ti.generalizedAlpha.computeInitialAccelerations = True
        if method == "galpha":
            ti.generalizedAlpha.useIndex2Constraints = False
            solver = exu.DynamicSolverType.GeneralizedAlpha
        elif method == "trapezoidal_index2":
            solver = exu.DynamicSolverType.TrapezoidalIndex2
        elif method in EXPLICIT_UNSUPPORTED:
            raise NotImplementedError(
                f"Exudyn {VERSION}: explicit solvers ({method}) do not support joints "
                "(algebraic constraints); use galpha or trapezoidal_index2")
        else:
            raise ValueError(f"unknown method {method!r}; known: {METHODS}")
        return s, solver, n_steps

    def simulate(self, t_end: float, h: float, method: str = "galpha", *, every: int = 1,
                 rho_inf: float = 0.8, newton_tol: float = 1e-12,
                 modified_newton: bool = True) -> dict:
        mbs = self.mbs
        s, solver, n_steps = self._settings(t_end, h, method, every, rho_inf, newton_tol,
                                            modified_newton)
        record = every > 0
        if record:
            sens = [mbs.AddSensor(eii.SensorNode(nodeNumber=nd, storeInternal=True,
                                                 writeToFile=False,
                                                 outputVariableType=exu.OutputVariableType.Coordinates))
                    for nd in self.nodes]
            mbs.Assemble()
        else:
            s.solution.sensors.writePeriod = 10.0 * t_end
        t0 = time.perf_counter()
        ok = mbs.SolveDynamic(s, solverType=solver)
        wall = time.perf_counter() - t0
        nb = len(self.nodes)
        q_end = np.array(mbs.systemData.GetODE2Coordinates()) + self.q0
        qd_end = np.array(mbs.systemData.GetODE2Coordinates_t())
        if record:
            data = [np.asarray(mbs.GetSensorStoredData(sn)) for sn in sens]
            t = data[0][:, 0]
            q = np.hstack([d[:, 1:4] for d in data]) + self.q0
            if t[0] > 0.5 * h:  # prepend the initial state if not stored
                t = np.concatenate([[0.0], t])
                q = np.vstack([self.q0, q])
            if len(t) != n_steps + 1:
                raise RuntimeError(f"exudyn sensors stored {len(t)} samples, "
                                   f"expected {n_steps + 1}")
            keep = np.arange(0, n_steps + 1, every)
            if keep[-1] != n_steps:
                keep = np.append(keep, n_steps)
            t, q = t[keep], q[keep]
        else:
            t = np.array([0.0, n_steps * h])
            q = np.vstack([self.q0, q_end])
        return {"t": t, "q": q, "q_end": q_end, "qd_end": qd_end, "wall_s": wall,
                "ok": bool(ok) if ok is not None else True, "n_steps": n_steps,
                "engine": f"exudyn {VERSION}", "method": method, "h": h,
                "variant": self.model.variant, "scene": self.scene,
                "n_bodies": nb}


def run(scene: str, t_end: float, h: float, method: str = "galpha", *,
        variant: str = "revolute", every: int = 1, rho_inf: float = 0.8,
        newton_tol: float = 1e-12, modified_newton: bool = True, model_path=None) -> dict:
    """Builds the leg, then integrates it with fixed step h.

    Returns dict(t (N,), q (N x 18, our absolute coordinates), wall_s (the
    integration only: time.perf_counter around SolveDynamic), q_end, qd_end,
    ...). ``every``: keep every k-th step in t, q (0: only the initial and the
    final state, no sensors in the timed loop).
    """
    return ExudynLeg(scene, variant, model_path).simulate(
        t_end, h, method, every=every, rho_inf=rho_inf, newton_tol=newton_tol,
        modified_newton=modified_newton)
