#!/usr/bin/env python3
"""Runs model_codegen.py on every bad fixture of tests/model/fixtures/expected.tsv and
checks that it fails with exactly the expected message (the one the run-time loader
gives too: test_model_toml checks that side), and that it accepts the good models.

    check_codegen_messages.py CODEGEN CONFIG_H  (run from the source tree's root)
"""
import contextlib
import importlib.util
import io
import os
import re
import subprocess
import sys

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

    for good in ("models/leg.toml", f"{FIXTURES}/good_mini.toml"):
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
