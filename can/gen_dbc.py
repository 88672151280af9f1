#!/usr/bin/env python3
"""can/legsim.dbc from can/legsim.dbc.in: the per-leg frames written once, for leg 0, and
repeated for every other leg k at id + k * 0x20, named NAME_Lk, sent or received by node HIL_Lk.

    python3 can/gen_dbc.py [--legs N] [-o can/legsim.dbc]      (default: the template's legs)

The template is a DBC whose lines are copied as they are, except these (none is copied):
    @legs SIDE...            the legs in order, by side ("right left"): how many there are
    @leg_comment TEXT        the comment of leg k's copy of a frame (see @copy)
    @copy SECTION FRAME...   for every leg k >= 1, leg 0's lines of these frames in SECTION
                             (BO_, CM_, BA_, VAL_ or SIG_VALTYPE_), moved to leg k; in CM_ a
                             frame's own comment becomes @leg_comment
    @each{ ... @}            the lines between, once per leg k = 0 .. N-1
    @rest{ ... @}            the lines between, once per leg k = 1 .. N-1
    @hex{ ... @}             the lines between, once per hexapod leg j = 0 .. 5 (hil_sim --hexapod:
                             its per-leg frames), H its suffix ("_Hj")
    @once TEXT               TEXT, once
In @each, @rest, @once and @leg_comment, {{EXPR}} is the value of a Python expression of
k (the leg), N (the legs), side (k's side), L ("" for leg 0, "_Lk" else), hil ("HIL" for leg 0,
"HIL_Lk" else), nodes ("HIL HIL_L1 ..."), and in @hex j and H; in @leg_comment also frame (leg 0's name), id0
(its id, hex) and route ("bench -> hil_sim leg k (side)" or "leg k (side) -> bench").
tests/bench/test_dbc.py checks that the committed can/legsim.dbc is this script's output.
"""
from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
LEG_OFFSET = 0x20
HEXAPOD_LEGS = 6
SECTIONS = ("BO_", "CM_", "BA_", "VAL_", "SIG_VALTYPE_")
_FIELD = re.compile(r"\{\{(.+?)\}\}")


class TemplateError(ValueError):
    pass


def _fill(text: str, env: dict) -> str:
    return _FIELD.sub(lambda m: str(eval(m.group(1), {"__builtins__": {"hex": hex}}, env)), text)


def _leg_env(k: int, sides: list[str]) -> dict:
    n = len(sides)
    return {"k": k, "N": n, "side": sides[k], "L": f"_L{k}" if k else "", "hil": f"HIL_L{k}" if k else "HIL",
            "nodes": " ".join(["HIL"] + [f"HIL_L{j}" for j in range(1, n)])}


def _frames(lines: list[str]) -> dict[str, tuple[int, str, list[str]]]:
    """Leg 0's frames in the template: name -> (id, sender, BO_ block lines)."""
    out, cur = {}, None
    for ln in lines:
        m = re.match(r"BO_ (\d+) (\w+): \d+ (\w+)$", ln)
        if m:
            cur = m.group(2)
            out[cur] = (int(m.group(1)), m.group(3), [ln])
        elif cur and ln.startswith(" SG_ "):
            out[cur][2].append(ln)
        else:
            cur = None
    return out


def _moved(line: str, fid: int, k: int) -> str:
    """One of leg 0's lines of frame `fid`, moved to leg k."""
    new = fid + k * LEG_OFFSET
    hil = f"HIL_L{k}"
    m = re.match(r"BO_ \d+ (\w+): (\d+) (\w+)$", line)
    if m:
        sender = hil if m.group(3) == "HIL" else m.group(3)
        return f"BO_ {new} {m.group(1)}_L{k}: {m.group(2)} {sender}"
    if line.startswith(" SG_ "):
        return re.sub(r" HIL$", " " + hil, line)
    return re.sub(rf"^((?:CM_ SG_|CM_ BO_|BA_ \"\w+\" BO_|VAL_|SIG_VALTYPE_) ){fid}\b", rf"\g<1>{new}", line)


