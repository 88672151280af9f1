#!/usr/bin/env python3
"""The robot's cost per step beside the one leg's, feet stuck and with a slipping foot
(issue 9, section 8), and the leg's under a controller that sends a new command every step
(leg-loop), as one command: instructions per step under valgrind's callgrind
and wall time (min over repetitions), for every case and integrator of robot_step_cost
(firmware_core/benchmarks/robot_step_cost.c), printed as a Markdown table.

    firmware_core/benchmarks/robot_step_cost.py [--bin build/host/firmware_core/benchmarks/robot_step_cost]
        [--steps 700] [--reps 5] [--no-callgrind] [--no-wall]

Instructions: one callgrind run per case and integrator; each kind of step (stuck,
slip1, slip2, change) runs through its own function, whose inclusive cost divided by the
program's count of that kind is the kind's instructions per step. Wall time: the
program's own min over --reps repetitions of each kind's median step time (set-up
excluded; the median leaves out the steps the OS preempted on a shared machine).
Needs valgrind (callgrind_annotate) unless --no-callgrind. Python 3 standard library only.

    firmware_core/benchmarks/robot_step_cost.py --legs [--bin build/host/firmware_core/benchmarks/robot_step_cost_legs]

--legs: the scaling case instead, the robot files of 2, 4 and 6 legs (models/robot.toml,
robot4.toml, robot6.toml) standing on stuck feet (case stand:PATH, the general path), with
each one's cost over the two-leg robot's, by the program built in the six-leg capacities.
"""
import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile

CASES = ("leg", "leg-loop", "robot", "robot-slip")
INTEGRATORS = ("rk4", "galpha")
KINDS = ("stuck", "slip1", "slip2", "change")
KIND_TEXT = {"stuck": "no foot sliding", "slip1": "one foot sliding, one stuck",
             "slip2": "both feet sliding", "change": "a contact event in the step"}
INTEGRATOR_TEXT = {"rk4": "RK4", "galpha": "generalized-alpha"}
LEG_FILES = ((2, "models/robot.toml"), (4, "models/robot4.toml"), (6, "models/robot6.toml"))


def run(cmd):
    r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if r.returncode != 0:
        sys.exit(f"robot_step_cost.py: {' '.join(cmd)} failed ({r.returncode}):\n{r.stdout}{r.stderr}")
    return r.stdout


def kind_counts(text):
    m = re.search(r"steps by kind:((?: \w+ \d+)+)", text)
    if not m:
        sys.exit(f"robot_step_cost.py: no 'steps by kind' in:\n{text}")
    f = m.group(1).split()
    return {f[i]: int(f[i + 1]) for i in range(0, len(f), 2)}


def instructions(binary, case, integrator, steps, tmp):
    """{kind: instructions per step} and the counts, from one callgrind run"""
    out = os.path.join(tmp, f"cg.{re.sub(r'[^A-Za-z0-9.-]', '_', case)}.{integrator}")
    text = run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}",
                binary, case, integrator, str(steps)])
    counts = kind_counts(text)
    ann = run(["callgrind_annotate", "--inclusive=yes", "--threshold=100", out])
    per = {}
    for kind in KINDS:
        m = re.search(r"^\s*([\d,]+) .*\bstep_" + kind + r"\b", ann, re.M)
        if counts.get(kind):
            if not m:
                sys.exit(f"robot_step_cost.py: step_{kind} not in callgrind's output for {case} {integrator}")
            per[kind] = int(m.group(1).replace(",", "")) / counts[kind]
    return per, counts


