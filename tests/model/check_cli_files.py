#!/usr/bin/env python3
"""legsim_cli and the files its readers open (run from the source tree's root).

    check_cli_files.py CLI WORKDIR

Every file the model and scene readers open is a regular file or refused at once with a
message (a FIFO never blocks the CLI): a scene file, a model file, a robot's leg file.
A robot's leg file that states another gravity is refused with a message naming both
files and both values. The ground's slope rule is legsim.h's LEGSIM_MAX_SLOPE_RAD: a slope
of the bound loads, the next one past it is refused with the range in the message.
Each case runs the CLI with a time limit: a reader that blocks fails the check.
"""
import math
import os
import re
import shutil
import subprocess
import sys

TIME_LIMIT_S = 20
failures = []


def check(cond, what):
    if not cond:
        failures.append(what)
    return cond


def run(cli, scene, what):
    """(exit status, stderr), or None when the CLI did not finish within the limit."""
    try:
        r = subprocess.run([cli, scene, "--out", os.devnull], capture_output=True, text=True,
                           timeout=TIME_LIMIT_S, stdin=subprocess.DEVNULL)
    except subprocess.TimeoutExpired:
        check(False, f"{what}: legsim_cli still running after {TIME_LIMIT_S} s (a reader blocks)")
        return None
    return r.returncode, r.stderr


def expect_error(cli, scene, what, *needles):
    got = run(cli, scene, what)
    if got is None:
        return
    rc, err = got
    check(rc != 0, f"{what}: exit {rc}, expected a failure; stderr: {err.strip()}")
    for n in needles:
        check(n in err, f"{what}: stderr lacks {n!r}: {err.strip()}")


def write(path, text):
    with open(path, "w", encoding="utf-8") as f:
        f.write(text)


def robot_text(gravity_line=None, slope=None):
    """models/robot.toml with its leg file at ./leg.toml (the folder of the copy)."""
    with open("models/robot.toml", encoding="utf-8") as f:
        text = f.read()
    if gravity_line is not None:
        text, n = re.subn(r"^gravity = .*$", gravity_line, text, count=1, flags=re.M)
        assert n == 1
    if slope is not None:
        text, n = re.subn(r"^slope = 0\.0", f"slope = {slope!r}", text, count=1, flags=re.M)
        assert n == 1, "models/robot.toml has no 'slope = 0.0'"
    return text


def scene_text(model):
    return (f'model = "{model}"\nanalysis = "dynamics"\nintegrator = "rk4"\nstep_s = 0.001\n'
            'duration = 0.002\n')


def slope_bound():
    with open("firmware_core/include/legsim/legsim.h", encoding="utf-8") as f:
        m = re.search(r"^#define LEGSIM_MAX_SLOPE_RAD\s+(\S+)", f.read(), re.M)
    assert m, "legsim.h defines no LEGSIM_MAX_SLOPE_RAD"
    return float(m.group(1))


def main():
    cli, work = sys.argv[1], os.path.join(sys.argv[2], f"cli_files_{os.getpid()}")
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    try:
        # a robot whose leg file is a FIFO (nobody ever writes it)
        d = os.path.join(work, "fifo_leg")
        os.makedirs(d)
        os.mkfifo(os.path.join(d, "leg.toml"))
        write(os.path.join(d, "robot.toml"), robot_text())
        write(os.path.join(d, "scene.toml"), scene_text("robot.toml"))
        expect_error(cli, os.path.join(d, "scene.toml"), "leg file a FIFO",
                     "leg 'right': file 'leg.toml': cannot read: not a regular file")
        # the model file a FIFO, the scene file a FIFO, the scene file a folder
        write(os.path.join(d, "scene_fifo_model.toml"), scene_text("leg.toml"))
        expect_error(cli, os.path.join(d, "scene_fifo_model.toml"), "model file a FIFO",
                     "leg.toml: cannot read: not a regular file")
        os.mkfifo(os.path.join(d, "fifo_scene.toml"))
        expect_error(cli, os.path.join(d, "fifo_scene.toml"), "scene file a FIFO",
                     "fifo_scene.toml: cannot read: not a regular file")
        expect_error(cli, d, "scene file a folder", f"{d}: cannot read: not a regular file")

        # a leg file's gravity differs from the robot's: both files and values named
        d = os.path.join(work, "gravity")
        os.makedirs(d)
        shutil.copy("models/leg.toml", os.path.join(d, "leg.toml"))
        write(os.path.join(d, "robot.toml"), robot_text(gravity_line="gravity = [0.0, -1.62]"))
        write(os.path.join(d, "scene.toml"), scene_text("robot.toml"))
        expect_error(cli, os.path.join(d, "scene.toml"), "leg gravity differs",
                     "robot.toml", "the gravity of 'leg.toml', [0, -9.81] m/s^2, differs from the "
                     "robot's [0, -1.62] m/s^2")
        # the same gravity stated in both loads and runs
        write(os.path.join(d, "robot.toml"), robot_text(gravity_line="gravity = [0.0, -9.81]"))
        got = run(cli, os.path.join(d, "scene.toml"), "same gravity")
        if got is not None:
            check(got[0] == 0, f"same gravity: exit {got[0]}: {got[1].strip()}")

        # the slope: the bound loads, the next double past it is refused, on either side
        bound = slope_bound()
        past = math.nextafter(bound, 2.0)
        for slope, ok in ((bound, True), (-bound, True), (past, False), (-past, False)):
            d = os.path.join(work, f"slope_{slope!r}")
            os.makedirs(d)
            shutil.copy("models/leg.toml", os.path.join(d, "leg.toml"))
            write(os.path.join(d, "robot.toml"), robot_text(slope=slope))
            write(os.path.join(d, "scene.toml"), scene_text("robot.toml"))
            what = f"slope {slope!r}"
            if ok:
                # the model loads; the scene may still fail later (the stand on so steep a
                # ground need not hold), but never in the loader
                got = run(cli, os.path.join(d, "scene.toml"), what)
                if got is not None:
                    check("'slope'" not in got[1], f"{what}: refused: {got[1].strip()}")
            else:
                expect_error(cli, os.path.join(d, "scene.toml"), what,
                             f"ground: 'slope' must be in [{-bound:g}, {bound:g}] rad (got {slope!r})")
    finally:
        shutil.rmtree(work, ignore_errors=True)
    for f in failures:
        print("FAIL:", f)
    print(f"{len(failures)} failure(s)")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
