#!/usr/bin/env python3
"""Compile a legsim model TOML (models/leg.toml) into C data.

    model_codegen.py TOML --symbol leg --out-c legsim_models.c --out-h legsim/models.h

Validates the model and writes, for the default variant "revolute" and every
[variant.X] of the file, a `const legsim_model_desc legsim_model_<symbol>_<variant>`
plus the table `legsim_model_<symbol>_variants[]` and its count. Exits non-zero with
"FILE: ITEM: PROBLEM" on stderr when the model is invalid.

The mapping and every check (and message) are the same as the host's run-time loader
firmware_core/host/model_toml.cpp: keep the two in step (tests/model checks that the
descriptions and the messages agree).

Capacities are the build's (legsim/config.h): the generated source checks them with
#if/#error; --config legsim/config.h (or --max-bodies etc.) checks them here too, with
the loader's messages. Python 3.11+, standard library only.

The format (models/leg.toml shows most of it; every key not listed is an error):
  name = "..."  (1..23 of [A-Za-z0-9_.-]);  gravity = [gx, gy] (default [0, -9.81])
  [frame]        NAME = [x, y]                       points fixed on the ground
  [[body]]       id (1..n, body index id - 1), name, length > 0, mass > 0,
                 inertia > 0 (default mass * length^2 / 12)
  [[joint]]      name, kind and, by kind:
    revolute_to_frame  body, end, point (a [frame] name)   -> body[1] = LEGSIM_FRAME
    revolute           bodies = [i, j], ends = [e0, e1]
    prismatic          bodies = [cylinder, rod]             (points unused: 0)
    slot               bodies = [i, j], ends = [e0, "axis"] (point[0] on i, line = axis of j)
  an end is "proximal" (-L/2, 0), "distal" (+L/2, 0) or "at": then at = [xi, eta]
  (at = [[xi, eta], [xi, eta]] when both ends are "at").
  [variant.X]    JOINT = { kind = ..., ... }  replaces that joint's keys (not its name)
                 in variant X (a C identifier; "revolute" is the default variant's name)
  [[actuator]]   name, joint (a prismatic joint's name), stroke = [min, max] (0 < min < max),
                 max_force > 0, servo_kp >= 0, servo_kd >= 0
  [[force]]      name, kind and, by kind:
    point          body, end (+ at), value = [Fx, Fy] (default 0)
    torque         body, value = T (default 0)
    spring_damper  bodies, ends (+ at) -- or body, end (+ at), point = FRAME_POINT --
                   stiffness >= 0, damping >= 0, rest_length >= 0
  [foot]         body, end (+ at)
  [pose.NAME]    phiN / xN / yN = value (drive coordinate phi / x / y of body N; sorted by
                 body, then x, y, phi), guess = [[x, y, phi], ...] one row per body

Sane ranges (inclusive; legsim.h's LEGSIM_MAX_* / LEGSIM_MIN_*, which the core checks too):
  gravity components |g| <= 1e3 m/s^2; frame points, "at" points, pose driver values and
  guesses |x| <= 1e3 (m or rad); body length [1e-3, 1e3] m, mass [1e-3, 1e6] kg, inertia
  [1e-12, 1e6] kg m^2 (the default too); stroke ends [1e-3, 1e3] m; max_force [1e-3, 1e6] N;
  point loads and torques |F| <= 1e6 N (N m); servo_kp and stiffness [0, 1e9] N/m; servo_kd
  and damping [0, 1e7] N s/m; rest_length [0, 1e3] m. Outside: "ITEM: 'KEY' must be in
  [LO, HI] (got X)".

The text is bounded before it is parsed (as the run-time loader does for toml++, see
firmware_core/host/toml_limits.hpp): at most 1 MiB, valid UTF-8, non-ASCII only inside
strings and comments and never right after a backslash, keys and table headers of at most
16 dotted parts, brackets nested at most 16 deep. Else "FILE: TOML input refused: REASON (line N)".
"""
from __future__ import annotations

import argparse
import math
import os
import re
import sys
import tomllib

NAME_LEN = 24  # LEGSIM_NAME_LEN (config.h.in), NUL included
DEFAULT_VARIANT = "revolute"
DEFAULT_GRAVITY = [0.0, -9.81]

# legsim_status values used here (legsim.h)
ERR_BAD_INPUT = 5
ERR_MODEL = 3
ERR_CAPACITY = 4

JOINT_KINDS = ["revolute_to_frame", "revolute", "prismatic", "slot"]
JOINT_ENUM = {
    "revolute_to_frame": "LEGSIM_JOINT_REVOLUTE_TO_FRAME",
    "revolute": "LEGSIM_JOINT_REVOLUTE",
    "prismatic": "LEGSIM_JOINT_PRISMATIC",
    "slot": "LEGSIM_JOINT_SLOT",
}
JOINT_KEYS = {
    "revolute_to_frame": ["name", "kind", "body", "end", "at", "point"],
    "revolute": ["name", "kind", "bodies", "ends", "at"],
    "prismatic": ["name", "kind", "bodies"],
    "slot": ["name", "kind", "bodies", "ends", "at"],
}
FORCE_KINDS = ["point", "torque", "spring_damper"]
FORCE_ENUM = {
    "point": "LEGSIM_FORCE_POINT",
    "torque": "LEGSIM_FORCE_TORQUE",
    "spring_damper": "LEGSIM_FORCE_SPRING_DAMPER",
}
TOP_KEYS = ["name", "gravity", "frame", "body", "joint", "variant", "actuator", "force",
            "foot", "pose"]
BODY_KEYS = ["id", "name", "length", "mass", "inertia"]
ACTUATOR_KEYS = ["name", "joint", "stroke", "max_force", "servo_kp", "servo_kd"]
FOOT_KEYS = ["body", "end", "at"]
NAME_RE = re.compile(r"[A-Za-z0-9_.\-]+")
IDENT_RE = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
DRIVER_RE = re.compile(r"(phi|x|y)([1-9][0-9]{0,8})")
DRIVER_COORD = {"x": 0, "y": 1, "phi": 2}
FRAME = -1

# Sane ranges: legsim.h's LEGSIM_MAX_* / LEGSIM_MIN_* (check_codegen_messages.py checks
# that they agree with the header), the same in host/model_toml.cpp.
MAX_COORD = 1e3        # LEGSIM_MAX_COORD
MAX_GRAVITY = 1e3      # LEGSIM_MAX_GRAVITY_MPS2
MIN_LENGTH = 1e-3      # LEGSIM_MIN_LENGTH_M
MIN_MASS = 1e-3        # LEGSIM_MIN_MASS_KG
MAX_MASS = 1e6         # LEGSIM_MAX_MASS_KG
MIN_INERTIA = 1e-12    # LEGSIM_MIN_INERTIA_KGM2
MAX_INERTIA = 1e6      # LEGSIM_MAX_INERTIA_KGM2
MIN_FORCE = 1e-3       # LEGSIM_MIN_FORCE_N
MAX_FORCE = 1e6        # LEGSIM_MAX_FORCE_N
MAX_STIFFNESS = 1e9    # LEGSIM_MAX_STIFFNESS_N_PER_M
MAX_DAMPING = 1e7      # LEGSIM_MAX_DAMPING_NS_PER_M

# Bounds on the TOML text (host/toml_limits.hpp: kTomlMaxBytes, kTomlMaxKeyParts, kTomlMaxNesting).
TOML_MAX_BYTES = 1024 * 1024
TOML_MAX_KEY_PARTS = 16
TOML_MAX_NESTING = 16


