"""PNG plots of a checked run (matplotlib, Agg backend: no display needed).

motion.png      the leg as a stick figure at instants over the run (colour = time), the foot's
                path from hil_sim (solid) and the reference model (dashed)
actuators.png   actuator forces and lengths (hil_sim vs reference, stroke ends)
reactions.png   joint reaction forces fx, fy (hil_sim vs reference)
errors.png      |hil_sim - reference| over time with the scene's tolerances
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..scene import ACTUATORS
from ..verdict.result import Evaluation

__all__ = ["write_plots"]


def _plt():
    # matplotlib (heavy, optional for the rest of the bench) is imported when a figure is drawn
    import matplotlib
    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt
    return plt


def _shade_outside(ax, ev):
    """Grey where the reference does not apply (after a stroke stop)."""
    w = ev.data.get("window")
    if w is None or ev.ref is None or w.all() or not w.any():
        return
    t = ev.data["t"]
    ax.axvspan(t[w][-1], t[-1], color="0.85", alpha=0.6, lw=0, label="reference not applicable")


def _segments(leg, q):
    """(proximal, distal) world points of each body for one q (18,)."""
    out = []
    for b in range(len(leg.lengths)):
        L = leg.lengths[b]
        out.append((leg.world(q, b, (-L / 2, 0.0)), leg.world(q, b, (L / 2, 0.0))))
    return out


def _foot(leg, q):
    return leg.world(q, leg.load_body, leg.load_point)


def plot_motion(ev: Evaluation, path: Path, n_frames: int = 8) -> Path:
    plt = _plt()
    leg, d = ev.leg, ev.data
    fig, ax = plt.subplots(figsize=(7, 7))
    n = len(d["t"])
    idx = np.unique(np.linspace(0, n - 1, min(n_frames, n)).round().astype(int))
    cmap = plt.get_cmap("viridis", len(idx))
    widths = [5, 3, 4, 5, 3, 4]
    for k, i in enumerate(idx):
        c = cmap(k)
        for b, (p0, p1) in enumerate(_segments(leg, d["q"][i])):
            ax.plot([p0[0], p1[0]], [p0[1], p1[1]], "-", color=c, lw=widths[b % len(widths)],
                    alpha=0.85, solid_capstyle="round")
        f = _foot(leg, d["q"][i])
        ax.plot(f[0], f[1], "o", color=c, ms=5)
    # the instants' times on a colour bar, evenly spaced: labels beside the feet overlapped
    # where the foot barely moves
    import matplotlib as mpl
    norm = mpl.colors.BoundaryNorm(np.arange(len(idx) + 1) - 0.5, len(idx))
    cb = fig.colorbar(mpl.cm.ScalarMappable(norm=norm, cmap=cmap), ax=ax, shrink=0.8,
                      ticks=np.arange(len(idx)))
    cb.ax.set_yticklabels([f"{d['t'][i]:.4g}" for i in idx])
    cb.ax.minorticks_off()
    cb.set_label("t (s) of each instant")
    foot = _foot(leg, d["q"])
    ax.plot(foot[:, 0], foot[:, 1], "-", color="k", lw=1, label="foot, hil_sim")
    if ev.ref is not None:
        fr = _foot(leg, ev.ref["q"])
        ok = np.all(np.isfinite(fr), axis=1) & d.get("window", np.ones(n, bool))
        ax.plot(fr[ok, 0], fr[ok, 1], "--", color="tab:red", lw=1, label="foot, reference")
    for name, p in leg.frame.items():
        ax.plot(*p, "ks", ms=7)
        ax.annotate(name, p, textcoords="offset points", xytext=(-12, 4))
    ax.set_aspect("equal")
    ax.grid(True, alpha=0.3)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(f"{ev.scene.name}: leg over {d['t'][-1]:.3g} s ({len(idx)} instants)")
    ax.legend(loc="best", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_actuators(ev: Evaluation, path: Path) -> Path:
    plt = _plt()
    d, ref, leg = ev.data, ev.ref, ev.leg
    fig, axes = plt.subplots(2, 2, figsize=(10, 6), sharex=True)
    m = d["step"] > 0
    for a in range(2):
        ax = axes[0, a]
        ax.plot(d["t"][m], d["forces"][m, a], "-", lw=1.5, label="hil_sim")
        if ref is not None:
            ax.plot(ref["t"][m], ref["forces"][m, a], "--", lw=1, label="reference")
        ax.set_title(f"{ACTUATORS[a]} actuator force (N)")
        _shade_outside(ax, ev)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
        ax = axes[1, a]
        ax.plot(d["t"], d["lengths"][:, a], "-", lw=1.5, label="hil_sim")
        if ref is not None:
            ax.plot(ref["t"], ref["lengths"][:, a], "--", lw=1, label="reference")
        lo, hi = leg.actuators[a]["stroke"]
        span = np.nanmax(d["lengths"][:, a]) - np.nanmin(d["lengths"][:, a])
        label = "stroke end"
        for e in (lo, hi):
            if np.nanmin(np.abs(d["lengths"][:, a] - e)) < max(3 * span, 0.01):
                ax.axhline(e, color="tab:red", lw=0.8, ls=":", label=label)
                label = None
        _shade_outside(ax, ev)
        ax.set_title(f"{ACTUATORS[a]} actuator length (m)")
        ax.set_xlabel("t (s)")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(ev.scene.name)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_reactions(ev: Evaluation, path: Path) -> Path:
    plt = _plt()
    d, ref, leg = ev.data, ev.ref, ev.leg
    nj = len(leg.joints)
    fig, axes = plt.subplots(2, (nj + 1) // 2, figsize=(14, 6), sharex=True)
    m = d["step"] > 0
    for j, ax in enumerate(axes.flat):
        if j >= nj:
            ax.axis("off")
            continue
        for c, col in ((0, "tab:blue"), (1, "tab:orange")):
            ax.plot(d["t"][m], d["reactions"][m, j, c], "-", color=col, lw=1.5, label=f"f{'xy'[c]} hil_sim")
            if ref is not None:
                ax.plot(ref["t"][m], ref["reactions"][m, j, c], "--", color="k", lw=0.8,
                        label="reference" if c == 0 else None)
        ax.set_title(f"{leg.joint_names[j]} ({leg.joints[j].kind})", fontsize=9)
        _shade_outside(ax, ev)
        ax.grid(True, alpha=0.3)
        if j == 0:
            ax.legend(fontsize=7)
        if j >= nj - (nj + 1) // 2:
            ax.set_xlabel("t (s)")
    fig.suptitle(f"{ev.scene.name}: joint reactions on the first-listed body (N, world axes)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_errors(ev: Evaluation, path: Path) -> Path | None:
    if ev.ref is None:
        return None
    plt = _plt()
    d, ref = ev.data, ev.ref
    ch = ev.scene.checks
    n = len(d["t"])
    dq = np.abs(d["q"] - ref["q"]).reshape(n, 6, 3)
    series = [("positions x, y (m)", np.nanmax(dq[..., 0:2].reshape(n, -1), 1), ch.position_m),
              ("angles (rad)", np.nanmax(dq[..., 2], 1), ch.angle_rad)]
    m = d["step"] > 0
    if ch.reaction_n is not None:
        series.append(("reaction forces (N)",
                       np.where(m, np.nanmax(np.abs(d["reactions"] - ref["reactions"])[..., 0:2].reshape(n, -1), 1), np.nan),
                       ch.reaction_n))
    if ch.actuator_force_n is not None:
        series.append(("actuator forces (N)", np.where(m, np.nanmax(np.abs(d["forces"] - ref["forces"]), 1), np.nan),
                       ch.actuator_force_n))
    fig, axes = plt.subplots(len(series), 1, figsize=(8, 2.2 * len(series)), sharex=True)
    for ax, (name, e, tol) in zip(np.atleast_1d(axes), series):
        ax.semilogy(d["t"], np.maximum(e, 1e-16), "-", lw=1.2)
        if tol is not None:
            ax.axhline(tol, color="tab:red", ls="--", lw=1, label=f"tolerance {tol:g}")
            ax.legend(fontsize=8, loc="lower right")
        ax.set_ylabel(name, fontsize=8)
        _shade_outside(ax, ev)
        ax.grid(True, which="both", alpha=0.3)
    np.atleast_1d(axes)[-1].set_xlabel("t (s)")
    fig.suptitle(f"{ev.scene.name}: |hil_sim - reference| (max over coordinates)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def write_plots(ev: Evaluation, out: str | Path) -> dict[str, Path]:
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    if not ev.data or ev.leg is None:
        return {}
    files = {"motion": plot_motion(ev, out / "motion.png"),
             "actuators": plot_actuators(ev, out / "actuators.png"),
             "reactions": plot_reactions(ev, out / "reactions.png")}
    e = plot_errors(ev, out / "errors.png")
    if e is not None:
        files["errors"] = e
    return files
