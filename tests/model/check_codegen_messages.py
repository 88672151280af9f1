#!/usr/bin/env python3
"""Runs model_codegen.py on every bad fixture of tests/model/fixtures/expected.tsv and
checks that it fails with exactly the expected message (the one the run-time loader
gives too: test_model_toml checks that side), and that it accepts the good models.
Also: its sane ranges and TOML input limits are legsim.h's and toml_limits.hpp's, and
hostile text too large to commit (made here) gets the loader's messages.

    check_codegen_messages.py CODEGEN CONFIG_H  (run from the source tree's root)
"""
import contextlib
import importlib.util
import io
import os
import re
import subprocess
import sys
import tempfile

FIXTURES = "tests/model/fixtures"


def capacities(config_h):
    caps = {}
    with open(config_h, encoding="utf-8") as f:
        for line in f:
            m = re.match(r"\s*#\s*define\s+(LEGSIM_MAX_[A-Z_]+)\s+([0-9]+)\b", line)
            if m:
                caps[m.group(1)] = m.group(2)
    return caps


def main():
    codegen, config_h = sys.argv[1], sys.argv[2]
    caps = capacities(config_h)
    passed = failed = 0

    # In-process (67 interpreter starts would take seconds): main() as the command line
    # runs it, stderr captured. One real subprocess run at the end checks the exit status.
    spec = importlib.util.spec_from_file_location("model_codegen", codegen)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)

    def run(path):
        err, out = io.StringIO(), io.StringIO()
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(out):
            rc = mod.main([path, "--symbol", "t", "--check", "--config", config_h])
        return subprocess.CompletedProcess([], rc, out.getvalue(), err.getvalue())

    goods = ["models/leg.toml", f"{FIXTURES}/good_mini.toml"]
    # the two-leg robot, where the build's capacities hold it (else the capacity message)
    robot_fits = all(int(caps.get(k, 0)) >= n for k, n in (
        ("LEGSIM_MAX_BODIES", 13), ("LEGSIM_MAX_JOINTS", 16), ("LEGSIM_MAX_ACTUATORS", 4),
        ("LEGSIM_MAX_CONTACTS", 2)))
    if robot_fits:
        goods.append("models/robot.toml")
    for good in goods:
        r = run(good)
        if r.returncode == 0:
            passed += 1
        else:
            failed += 1
            print(f"FAIL {good}: rejected: {r.stderr.strip()}")

    with open(f"{FIXTURES}/expected.tsv", encoding="utf-8") as f:
        rows = [line.rstrip("\n").split("\t") for line in f if line.strip() and not line.startswith("#")]
    for fixture, _variant, _status, tools, match, message in rows:
        if tools != "both":
            continue
        message = re.sub(r"\$\{(LEGSIM_MAX_[A-Z_]+)\}", lambda m: caps[m.group(1)], message)
        path = f"{FIXTURES}/{fixture}"
        want = f"model_codegen: error: {path}: {message}"
        r = run(path)
        got = r.stderr.strip()
        ok = r.returncode != 0 and (got == want if match == "exact" else got.startswith(want))
        if ok:
            passed += 1
        else:
            failed += 1
            print(f"FAIL {fixture}: exit {r.returncode}\n  want: {want}\n  got:  {got}")
    # The sane ranges and the TOML input limits are the C side's: legsim.h and toml_limits.hpp.
    header = open("firmware_core/include/legsim/legsim.h", encoding="utf-8").read()
    defines = dict(re.findall(r"#define\s+(LEGSIM_(?:MAX|MIN)_[A-Z0-9_]+)\s+([0-9.e+-]+)", header))
    same = {"MAX_COORD": "LEGSIM_MAX_COORD", "MAX_GRAVITY": "LEGSIM_MAX_GRAVITY_MPS2",
            "MIN_LENGTH": "LEGSIM_MIN_LENGTH_M", "MIN_MASS": "LEGSIM_MIN_MASS_KG",
            "MAX_MASS": "LEGSIM_MAX_MASS_KG", "MIN_INERTIA": "LEGSIM_MIN_INERTIA_KGM2",
            "MAX_INERTIA": "LEGSIM_MAX_INERTIA_KGM2", "MIN_FORCE": "LEGSIM_MIN_FORCE_N",
            "MAX_FORCE": "LEGSIM_MAX_FORCE_N", "MAX_STIFFNESS": "LEGSIM_MAX_STIFFNESS_N_PER_M",
            "MAX_DAMPING": "LEGSIM_MAX_DAMPING_NS_PER_M"}
    limits = open("firmware_core/host/toml_limits.hpp", encoding="utf-8").read()
    consts = {k: v.replace(" ", "") for k, v in
              re.findall(r"constexpr \S+ (kToml\w+) = ([0-9 *]+);", limits)}
    same_limits = {"TOML_MAX_BYTES": "kTomlMaxBytes", "TOML_MAX_KEY_PARTS": "kTomlMaxKeyParts",
                   "TOML_MAX_NESTING": "kTomlMaxNesting"}
    for py, c in same.items():
        ok = c in defines and float(defines[c]) == getattr(mod, py)
        passed, failed = passed + ok, failed + (not ok)
        if not ok:
            print(f"FAIL range {py} = {getattr(mod, py)} but legsim.h {c} = {defines.get(c)}")
    for py, c in same_limits.items():
        ok = c in consts and eval(consts[c]) == getattr(mod, py)
        passed, failed = passed + ok, failed + (not ok)
        if not ok:
            print(f"FAIL limit {py} = {getattr(mod, py)} but toml_limits.hpp {c} = {consts.get(c)}")

    # Hostile text too large to commit, made here as test_model_toml.cpp makes it: the same
    # messages ("larger than", dotted parts, nesting) as the loader's.
    leg = open("models/leg.toml", "rb").read()
    parts = "a key or table header of more than 16 dotted parts (line 1)"
    nested = "arrays, inline tables or headers nested deeper than 16 (line 1)"
    hostile = [
        ("dotted_key", b".".join([b"a"] * 50000) + b" = 1\n", parts),
        ("dotted_header", b"[" + b".".join([b"a"] * 50000) + b"]\n", parts),
        ("nested_arrays", b"a = " + b"[" * 10000 + b"]" * 10000 + b"\n", nested),
        ("nested_tables", b"a = " + b"{b = " * 10000 + b"1" + b"}" * 10000 + b"\n", nested),
        ("big", leg + b"#" + b"x" * (mod.TOML_MAX_BYTES - len(leg)), "larger than 1048576 bytes"),
    ]
    with tempfile.TemporaryDirectory() as tmp:
        for name, data, why in hostile:
            path = os.path.join(tmp, name + ".toml")
            with open(path, "wb") as f:
                f.write(data)
            r = run(path)
            want = f"model_codegen: error: {path}: TOML input refused: {why}"
            ok = r.returncode != 0 and r.stderr.strip() == want
            passed, failed = passed + ok, failed + (not ok)
            if not ok:
                print(f"FAIL generated {name}: exit {r.returncode}\n  want: {want}\n  got:  {r.stderr.strip()}")
        # exactly 1 MiB with non-ASCII in comments: accepted
        path = os.path.join(tmp, "edge.toml")
        text = leg + "# \u00e9t\u00e9 \u03b1\n".encode()
        with open(path, "wb") as f:
            f.write(text + b"#" + b"x" * (mod.TOML_MAX_BYTES - len(text) - 2) + b"\n")
        r = run(path)
        ok = r.returncode == 0 and os.path.getsize(path) == mod.TOML_MAX_BYTES
        passed, failed = passed + ok, failed + (not ok)
        if not ok:
            print(f"FAIL a 1 MiB model within the limits was refused: {r.stderr.strip()}")

    r = subprocess.run([sys.executable, codegen, f"{FIXTURES}/bad_end.toml", "--symbol", "t",
                        "--check"], capture_output=True, text=True)
    if r.returncode == 1 and "bad end 'middle'" in r.stderr:
        passed += 1
    else:
        failed += 1
        print(f"FAIL bad_end.toml as a command: exit {r.returncode}: {r.stderr.strip()}")
    print(f"{passed} passed, {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    os.environ.setdefault("PYTHONDONTWRITEBYTECODE", "1")
    sys.exit(main())