class ModelError(Exception):
    def __init__(self, status: int, message: str):
        super().__init__(message)
        self.status = status
        self.message = message


def g(x: float) -> str:
    """Numbers in messages: C's %g (the loader uses snprintf("%g"))."""
    return "%g" % x


def fail(label: str, problem: str, status: int = ERR_MODEL):
    raise ModelError(status, f"{label}: {problem}")


# ---- typed access (identical rules and messages in model_toml.cpp) --------------
def is_table(v) -> bool:
    return isinstance(v, dict)


def is_int(v) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def is_number(v) -> bool:
    return (isinstance(v, (int, float))) and not isinstance(v, bool)


def check_keys(tbl: dict, allowed: list[str], label: str):
    for key in sorted(tbl):
        if key not in allowed:
            fail(label, f"unknown key '{key}' (allowed: {', '.join(sorted(allowed))})")


def req(tbl: dict, key: str, label: str):
    if key not in tbl:
        fail(label, f"missing key '{key}'")
    return tbl[key]


def get_string(tbl: dict, key: str, label: str) -> str:
    v = req(tbl, key, label)
    if not isinstance(v, str):
        fail(label, f"'{key}' must be a string")
    return v


def check_unique(name: str, earlier: list[str], kind: str, label: str) -> None:
    """A name not taken by an earlier item of its kind (the message names which one has it)."""
    if name in earlier:
        fail(label, f"duplicate name '{name}' ({kind} #{earlier.index(name) + 1} has it too)")


def check_name(name: str, label: str, what: str = "name"):
    n = len(name.encode("utf-8"))
    if n < 1 or n > NAME_LEN - 1:
        fail(label, f"{what} must be 1 to {NAME_LEN - 1} characters (got {n})")
    if not NAME_RE.fullmatch(name):
        fail(label, f"{what} '{name}' may hold only letters, digits, '_', '-' and '.'")


def as_real(v, key: str, label: str) -> float:
    if not is_number(v):
        fail(label, f"'{key}' must be a number")
    x = float(v)
    if not math.isfinite(x):
        fail(label, f"'{key}' is not finite")
    return x


def get_real(tbl: dict, key: str, label: str) -> float:
    return as_real(req(tbl, key, label), key, label)


def get_positive(tbl: dict, key: str, label: str) -> float:
    x = get_real(tbl, key, label)
    if not x > 0.0:
        fail(label, f"'{key}' must be positive (got {g(x)})")
    return x


def get_nonnegative(tbl: dict, key: str, label: str) -> float:
    x = get_real(tbl, key, label)
    if not x >= 0.0:
        fail(label, f"'{key}' must be non-negative (got {g(x)})")
    return x


def ranged(x: float, lo: float, hi: float, key: str, label: str) -> float:
    if not lo <= x <= hi:
        fail(label, f"'{key}' must be in [{g(lo)}, {g(hi)}] (got {g(x)})")
    return x


def ranged_vec(v: list[float], lo: float, hi: float, key: str, label: str) -> list[float]:
    for x in v:
        ranged(x, lo, hi, key, label)
    return v


def as_vec(v, n: int, key: str, label: str) -> list[float]:
    if not isinstance(v, list) or len(v) != n or not all(is_number(e) for e in v):
        fail(label, f"'{key}' must be an array of {n} numbers")
    out = [float(e) for e in v]
    if not all(math.isfinite(e) for e in out):
        fail(label, f"'{key}' is not finite")
    return out


def get_vec(tbl: dict, key: str, n: int, label: str) -> list[float]:
    return as_vec(req(tbl, key, label), n, key, label)


def get_int(tbl: dict, key: str, label: str) -> int:
    v = req(tbl, key, label)
    if not is_int(v):
        fail(label, f"'{key}' must be an integer")
    return v


def get_table_array(tbl: dict, key: str, label: str) -> list[dict]:
    if key not in tbl:
        return []
    v = tbl[key]
    if not isinstance(v, list) or not all(is_table(e) for e in v):
        fail(label, f"'{key}' must be an array of tables ([[{key}]])")
    return v


def capacity(count: int, what: str, macro: str, cap: int | None, label: str = "model"):
    if cap is not None and count > cap:
        fail(label, f"{count} {what} exceed the capacity {macro} = {cap}", ERR_CAPACITY)


# ---- the model -------------------------------------------------------------------
class Ctx:
    def __init__(self, caps: dict):
        self.caps = caps
        self.frame: dict[str, list[float]] = {}
        self.bodies: list[dict] = []  # by index (id - 1)

    def body_ref(self, v, key: str, label: str) -> int:
        """A body id (1..n) -> 0-based index."""
        if not is_int(v):
            fail(label, f"'{key}' must be an integer body id")
        n = len(self.bodies)
        if v < 1 or v > n:
            fail(label, f"body {v} does not exist (ids are 1..{n})")
        return v - 1

    def end_point(self, body: int, end, at_value, label: str) -> list[float]:
        """(xi, eta) of an end ("proximal", "distal" or "at") of body (0-based)."""
        half = self.bodies[body]["length"] / 2.0
        if end == "proximal":
            return [-half, 0.0]
        if end == "distal":
            return [half, 0.0]
        return ranged_vec(as_vec(at_value, 2, "at", label), -MAX_COORD, MAX_COORD, "at", label)

    def frame_point(self, tbl: dict, label: str) -> list[float]:
        name = get_string(tbl, "point", label)
        if name not in self.frame:
            fail(label, f"frame point '{name}' does not exist")
        return list(self.frame[name])


def check_end(end: str, label: str) -> str:
    if end not in ("proximal", "distal", "at"):
        fail(label, f"bad end '{end}' (expected proximal, distal or at)")
    return end


def single_point(ctx: Ctx, tbl: dict, label: str) -> tuple[int, list[float]]:
    """body + end (+ at): a point on one body."""
    body = ctx.body_ref(req(tbl, "body", label), "body", label)
    end = check_end(get_string(tbl, "end", label), label)
    if end == "at":
        return body, ctx.end_point(body, end, req(tbl, "at", label), label)
    if "at" in tbl:
        fail(label, "'at' given but the end is not \"at\"")
    return body, ctx.end_point(body, end, None, label)


def two_bodies(ctx: Ctx, tbl: dict, label: str) -> list[int]:
    v = req(tbl, "bodies", label)
    if not isinstance(v, list) or len(v) != 2 or not all(is_int(e) for e in v):
        fail(label, "'bodies' must be an array of 2 integer body ids")
    b = [ctx.body_ref(v[0], "bodies", label), ctx.body_ref(v[1], "bodies", label)]
    if b[0] == b[1]:
        fail(label, f"bodies must differ (got {v[0]} and {v[1]})")
    return b


def two_ends(ctx: Ctx, tbl: dict, bodies: list[int], label: str, slot: bool) -> list[list[float]]:
    v = req(tbl, "ends", label)
    if not isinstance(v, list) or len(v) != 2 or not all(isinstance(e, str) for e in v):
        fail(label, "'ends' must be an array of 2 strings")
    e0 = check_end(v[0], label)
    if slot:
        if v[1] != "axis":
            fail(label, f"bad end '{v[1]}' for the slot line (expected axis)")
        ends = [e0]
    else:
        ends = [e0, check_end(v[1], label)]
    n_at = sum(1 for e in ends if e == "at")
    if n_at == 0:
        if "at" in tbl:
            fail(label, "'at' given but no end is \"at\"")
        ats = [None, None]
    elif n_at == 1:
        a = req(tbl, "at", label)
        ats = [a if e == "at" else None for e in ends] + [None]
    else:
        a = req(tbl, "at", label)
        if not isinstance(a, list) or len(a) != 2:
            fail(label, "'at' must be an array of 2 [xi, eta] arrays (both ends are \"at\")")
        ats = [a[0], a[1]]
    pts = [ctx.end_point(bodies[i], ends[i], ats[i], label) for i in range(len(ends))]
    if slot:
        pts.append([0.0, 0.0])
    return pts


