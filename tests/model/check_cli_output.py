#!/usr/bin/env python3
"""Checks legsim_cli's output (run from the source tree's root).

    check_cli_output.py CLI SCENE.toml OUTDIR
        runs the scene to JSON and to CSV: both parse, hold the expected keys and
        columns, agree, and report status ok with a small constraint residual.
    check_cli_output.py CLI --same SCENE_A SCENE_B OUTDIR
        the two scenes (same inputs, the model from the TOML file and compiled in) give
        exactly the same samples.
    check_cli_output.py CLI --bad EXPECTED.tsv OUTDIR
        runs each bad scene of EXPECTED.tsv: the exit status and the message on stderr
        are the expected ones; a failed run (exit 1) still writes JSON with status "error".
"""
import csv
import json
import math
import os
import subprocess
import sys
import tomllib

failures = []
# per contact in legsim_cli's output, after its state (firmware_core/host/scene_write.cpp)
CONTACT_NUMBERS = ("normal", "tangential", "friction_use", "x", "y", "slip", "impulse_n", "impulse_t")
CONTACT_COLUMNS = ("normal_n", "tangential_n", "friction_use", "x_m", "y_m", "slip_m_per_s", "impulse_n_n_s",
                   "impulse_t_n_s")


def check(cond, what):
    if not cond:
        failures.append(what)
    return cond


def run(cli, scene, out=None, fmt=None):
    cmd = [cli, scene]
    if out:
        cmd += ["--out", out]
    if fmt:
        cmd += ["--format", fmt]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=600)


