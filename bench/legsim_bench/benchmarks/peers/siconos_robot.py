"""The two-leg robot in Siconos: Moreau-Jean time stepping with 2D Coulomb friction.

Siconos comes from Debian (``python3-siconos`` 4.4.0, with ``python3-scipy``
for the bench's reference), so it lives in the SYSTEM Python (/usr/bin/python3),
not in the bench's venv. The bench side (:func:`run`, :func:`available`) runs
this module there as a separate process (``/usr/bin/python3 -m
legsim_bench.benchmarks.peers.siconos_robot --scene ... --h ...`` with the bench's source
on PYTHONPATH), which prints one JSON object.

The model (the choice, stated): a Siconos ``LagrangianDS`` in the reference's
7 coordinates z = (x, y, psi, right (phi3, phi6), left (phi3, phi6)): box pose
and each leg's two minimal coordinates. Each six-bar leg's loops are closed in
those coordinates (the leg's shape follows from phi3, phi6 in closed form), so
the smooth part needs no bilateral constraint:

    M(z) z'' = A^T (Q - M_b b(z, z')) + (dl/dz)^T F(t, l, l') + r

with A = dq/dz (39 x 7: the 13 bodies' world poses), b = dA/dt z', M_b the
bodies' masses and inertias, Q gravity, F the actuator forces (force mode, or
the servo law of leg.toml) -- all from RobotModel.kinematics (read only). The
feet are NOT held: each foot is a Siconos interaction with the ground line,
y = (n.(p - g), t.(p - g)) (normal gap, tangential position), and a
``NewtonImpactFrictionNSL(e = 0, e_t = 0, mu, 2)``: unilateral contact with
exact 2D Coulomb friction (one coefficient mu; the scene says which). Siconos
decides stick, slip and lift-off every step. The relation is a
``LagrangianLinearTIR`` y = C z + e whose C (the foot's Jacobian) and e (so
that y is the exact gap) are rewritten in place at the start of every step:
a Python subclass of ``LagrangianScleronomousR`` (the nonlinear relation)
crashes Siconos 4.4 in MoreauJeanOSI::computeFreeOutput (a segmentation
fault, reproduced with a single ball), so the contact rows are the relation
linearized at the step's start (Siconos would evaluate them at each Newton
iterate; the difference is O(h) per step on a first-order scheme).

Time stepping: ``MoreauJeanOSI(theta)`` (default theta = 0.5), ``TimeStepping``
with its Newton loop on the smooth part (tolerance 1e-10, no force Jacobians
given, so W = M and Newton is a fixed-point iteration), ``FrictionContact(2)``
solved by the 2D Lemke solver (``SICONOS_FRICTION_2D_LEMKE``; ``nsgs`` also).
Ground forces per foot: the step's impulse / h, (N, T).

Cost: wall time per step (time.perf_counter around computeOneStep + nextStep
over the run, divided by the steps), which includes the Python callbacks of
the smooth part (mass, forces, contact kinematics) -- that is how this peer is
built, not Siconos's own kernel cost.
"""
from __future__ import annotations

import argparse
import functools
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from . import robot_scenes as rs

SYSTEM_PYTHON = os.environ.get("LEGSIM_SICONOS_PYTHON", "/usr/bin/python3")
BENCH_DIR = Path(__file__).resolve().parents[3]
SOLVERS = ("lemke", "nsgs")


@functools.lru_cache(maxsize=None)
def probe() -> tuple:
    """(True, version) when the system Python imports siconos, else (False, why)."""
    try:
        r = subprocess.run([SYSTEM_PYTHON, "-c", "import siconos, scipy, numpy; print(siconos.__version__)"],
                           capture_output=True, text=True, timeout=120)
    except (OSError, subprocess.SubprocessError) as e:
        return False, f"{SYSTEM_PYTHON}: {e}"
    if r.returncode != 0:
        last = (r.stderr.strip().splitlines() or ["no output"])[-1]
        return False, (f"{SYSTEM_PYTHON} cannot import siconos/scipy ({last}); install Debian's "
                       "python3-siconos and python3-scipy")
    try:   # siconos.__version__ says "0" in Debian's build: ask dpkg
        v = subprocess.run(["dpkg-query", "-W", "-f=${Version}", "python3-siconos"],
                           capture_output=True, text=True, timeout=30).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        v = ""
    return True, v or r.stdout.strip()


def available() -> bool:
    return probe()[0]