def parse_joint(ctx: Ctx, name: str, tbl: dict, label: str, override: bool) -> dict:
    """override: a [variant.X] table, which names no joint (its key does)."""
    kind = get_string(tbl, "kind", label)
    if kind not in JOINT_KINDS:
        fail(label, f"unknown kind '{kind}' (expected revolute_to_frame, revolute, prismatic or slot)")
    check_keys(tbl, [k for k in JOINT_KEYS[kind] if not (override and k == "name")], label)
    j = {"name": name, "kind": kind}
    if kind == "revolute_to_frame":
        body, p0 = single_point(ctx, tbl, label)
        j["body"] = [body, FRAME]
        j["point"] = [p0, ctx.frame_point(tbl, label)]
    elif kind == "prismatic":
        j["body"] = two_bodies(ctx, tbl, label)
        j["point"] = [[0.0, 0.0], [0.0, 0.0]]
    else:
        j["body"] = two_bodies(ctx, tbl, label)
        j["point"] = two_ends(ctx, tbl, j["body"], label, kind == "slot")
    return j


def parse_force(ctx: Ctx, name: str, tbl: dict) -> dict:
    label = f"force '{name}'"
    kind = get_string(tbl, "kind", label)
    if kind not in FORCE_KINDS:
        fail(label, f"unknown kind '{kind}' (expected point, torque or spring_damper)")
    f = {"name": name, "kind": kind, "body": [0, FRAME], "point": [[0.0, 0.0], [0.0, 0.0]],
         "value": [0.0, 0.0], "stiffness": 0.0, "damping": 0.0, "rest_length": 0.0}
    if kind == "point":
        check_keys(tbl, ["name", "kind", "body", "end", "at", "value"], label)
        f["body"][0], f["point"][0] = single_point(ctx, tbl, label)
        if "value" in tbl:
            f["value"] = ranged_vec(get_vec(tbl, "value", 2, label), -MAX_FORCE, MAX_FORCE,
                                    "value", label)
    elif kind == "torque":
        check_keys(tbl, ["name", "kind", "body", "value"], label)
        f["body"][0] = ctx.body_ref(req(tbl, "body", label), "body", label)
        if "value" in tbl:
            f["value"] = [ranged(get_real(tbl, "value", label), -MAX_FORCE, MAX_FORCE, "value",
                                 label), 0.0]
    else:
        common = ["name", "kind", "at", "stiffness", "damping", "rest_length"]
        if "bodies" in tbl:
            check_keys(tbl, common + ["bodies", "ends"], label)
            f["body"] = two_bodies(ctx, tbl, label)
            f["point"] = two_ends(ctx, tbl, f["body"], label, False)
        else:
            check_keys(tbl, common + ["body", "end", "point"], label)
            f["body"][0], f["point"][0] = single_point(ctx, tbl, label)
            f["body"][1] = FRAME
            f["point"][1] = ctx.frame_point(tbl, label)
        f["stiffness"] = ranged(get_nonnegative(tbl, "stiffness", label), 0.0, MAX_STIFFNESS,
                                "stiffness", label)
        f["damping"] = ranged(get_nonnegative(tbl, "damping", label), 0.0, MAX_DAMPING, "damping",
                              label)
        f["rest_length"] = ranged(get_nonnegative(tbl, "rest_length", label), 0.0, MAX_COORD,
                                  "rest_length", label)
    return f


def variant_tables(doc: dict, joint_names: list[str]) -> list[tuple[str, dict]]:
    """[variant.X] tables in file order, checked: X = { JOINT = {...}, ... }."""
    if "variant" not in doc:
        return []
    vt = doc["variant"]
    if not is_table(vt):
        fail("model", "'variant' must be a table of [variant.NAME] tables")
    out = []
    for vname, v in vt.items():
        label = f"variant '{vname}'"
        if not IDENT_RE.fullmatch(vname) or len(vname) > NAME_LEN - 1:
            fail(label, f"the name must be a C identifier of at most {NAME_LEN - 1} characters")
        if vname == DEFAULT_VARIANT:
            fail(label, "the default variant cannot be overridden")
        if not is_table(v):
            fail(label, "must be a table of JOINT = { ... } overrides")
        for jname in sorted(v):
            if jname not in joint_names:
                fail(label, f"no joint named '{jname}'")
            if not is_table(v[jname]):
                fail(label, f"'{jname}' must be a table (the joint's keys without its name)")
        out.append((vname, v))
    return out


