"""Where the benchmarks write, and which machine made their figures.

Every benchmark (`legsim-bench workprecision`, `options`, `stress`, `mcu`) takes the same
output options (add_output_options): by default it writes to out/bench-results/ in the
repository, `--out/-o DIR` elsewhere, and only `--update-results` replaces the committed
files in bench/results/. Each result file opens with the same machine section
(machine_section): CPU model, core count, load average before and after the run, date and
commit, because timings mean nothing without the machine and its load.
"""
from __future__ import annotations

import argparse
import datetime as _dt
import os
import platform
import subprocess
from pathlib import Path

from ..scene import find_root

DEFAULT_OUT = Path("out") / "bench-results"     # relative to the repository
COMMITTED = Path("bench") / "results"            # the committed results


# ---- output directory ------------------------------------------------------------------------

def add_output_options(p: argparse.ArgumentParser) -> None:
    """--out/-o DIR and --update-results (one or the other)."""
    g = p.add_mutually_exclusive_group()
    g.add_argument("--out", "-o", metavar="DIR",
                   help=f"output directory (default: {DEFAULT_OUT}/ in the repository)")
    g.add_argument("--update-results", action="store_true",
                   help=f"write to {COMMITTED}/, replacing the committed results")


def output_dir(args, root: Path | None = None) -> Path:
    """The directory the options of add_output_options name (not created here)."""
    if getattr(args, "update_results", False):
        return (root or find_root()) / COMMITTED
    if getattr(args, "out", None):
        return Path(args.out)
    return (root or find_root()) / DEFAULT_OUT


class _Renamed(argparse.Action):
    def __init__(self, option_strings, dest, new: str, meaning: str, **kw):
        self.new, self.meaning = new, meaning
        super().__init__(option_strings, dest, nargs="*", help=argparse.SUPPRESS, **kw)

    def __call__(self, parser, namespace, values, option_string=None):
        parser.error(f"{option_string} was renamed: use {self.new} ({self.meaning})")


def refuse_renamed(p: argparse.ArgumentParser, old: str, new: str, meaning: str) -> None:
    """An option that was renamed: refused with a message naming the new spelling."""
    p.add_argument(old, action=_Renamed, new=new, meaning=meaning, dest=argparse.SUPPRESS,
                   default=argparse.SUPPRESS)


# ---- the machine -------------------------------------------------------------------------------

def cpu_model() -> str:
    """The CPU's model name (/proc/cpuinfo, else what platform knows)."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            key = line.split(":", 1)[0].strip()
            if key in ("model name", "Model", "Hardware", "cpu model"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine() or "unknown CPU"


def load_average() -> str:
    try:
        return " ".join(f"{x:.2f}" for x in os.getloadavg())
    except OSError:
        return "unknown"


def commit(root: Path | None = None, paths: tuple[str, ...] = ()) -> str:
    """The repository's commit, with a note when tracked files (under `paths`, or anywhere)
    differ from it; the COMMIT file of an exported tree; else 'unknown'."""
    try:
        root = Path(root) if root else find_root()
    except Exception:  # noqa: BLE001 - no repository: say so in the line
        return "unknown (no repository)"
    if (root / ".git").exists():
        try:
            r = subprocess.run(["git", "-C", str(root), "rev-parse", "--short", "HEAD"],
                               capture_output=True, text=True, timeout=20)
            if r.returncode == 0:
                dirty = subprocess.run(["git", "-C", str(root), "status", "--porcelain", "--",
                                        *paths],
                                       capture_output=True, text=True, timeout=20).stdout.strip()
                return r.stdout.strip() + (" with uncommitted changes" if dirty else "")
        except (OSError, subprocess.SubprocessError):
            pass
    if (root / "COMMIT").is_file():
        return (root / "COMMIT").read_text().strip()[:12] + " (exported tree)"
    return "unknown (no git)"


def snapshot(root: Path | None = None) -> dict:
    """The machine now: CPU model, cores, load average, date, platform, commit."""
    return {"cpu": cpu_model(), "cores": os.cpu_count(), "loadavg": load_average(),
            "date": _dt.datetime.now().isoformat(timespec="seconds"),
            "platform": platform.platform(), "commit": commit(root)}


def machine_section(before: dict, after: dict | None = None, *, heading: str = "## Machine") -> list[str]:
    """The lines every result file carries (Markdown): CPU model and cores, load average
    before and after the run, date, commit. `before`/`after` come from snapshot()."""
    after = after or {}
    lines = [heading, "",
             f"- CPU: {before['cpu']}, {before['cores']} cores; {before['platform']}",
             f"- load average (1, 5, 15 min) before / after: {before['loadavg']} / "
             f"{after.get('loadavg', 'not taken')}",
             f"- date: {before['date']}" + (f" to {after['date']}" if after.get("date") else ""),
             f"- commit: {before['commit']}"]
    return lines + [""]
