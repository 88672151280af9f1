"""The hexapod walking on its tripod gait (legsim.Hexapod.walk), checked against the gait's plan
and the contact's invariants, with its 3D animation and summary plot: `legsim-bench hexapod`
(its options: cli.py) and the demo's last part. In process (no bus: the hexapod has no CAN node yet).

On a slope (`--slope-deg`, rising toward `--uphill-deg` about the world's z from the walk's
heading: 0 up the fall line, 90 across it) the box stays level, its height over the ground below it.

Checks (the same as tests/python/test_hexapod_walk.py): the box's advance (or turn) against the
plan (step_length / duty, turn / duty a period) to 10 %, its height over the ground below it
within 2 cm of the gait's and its tilt under 3 degrees; no foot below the ground (1e-9 m); every
foot on the ground pushing and every stuck one inside its cone (about the ground's normal); the
stance's static stability margin (the centre of mass projected along gravity) positive; every
contact problem on the cones solved to the solver's tolerance (1e-10), with how many there were
and how hard they were.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

GAIT = dict(period_s=1.2, duty=0.6, step_height_m=0.05, box_height_m=1.0)


def walk_checks(hexapod, walk: dict, step_length: float, turn: float, periods: int,
                box_height: float | None = None) -> list[tuple[str, str, bool]]:
    """(check, value, passed) rows; hexapod on the walk's ground."""
    box_height = GAIT["box_height_m"] if box_height is None else box_height
    n = np.array(hexapod.desc.ground_normal[:])
    p0 = np.array(hexapod.desc.ground_point_m[:])
    q = walk["box_quat"]
    yaw = 2 * np.arctan2(q[:, 3], q[:, 0])
    tilt = np.degrees(2 * np.arcsin(np.clip(np.hypot(q[:, 1], q[:, 2]), 0, 1)))
    plan_x = periods * step_length / GAIT["duty"]
    plan_yaw = periods * turn / GAIT["duty"]
    rows = []
    if step_length > 0:
        x = walk["box_m"][-1, 0]
        rows.append(("advance (m) against the plan", f"{x:.4f} / {plan_x:.4f}", abs(x - plan_x) <= 0.1 * plan_x))
    if turn != 0:
        rows.append(("turn (rad) against the plan", f"{yaw[-1]:.4f} / {plan_yaw:.4f}",
                     abs(yaw[-1] - plan_yaw) <= 0.1 * abs(plan_yaw)))
    box = walk["box_m"]
    below = p0[2] - (n[0] * (box[:, 0] - p0[0]) + n[1] * (box[:, 1] - p0[1])) / n[2]
    dz = np.abs(box[:, 2] - below - box_height).max()
    rows.append(("box height over the ground off the gait's (m)", f"{dz:.4f}", dz < 0.02))
    rows.append(("largest tilt (deg)", f"{tilt.max():.2f}", tilt.max() < 3))
    under = -((walk["foot_m"] - p0) @ n).min()
    rows.append(("deepest foot under the ground (m)", f"{max(under, 0):.1e}", under < 1e-9))
    on = walk["foot_state"] > 0
    F = walk["foot_force_n"]
    N = F @ n
    pull = max(0.0, -N[on].min()) if on.any() else 0.0
    rows.append(("largest pull of a foot on the ground (N)", f"{pull:.1e}", pull < 1e-6))
    stuck = walk["foot_state"] == 1
    Ft = np.linalg.norm(F - N[..., None] * n, axis=-1)
    excess = max(0.0, (Ft - hexapod.desc.mu_static * N)[stuck].max()) if stuck.any() else 0.0
    rows.append(("a stuck foot's force past its cone (N)", f"{excess:.1e}", excess < 1e-6))
    margin = walk["margin_m"].min()
    rows.append(("least static stability margin of the stance (m)", f"{margin:.4f}", margin > 0))
    rows.append(("touchdowns (impacts), events", f"{int(walk['impacts'][-1])}, {int(walk['events'].sum())}",
                 walk["impacts"][-1] >= 3 * periods))
    c = walk["cone"]
    rows.append(("contact problems: solved, by sweeps, most iterations, largest residual",
                 f"{c['solved']}, {c['by_sweeps']}, {c['max_iterations']}, {c['max_residual']:.1e}",
                 c["max_residual"] <= 1e-10))
    return rows


def run_walk(root: Path, out_dir: Path | None, step_length: float = 0.12, turn: float = 0.0, periods: int = 2,
             plots: bool = True, slope_deg: float = 0.0, uphill_deg: float = 0.0,
             box_height: float | None = None) -> tuple[bool, list[tuple[str, str, bool]], list[Path]]:
    import legsim

    h = legsim.Hexapod.from_toml(Path(root) / "models" / "hexapod.toml")
    gait = dict(GAIT, box_height_m=GAIT["box_height_m"] if box_height is None else box_height)
    ground = None
    if slope_deg:
        ground = dict(slope_rad=np.radians(slope_deg), uphill_rad=np.radians(uphill_deg))
        h = h.on_ground(**ground)
    w = h.walk(**gait, step_length_m=step_length, turn_rad=turn, t_end_s=periods * GAIT["period_s"])
    rows = walk_checks(h, w, step_length, turn, periods, gait["box_height_m"])
    files = []
    if plots and out_dir is not None:
        from .report.hexapod_plots import plot_hexapod_walk, write_hexapod_animation

        files.append(plot_hexapod_walk(w, Path(out_dir) / "hexapod_walk.png"))
        files.append(write_hexapod_animation(w, h, Path(out_dir) / "hexapod_walk.gif", fps=10))
    return all(ok for _, _, ok in rows), rows, files


def print_rows(title: str, rows) -> None:
    print(title)
    width = max(len(r[0]) for r in rows)
    for name, value, ok in rows:
        print(f"  {'PASS' if ok else 'FAIL'}  {name:<{width}}  {value}")


def run(args) -> int:
    from .scene import find_root

    root = find_root(None)
    out = Path(args.out) if args.out else root / "out" / "hexapod_walk"
    ok, rows, files = run_walk(root, out, args.step_length, args.turn, args.periods, plots=not args.no_plots,
                               slope_deg=args.slope_deg, uphill_deg=args.uphill_deg, box_height=args.box_height)
    on = f", on a {args.slope_deg} deg slope rising toward {args.uphill_deg} deg" if args.slope_deg else ""
    print_rows(f"the hexapod walking {args.periods} periods (step {args.step_length} m, turn {args.turn} rad{on})",
               rows)
    if files:
        print(f"  files: {out}/ ({', '.join(p.name for p in files)})")
    return 0 if ok else 1