def run(scene: str, h: float, *, theta: float = 0.5, solver: str = "lemke", every: int = 1,
        t_end=None, robot_path=None, timeout: float = 600.0) -> dict:
    """Run one scene (a name of robot_scenes.SCENES) in the system Python.

    Returns t, z (N, 7), normal, tangential (2,) at the end, per_step_s,
    wall_s, n_steps, ok, engine, ... (arrays as numpy). Raises RuntimeError
    with the process's message when Siconos is missing or the run fails."""
    ok, why = probe()
    if not ok:
        raise RuntimeError(why)
    cmd = [SYSTEM_PYTHON, "-m", "legsim_bench.benchmarks.peers.siconos_robot", "--scene", scene, "--h", repr(float(h)),
           "--theta", repr(float(theta)), "--solver", solver, "--every", str(int(every))]
    if t_end is not None:
        cmd += ["--t-end", repr(float(t_end))]
    if robot_path is not None:
        cmd += ["--robot", str(Path(robot_path).resolve())]
    env = dict(os.environ, PYTHONPATH=str(BENCH_DIR))
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, env=env, cwd=str(BENCH_DIR))
    if r.returncode != 0:
        raise RuntimeError(f"siconos run failed ({r.returncode}): {r.stderr.strip()[-2000:]}")
    out = json.loads(r.stdout.strip().splitlines()[-1])
    out["engine"] = f"siconos {probe()[1]}"
    for k in ("t", "z", "normal", "tangential", "q"):
        out[k] = np.array(out[k], float)
    return out


def compare(scene: str, h: float, *, sample_dt: float = 1e-3, ref=None, robot_path=None, **kw) -> dict:
    """As mujoco_robot.compare: err_z along the trajectory, err_NT at the end."""
    every = int(round(sample_dt / h))
    if every < 1 or abs(every * h - sample_dt) > 1e-9:
        raise ValueError(f"sample_dt={sample_dt} is not a multiple of h={h}")
    r = run(scene, h, every=every, robot_path=robot_path, **kw)
    if ref is None:
        ref = rs.reference(rs.setup(scene, robot_path), r["t"])
    r["err_z"] = rs.trajectory_error(r["z"], ref["z"])
    r["err_NT"] = float(max(np.max(np.abs(r["normal"] - ref["normal"][-1])),
                            np.max(np.abs(r["tangential"] - ref["tangential"][-1]))))
    r["ref"] = ref
    return r


