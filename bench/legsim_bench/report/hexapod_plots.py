"""The hexapod walking (legsim.Hexapod.walk): a 3D animation and a summary plot.

matplotlib with the Agg backend (no display needed); the GIF goes through Pillow.

write_hexapod_animation   the walk as a GIF: the box, every bar of every leg, the feet coloured by
                          their contact state (free, stuck, sliding), the ground, the time
plot_hexapod_walk         the box's path and height, its tilt, and each foot's contact state over
                          time (the gait as it happened, beside the gait's stance)
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["write_hexapod_animation", "plot_hexapod_walk", "quat_matrix"]

STATE_COLOURS = ("#9e9e9e", "#2e7d32", "#ef6c00")  # free, stuck, sliding
STATE_NAMES = ("free", "stuck", "sliding")


def quat_matrix(q) -> np.ndarray:
    """The rotation matrix of a unit quaternion (w, x, y, z)."""
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def _bar_lengths(hexapod) -> list[list[float]]:
    d = hexapod.desc
    return [[d.leg[k].leg.body[b].length_m for b in range(d.leg[k].leg.n_bodies)] for k in range(6)]


def _box_edges(pose, size):
    R, c = quat_matrix(pose[3:7]), np.asarray(pose[:3])
    h = 0.5 * np.asarray(size)
    corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * h
    corners = corners @ R.T + c
    edges = [(i, j) for i in range(8) for j in range(i + 1, 8) if bin(i ^ j).count("1") == 1]
    return [(corners[i], corners[j]) for i, j in edges]


def _bars(poses, lengths):
    """Each bar's two ends (world) from the body poses: the box, then per leg its yoke and bars."""
    segs, b = [], 1
    for leg in lengths:
        b += 1  # the yoke
        for L in leg:
            p = poses[b]
            u = quat_matrix(p[3:7])[:, 0]
            segs.append((p[:3] - 0.5 * L * u, p[:3] + 0.5 * L * u))
            b += 1
    return segs


def write_hexapod_animation(walk: dict, hexapod, path, fps: float = 20.0) -> Path:
    """A GIF of walk (Hexapod.walk's samples) in real time at fps frames a second."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib import animation

    path = Path(path)
    if path.suffix.lower() != ".gif":
        raise ValueError(f"animation: {path.name}: use a .gif file name")
    if not (np.isfinite(fps) and fps > 0):
        raise ValueError("animation: fps must be positive and finite")
    t = walk["t_s"]
    frames = np.searchsorted(t, np.arange(t[0], t[-1] + 1e-12, 1.0 / fps))
    frames = frames[frames < len(t)]
    lengths = _bar_lengths(hexapod)
    size = list(hexapod.desc.box_size_m)
    feet = walk["foot_m"]
    lo = np.minimum(feet.min(axis=(0, 1)), walk["box_m"].min(axis=0)) - 0.3
    hi = np.maximum(feet.max(axis=(0, 1)), walk["box_m"].max(axis=0)) + 0.3
    span = (hi - lo).max()
    mid = 0.5 * (hi + lo)
    # the ground plane: its z below (x, y)
    n, p0 = np.array(hexapod.desc.ground_normal[:]), np.array(hexapod.desc.ground_point_m[:])

    def ground_z(x, y):
        return p0[2] - (n[0] * (np.asarray(x) - p0[0]) + n[1] * (np.asarray(y) - p0[1])) / n[2]

    z0 = min(0.0, min(ground_z(mid[0] + a * span / 2, mid[1] + b * span / 2) for a in (-1, 1) for b in (-1, 1)))

    fig = plt.figure(figsize=(6.4, 5.2))
    ax = fig.add_subplot(projection="3d")

    def draw(i):
        ax.cla()
        k = frames[i]
        ax.set_xlim(mid[0] - span / 2, mid[0] + span / 2)
        ax.set_ylim(mid[1] - span / 2, mid[1] + span / 2)
        ax.set_zlim(z0, z0 + span)
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        ax.set_zlabel("z (m)")
        gx = np.linspace(mid[0] - span / 2, mid[0] + span / 2, 7)
        gy = np.linspace(mid[1] - span / 2, mid[1] + span / 2, 7)
        for x in gx:
            ax.plot([x, x], [gy[0], gy[-1]], ground_z([x, x], [gy[0], gy[-1]]), color="#dddddd", lw=0.6)
        for y in gy:
            ax.plot([gx[0], gx[-1]], [y, y], ground_z([gx[0], gx[-1]], [y, y]), color="#dddddd", lw=0.6)
        for a, b in _box_edges(walk["body_pose"][k][0], size):
            ax.plot(*zip(a, b), color="#37474f", lw=1.2)
        for a, b in _bars(walk["body_pose"][k], lengths):
            ax.plot(*zip(a, b), color="#1565c0", lw=1.5)
        for leg in range(6):
            s = int(walk["foot_state"][k][leg])
            ax.scatter(*feet[k][leg], color=STATE_COLOURS[s], s=18, depthshade=False)
        ax.plot(walk["box_m"][:k + 1, 0], walk["box_m"][:k + 1, 1],
                ground_z(walk["box_m"][:k + 1, 0], walk["box_m"][:k + 1, 1]), color="#c62828", lw=0.8)
        ax.set_title(f"hexapod walking (tripod gait)   t = {t[k]:.2f} s\n"
                     "feet: grey free, green stuck, orange sliding", fontsize=9)
        return []

    anim = animation.FuncAnimation(fig, draw, frames=len(frames), blit=False)
    path.parent.mkdir(parents=True, exist_ok=True)
    anim.save(str(path), writer=animation.PillowWriter(fps=fps))
    plt.close(fig)
    return path


def plot_hexapod_walk(walk: dict, path, stance=None) -> Path:
    """The box's x, y and height and its tilt against time, and each foot's state as a band
    (free, stuck, sliding); stance (n, 6 bools), when given, outlines the gait's planned stance."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Patch

    path = Path(path)
    t = walk["t_s"]
    fig, (a1, a2, a3) = plt.subplots(3, 1, figsize=(7.5, 7.5), sharex=True)
    for i, name in enumerate("xyz"):
        a1.plot(t, walk["box_m"][:, i], label=f"box {name}")
    a1.set_ylabel("m")
    a1.legend(loc="best", fontsize=8)
    a1.set_title("the hexapod's box and feet along the walk")
    q = walk["box_quat"]
    tilt = 2 * np.degrees(np.arcsin(np.clip(np.hypot(q[:, 1], q[:, 2]), 0, 1)))
    yaw = np.degrees(2 * np.arctan2(q[:, 3], q[:, 0]))
    a2.plot(t, tilt, label="tilt (deg)")
    a2.plot(t, yaw, label="yaw (deg)")
    a2.set_ylabel("deg")
    a2.legend(loc="best", fontsize=8)
    for leg in range(6):
        s = walk["foot_state"][:, leg].astype(int)
        for k in range(len(t) - 1):
            a3.barh(leg, t[k + 1] - t[k], left=t[k], color=STATE_COLOURS[s[k]], height=0.7)
        if stance is not None:
            on = np.asarray(stance)[:, leg]
            a3.plot(t[on], np.full(on.sum(), leg + 0.42), "k.", ms=1)
    a3.set_yticks(range(6))
    a3.set_ylabel("leg")
    a3.set_xlabel("t (s)")
    a3.legend(handles=[Patch(color=c, label=n) for c, n in zip(STATE_COLOURS, STATE_NAMES)], loc="upper right",
              fontsize=8, ncol=3)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
