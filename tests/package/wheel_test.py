#!/usr/bin/env python3
"""The Python wheel as a user installs it (tests/package/CMakeLists.txt: package_wheel).

    wheel_test.py --source SOURCE_DIR --work WORK_DIR [--python PYTHON] [--reference-cli CLI]

1. ``pip wheel SOURCE/python`` builds the wheel (scikit-build-core over the project's
   CMake; pip fetches the build requirements from PyPI), and its contents are checked:
   the shared libraries, legsim_cli, the models, scenes and DBC inside the package, the
   ``legsim`` console script, no headers or static libraries;
2. a fresh virtual environment in WORK (outside the checkout when WORK is, e.g. /tmp)
   installs that wheel (numpy from PyPI);
3. from WORK, with no LEGSIM_* variable and no PYTHONPATH: ``import legsim`` loads the
   package's own library (not a build tree), stands the robot on the ground
   (models/robot.toml from the package data) and steps it, and the ``legsim`` command runs
   a shipped robot scene, whose CSV equals the build tree's CLI run of the same scene
   (--reference-cli) byte for byte.
Exits non-zero with a message on failure. Python 3.11+, standard library only.
"""
from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import textwrap
import zipfile
from pathlib import Path

SCENE = "robot_stand_servo.toml"


def fail(msg: str) -> None:
    print(f"FAIL: {msg}", file=sys.stderr)
    sys.exit(1)


def run(cmd, **kw) -> subprocess.CompletedProcess:
    print("+", " ".join(str(c) if "\n" not in str(c) else "<script>" for c in cmd), flush=True)
    r = subprocess.run([str(c) for c in cmd], **kw)
    if r.returncode != 0:
        fail(f"{cmd[0]} exited {r.returncode}: {getattr(r, 'stderr', '') or ''}")
    return r


def clean_env() -> dict:
    """The user's environment: nothing that points into the checkout or a build tree."""
    env = {k: v for k, v in os.environ.items()
           if not k.startswith("LEGSIM_") and k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    env["PIP_DISABLE_PIP_VERSION_CHECK"] = "1"
    return env


CHECK = textwrap.dedent("""
    import pathlib, sys
    import numpy as np
    import legsim
    pkg = pathlib.Path(legsim.__file__).resolve().parent
    lib = legsim.find_library()
    assert pathlib.Path(sys.prefix).resolve() in pkg.parents, (pkg, sys.prefix)
    assert lib.parent == pkg / "lib", lib
    assert legsim.cli_path() == pkg / "bin" / "legsim_cli", legsim.cli_path()
    assert legsim.data_dir() == pkg / "share" / "legsim", legsim.data_dir()
    # the leg compiled in: its statics at the stand pose (python/README.md's figures)
    leg = legsim.Sim()
    leg.assemble_pose("stand")
    assert np.allclose(leg.statics(), [-93.929, 1.387], atol=5e-4), leg.statics()
    # the robot from the shipped model file, stood on the ground, held by its statics forces
    robot = legsim.Sim(legsim.data_path("models/robot.toml"), integrator="rk4", step=1e-3)
    robot.assemble_on_ground()
    F = robot.statics()
    weight = 9.81 * robot.model.masses.sum()
    assert abs(robot.contacts()["normal"].sum() - weight) < 1e-6 * weight
    for name, f in zip(robot.model.actuator_names, F):
        robot.command_force(name, f)
    robot.run(0.05)
    assert abs(robot.box()[1] - 1.0) < 1e-6, robot.box()
    print("legsim", legsim.__version__, "from", lib)
    print("robot statics (N):", np.round(F, 3), "feet carry the weight", round(weight, 3), "N")
""")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--source", required=True, type=Path)
    ap.add_argument("--work", required=True, type=Path)
    ap.add_argument("--python", default=sys.executable)
    ap.add_argument("--reference-cli", type=Path, help="the build tree's legsim_cli")
    a = ap.parse_args()
    work = a.work.resolve()
    shutil.rmtree(work, ignore_errors=True)
    (work / "wheelhouse").mkdir(parents=True)
    env = clean_env()

    # 1. the wheel
    run([a.python, "-m", "pip", "wheel", "--no-deps", "-w", work / "wheelhouse",
         a.source / "python"], env=env)
    wheels = sorted((work / "wheelhouse").glob("legsim-*.whl"))
    if len(wheels) != 1:
        fail(f"expected one legsim wheel in {work / 'wheelhouse'}, found {wheels}")
    names = set(zipfile.ZipFile(wheels[0]).namelist())
    want = ["legsim/__init__.py", "legsim/lib/liblegsim.so", "legsim/lib/liblegsim_f32.so",
            "legsim/bin/legsim_cli", "legsim/share/legsim/models/robot.toml",
            "legsim/share/legsim/scenes/" + SCENE, "legsim/share/legsim/can/legsim.dbc"]
    missing = [n for n in want if n not in names]
    if missing:
        fail(f"{wheels[0].name} lacks {missing}")
    extra = sorted(n for n in names if n.endswith((".h", ".a", ".cmake", ".pc")))
    if extra:
        fail(f"{wheels[0].name} holds development files: {extra}")
    entry = [n for n in names if n.endswith(".dist-info/entry_points.txt")]
    if not entry or "legsim = legsim.cli:main" not in zipfile.ZipFile(wheels[0]).read(entry[0]).decode():
        fail(f"{wheels[0].name}: no console script legsim = legsim.cli:main")
    print(f"wheel {wheels[0].name}: {len(names)} files, library, CLI and data inside")

    # 2. a fresh virtual environment, the wheel installed
    venv = work / "venv"
    run([a.python, "-m", "venv", venv], env=env)
    py, bindir = venv / "bin" / "python", venv / "bin"
    run([py, "-m", "pip", "install", "-q", wheels[0]], env=env)

    # 3. used from outside the checkout
    r = run([py, "-c", CHECK], cwd=work, env=env, capture_output=True, text=True)
    print(r.stdout, end="")
    out = work / "scene.csv"
    r = run([bindir / "legsim", SCENE, "--out", out], cwd=work, env=env,
            capture_output=True, text=True)
    if not out.is_file() or len(out.read_text().splitlines()) < 3:
        fail(f"legsim {SCENE} wrote no samples to {out}")
    print(f"legsim {SCENE} --out scene.csv: {len(out.read_text().splitlines()) - 1} samples")
    if a.reference_cli:
        ref = work / "reference.csv"
        run([a.reference_cli, a.source / "scenes" / SCENE, "--out", ref], env=env,
            capture_output=True, text=True)
        if ref.read_bytes() != out.read_bytes():
            fail(f"the wheel's CLI and {a.reference_cli} differ on {SCENE}")
        print(f"equal, byte for byte, to {a.reference_cli} on scenes/{SCENE}")
    print("PASS")


if __name__ == "__main__":
    main()