def check_good(cli, scene, outdir):
    name = os.path.splitext(os.path.basename(scene))[0]
    with open(scene, "rb") as f:
        spec = tomllib.load(f)
    analysis = spec.get("analysis", "dynamics")
    js, cs = os.path.join(outdir, name + ".json"), os.path.join(outdir, name + ".csv")
    r = run(cli, scene, js)
    if not check(r.returncode == 0, f"{name}: exit {r.returncode}: {r.stderr.strip()}"):
        return
    with open(js, encoding="utf-8") as f:
        d = json.load(f)  # raises (test fails) if it is not JSON
    if d.get("kind") == "hexapod":
        check_hexapod(cli, scene, spec, d, name)
        return
    if d.get("kind") == "block":
        check_block(cli, scene, spec, d, name)
        return
    for key in ("scene", "model", "analysis", "integrator", "step_s", "record_every", "status", "status_code", "bodies",
                "joints", "actuators", "samples"):
        check(key in d, f"{name}: JSON lacks '{key}'")
    check(d.get("status") == "ok" and d.get("status_code") == "LEGSIM_OK", f"{name}: status {d.get('status')}")
    check(d.get("analysis") == analysis, f"{name}: analysis {d.get('analysis')}")
    check(d["model"].get("variant") == spec.get("variant", "revolute"), f"{name}: variant")
    bodies, joints, acts = d["bodies"], d["joints"], d["actuators"]
    contacts = d.get("contacts", [])
    robot = bool(contacts)
    if robot:  # models/robot.toml: the box on two legs, a contact per foot
        check(len(bodies) == 13 and len(joints) == 16 and len(acts) == 4 and len(contacts) == 2,
              f"{name}: robot sizes")
        check(set(d["ground"]) == {"point", "slope", "mu_static", "mu_kinetic"}, f"{name}: ground")
        check(len(d["body_lengths"]) == len(bodies), f"{name}: body_lengths")
    else:
        check(len(bodies) == 6 and len(joints) == 8 and len(acts) == 2, f"{name}: leg sizes")
    samples = d["samples"]
    if analysis == "statics_sweep":
        w = d.get("worst_case")
        if check(isinstance(w, dict), f"{name}: no worst_case"):
            check(w["n_poses"] > 0, f"{name}: sweep evaluated no pose")
            check(w["n_poses"] + w["n_failed"] == w["grid"] ** 2, f"{name}: sweep count")
            check(set(w["reactions"]) == set(joints), f"{name}: worst-case reactions by joint")
            check(set(w["actuators"]) == set(acts), f"{name}: worst-case actuators")
            for j, v in w["reactions"].items():
                check(v["max_force"] >= 0 and set(v["at_lengths"]) == set(acts), f"{name}: reaction {j}")
    else:
        # Residual bound loose enough for a float build (newton_tol 1e-5 there).
        check(len(samples) >= 1, f"{name}: no samples")
        if analysis in ("dynamics", "inverse_dynamics"):
            n = round(spec["duration"] / spec.get("step_s", 0.001))
            check(abs(n * spec.get("step_s", 0.001) - spec["duration"]) < 1e-9, f"{name}: duration off the grid")
            every = spec.get("record_every", 1)
            check(d["record_every"] == every, f"{name}: record_every {d['record_every']}")
            check(len(samples) >= n // every, f"{name}: {len(samples)} samples for {n} steps / {every}")
            check(abs(samples[-1]["t"] - spec["duration"]) < 1e-9, f"{name}: last t {samples[-1]['t']}")
        reactions_on = "reactions" not in spec.get("disable", [])
        prev_t = -1.0
        for s in samples:
            check(s["t"] > prev_t, f"{name}: time not increasing")
            prev_t = s["t"]
            check(set(s["q"]) == set(bodies), f"{name}: q by body")
            for b, c in s["q"].items():
                check(set(c) == {"x", "y", "phi"} and all(math.isfinite(v) for v in c.values()),
                      f"{name}: q of {b}")
            check(set(s["actuators"]) == set(acts), f"{name}: actuators by name")
            for a, v in s["actuators"].items():
                check(set(v) == {"length", "rate", "force"}, f"{name}: actuator {a} keys")
            if reactions_on and s["reactions"] is not None:
                check(set(s["reactions"]) == set(joints), f"{name}: reactions by joint")
                for j, v in s["reactions"].items():
                    check(set(v) == {"fx", "fy", "moment"}, f"{name}: reaction {j} keys")
            check(s["residual"] is not None and s["residual"] < 1e-4, f"{name}: residual {s['residual']}")
            if robot:
                check(s["foot"] is None and set(s["contacts"]) == set(contacts), f"{name}: contacts by name")
                for c, v in s["contacts"].items():
                    check(set(v) == {"state", *CONTACT_NUMBERS, "holds"}, f"{name}: contact {c} keys")
                    check(v["holds"] in (None, True, False), f"{name}: contact {c} holds")
                    check(v["state"] in ("free", "stuck", "sliding"), f"{name}: contact {c} state")
                    check(all(v[k] is None or math.isfinite(v[k]) for k in CONTACT_NUMBERS),
                          f"{name}: contact {c} numbers")
                    # a stuck foot is on the ground line (the model's: a point and a slope)
                    g = d["ground"]
                    gap = (-math.sin(g["slope"]) * (v["x"] - g["point"][0])
                           + math.cos(g["slope"]) * (v["y"] - g["point"][1])) if v["state"] == "stuck" else 0.0
                    check(abs(gap) < 1e-9, f"{name}: stuck {c} off the ground by {gap:.3g} m")
            else:
                check(s["foot"] is not None, f"{name}: foot")
        if analysis in ("statics",):
            check(samples[0]["reactions"] is not None, f"{name}: statics without reactions")
    # The same run as CSV (format from the extension).
    r = run(cli, scene, cs)
    if not check(r.returncode == 0, f"{name}: CSV run exit {r.returncode}: {r.stderr.strip()}"):
        return
    with open(cs, newline="", encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
        header = list(rows[0].keys()) if rows else []
    if analysis == "statics_sweep":
        check(len(rows) == len(joints) + len(acts), f"{name}: CSV sweep rows")
        check(header == ["item", "kind", "max_force_n", *[f"at_{a}_m" for a in acts], "status"],
              f"{name}: CSV sweep header {header}")
        return
    check(len(rows) == len(samples), f"{name}: CSV has {len(rows)} rows for {len(samples)} samples")
    # the columns carry their SI units
    want = ["t_s"] + [f"{b}.{c}" for b in bodies for c in ("x_m", "y_m", "phi_rad")] + \
        [f"{a}.{k}" for a in acts for k in ("length_m", "rate_m_per_s", "force_n")] + \
        [f"{j}.{k}" for j in joints for k in ("fx_n", "fy_n", "moment_nm")] + \
        ([f"{c}.{k}" for c in contacts for k in ("state", *CONTACT_COLUMNS, "holds")] if robot
         else ["foot.x_m", "foot.y_m"]) + \
        ["residual", "events", "status"]
    check(header == want, f"{name}: CSV header {header}")
    for row, s in zip(rows, samples):
        check(row["status"] == "ok", f"{name}: CSV status {row['status']}")
        check((row["events"].split(";") if row["events"] != "none" else []) == s["events"],
              f"{name}: CSV events {row['events']!r} vs JSON {s['events']}")
        check(float(row["t_s"]) == s["t"], f"{name}: CSV t")
        b0 = bodies[0]
        check(float(row[f"{b0}.phi_rad"]) == s["q"][b0]["phi"], f"{name}: CSV and JSON disagree")
    # stdout and --format
    r = run(cli, scene, None, "csv")
    check(r.returncode == 0 and r.stdout.startswith("t_s,"), f"{name}: CSV on stdout")


def _dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def ground_split(d, force):
    """A ground force on a foot: (N along the header's ground normal, |F_t| along the plane)."""
    n = d["ground"]["normal"]
    N = _dot(force, n)
    return N, math.sqrt(max(0.0, _dot(force, force) - N * N))


def over_ground(d, x):
    """A point's height over the header's ground plane, along its normal."""
    g = d["ground"]
    return _dot([a - b for a, b in zip(x, g["point"])], g["normal"])


def below_z(d, x, y):
    """The ground's z directly below (x, y)."""
    g = d["ground"]
    p, n = g["point"], g["normal"]
    return p[2] - (n[0] * (x - p[0]) + n[1] * (y - p[1])) / n[2]


def slip_and_work(d, points, com, commands=0.0):
    """The sliding contact points between consecutive samples (record_every 1; points(sample): name
    -> {state, x, force}): the worst | |F_t| - mu_k N | / N, the worst angle between the friction
    and the slip (the point's displacement, against the mean of the tangential forces at both
    ends; from the fourth step in a row it slides faster than 0.1 mm/s: slower, the core keeps a
    slip's direction (docs/design/spatial.md "Moving"), and a slip from rest turns onto its
    velocity over its first steps), and the energy balance as
    tests/model/test_hexapod_contact.cpp's: the energy (kinetic and gravity's at the centre of
    mass com(sample), less the commands' work) changes by the friction's work, | dE - W | / |W|,
    both works by the trapezoid rule."""
    mu_k, n = d["ground"]["mu_kinetic"], d["ground"]["normal"]
    mu_off = angle = work = 0.0
    samples = d["samples"]
    slow = 1e-4 * d["step_s"] * d["record_every"]  # m a sample at 0.1 mm/s
    fast = {k: 0 for k in points(samples[0])}  # steps in a row it slid faster than that
    for a, b in zip(samples, samples[1:]):
        pa, pb = points(a), points(b)
        for k in fast:
            fa, fb = pa[k], pb[k]
            dx = [q - p for p, q in zip(fa["x"], fb["x"])]
            f = [(p + q) / 2 for p, q in zip(fa["force"], fb["force"])]
            work += _dot(f, dx)
            moving = fa["state"] == fb["state"] == "sliding" and math.sqrt(_dot(dx, dx)) > slow
            fast[k] = fast[k] + 1 if moving else 0
            if fb["state"] != "sliding":
                continue
            N, Ft = ground_split(d, fb["force"])
            mu_off = max(mu_off, abs(Ft - mu_k * N) / N)
            if fast[k] >= 4:
                ft = [x - _dot(f, n) * m for x, m in zip(f, n)]
                c = -_dot(ft, dx) / math.sqrt(_dot(ft, ft) * _dot(dx, dx))
                angle = max(angle, math.acos(max(-1.0, min(1.0, c))))

    def mechanical(s):
        return s["kinetic_energy"] - d["mass"] * _dot(d["gravity"], com(s))

    lost = mechanical(samples[-1]) - mechanical(samples[0]) - commands
    return mu_off, angle, abs(lost - work) / abs(work) if work else math.inf


def hexapod_slip(d):
    """slip_and_work over the hexapod's feet, the actuators' and rowing motors' work the commands'."""
    commands = 0.0
    samples = d["samples"]
    for a, b in zip(samples, samples[1:]):
        for j in range(6):
            for i in range(2):
                commands += (a["actuator_forces"][j][i] + b["actuator_forces"][j][i]) / 2 * \
                    (b["lengths"][j][i] - a["lengths"][j][i])
            commands += (a["rowing_torques"][j] + b["rowing_torques"][j]) / 2 * (b["rowing"][j] - a["rowing"][j])
    return slip_and_work(d, lambda s: s["feet"], lambda s: s["com"], commands)


def block_check(d, key, want):
    """A block scene's [checks] key against its JSON (scenes/README.md, "A block"): (what the run
    gave, passed)."""
    samples, last = d["samples"], d["samples"][-1]
    final = {"box_x_m": last["box"][0], "box_y_m": last["box"][1], "box_z_m": last["box"][2]}
    if key in final:
        return final[key], abs(final[key] - want["value"]) <= want["tolerance"]
    if key == "rest_s":  # the first sample with every point stuck after one slid
        slid = False
        got = None
        for s in samples:
            states = [c["state"] for c in s["contacts"]]
            slid = slid or "sliding" in states
            if slid and all(x == "stuck" for x in states):
                got = s["t"]
                break
        return got, got is not None and abs(got - want["value"]) <= want["tolerance"]
    if key == "impacts_min":
        return last["impacts"], last["impacts"] >= want
    if key in ("slip_mu_off", "friction_work_off"):
        r = slip_and_work(d, lambda s: dict(enumerate(s["contacts"])), lambda s: s["box"])
        got = r[0] if key == "slip_mu_off" else r[2]
        return got, got <= want
    return None, False


def check_block(cli, scene, spec, d, name):
    """A block scene's JSON (scenes/README.md, "A block"): the run's samples on the step grid, its
    points on or above the ground, the stuck ones on it and inside their cones, its checks; CSV
    refused."""
    check(d["status"] == "ok" and d["status_code"] == "LEGSIM_OK", f"{name}: status {d['status']}")
    n, every, samples = d["n_steps"], d["record_every"], d["samples"]
    check(len(samples) == n // every + 1 + (1 if n % every else 0), f"{name}: {len(samples)} samples")
    check(abs(samples[-1]["t"] - spec["duration"]) < 1e-9, f"{name}: last t {samples[-1]['t']}")
    mu = d["ground"]["mu_static"]
    for s in samples:
        check(len(s["contacts"]) == len(d["box_contacts"]) > 0, f"{name}: contacts at t = {s['t']}")
        for k, c in enumerate(s["contacts"]):
            check(over_ground(d, c["x"]) > -1e-9, f"{name}: point {k} under the ground at t = {s['t']}")
            if c["state"] == "stuck":
                check(abs(over_ground(d, c["x"])) < 1e-9, f"{name}: stuck point {k} off the ground at t = {s['t']}")
                N, Ft = ground_split(d, c["force"])
                check(Ft <= mu * N + 1e-9, f"{name}: stuck point {k} outside its cone at t = {s['t']}")
            elif c["state"] == "free":
                check(c["force"] == [0, 0, 0], f"{name}: free point {k} with a force at t = {s['t']}")
        check(all(math.isfinite(v) for v in s["box"] + s["box_quat"]), f"{name}: box at t = {s['t']}")
    check((d["checks"] is None) == ("checks" not in spec) and set(d["checks"] or {}) == set(spec.get("checks", {})),
          f"{name}: checks {d['checks']}")
    for key, want in (d["checks"] or {}).items():
        got, ok = block_check(d, key, want)
        check(ok, f"{name}: checks.{key}: got {got}, want {want}")
    r = run(cli, scene, None, "csv")
    check(r.returncode == 2 and "JSON only" in r.stderr, f"{name}: CSV not refused: {r.stderr.strip()}")
    r = subprocess.run([cli, scene, "--check"], capture_output=True, text=True, timeout=60)
    check(r.returncode == 0 and json.loads(r.stdout)["kind"] == "block", f"{name}: --check")


def hexapod_check(d, key, want):
    """A hexapod scene's [checks] key against its JSON (scenes/README.md, "The hexapod"):
    (what the run gave, passed)."""
    if key == "margin_m":
        got = d["statics"]["margin"]
        return got, abs(got - want["value"]) <= want["tolerance"]
    samples, last = d["samples"], d["samples"][-1]
    w, x, y, z = last["box_quat"]
    final = {"box_x_m": last["box"][0], "box_y_m": last["box"][1], "box_z_m": last["box"][2],
             "yaw_rad": math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z)),
             "roll_rad": math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))}
    if key in final:
        return final[key], abs(final[key] - want["value"]) <= want["tolerance"]
    if key == "touchdown_s":
        got = next((s["t"] for s in samples if s["impacts"] > 0), None)
        return got, got is not None and abs(got - want["value"]) <= want["tolerance"]
    # the box's height over the ground directly below it, against the gait's (else the start's)
    p0 = d["pose"]["box"]
    height = d["gait"]["box_height_m"] if d["gait"] else p0[2] - d["lift"] - below_z(d, p0[0], p0[1])
    off = [abs(s["box"][2] - below_z(d, s["box"][0], s["box"][1]) - height) for s in samples]
    if key == "height_off_m":
        got = max(off)
    elif key == "settle_m":
        got = off[-1]
    elif key == "margin_min_m":
        got = min(s["margin"] for s in samples)
        return got, got >= want
    elif key == "friction_use_max":
        use = [Ft / N for s in samples if s["t"] > 0 for f in s["feet"].values() if f["state"] == "stuck"
               for N, Ft in [ground_split(d, f["force"])]]
        got = max(use) if use else 0.0
    elif key in ("slip_mu_off", "slip_angle_max_rad", "friction_work_off"):
        got = hexapod_slip(d)[("slip_mu_off", "slip_angle_max_rad", "friction_work_off").index(key)]
    elif key == "tilt_max_rad":
        got = max(2 * math.asin(min(1.0, math.hypot(*s["box_quat"][1:3]))) for s in samples)
    elif key == "impacts_min":
        return last["impacts"], last["impacts"] >= want
    elif key == "stuck_at_end":
        got = [k for k in d["legs"] if last["feet"][k]["state"] == "stuck"]
        return got, set(want) <= set(got)
    else:
        return None, False
    return got, got <= want