# ------------------------------------------------------------ the system-Python side
def simulate(scene_name: str, h: float, *, theta: float = 0.5, solver: str = "lemke", every: int = 1,
             t_end=None, robot_path=None) -> dict:
    """The Siconos run itself (needs siconos: the system Python)."""
    import siconos.kernel as sk
    import siconos.numerics as sn

    if solver not in SOLVERS:
        raise ValueError(f"solver must be one of {SOLVERS}")
    if not (h > 0 and 0.0 < theta <= 1.0):
        raise ValueError("need h > 0 and 0 < theta <= 1")
    sc = rs.setup(scene_name, robot_path)
    robot = sc.robot
    t_end = sc.t_end if t_end is None else float(t_end)
    n_steps = int(round(t_end / h))
    if n_steps < 1 or abs(n_steps * h - t_end) > 1e-9 * max(1.0, t_end):
        raise ValueError(f"t_end={t_end} is not a positive multiple of h={h}")
    cmds = sc.commands
    grav = robot._gravity(True)
    Q = robot._applied(grav, (0.0, 0.0, 0.0))      # gravity, (39,)
    Mb = robot._Mflat                              # (39,) m, m, J per body
    ground = robot.ground
    gn, gt, gp = ground.normal, ground.tangent, np.asarray(ground.point, float)

    class RobotDS(sk.LagrangianDS):
        """M(z) and the smooth forces from the reference's kinematics."""

        def _kin(self, z, zd):
            return robot.kinematics(np.array(z, float), np.array(zd, float))

        def computeMass(self, *args):
            z = args[0] if args else self.q()
            K = self._kin(z, np.zeros(7))
            A = K.J.reshape(-1, 7)
            self.mass()[:, :] = A.T @ (Mb[:, None] * A)

        def computeForces(self, time, q, v):
            K = self._kin(q, v)
            A = K.J.reshape(-1, 7)
            F = robot._forces(cmds, time, K)
            if self.forces() is None:     # first call: let Siconos allocate the vector
                sk.LagrangianDS.computeForces(self, time, q, v)
            self.forces()[:] = A.T @ (Q - Mb * K.b.reshape(-1)) + K.lz.T @ F

    def foot_rows(z):
        """Per foot: (C (2, 7), e (2,)) with C z + e = (n.(p - g), t.(p - g)) at z
        and C the foot's Jacobian (the relation linearized at z)."""
        K = robot.kinematics(np.asarray(z, float), np.zeros(7))
        out = []
        for k in range(2):
            C = np.vstack([gn @ K.footJ[k], gt @ K.footJ[k]])
            d = K.foot[k] - gp
            out.append((C, np.array([d @ gn, d @ gt]) - C @ z))
        return out

    z0 = np.array(sc.z0, float)
    M0 = np.eye(7)
    ds = RobotDS(z0.copy(), np.zeros(7), M0)
    ds.setFExtPtr(np.zeros(7))         # makes Siconos allocate its forces vector
    ds.computeMass()
    mass = float(ds.mass()[0, 0])      # the model's total mass: every body moves with x
    nsds = sk.NonSmoothDynamicalSystem(0.0, t_end)
    nsds.insertDynamicalSystem(ds)
    inters = []
    rels = []
    for C, e in foot_rows(z0):
        law = sk.NewtonImpactFrictionNSL(0.0, 0.0, float(sc.mu), 2)
        rel = sk.LagrangianLinearTIR(C, e)
        inter = sk.Interaction(law, rel)
        nsds.link(inter, ds)
        inters.append(inter)
        rels.append(rel)
    td = sk.TimeDiscretisation(0.0, h)
    osi = sk.MoreauJeanOSI(theta)
    sid = sn.SICONOS_FRICTION_2D_LEMKE if solver == "lemke" else sn.SICONOS_FRICTION_2D_NSGS
    osnspb = sk.FrictionContact(2, sid)
    opts = osnspb.numericsSolverOptions()
    opts.dparam[sn.SICONOS_DPARAM_TOL] = 1e-12
    opts.iparam[sn.SICONOS_IPARAM_MAX_ITER] = 10000
    sim = sk.TimeStepping(nsds, td, osi, osnspb)
    sim.setNewtonTolerance(1e-10)
    sim.setNewtonMaxIteration(50)

    ts, zs, qs = [0.0], [z0.copy()], [robot.absolute_q(z0)]
    wall = 0.0
    k = 0
    ok = True
    while sim.hasNextEvent() and k < n_steps:
        t0 = time.perf_counter()
        # the contact rows at the start of the step (in place: Siconos keeps the pointers)
        for rel, (C, e) in zip(rels, foot_rows(np.array(ds.q(), float))):
            rel.C()[:, :] = C
            rel.e()[:] = e
        sim.computeOneStep()
        lam = [np.array(it.lambda_(1), float).copy() for it in inters]
        sim.nextStep()
        wall += time.perf_counter() - t0
        k += 1
        z = np.array(ds.q(), float)
        if not np.all(np.isfinite(z)):
            ok = False
            break
        if k % max(every, 1) == 0 or k == n_steps:
            ts.append(k * h)
            zs.append(z.copy())
            qs.append(robot.absolute_q(z))
    N = [float(l_[0] / h) if l_.size else 0.0 for l_ in lam]
    T = [float(l_[1] / h) if l_.size > 1 else 0.0 for l_ in lam]
    return {"t": ts, "z": [list(map(float, z)) for z in zs], "q": [list(map(float, q)) for q in qs],
            "normal": N, "tangential": T, "wall_s": wall, "per_step_s": wall / max(k, 1),
            "n_steps": k, "ok": ok and k == n_steps, "engine": "siconos",
            "method": f"moreau-jean theta={theta} {solver}", "h": h, "scene": scene_name,
            "mass": mass}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description="One robot scene in Siconos (run by the system Python); "
                                            "prints a JSON object")
    p.add_argument("--scene", required=True, choices=rs.SCENES)
    p.add_argument("--h", type=float, required=True)
    p.add_argument("--theta", type=float, default=0.5)
    p.add_argument("--solver", choices=SOLVERS, default="lemke")
    p.add_argument("--every", type=int, default=1)
    p.add_argument("--t-end", type=float, default=None)
    p.add_argument("--robot", default=None)
    a = p.parse_args(argv)
    out = simulate(a.scene, a.h, theta=a.theta, solver=a.solver, every=a.every, t_end=a.t_end,
                   robot_path=a.robot)
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