def parse_model(doc: dict, variant: str, caps: dict) -> dict:
    check_keys(doc, TOP_KEYS, "model")
    name = get_string(doc, "name", "model")
    check_name(name, "model")
    gravity = get_vec(doc, "gravity", 2, "model") if "gravity" in doc else list(DEFAULT_GRAVITY)
    ranged_vec(gravity, -MAX_GRAVITY, MAX_GRAVITY, "gravity", "model")

    ctx = Ctx(caps)
    if "frame" in doc:
        ft = doc["frame"]
        if not is_table(ft):
            fail("model", "'frame' must be a table of NAME = [x, y] points")
        for key in sorted(ft):
            ctx.frame[key] = ranged_vec(as_vec(ft[key], 2, key, f"frame point '{key}'"),
                                        -MAX_COORD, MAX_COORD, key, f"frame point '{key}'")

    # bodies
    body_tables = get_table_array(doc, "body", "model")
    if not body_tables:
        fail("model", "no [[body]]")
    n = len(body_tables)
    capacity(n, "bodies", "LEGSIM_MAX_BODIES", caps.get("bodies"))
    parsed = []
    for k, tb in enumerate(body_tables, 1):
        label = f"body #{k}"
        bname = get_string(tb, "name", label)
        check_name(bname, label)
        check_unique(bname, [other["name"] for other in parsed], "body", label)
        label = f"body '{bname}'"
        check_keys(tb, BODY_KEYS, label)
        bid = get_int(tb, "id", label)
        length = ranged(get_positive(tb, "length", label), MIN_LENGTH, MAX_COORD, "length", label)
        mass = ranged(get_positive(tb, "mass", label), MIN_MASS, MAX_MASS, "mass", label)
        if "inertia" in tb:
            inertia = get_positive(tb, "inertia", label)
        else:
            inertia = mass * length * length / 12.0
        ranged(inertia, MIN_INERTIA, MAX_INERTIA, "inertia", label)
        parsed.append({"id": bid, "name": bname, "length": length, "mass": mass,
                       "inertia": inertia})
    by_id: dict[int, dict] = {}
    for b in parsed:
        label = f"body '{b['name']}'"
        if b["id"] < 1 or b["id"] > n:
            fail(label, f"id {b['id']} out of range (ids must be 1..{n})")
        if b["id"] in by_id:
            fail(label, f"duplicate id {b['id']} (body '{by_id[b['id']]['name']}' has it too)")
        by_id[b["id"]] = b
    ctx.bodies = [by_id[i] for i in range(1, n + 1)]

    # joints: names first (variants refer to them)
    joint_tables = get_table_array(doc, "joint", "model")
    capacity(len(joint_tables), "joints", "LEGSIM_MAX_JOINTS", caps.get("joints"))
    joint_names: list[str] = []
    for k, tj in enumerate(joint_tables, 1):
        label = f"joint #{k}"
        jname = get_string(tj, "name", label)
        check_name(jname, label)
        check_unique(jname, joint_names, "joint", label)
        joint_names.append(jname)

    variants = variant_tables(doc, joint_names)
    names = [DEFAULT_VARIANT] + [v for v, _ in variants]
    if variant not in names:
        fail("model", f"unknown variant '{variant}' (available: {', '.join(names)})", ERR_BAD_INPUT)
    overrides = dict(variants).get(variant, {})

    joints = []
    for jname, tj in zip(joint_names, joint_tables):
        if jname in overrides:
            joints.append(parse_joint(ctx, jname, overrides[jname],
                                      f"joint '{jname}' (variant '{variant}')", True))
        else:
            joints.append(parse_joint(ctx, jname, tj, f"joint '{jname}'", False))

    # actuators
    act_tables = get_table_array(doc, "actuator", "model")
    capacity(len(act_tables), "actuators", "LEGSIM_MAX_ACTUATORS", caps.get("actuators"))
    actuators = []
    for k, ta in enumerate(act_tables, 1):
        label = f"actuator #{k}"
        aname = get_string(ta, "name", label)
        check_name(aname, label)
        check_unique(aname, [other["name"] for other in actuators], "actuator", label)
        label = f"actuator '{aname}'"
        check_keys(ta, ACTUATOR_KEYS, label)
        jname = get_string(ta, "joint", label)
        if jname not in joint_names:
            fail(label, f"joint '{jname}' does not exist")
        ji = joint_names.index(jname)
        if joints[ji]["kind"] != "prismatic":
            fail(label, f"joint '{jname}' is {joints[ji]['kind']}, not prismatic")
        for other in actuators:
            if other["joint"] == ji:
                fail(label, f"joint '{jname}' is already driven by actuator '{other['name']}'")
        stroke = get_vec(ta, "stroke", 2, label)
        if not stroke[0] > 0.0:
            fail(label, f"stroke min must be positive (got {g(stroke[0])})")
        if stroke[0] >= stroke[1]:
            fail(label, f"stroke min {g(stroke[0])} >= max {g(stroke[1])}")
        ranged_vec(stroke, MIN_LENGTH, MAX_COORD, "stroke", label)
        actuators.append({
            "name": aname, "joint": ji, "stroke": stroke,
            "max_force": ranged(get_positive(ta, "max_force", label), MIN_FORCE, MAX_FORCE,
                                "max_force", label),
            "kp": ranged(get_nonnegative(ta, "servo_kp", label), 0.0, MAX_STIFFNESS, "servo_kp",
                         label),
            "kd": ranged(get_nonnegative(ta, "servo_kd", label), 0.0, MAX_DAMPING, "servo_kd",
                         label)})

    # force elements
    force_tables = get_table_array(doc, "force", "model")
    capacity(len(force_tables), "force elements", "LEGSIM_MAX_FORCES", caps.get("forces"))
    forces = []
    for k, tf in enumerate(force_tables, 1):
        label = f"force #{k}"
        fname = get_string(tf, "name", label)
        check_name(fname, label)
        check_unique(fname, [other["name"] for other in forces], "force", label)
        forces.append(parse_force(ctx, fname, tf))

    # foot
    foot_body, foot_point = FRAME, [0.0, 0.0]
    if "foot" in doc:
        tf = doc["foot"]
        if not is_table(tf):
            fail("model", "'foot' must be a table")
        check_keys(tf, FOOT_KEYS, "foot")
        foot_body, foot_point = single_point(ctx, tf, "foot")

    # poses
    poses = []
    if "pose" in doc:
        tp = doc["pose"]
        if not is_table(tp):
            fail("model", "'pose' must be a table of [pose.NAME] tables")
        capacity(len(tp), "poses", "LEGSIM_MAX_POSES", caps.get("poses"))
        for pname, pt in tp.items():
            label = f"pose '{pname}'"
            check_name(pname, label)
            if not is_table(pt):
                fail(label, "must be a table")
            drivers = []
            for key in sorted(pt):
                if key == "guess":
                    continue
                m = DRIVER_RE.fullmatch(key)
                if not m:
                    fail(label, f"unknown key '{key}' (expected guess, phiN, xN or yN with N a body id)")
                bid = int(m.group(2))
                if bid > n:
                    fail(label, f"'{key}': body {bid} does not exist (ids are 1..{n})")
                value = ranged(as_real(pt[key], key, label), -MAX_COORD, MAX_COORD, key, label)
                drivers.append((bid - 1, DRIVER_COORD[m.group(1)], value))
            capacity(len(drivers), "drivers", "LEGSIM_MAX_POSE_DRIVERS", caps.get("pose_drivers"),
                     label)
            drivers.sort(key=lambda d: (d[0], d[1]))
            gv = req(pt, "guess", label)
            if not isinstance(gv, list) or len(gv) != n or not all(
                    isinstance(r, list) and len(r) == 3 and all(is_number(e) for e in r) for r in gv):
                fail(label, f"'guess' must be an array of {n} [x, y, phi] arrays (one per body)")
            guess = [[float(e) for e in r] for r in gv]
            if not all(math.isfinite(e) for r in guess for e in r):
                fail(label, "'guess' is not finite")
            for r in guess:
                ranged_vec(r, -MAX_COORD, MAX_COORD, "guess", label)
            poses.append({"name": pname, "drivers": drivers, "guess": guess})

    return {"name": name, "gravity": gravity, "bodies": ctx.bodies, "joints": joints,
            "contacts": [], "ground": NO_GROUND,
            "actuators": actuators, "forces": forces, "poses": poses,
            "foot_body": foot_body, "foot_point": foot_point}


# ---- a robot file: a box with leg files placed on it (docs/design/robot-on-ground.md) ----
ROBOT_KEYS = ["name", "gravity", "box", "leg", "ground", "pose"]
BOX_KEYS = ["name", "mass", "inertia", "size"]
LEG_KEYS = ["name", "file", "variant", "prefix", "mirror", "attach"]
GROUND_KEYS = ["point", "slope", "mu_static", "mu_kinetic"]
ROBOT_POSE_KEYS = ["legs", "feet_mid", "contact"]
MAX_FRICTION = 10.0    # LEGSIM_MAX_FRICTION
MAX_SLOPE = 1.5        # rad, as legsim_model_check
CONGRUENT_TOL = 1e-12  # m: attach points against the leg's frame
NO_GROUND = {"point": [0.0, 0.0], "slope": 0.0, "mu_static": 0.0, "mu_kinetic": 0.0}


def is_robot(doc: dict) -> bool:
    """A robot file has a [box] and [[leg]]s; anything else is a leg (model) file."""
    return "box" in doc and "leg" in doc


