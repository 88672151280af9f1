"""The ``legsim`` command: the scene runner (legsim_cli) of this installation.

    legsim SCENE.toml [--out FILE.json|FILE.csv] [--format json|csv]
    legsim SCENE.toml --check
    legsim --scenes        the shipped scenes (run one by its name: legsim robot_swing.toml)
    legsim --data-dir      where the shipped models/, scenes/ and can/legsim.dbc are

Everything but --scenes and --data-dir goes to legsim_cli unchanged (its usage:
``legsim --help``), but for a scene argument that names no file here and is a shipped
scene (``robot_swing.toml`` or ``scenes/robot_swing.toml``): that one is run.
"""
from __future__ import annotations

import os
import sys
from pathlib import Path

from .resources import cli_path, data_dir


def _shipped_scene(arg: str) -> str:
    """``arg``, or the shipped scene it names when it is no file of the working directory."""
    if arg.startswith("-") or Path(arg).exists():
        return arg
    try:
        root = data_dir()
    except FileNotFoundError:
        return arg
    for cand in (root / arg, root / "scenes" / arg):
        if cand.is_file() and cand.suffix == ".toml":
            return str(cand)
    return arg


def main(argv: list[str] | None = None) -> int:
    args = list(sys.argv[1:] if argv is None else argv)
    if args == ["--data-dir"]:
        print(data_dir())
        return 0
    if args == ["--scenes"]:
        for scene in sorted((data_dir() / "scenes").glob("*.toml")):
            print(scene.name)
        return 0
    try:
        exe = cli_path()
    except FileNotFoundError as e:
        print(f"legsim: error: {e}", file=sys.stderr)
        return 2
    # the scene: the first argument that is not an option or an option's value
    for i, a in enumerate(args):
        if a.startswith("-"):
            continue
        if i > 0 and args[i - 1] in ("--out", "-o", "--format"):
            continue
        args[i] = _shipped_scene(a)
        break
    sys.stdout.flush()
    os.execv(exe, [str(exe), *args])  # the CLI's own exit status and streams


if __name__ == "__main__":
    sys.exit(main())
