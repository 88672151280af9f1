#!/usr/bin/env python3
"""Emit legsim_can_layout.h: the start bit of every signal of can/legsim.dbc.

cantools generate_c_source emits pack/unpack code but not the signals' positions;
hil_sim names the offending signal in a FAULT frame by its start bit
(Fault_Detail), so the positions come from the same DBC at build time.
"""
import argparse
import sys

import cantools
from cantools.database.can.c_source import camel_to_snake_case


def macro(*parts):
    """The spelling of generate_c_source (e.g. ST_STATUS + St_StepCount -> ST_STATUS_ST_STEP_COUNT)."""
    return '_'.join(camel_to_snake_case(p).upper() for p in parts)


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument('dbc')
    ap.add_argument('--database-name', default='legsim_can')
    ap.add_argument('-o', '--output', required=True)
    args = ap.parse_args()
    db = cantools.database.load_file(args.dbc, strict=True)
    guard = macro(args.database_name, 'LAYOUT_H')
    lines = [f'/* Generated from {args.dbc.split("/")[-1]} by hil_sim/can_layout.py: do not edit. */',
             f'#ifndef {guard}', f'#define {guard}', '']
    for msg in db.messages:
        for sig in msg.signals:
            lines.append(f'#define {macro(args.database_name, msg.name, sig.name)}_START_BIT '
                         f'({sig.start}u)')
        lines.append('')
    lines.append(f'#endif /* {guard} */')
    with open(args.output, 'w', encoding='utf-8') as f:
        f.write('\n'.join(lines) + '\n')
    return 0


if __name__ == '__main__':
    sys.exit(main())