def check_reaction_sweep(d, name):
    """The Section V sweep's points (scenes/README.md, "Section V"): its part's indices in order;
    each standing point's stance feet on one level plane carrying the weight, the others' forces
    zero, and on a tripod the vertical forces the closed form of the centre of mass in the
    support triangle (to 1e-9 of the weight)."""
    sw, pts = d["sweep"], d["points"]
    check([p["index"] for p in pts] == list(range(sw["first"], sw["first"] + sw["count"])), f"{name}: indices")
    stance = sw["stance"]
    standing = [p for p in pts if p["status_code"] == "LEGSIM_OK"]
    check(len(standing) == d["summary"]["standing"] > 0, f"{name}: {len(standing)} standing points")
    weight = -d["mass"] * d["gravity"][2]
    for p in standing:
        feet = p["feet"]
        W = sum(feet[k]["force"][2] for k in stance)
        z = [feet[k]["x"][2] for k in stance]
        check(abs(W - weight) < 1e-9 * weight and max(z) - min(z) < 1e-9,
              f"{name}: point {p['index']}: the feet carry {W} N of the weight {weight} N, feet at z {z}")
        check(all(feet[k]["force"] == [0, 0, 0] for k in feet if k not in stance), f"{name}: forces off the stance")
        if len(stance) == 3:
            (ax, ay, _), (bx, by, _), (cx, cy, _) = (feet[k]["x"] for k in stance)
            gx, gy = p["com"][0], p["com"][1]
            det = (ax - cx) * (by - cy) - (bx - cx) * (ay - cy)
            wa = ((gx - cx) * (by - cy) - (bx - cx) * (gy - cy)) / det
            wb = ((ax - cx) * (gy - cy) - (gx - cx) * (ay - cy)) / det
            closed = (wa * W, wb * W, (1 - wa - wb) * W)
            off = max(abs(feet[k]["force"][2] - c) for k, c in zip(stance, closed))
            check(off < 1e-9 * W, f"{name}: point {p['index']}: vertical forces off the closed form by {off} N")