def _section_lines(lines: list[str], section: str, fid: int) -> list[str]:
    """Leg 0's lines of frame `fid` in a section (CM_: the signals' comments, not the frame's)."""
    if section == "CM_":
        pat = re.compile(rf"^CM_ SG_ {fid} ")
    elif section == "BA_":
        pat = re.compile(rf"^BA_ \"\w+\" BO_ {fid} ")
    else:
        pat = re.compile(rf"^{section} {fid} ")
    return [ln for ln in lines if pat.match(ln)]


def generate(template: str, legs: int | None = None) -> str:
    lines = template.split("\n")
    sides = None
    leg_comment = None
    for ln in lines:
        if ln.startswith("@legs "):
            sides = ln.split()[1:]
        elif ln.startswith("@leg_comment "):
            leg_comment = ln[len("@leg_comment "):]
    if not sides:
        raise TemplateError("the template names no legs (@legs SIDE...)")
    if legs is not None:
        if legs < 1:
            raise TemplateError(f"--legs {legs}: a robot has at least one leg")
        sides = (sides + [f"leg{j}" for j in range(len(sides), legs)])[:legs]
    literal = [ln for ln in lines if not ln.startswith("@")]
    frames = _frames(literal)
    out: list[str] = []
    block: list[str] | None = None
    block_legs: range | None = None
    block_hex = False
    for ln in lines:
        if block is not None:
            if ln == "@}":
                for k in block_legs:
                    env = _leg_env(0 if block_hex else k, sides)
                    if block_hex:
                        env.update(j=k, H=f"_H{k}")
                    out.extend(_fill(b, env) for b in block)
                block = None
            else:
                block.append(ln)
            continue
        if ln in ("@each{", "@rest{"):
            block, block_legs, block_hex = [], range(0 if ln == "@each{" else 1, len(sides)), False
        elif ln == "@hex{":
            block, block_legs, block_hex = [], range(HEXAPOD_LEGS), True
        elif ln.startswith("@once "):
            out.append(_fill(ln[len("@once "):], _leg_env(0, sides)))
        elif ln.startswith("@copy "):
            section, *names = ln.split()[1:]
            if section not in SECTIONS:
                raise TemplateError(f"@copy {section}: not one of {', '.join(SECTIONS)}")
            for k in range(1, len(sides)):
                for name in names:
                    if name not in frames:
                        raise TemplateError(f"@copy: no frame {name} in the template")
                    fid, sender, bo = frames[name]
                    src = bo + [""] if section == "BO_" else _section_lines(literal, section, fid)
                    out.extend(_moved(s, fid, k) for s in src)
                    if section == "CM_":
                        if leg_comment is None:
                            raise TemplateError("@copy CM_ needs @leg_comment")
                        env = _leg_env(k, sides)
                        env.update(frame=name, id0=f"0x{fid:03X}",
                                   route=(f"bench -> hil_sim leg {k} ({sides[k]})" if sender == "BENCH"
                                          else f"leg {k} ({sides[k]}) -> bench"))
                        out.append(f'CM_ BO_ {fid + k * LEG_OFFSET} "{_fill(leg_comment, env)}";')
        elif ln.startswith(("@legs ", "@leg_comment ")):
            continue
        elif ln.startswith("@"):
            raise TemplateError(f"unknown directive {ln.split()[0]}")
        else:
            out.append(ln)
    if block is not None:
        raise TemplateError("a block (@each{, @rest{ or @hex{) has no @}")
    return "\n".join(out)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("template", nargs="?", default=str(HERE / "legsim.dbc.in"))
    p.add_argument("--legs", type=int, default=None, help="legs (default: the template's @legs)")
    p.add_argument("-o", "--output", default="-", help="output file (default: stdout)")
    a = p.parse_args(argv)
    try:
        text = generate(Path(a.template).read_text(), a.legs)
    except (OSError, TemplateError) as e:
        print(f"gen_dbc: {e}", file=sys.stderr)
        return 2
    if a.output == "-":
        sys.stdout.write(text)
    else:
        Path(a.output).write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
