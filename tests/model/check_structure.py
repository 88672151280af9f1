#!/usr/bin/env python3
"""`legsim_model FILE --emit-structure` gives what the kernel generator reads, checked
against the model files read here on their own (tomllib), through kernel_codegen.py's
load_structure.

    check_structure.py LEGSIM_MODEL   (run from the source tree's root)
"""
import importlib.util
import os
import subprocess
import sys
import tempfile
import tomllib

FRAME = -1


def structure(tool, path, out):
    subprocess.run([tool, path, "--emit-structure", "--out", out], check=True)
    spec = importlib.util.spec_from_file_location("kernel_codegen", "firmware_core/tools/kernel_codegen.py")
    kc = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(kc)
    return kc.load_structure(out)


def expected_leg(doc, variant):
    """A leg file's structure from its TOML: bodies by id, joints in file order."""
    names = [b["name"] for b in sorted(doc["body"], key=lambda b: b["id"])]
    joints = []
    for j in doc["joint"]:
        j = dict(j, **doc.get("variant", {}).get(variant, {}).get(j["name"], {}))
        body = [j["body"] - 1, FRAME] if j["kind"] == "revolute_to_frame" else [b - 1 for b in j["bodies"]]
        joints.append({"name": j["name"], "kind": j["kind"], "body": body})
    jn = [j["name"] for j in doc["joint"]]
    acts = [{"name": a["name"], "joint": jn.index(a["joint"])} for a in doc.get("actuator", [])]
    return {"bodies": [{"name": n} for n in names], "joints": joints, "actuators": acts, "contacts": []}


def main():
    tool = sys.argv[1]
    failures = []
    with tempfile.TemporaryDirectory() as tmp:
        for path in ("models/leg.toml", "tests/model/fixtures/good_mini.toml"):
            with open(path, "rb") as f:
                doc = tomllib.load(f)
            got = structure(tool, path, os.path.join(tmp, "s.json"))
            want_names = ["revolute"] + list(doc.get("variant", {}))
            if [v for v, _ in got] != want_names:
                failures.append(f"{path}: variants {[v for v, _ in got]} != {want_names}")
            for v, model in got:
                want = expected_leg(doc, v)
                if model != want:
                    failures.append(f"{path} [{v}]: {model} != {want}")
        # the robot: the box, each leg's bodies after it, frame joints on the box, one contact
        # per leg on its foot's body
        got = structure(tool, "models/robot.toml", os.path.join(tmp, "r.json"))
        with open("models/leg.toml", "rb") as f:
            leg_doc = tomllib.load(f)
        leg = expected_leg(leg_doc, "revolute")
        with open("models/robot.toml", "rb") as f:
            robot = tomllib.load(f)
        (name, model), = got
        nb = len(leg["bodies"])
        want_joints = []
        for k in range(len(robot["leg"])):
            for j in leg["joints"]:
                a, b = j["body"]
                kind = "revolute" if j["kind"] == "revolute_to_frame" else j["kind"]
                want_joints.append([kind, [1 + k * nb + a, 0 if b == FRAME else 1 + k * nb + b]])
        if name != "revolute" or len(model["bodies"]) != 1 + nb * len(robot["leg"]):
            failures.append(f"robot: {name}, {len(model['bodies'])} bodies")
        if [[j["kind"], j["body"]] for j in model["joints"]] != want_joints:
            failures.append(f"robot joints: {model['joints']}")
        foot = leg_doc["foot"]["body"] - 1
        if [c["body"] for c in model["contacts"]] != [1 + k * nb + foot for k in range(len(robot["leg"]))]:
            failures.append(f"robot contacts: {model['contacts']}")
        # the generator's separator (layout.cpp's rule): the box of four and six legs, none for
        # the leg (six rows on its upper rod) or two legs (twelve hip rows); generate() leaves
        # the separated ones to the general path
        spec = importlib.util.spec_from_file_location("kernel_codegen", "firmware_core/tools/kernel_codegen.py")
        kc = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(kc)
        for path, want in (("models/leg.toml", None), ("models/robot.toml", None),
                           ("models/robot4.toml", 0), ("models/robot6.toml", 0)):
            js = os.path.join(tmp, "sep.json")
            (_, model), *_ = structure(tool, path, js)
            for stance in (False, True):
                got_sep = kc.separator(kc.Kernel("x", model, stance).rows)
                if got_sep != want:
                    failures.append(f"{path}: separator {got_sep} != {want} (stance {stance})")
            if want is not None and "kernel_" in kc.generate([js]).split("kKernels[] = {")[1].split("nullptr")[0]:
                failures.append(f"{path}: a kernel generated for a separated block")
        # a bad model: no structure, the loader's message
        r = subprocess.run([tool, "tests/model/fixtures/joint_body_zero.toml", "--emit-structure"],
                           capture_output=True, text=True)
        if r.returncode != 1 or not r.stderr.startswith("legsim_model: error: tests/model/fixtures/joint_body_zero.toml: "):
            failures.append(f"bad model: exit {r.returncode}, {r.stderr!r}")
    for f in failures:
        print("FAIL", f)
    print(f"{'FAILED' if failures else 'OK'}: structure of leg.toml, good_mini.toml, robot.toml; separators")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