def check_hexapod(cli, scene, spec, d, name):
    """A hexapod scene's JSON (scenes/README.md, "The hexapod"): its keys, the statics' balance,
    the run's samples on the step grid, the feet on or above the ground (the header's plane), the
    stuck ones on it and inside their cones; CSV refused."""
    legs = d["legs"]
    check(len(legs) == 6 and d["status"] == "ok" and d["status_code"] == "LEGSIM_OK", f"{name}: status {d['status']}")
    check(d["analysis"] == spec.get("analysis", "dynamics"), f"{name}: analysis {d['analysis']}")
    mu = d["ground"]["mu_static"]
    if d["analysis"] == "reaction_sweep":
        check_reaction_sweep(d, name)
    elif d["analysis"] == "statics":
        st = d["statics"]
        stance = set(d["stance"])
        check(stance == set(spec.get("stance", legs)), f"{name}: stance {d['stance']}")
        fz = sum(st["feet"][k]["force"][2] for k in legs)
        check(fz > 0 and all(st["feet"][k]["force"] == [0, 0, 0] for k in legs if k not in stance),
              f"{name}: forces off the stance")
        check(st["margin"] > 0, f"{name}: margin {st['margin']}")
    else:
        n, every = d["n_steps"], d["record_every"]
        samples = d["samples"]
        check(len(samples) == n // every + 1 + (1 if n % every else 0), f"{name}: {len(samples)} samples")
        check(abs(samples[-1]["t"] - spec["duration"]) < 1e-9, f"{name}: last t {samples[-1]['t']}")
        for s in samples:
            for k in legs:
                f = s["feet"][k]
                check(over_ground(d, f["x"]) > -1e-9, f"{name}: {k} under the ground at t = {s['t']}")
                if f["state"] == "stuck":
                    check(abs(over_ground(d, f["x"])) < 1e-9, f"{name}: stuck {k} off the ground at t = {s['t']}")
                    if s["t"] > 0:
                        N, Ft = ground_split(d, f["force"])
                        check(Ft <= mu * N + 1e-6, f"{name}: stuck {k} outside its cone at t = {s['t']}")
            check(all(math.isfinite(v) for v in s["box"] + s["box_quat"]), f"{name}: box at t = {s['t']}")
    check((d["checks"] is None) == ("checks" not in spec) and set(d["checks"] or {}) == set(spec.get("checks", {})),
          f"{name}: checks {d['checks']}")
    for key, want in (d["checks"] or {}).items():
        got, ok = hexapod_check(d, key, want)
        check(ok, f"{name}: checks.{key}: got {got}, want {want}")
    r = run(cli, scene, None, "csv")
    check(r.returncode == 2 and "JSON only" in r.stderr, f"{name}: CSV not refused: {r.stderr.strip()}")
    r = subprocess.run([cli, scene, "--check"], capture_output=True, text=True, timeout=60)
    check(r.returncode == 0 and json.loads(r.stdout)["kind"] == "hexapod", f"{name}: --check")


def check_bad(cli, table, outdir):
    base = os.path.dirname(table)
    with open(table, encoding="utf-8") as f:
        rows = [line.rstrip("\n").split("\t") for line in f if line.strip() and not line.startswith("#")]
    check(len(rows) >= 10, "too few bad scenes")
    for scene, code, *texts in rows:
        path = os.path.relpath(os.path.join(base, scene))
        out = os.path.join(outdir, "bad_" + os.path.splitext(scene)[0] + ".json")
        if os.path.exists(out):
            os.remove(out)
        r = run(cli, path, out)
        check(r.returncode == int(code), f"{scene}: exit {r.returncode}, want {code}: {r.stderr.strip()}")
        check(r.stderr.startswith("legsim_cli: error: "), f"{scene}: stderr {r.stderr.strip()!r}")
        for t in texts:
            check(t in r.stderr, f"{scene}: stderr lacks {t!r}: {r.stderr.strip()!r}")
        if code == "1":
            if check(os.path.exists(out), f"{scene}: a failed run wrote no output"):
                with open(out, encoding="utf-8") as f:
                    d = json.load(f)
                check(d["status"] == "error" and d["status_code"].startswith("LEGSIM_ERR_") and d["error"],
                      f"{scene}: JSON status {d.get('status')}")
            if d.get("kind") in ("hexapod", "block"):  # JSON only (its CSV is refused: check_hexapod)
                continue
            # The same failed run as CSV: the samples up to the failure, every field a number
            # (no row of empty fields for the failure: that is in the exit status and stderr).
            cs = out[:-len(".json")] + ".csv"
            r = run(cli, path, cs)
            check(r.returncode == 1, f"{scene}: CSV run exit {r.returncode}")
            with open(cs, newline="", encoding="utf-8") as f:
                rows = list(csv.reader(f))
            check(len(rows) >= 1 and rows[0][0] in ("t_s", "item"), f"{scene}: CSV header {rows[:1]}")
            for row in rows[1:]:
                check(len(row) == len(rows[0]) and all(v != "" for v in row),
                      f"{scene}: CSV row with empty fields {row[:4]}...")
                check(row[-1] == "ok", f"{scene}: CSV row status {row[-1]}")
            if "failed_at" in d and len(rows) > 1:
                check(float(rows[-1][0]) <= d["failed_at"], f"{scene}: a CSV row after the failure")
        else:
            check(not os.path.exists(out), f"{scene}: output written for a bad scene")


def check_same(cli, scene_a, scene_b, outdir):
    """Two scenes that differ only in where the model comes from give the same numbers."""
    out = []
    for scene in (scene_a, scene_b):
        path = os.path.join(outdir, "same_" + os.path.basename(scene) + ".json")
        r = run(cli, scene, path)
        if not check(r.returncode == 0, f"{scene}: exit {r.returncode}: {r.stderr.strip()}"):
            return
        with open(path, encoding="utf-8") as f:
            out.append(json.load(f))
    check(out[0]["samples"] == out[1]["samples"], f"{scene_a} and {scene_b} differ")
    check(out[0]["samples"] and out[0]["samples"][0]["reactions"], "no reactions to compare")


def main():
    cli = sys.argv[1]
    if sys.argv[2] == "--same":
        outdir = sys.argv[5]
        os.makedirs(outdir, exist_ok=True)
        check_same(cli, sys.argv[3], sys.argv[4], outdir)
    elif sys.argv[2] == "--bad":
        outdir = sys.argv[4]
        os.makedirs(outdir, exist_ok=True)
        check_bad(cli, sys.argv[3], outdir)
    else:
        outdir = sys.argv[3]
        os.makedirs(outdir, exist_ok=True)
        check_good(cli, sys.argv[2], outdir)
    for f in failures:
        print("FAIL", f)
    print(f"{0 if failures else 1} passed, {1 if failures else 0} failed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