def wall(binary, case, integrator, steps, reps):
    text = run([binary, case, integrator, str(steps), str(reps)])
    m = re.search(r"each kind's median:((?: \w+ [\d.]+)+)", text)
    if not m:
        sys.exit(f"robot_step_cost.py: no wall times in:\n{text}")
    f = m.group(1).split()
    return {f[i]: float(f[i + 1]) for i in range(0, len(f), 2)}, kind_counts(text)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    ap.add_argument("--bin", default=os.path.join(root, "build/host/firmware_core/benchmarks/robot_step_cost"))
    ap.add_argument("--steps", type=int, default=700,
                    help="steps per run (700: robot-slip's feet all stay on the ground)")
    ap.add_argument("--reps", type=int, default=5, help="wall-time repetitions")
    ap.add_argument("--no-callgrind", action="store_true")
    ap.add_argument("--no-wall", action="store_true")
    ap.add_argument("--legs", action="store_true", help="the scaling case: 2, 4 and 6 legs, feet stuck")
    a = ap.parse_args()
    if a.legs and "--bin" not in " ".join(sys.argv):
        a.bin += "_legs"
    if not os.access(a.bin, os.X_OK):
        sys.exit(f"robot_step_cost.py: {a.bin} not built (cmake --build <dir> --target robot_step_cost)")
    if not a.no_callgrind and not (shutil.which("valgrind") and shutil.which("callgrind_annotate")):
        sys.exit("robot_step_cost.py: valgrind not found (apt-get install valgrind), or pass --no-callgrind")

    if a.legs:
        return legs_table(a, root)
    rows = {}
    with tempfile.TemporaryDirectory() as tmp:
        for case in CASES:
            for integ in INTEGRATORS:
                ins, counts = ({}, None) if a.no_callgrind else instructions(a.bin, case, integ, a.steps, tmp)
                us, counts_w = ({}, None) if a.no_wall else wall(a.bin, case, integ, a.steps, a.reps)
                rows[case, integ] = (ins, us, counts or counts_w)
                print(f"{case} {integ}: steps {counts or counts_w} insns {ins} us {us}", file=sys.stderr)

    print(f"`{' '.join([os.path.relpath(sys.argv[0], root)] + sys.argv[1:])}`: {a.steps} steps (h = 1 ms), "
          f"wall time the min over {a.reps} repetitions of each kind's median step\n")
    print("| case | integrator | steps of the kind | steps | instructions/step | x one leg | wall us/step | x one leg |")
    print("|---|---|---|---|---|---|---|---|")
    for case in CASES:
        for integ in INTEGRATORS:
            ins, us, counts = rows[case, integ]
            leg_ins, leg_us, _ = rows["leg", integ]
            for kind in KINDS:
                if not counts.get(kind):
                    continue
                i = ins.get(kind)
                w = us.get(kind)
                ri = f"{i / leg_ins['stuck']:.2f}" if i and leg_ins else "-"
                rw = f"{w / leg_us['stuck']:.2f}" if w and leg_us else "-"
                print(f"| {case} | {INTEGRATOR_TEXT[integ]} | {KIND_TEXT[kind]} | {counts[kind]} | "
                      f"{f'{i:,.0f}' if i else '-'} | {ri} | {f'{w:.2f}' if w else '-'} | {rw} |")
    return 0


def legs_table(a, root):
    """instructions (and wall time) per stuck step of the 2-, 4- and 6-leg robots"""
    rows = {}
    with tempfile.TemporaryDirectory() as tmp:
        for legs, path in LEG_FILES:
            case = "stand:" + os.path.join(root, path)
            for integ in INTEGRATORS:
                ins, counts = ({}, None) if a.no_callgrind else instructions(a.bin, case, integ, a.steps, tmp)
                us, counts_w = ({}, None) if a.no_wall else wall(a.bin, case, integ, a.steps, a.reps)
                counts = counts or counts_w
                if counts.get("stuck") != a.steps:
                    sys.exit(f"robot_step_cost.py: {path} {integ}: not every step with the feet stuck: {counts}")
                rows[legs, integ] = (ins.get("stuck"), us.get("stuck"))
                print(f"{path} {integ}: insns {ins} us {us}", file=sys.stderr)
    print(f"`{' '.join([os.path.relpath(sys.argv[0], root)] + sys.argv[1:])}`: {a.steps} steps (h = 1 ms), "
          f"feet stuck, the general path\n")
    print("| legs | file | integrator | instructions/step | x two legs | wall us/step | x two legs |")
    print("|---|---|---|---|---|---|---|")
    for legs, path in LEG_FILES:
        for integ in INTEGRATORS:
            i, w = rows[legs, integ]
            i2, w2 = rows[2, integ]
            print(f"| {legs} | {path} | {INTEGRATOR_TEXT[integ]} | {f'{i:,.0f}' if i else '-'} | "
                  f"{f'{i / i2:.2f}' if i else '-'} | {f'{w:.2f}' if w else '-'} | {f'{w / w2:.2f}' if w else '-'} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
