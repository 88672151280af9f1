#!/usr/bin/env python3
"""Emit can_tx_checks.h: every frame hil_sim may send, checked against can/legsim.dbc.

For each message the HIL nodes send (FAULT, ST_*, HEARTBEAT; the robot's leg 1, HIL_L1, its
ST_*_L1) a function unpacks the
payload with the code cantools generated from the same DBC (legsim_can.c) and reports,
signal by signal, whether the value is inside the DBC's range (a NaN is never inside).
The fuzz target of hil_sim's frame handling (fuzz/fuzz_can.cpp) applies the DBC's
documented exceptions (Fault_Value may be NaN/Inf for NOT_FINITE).
"""
import argparse
import sys

import cantools
from cantools.database.can.c_source import camel_to_snake_case


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument('dbc')
    ap.add_argument('--node', action='append',
                    help='a sender whose frames are checked (repeatable; default HIL and HIL_L1)')
    ap.add_argument('--database-name', default='legsim_can')
    ap.add_argument('-o', '--output', required=True)
    args = ap.parse_args()
    db = cantools.database.load_file(args.dbc, strict=True)
    nodes = args.node or ['HIL', 'HIL_L1']
    dbn = args.database_name
    out = [f'/* Generated from {args.dbc.split("/")[-1]} by fuzz/can_tx_checks.py: do not edit. */',
           '#ifndef LEGSIM_FUZZ_CAN_TX_CHECKS_H', '#define LEGSIM_FUZZ_CAN_TX_CHECKS_H', '',
           '#include <stddef.h>', '#include <stdint.h>', '', f'#include "{dbn}.h"', '',
           '/* One signal of an unpacked frame: its DBC name, value and whether it is in range. */',
           'typedef struct { const char *name; double value; int in_range; } can_tx_signal;', '',
           '/* Unpacks a frame the node sends: the number of signals written to sig (at most',
           ' * max), or -1 when the id is not one the node sends or the payload does not unpack. */',
           'static inline int can_tx_check(uint32_t id, const uint8_t *data, size_t len,',
           '                               can_tx_signal *sig, int max) {',
           '  int n = 0;',
           '  (void)max;',
           '  switch (id) {']
    n_msgs = 0
    for msg in db.messages:
        if not any(n in msg.senders for n in nodes):
            continue
        n_msgs += 1
        m = camel_to_snake_case(msg.name)
        out.append(f'    case {msg.frame_id}u: {{  /* {msg.name} */')
        out.append(f'      struct {dbn}_{m}_t v;')
        out.append(f'      if ({dbn}_{m}_unpack(&v, data, len) != 0) return -1;')
        for sig in msg.signals:
            s = camel_to_snake_case(sig.name)
            out.append(f'      if (n < max) {{ sig[n].name = "{sig.name}"; '
                       f'sig[n].value = (double)v.{s}; '
                       f'sig[n].in_range = {dbn}_{m}_{s}_is_in_range(v.{s}); }} ++n;')
        out.append('      return n;')
        out.append('    }')
    out += ['    default: return -1;', '  }', '}', '', '#endif', '']
    if n_msgs == 0:
        sys.exit(f'{args.dbc}: no message sent by {", ".join(nodes)}')
    with open(args.output, 'w', encoding='utf-8') as f:
        f.write('\n'.join(out))
    return 0


if __name__ == '__main__':
    sys.exit(main())