def read_toml(path: str, label: str, shown: str) -> dict:
    """A leg file of a robot: read, bounded and parsed (errors name the robot's item)."""
    try:
        with open(path, "rb") as f:
            raw = f.read(TOML_MAX_BYTES + 1)
    except OSError as e:
        fail(label, f"file '{shown}': cannot read: {e.strerror}", ERR_BAD_INPUT)
    why = toml_input_within_limits(raw)
    if why is not None:
        fail(label, f"file '{shown}': TOML input refused: {why}")
    try:
        return tomllib.loads(raw.decode("utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as e:
        fail(label, f"file '{shown}': TOML syntax error: {e}")


def box_xy_to_body(xy: list[float]) -> list[float]:
    """A box-frame point (x, y) in the box's body coordinates (xi, eta) = (-y, x)."""
    return [-xy[1], xy[0]]


def parse_robot(doc: dict, base_dir: str, variant: str, caps: dict) -> dict:
    check_keys(doc, ROBOT_KEYS, "robot")
    name = get_string(doc, "name", "robot")
    check_name(name, "robot")
    gravity = get_vec(doc, "gravity", 2, "robot") if "gravity" in doc else list(DEFAULT_GRAVITY)
    ranged_vec(gravity, -MAX_GRAVITY, MAX_GRAVITY, "gravity", "robot")
    if variant != DEFAULT_VARIANT:
        fail("robot", f"unknown variant '{variant}' (available: {DEFAULT_VARIANT})", ERR_BAD_INPUT)

    bt = doc["box"]
    if not is_table(bt):
        fail("robot", "'box' must be a table")
    check_keys(bt, BOX_KEYS, "box")
    bname = get_string(bt, "name", "box") if "name" in bt else "box"
    check_name(bname, "box")
    size = ranged_vec(get_vec(bt, "size", 2, "box"), MIN_LENGTH, MAX_COORD, "size", "box")
    bodies = [{"name": bname, "length": size[0],
               "mass": ranged(get_positive(bt, "mass", "box"), MIN_MASS, MAX_MASS, "mass", "box"),
               "inertia": ranged(get_positive(bt, "inertia", "box"), MIN_INERTIA, MAX_INERTIA,
                                 "inertia", "box")}]
    joints, actuators, forces, contacts, legs = [], [], [], [], []

    leg_tables = get_table_array(doc, "leg", "robot")
    if not leg_tables:
        fail("robot", "no [[leg]]")
    for k, tl in enumerate(leg_tables, 1):
        label = f"leg #{k}"
        lname = get_string(tl, "name", label)
        check_name(lname, label)
        check_unique(lname, [other["name"] for other in legs], "leg", label)
        label = f"leg '{lname}'"
        check_keys(tl, LEG_KEYS, label)
        lfile = get_string(tl, "file", label)
        lvariant = get_string(tl, "variant", label) if "variant" in tl else DEFAULT_VARIANT
        prefix = get_string(tl, "prefix", label) if "prefix" in tl else lname + "."
        for other in legs:
            if other["prefix"] == prefix:
                fail(label, f"prefix '{prefix}' is taken by leg '{other['name']}'")
        mirror = tl.get("mirror", False)
        if not isinstance(mirror, bool):
            fail(label, "'mirror' must be true or false")
        attach = req(tl, "attach", label)
        if not is_table(attach):
            fail(label, "'attach' must be a table of POINT = [x, y]")
        ldoc = read_toml(os.path.join(base_dir, lfile), label, lfile)
        if is_robot(ldoc):
            fail(label, f"file '{lfile}' is a robot file, not a leg")
        try:
            lm = parse_model(ldoc, lvariant, {})
        except ModelError as e:
            raise ModelError(e.status, f"{label}: {lfile}: {e.message}")
        frame = ldoc.get("frame", {})
        fnames = sorted(frame)
        if not fnames:
            fail(label, "the leg file has no [frame] points to attach")
        if sorted(attach) != fnames:
            fail(label, f"'attach' must name the leg file's frame points ({', '.join(fnames)})")
        sign = -1.0 if mirror else 1.0
        offs = []
        for key in fnames:
            a = ranged_vec(as_vec(attach[key], 2, key, label), -MAX_COORD, MAX_COORD, key, label)
            fp = frame[key]
            offs.append([a[0] - sign * fp[0], a[1] - fp[1]])
        for o in offs:
            if abs(o[0] - offs[0][0]) > CONGRUENT_TOL or abs(o[1] - offs[0][1]) > CONGRUENT_TOL:
                fail(label, "the box points are not congruent with the leg's frame")
        off = offs[0]
        if lm["foot_body"] == FRAME:
            fail(label, "the leg file has no [foot]")
        b0, j0 = len(bodies), len(joints)

        def mir(p):
            return [p[0], sign * p[1]]

        def on_box(p):  # a point of the leg's frame, in the box's body coordinates
            return box_xy_to_body([off[0] + sign * p[0], off[1] + p[1]])

        def named(what, n):
            full = prefix + n
            check_name(full, label, what)
            return full
        for b in lm["bodies"]:
            bodies.append({"name": named("body name", b["name"]), "length": b["length"],
                           "mass": b["mass"], "inertia": b["inertia"]})
        for j in lm["joints"]:
            nj = {"name": named("joint name", j["name"]), "kind": j["kind"],
                  "body": [j["body"][0] + b0, j["body"][1] + b0],
                  "point": [mir(j["point"][0]), mir(j["point"][1])]}
            if j["kind"] == "revolute_to_frame":
                nj["kind"] = "revolute"
                nj["body"][1] = 0
                nj["point"][1] = on_box(j["point"][1])
            joints.append(nj)
        for a in lm["actuators"]:
            actuators.append(dict(a, name=named("actuator name", a["name"]), joint=a["joint"] + j0))
        for f in lm["forces"]:
            nf = dict(f, name=named("force name", f["name"]), body=list(f["body"]),
                      point=[mir(f["point"][0]), mir(f["point"][1])], value=list(f["value"]))
            for s_ in range(2):
                if f["body"][s_] == FRAME:
                    if f["kind"] == "spring_damper":
                        nf["body"][s_] = 0
                        nf["point"][s_] = on_box(f["point"][s_])
                else:
                    nf["body"][s_] = f["body"][s_] + b0
            if f["kind"] == "point":
                nf["value"] = [sign * f["value"][0], f["value"][1]]
            elif f["kind"] == "torque":
                nf["value"] = [sign * f["value"][0], 0.0]
            forces.append(nf)
        contacts.append({"name": named("contact name", "foot"), "body": lm["foot_body"] + b0,
                         "point": mir(lm["foot_point"])})
        legs.append({"name": lname, "prefix": prefix, "sign": sign, "off": off, "model": lm,
                     "body0": b0})

    gt = req(doc, "ground", "robot")
    if not is_table(gt):
        fail("robot", "'ground' must be a table")
    check_keys(gt, GROUND_KEYS, "ground")
    gpoint = ranged_vec(get_vec(gt, "point", 2, "ground"), -MAX_COORD, MAX_COORD, "point",
                        "ground") if "point" in gt else [0.0, 0.0]
    slope = ranged(get_real(gt, "slope", "ground"), -MAX_SLOPE, MAX_SLOPE, "slope",
                   "ground") if "slope" in gt else 0.0
    mu_s = ranged(get_nonnegative(gt, "mu_static", "ground"), 0.0, MAX_FRICTION, "mu_static",
                  "ground")
    mu_k = ranged(get_nonnegative(gt, "mu_kinetic", "ground"), 0.0, MAX_FRICTION, "mu_kinetic",
                  "ground")
    if mu_k > mu_s:
        fail("ground", f"mu_kinetic {g(mu_k)} > mu_static {g(mu_s)}")
    ground = {"point": gpoint, "slope": slope, "mu_static": mu_s, "mu_kinetic": mu_k}

    poses = []
    if "pose" in doc:
        tp = doc["pose"]
        if not is_table(tp):
            fail("robot", "'pose' must be a table of [pose.NAME] tables")
        capacity(len(tp), "poses", "LEGSIM_MAX_POSES", caps.get("poses"), "robot")
        for pname, pt in tp.items():
            label = f"pose '{pname}'"
            check_name(pname, label)
            if not is_table(pt):
                fail(label, "must be a table")
            check_keys(pt, ROBOT_POSE_KEYS, label)
            legs_pose = get_string(pt, "legs", label) if "legs" in pt else "stand"
            mid = ranged(get_real(pt, "feet_mid", label), -MAX_COORD, MAX_COORD, "feet_mid",
                         label) if "feet_mid" in pt else 0.0
            state = get_string(pt, "contact", label) if "contact" in pt else "stuck"
            if state != "stuck":
                fail(label, f"'contact' must be \"stuck\" (got '{state}')")
            if len(legs) > 2:
                fail(label, "a pose on the ground needs one or two legs")
            poses.append({"name": pname, "drivers": [],
                          "guess": robot_guess(legs, bodies, ground, legs_pose, mid, label)})

    # the capacities last: every other check of the file comes first, in any build
    capacity(len(bodies), "bodies", "LEGSIM_MAX_BODIES", caps.get("bodies"), "robot")
    capacity(len(joints), "joints", "LEGSIM_MAX_JOINTS", caps.get("joints"), "robot")
    capacity(len(actuators), "actuators", "LEGSIM_MAX_ACTUATORS", caps.get("actuators"), "robot")
    capacity(len(forces), "force elements", "LEGSIM_MAX_FORCES", caps.get("forces"), "robot")
    capacity(len(contacts), "contacts", "LEGSIM_MAX_CONTACTS", caps.get("contacts"), "robot")
    return {"name": name, "gravity": gravity, "bodies": bodies, "joints": joints,
            "actuators": actuators, "forces": forces, "poses": poses,
            "foot_body": FRAME, "foot_point": [0.0, 0.0], "contacts": contacts, "ground": ground}


def robot_guess(legs: list[dict], bodies: list[dict], ground: dict, legs_pose: str, mid: float,
                label: str) -> list[list[float]]:
    """The pose's guess: each leg's own pose guess placed on the box, and the box put
    where both feet lie on the ground line, their midpoint at `mid` along it (a rigid
    motion of the whole guess; the same operations in model_toml.cpp)."""
    rows = [[0.0, 0.0, 0.0]]
    feet = []
    for leg in legs:
        lm, sign, off = leg["model"], leg["sign"], leg["off"]
        lp = [p for p in lm["poses"] if p["name"] == legs_pose]
        if not lp:
            fail(label, f"leg '{leg['name']}' has no pose '{legs_pose}'")
        for r in lp[0]["guess"]:
            rows.append([off[0] + sign * r[0], off[1] + r[1], sign * r[2]])
        bx, by, bphi = rows[leg["body0"] + lm["foot_body"]]
        xi, eta = lm["foot_point"][0], sign * lm["foot_point"][1]
        feet.append([bx + xi * math.sin(bphi) + eta * math.cos(bphi),
                     by - xi * math.cos(bphi) + eta * math.sin(bphi)])
    if len(feet) > 1:
        theta = math.atan2(feet[0][1] - feet[1][1], feet[0][0] - feet[1][0])
        m0 = 0.5 * (feet[0][0] + feet[1][0])
        m1 = 0.5 * (feet[0][1] + feet[1][1])
    else:
        theta = 0.0
        m0, m1 = feet[0]
    psi = ground["slope"] - theta
    c, s = math.cos(psi), math.sin(psi)
    ct, st = math.cos(ground["slope"]), math.sin(ground["slope"])
    r0 = ground["point"][0] + mid * ct - (c * m0 - s * m1)
    r1 = ground["point"][1] + mid * st - (s * m0 + c * m1)
    out = []
    for x, y, phi in rows:
        if not all(abs(v) <= MAX_COORD for v in (r0 + c * x - s * y, r1 + s * x + c * y, phi + psi)):
            fail(label, f"'guess' must be in [{g(-MAX_COORD)}, {g(MAX_COORD)}]")
        out.append([r0 + c * x - s * y, r1 + s * x + c * y, phi + psi])
    return out


def variant_names(doc: dict) -> list[str]:
    v = doc.get("variant", {})
    return [DEFAULT_VARIANT] + (list(v) if is_table(v) else [])


# ---- C output ----------------------------------------------------------------------
def c_real(x: float) -> str:
    s = repr(float(x))
    if "e" not in s and "." not in s:
        s += ".0"
    return s


def c_str(s: str) -> str:
    return '"' + s.replace("\\", "\\\\").replace('"', '\\"') + '"'


def c_vec(v) -> str:
    return "{" + ", ".join(c_real(x) for x in v) + "}"


def c_model(m: dict, cname: str, src: str, variant: str) -> str:
    o = [f"/* {src}, variant \"{variant}\" */",
         f"const legsim_model_desc {cname} = {{",
         f"  {c_str(m['name'])},",
         f"  {c_vec(m['gravity'])},",
         f"  {len(m['bodies'])}, {len(m['joints'])}, {len(m['actuators'])}, {len(m['forces'])}, "
         f"{len(m['poses'])}, /* bodies, joints, actuators, forces, poses */",
         "  { /* body: name, length, mass, inertia */"]
    for b in m["bodies"]:
        o.append(f"    {{{c_str(b['name'])}, {c_real(b['length'])}, {c_real(b['mass'])}, "
                 f"{c_real(b['inertia'])}}},")
    o.append("  },")
    o.append("  { /* joint: name, kind, body[2], point[2][2] */")
    for j in m["joints"]:
        o.append(f"    {{{c_str(j['name'])}, {JOINT_ENUM[j['kind']]}, {{{j['body'][0]}, {j['body'][1]}}}, "
                 f"{{{c_vec(j['point'][0])}, {c_vec(j['point'][1])}}}}},")
    if not m["joints"]:
        o.append('    {"", LEGSIM_JOINT_REVOLUTE_TO_FRAME, {0, 0}, {{0.0, 0.0}, {0.0, 0.0}}},')
    o.append("  },")
    o.append("  { /* actuator: name, joint, stroke min, max, max force, servo kp, kd */")
    for a in m["actuators"]:
        o.append(f"    {{{c_str(a['name'])}, {a['joint']}, {c_real(a['stroke'][0])}, "
                 f"{c_real(a['stroke'][1])}, {c_real(a['max_force'])}, {c_real(a['kp'])}, "
                 f"{c_real(a['kd'])}}},")
    if not m["actuators"]:
        o.append('    {"", 0, 0.0, 0.0, 0.0, 0.0, 0.0},')
    o.append("  },")
    o.append("  { /* force: name, kind, body[2], point[2][2], value[2], stiffness, damping, "
             "rest length */")
    for f in m["forces"]:
        o.append(f"    {{{c_str(f['name'])}, {FORCE_ENUM[f['kind']]}, {{{f['body'][0]}, {f['body'][1]}}}, "
                 f"{{{c_vec(f['point'][0])}, {c_vec(f['point'][1])}}}, {c_vec(f['value'])}, "
                 f"{c_real(f['stiffness'])}, {c_real(f['damping'])}, {c_real(f['rest_length'])}}},")
    if not m["forces"]:
        o.append('    {"", LEGSIM_FORCE_POINT, {0, 0}, {{0.0, 0.0}, {0.0, 0.0}}, {0.0, 0.0}, '
                 '0.0, 0.0, 0.0},')
    o.append("  },")
    o.append("  { /* pose: name, n_drivers, driver[] {body, coord, value}, guess[][3] */")
    for p in m["poses"]:
        drv = ", ".join(f"{{{b}, {c}, {c_real(v)}}}" for b, c, v in p["drivers"]) or "{0, 0, 0.0}"
        gs = ", ".join(c_vec(r) for r in p["guess"])
        o.append(f"    {{{c_str(p['name'])}, {len(p['drivers'])}, {{{drv}}},")
        o.append(f"     {{{gs}}}}},")
    if not m["poses"]:
        o.append('    {"", 0, {{0, 0, 0.0}}, {{0.0, 0.0, 0.0}}},')
    o.append("  },")
    o.append(f"  {m['foot_body']}, {c_vec(m['foot_point'])}, /* foot body, point */")
    o.append(f"  {len(m['contacts'])}, /* contacts */")
    o.append("  { /* contact: name, body, point */")
    for c in m["contacts"]:
        o.append(f"    {{{c_str(c['name'])}, {c['body']}, {c_vec(c['point'])}}},")
    if not m["contacts"]:
        o.append('    {"", 0, {0.0, 0.0}},')
    o.append("  },")
    gr = m["ground"]
    o.append(f"  {{{c_vec(gr['point'])}, {c_real(gr['slope'])}, {c_real(gr['mu_static'])}, "
             f"{c_real(gr['mu_kinetic'])}}} /* ground: point, slope, mu static, kinetic */")
    o.append("};")
    return "\n".join(o) + "\n"


def capacity_checks(models: list[tuple[str, dict]], symbol: str, src: str) -> str:
    need = {
        "LEGSIM_MAX_BODIES": ("bodies", max(len(m["bodies"]) for _, m in models)),
        "LEGSIM_MAX_JOINTS": ("joints", max(len(m["joints"]) for _, m in models)),
        "LEGSIM_MAX_ACTUATORS": ("actuators", max(len(m["actuators"]) for _, m in models)),
        "LEGSIM_MAX_FORCES": ("force elements", max(len(m["forces"]) for _, m in models)),
        "LEGSIM_MAX_POSES": ("poses", max(len(m["poses"]) for _, m in models)),
        "LEGSIM_MAX_CONTACTS": ("contacts", max(len(m["contacts"]) for _, m in models)),
        "LEGSIM_MAX_POSE_DRIVERS": ("pose drivers", max(
            [len(p["drivers"]) for _, m in models for p in m["poses"]] + [0])),
    }
    names = [m["name"] for _, m in models]
    names += [x["name"] for _, m in models for key in ("bodies", "joints", "actuators", "forces", "poses",
                                                       "contacts")
              for x in m[key]]
    longest = max(len(s.encode("utf-8")) for s in names)
    o = []
    for macro, (what, count) in need.items():
        o.append(f"#if !defined({macro}) || {macro} < {count}")
        o.append(f"#error \"legsim model '{symbol}' ({os.path.basename(src)}) needs {macro} >= "
                 f"{count} ({what}): raise it (the build's capacity, legsim/config.h)\"")
        o.append("#endif")
    o.append(f"#if !defined(LEGSIM_NAME_LEN) || LEGSIM_NAME_LEN < {longest + 1}")
    o.append(f"#error \"legsim model '{symbol}' ({os.path.basename(src)}) has names of {longest} "
             f"characters: LEGSIM_NAME_LEN must be at least {longest + 1}\"")
    o.append("#endif")
    return "\n".join(o) + "\n"


def write_file(path: str, text: str):
    """Always (re)written: the build tool compares its time with the inputs'."""
    d = os.path.dirname(path)
    if d:
        os.makedirs(d, exist_ok=True)
    tmp = path + ".tmp"
    with open(tmp, "w", encoding="utf-8") as f:
        f.write(text)
    os.replace(tmp, path)


def generate(src: str, symbol: str, models: list[tuple[str, dict]], include_as: str) -> tuple[str, str]:
    up = symbol.upper()
    guard = f"LEGSIM_MODELS_{up}_H"
    h = [f"/* Generated by firmware_core/tools/model_codegen.py from {os.path.basename(src)}."
         " Do not edit. */",
         f"#ifndef {guard}", f"#define {guard}", "", "#include \"legsim/legsim.h\"", "",
         "#ifdef __cplusplus", "extern \"C\" {", "#endif", "",
         "#ifndef LEGSIM_MODEL_VARIANT_DEFINED", "#define LEGSIM_MODEL_VARIANT_DEFINED",
         "/* A compiled-in model variant. */",
         "typedef struct legsim_model_variant {",
         "  const char *name;",
         "  const legsim_model_desc *model;",
         "} legsim_model_variant;", "#endif", ""]
    for v, _ in models:
        h.append(f"extern const legsim_model_desc legsim_model_{symbol}_{v};")
    h += ["", f"#define LEGSIM_MODEL_{up}_VARIANT_COUNT {len(models)}",
          f"/* \"{models[0][0]}\" (the default) first, then the file's [variant.X] in order. */",
          f"extern const legsim_model_variant legsim_model_{symbol}_variants[{len(models)}];",
          f"extern const int32_t legsim_model_{symbol}_variant_count;", "",
          "#ifdef __cplusplus", "}", "#endif", f"#endif /* {guard} */", ""]
    c = [f"/* Generated by firmware_core/tools/model_codegen.py from {os.path.basename(src)}."
         " Do not edit. */",
         f"#include \"{include_as}\"", "", capacity_checks(models, symbol, src)]
    for v, m in models:
        c.append(c_model(m, f"legsim_model_{symbol}_{v}", os.path.basename(src), v))
    c.append(f"const legsim_model_variant legsim_model_{symbol}_variants[{len(models)}] = {{")
    for v, _ in models:
        c.append(f"  {{{c_str(v)}, &legsim_model_{symbol}_{v}}},")
    c.append("};")
    c.append(f"const int32_t legsim_model_{symbol}_variant_count = {len(models)};")
    return "\n".join(c) + "\n", "\n".join(h)


# ---- bounds on the text (a mirror of host/toml_limits.cpp: same scan, same messages) ----
def _utf8_length(raw: bytes, i: int) -> int:
    """Length of the valid UTF-8 sequence at raw[i] (1..4), or 0."""
    c = raw[i]
    if c < 0x80:
        return 1
    if 0xC2 <= c <= 0xDF:
        n, cp = 2, c & 0x1F
    elif 0xE0 <= c <= 0xEF:
        n, cp = 3, c & 0x0F
    elif 0xF0 <= c <= 0xF4:
        n, cp = 4, c & 0x07
    else:
        return 0
    if i + n > len(raw):
        return 0
    for k in range(1, n):
        if raw[i + k] & 0xC0 != 0x80:
            return 0
        cp = (cp << 6) | (raw[i + k] & 0x3F)
    if cp < (0, 0, 0x80, 0x800, 0x10000)[n] or cp > 0x10FFFF or 0xD800 <= cp <= 0xDFFF:
        return 0
    return n


def toml_input_within_limits(raw: bytes) -> str | None:
    """None when the text is within the limits, else the reason (host/toml_limits.hpp)."""
    if len(raw) > TOML_MAX_BYTES:
        return f"larger than {TOML_MAX_BYTES} bytes"
    NORMAL, COMMENT, BASIC, LITERAL, MULTI_BASIC, MULTI_LITERAL = range(6)
    mode, line, depth, dots, i, size = NORMAL, 1, 0, 0, 0, len(raw)
    prev = "\n"  # the last non-blank character outside strings and comments: a quote opens
    # a string only where a token may start (after '=', '[', '{', ',', '.' or at a line start)

    def escapable(i: int) -> bool:  # a non-ASCII character after it was refused before
        return i + 1 < size and raw[i + 1] != 0x0A

    def backslash_non_ascii(i: int) -> bool:  # no TOML escape; toml++ 3.3.0 misparses some
        return i + 1 < size and raw[i + 1] >= 0x80

    while i < size:
        c = raw[i]
        if c >= 0x80:
            n = _utf8_length(raw, i)
            if n == 0:
                return f"invalid UTF-8 (line {line})"
            if mode == NORMAL:
                return f"a non-ASCII character outside a string or comment (line {line})"
            i += n
            continue
        if c == 0x0A:
            line += 1
            dots = 0
            if mode in (COMMENT, BASIC, LITERAL):
                mode = NORMAL
            if mode == NORMAL:
                prev = "\n"
            i += 1
            continue
        ch = chr(c)
        if mode == NORMAL:
            if ch == "#":
                mode = COMMENT
            elif ch in "\"'" and prev in "\n=[{,.":
                multi = raw[i:i + 3] == (b'"""' if ch == '"' else b"'''")
                if ch == '"':
                    mode = MULTI_BASIC if multi else BASIC
                else:
                    mode = MULTI_LITERAL if multi else LITERAL
                if multi:
                    i += 2
            elif ch in "[{":
                dots = 0
                depth += 1
                if depth > TOML_MAX_NESTING:
                    return (f"arrays, inline tables or headers nested deeper than "
                            f"{TOML_MAX_NESTING} (line {line})")
            elif ch in "]}":
                dots = 0
                if depth > 0:
                    depth -= 1
            elif ch in "=,":
                dots = 0
            elif ch == ".":
                dots += 1
                if dots >= TOML_MAX_KEY_PARTS:
                    return (f"a key or table header of more than {TOML_MAX_KEY_PARTS} dotted "
                            f"parts (line {line})")
            if mode == NORMAL and ch not in " \t\r":
                prev = ch
        elif mode == BASIC:
            if ch == "\\" and backslash_non_ascii(i):
                return f"a backslash before a non-ASCII character in a string (line {line})"
            if ch == "\\" and escapable(i):
                i += 1
            elif ch == '"':
                mode, prev = NORMAL, ch
        elif mode == LITERAL:
            if ch == "'":
                mode, prev = NORMAL, ch
        elif mode in (MULTI_BASIC, MULTI_LITERAL):
            quote = '"' if mode == MULTI_BASIC else "'"
            if mode == MULTI_BASIC and ch == "\\" and backslash_non_ascii(i):
                return f"a backslash before a non-ASCII character in a string (line {line})"
            if mode == MULTI_BASIC and ch == "\\" and escapable(i):
                i += 1
            elif ch == quote and raw[i:i + 3] == quote.encode() * 3:
                run = 3
                while run < 5 and i + run < size and raw[i + run] == c:
                    run += 1
                i += run - 1
                mode, prev = NORMAL, quote
        i += 1
    return None


def load_all(path: str, caps: dict) -> list[tuple[str, dict]]:
    """Every variant of the file, validated; raises ModelError("PATH: ITEM: PROBLEM")."""
    try:
        with open(path, "rb") as f:
            raw = f.read(TOML_MAX_BYTES + 1)  # a larger file is refused unread
    except OSError as e:
        raise ModelError(ERR_BAD_INPUT, f"{path}: cannot read: {e.strerror}")
    why = toml_input_within_limits(raw)
    if why is not None:
        raise ModelError(ERR_MODEL, f"{path}: TOML input refused: {why}")
    try:
        doc = tomllib.loads(raw.decode("utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as e:
        raise ModelError(ERR_MODEL, f"{path}: TOML syntax error: {e}")
    out = []
    try:
        # The default variant validates the base model and the [variant] tables' structure.
        if is_robot(doc):  # one model: its legs name their variants
            out.append((DEFAULT_VARIANT, parse_robot(doc, os.path.dirname(path), DEFAULT_VARIANT, caps)))
            return out
        out.append((DEFAULT_VARIANT, parse_model(doc, DEFAULT_VARIANT, caps)))
        for v in variant_names(doc)[1:]:
            out.append((v, parse_model(doc, v, caps)))
    except ModelError as e:
        raise ModelError(e.status, f"{path}: {e.message}")
    return out


def read_config(path: str) -> dict:
    """Capacities from a generated legsim/config.h (#define LEGSIM_MAX_X N)."""
    caps = {}
    try:
        with open(path, encoding="utf-8") as f:
            for line in f:
                m = re.match(r"\s*#\s*define\s+LEGSIM_MAX_([A-Z_]+)\s+([0-9]+)\s*(?:/[*/].*)?$", line)
                if m and m.group(1).lower() in ("bodies", "joints", "actuators", "forces", "poses",
                                                "pose_drivers", "contacts"):
                    caps[m.group(1).lower()] = int(m.group(2))
    except OSError as e:
        sys.exit(f"model_codegen: error: {path}: cannot read: {e.strerror}")
    return caps


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("toml", help="model file (models/leg.toml)")
    ap.add_argument("--symbol", required=True, help="C name part: legsim_model_<symbol>_<variant>")
    ap.add_argument("--out-c", help="C source to write")
    ap.add_argument("--out-h", help="header to write (e.g. .../legsim/models.h)")
    ap.add_argument("--include-as", help="how the source includes the header "
                    "(default: legsim/<name> when the header sits in a legsim/ folder)")
    ap.add_argument("--check", action="store_true", help="only validate (no output files)")
    ap.add_argument("--config", help="the build's generated legsim/config.h: check its "
                    "LEGSIM_MAX_* capacities here too (same messages as the run-time loader)")
    for what in ("bodies", "joints", "actuators", "forces", "poses", "pose-drivers", "contacts"):
        ap.add_argument(f"--max-{what}", type=int, default=None,
                        help=f"capacity LEGSIM_MAX_{what.upper().replace('-', '_')} to check "
                             "(the generated source checks it with #error anyway)")
    a = ap.parse_args(argv)
    if not IDENT_RE.fullmatch(a.symbol):
        ap.error(f"--symbol '{a.symbol}' is not a C identifier")
    if not a.check and not (a.out_c and a.out_h):
        ap.error("--out-c and --out-h are required (or --check)")
    caps = read_config(a.config) if a.config else {}
    for key in ("bodies", "joints", "actuators", "forces", "poses", "pose_drivers", "contacts"):
        v = getattr(a, "max_" + key)
        if v is not None:
            caps[key] = v
    try:
        models = load_all(a.toml, caps)
    except ModelError as e:
        print(f"model_codegen: error: {e.message}", file=sys.stderr)
        return 1
    if a.check:
        print(f"{a.toml}: OK ({', '.join(v for v, _ in models)})")
        return 0
    include_as = a.include_as
    if include_as is None:
        base = os.path.basename(a.out_h)
        parent = os.path.basename(os.path.dirname(os.path.abspath(a.out_h)))
        include_as = f"legsim/{base}" if parent == "legsim" else base
    c_text, h_text = generate(a.toml, a.symbol, models, include_as)
    write_file(a.out_h, h_text)
    write_file(a.out_c, c_text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
