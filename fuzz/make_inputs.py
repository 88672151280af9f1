#!/usr/bin/env python3
"""Fuzz inputs made at build time (nothing large is committed):

  can-seeds DBC OUTDIR    seed sequences for fuzz_can, frames encoded from can/legsim.dbc
                          with cantools (the input format: fuzz/README.md); the hexapod's
                          in OUTDIR/hexapod
  toml-dict OUT FILE...   a libFuzzer dictionary for the TOML targets: TOML's own tokens
                          and every key and short string value of the given files
  deep-keys OUTDIR        issue 10's stack overflow in toml++ 3.3.0: a key and a table
                          header of 50,000 dotted parts (about 100 KB each), as a model
                          file and as a scene file

Files are rewritten only when their content changes (no needless rebuilds of tests).
"""
import argparse
import math
import os
import struct
import sys

# fuzz_can.cpp's kIds (the leg's bus) and kRobotIds (the robot's: the same, then more): the
# selector of a frame's id
SEL = {'CONTROL': 0, 'ACT_CMD': 1, 'LOAD_CMD': 2, 'FAULT': 6, 'ST_POS': 7, 'HEARTBEAT': 9,
       'UNKNOWN': 12}
ROBOT_SEL = dict(SEL, ACT_CMD_L1=13, LOAD_CMD_L1=14, ST_BOX=17, ST_CONTACT_L1=18, ST_STATUS_L1=19)
# fuzz_can.cpp's kHexIds (hil_sim --hexapod's bus)
HEX_SEL = dict({'CONTROL': 0, 'ACT_CMD': 14, 'LOAD_CMD': 15, 'START_CMD': 16, 'FAULT': 17, 'ST_STATUS': 18,
                'HEARTBEAT': 19, 'HEX_BOX_POSE': 20, 'HEX_BOX_VEL': 21, 'HEX_LEG_H2': 22, 'HEX_FOOT_H5': 23,
                'UNKNOWN': 26}, **{f'HEX_CMD_H{k}': 2 + k for k in range(6)})
LEG_BUS, ROBOT_BUS, HEXAPOD_BUS = 0, 1, 2  # the input's first byte: hil_sim, --robot, --hexapod
RESET, STEP, START_RT, STOP_RT = 1, 2, 3, 4
KEEP, FORCE, LENGTH = 0, 1, 2
FLT_MAX = struct.unpack('<f', struct.pack('<I', 0x7f7fffff))[0]  # the largest finite float32


def write_if_changed(path, data):
    try:
        with open(path, 'rb') as f:
            if f.read() == data:
                return
    except OSError:
        pass
    with open(path, 'wb') as f:
        f.write(data)


class Seq:
    """One fuzz_can input: operations as fuzz_can.cpp reads them."""

    def __init__(self, db, bus=LEG_BUS):
        self.db = db
        self.sel = {ROBOT_BUS: ROBOT_SEL, HEXAPOD_BUS: HEX_SEL}.get(bus, SEL)
        self.out = bytearray([bus])

    def op(self, what, ms=0):
        assert 0 <= ms < 64
        self.out.append((ms << 2) | what)

    def frame(self, name, signals=None, ms=0, flags=0, length=64, raw_id=None, payload=None):
        self.op(0, ms)
        if raw_id is not None:
            self.out += bytes([0xF0]) + struct.pack('<I', raw_id)
        else:
            self.out.append(self.sel[name])
        self.out += bytes([flags, length])
        if payload is None:
            msg = self.db.get_message_by_name(name)
            full = {s.name: 0 for s in msg.signals}
            full.update(signals or {})
            payload = msg.encode(full, strict=False, padding=False)
        self.out += bytes(payload[:length]).ljust(length, b'\0')
        return self

    def control(self, seq, command, ms=0, **kw):
        sig = {'Ctrl_Seq': seq, 'Ctrl_Command': command, 'Ctrl_StepSize': 1000000,
               'Ctrl_NSteps': 1, 'Ctrl_RtStepsPerTick': 1}
        sig.update({f'Ctrl_{k}': v for k, v in kw.items()})
        return self.frame('CONTROL', sig, ms)

    def act(self, seq, mode_u, sp_u, mode_l=KEEP, sp_l=0.0, ms=0, leg=0):
        return self.frame('ACT_CMD_L1' if leg else 'ACT_CMD', {'Act_Seq': seq, 'Act_Mode_upper': mode_u,
                                      'Act_Setpoint_upper': sp_u, 'Act_Mode_lower': mode_l,
                                      'Act_Setpoint_lower': sp_l}, ms)

    def load(self, seq, index, v1, v2=0.0, ms=0, leg=0):
        return self.frame('LOAD_CMD_L1' if leg else 'LOAD_CMD', {'Load_Seq': seq, 'Load_Index': index, 'Load_Value1': v1,
                                       'Load_Value2': v2}, ms)

    def hex(self, leg, seq, upper=None, lower=None, rowing=None, ms=0):
        """HEX_CMD_H<leg>: each slot None (KEEP) or (mode, set-point, feed-forward)."""
        sig = {'Hc_Seq': seq}
        for name, slot in (('upper', upper), ('lower', lower), ('rowing', rowing)):
            mode, value, ff = (KEEP, 0.0, 0.0) if slot is None else slot
            sig.update({f'Hc_Mode_{name}': mode, f'Hc_Setpoint_{name}': value, f'Hc_Ff_{name}': ff})
        return self.frame(f'HEX_CMD_H{leg}', sig, ms)

    def work(self, n):
        self.op(1)
        self.out.append(n - 1)
        return self

    def tick(self, ms=1):
        self.op(2, ms)
        return self

    def heartbeat(self, ms=0):
        self.op(3, ms)
        return self


def can_seeds(db):
    S = lambda: Seq(db)  # noqa: E731
    R = lambda: Seq(db, ROBOT_BUS)  # noqa: E731
    nan, inf = math.nan, math.inf
    return {
        'reset_step': S().control(1, RESET).control(2, STEP, NSteps=25).heartbeat(),
        'force_and_length': S().control(1, RESET).act(1, FORCE, 200.0, LENGTH, 0.5)
        .control(2, STEP, NSteps=20).act(2, LENGTH, 0.6, FORCE, -100.0)
        .control(3, STEP, NSteps=20).heartbeat(),
        'slot_generalized_alpha': S().control(1, RESET, Variant=1, Integrator=1, ActInit=1)
        .control(2, STEP, NSteps=30).heartbeat(),
        'use_lengths': S().control(1, RESET, UseLengths=1, Length_upper=0.6, Length_lower=0.5)
        .control(2, STEP, NSteps=5),
        'load_foot': S().control(1, RESET).load(1, 0, 300.0, -50.0).control(2, STEP, NSteps=10),
        'disable_flags': S().control(1, RESET, Disable=63, StepSize=100000)
        .control(2, STEP, NSteps=10),
        'realtime': S().control(1, RESET).control(2, START_RT, RtStepsPerTick=2, RtDecimation=3)
        .tick().tick().tick().act(1, FORCE, 50.0).tick().tick().tick().heartbeat()
        .control(3, STOP_RT),
        'realtime_timeout': S().control(1, RESET, CmdTimeout=5).control(2, START_RT)
        .act(1, FORCE, 10.0).tick(2).tick(10).tick(10).control(3, STOP_RT),
        'lockstep_timeout': S().control(1, RESET, CmdTimeout=3).act(1, LENGTH, 0.6)
        .control(2, STEP, NSteps=10).heartbeat(),
        'sliced_step': S().control(1, RESET).control(2, STEP, NSteps=50).work(3).work(7)
        .heartbeat().act(1, FORCE, 20.0).control(3, STEP, NSteps=40).work(1),
        'bad_frames': S().control(1, STEP, NSteps=5).act(1, FORCE, 1.0).control(1, RESET)
        .act(1, FORCE, nan).act(2, KEEP, 0.0, LENGTH, inf).act(3, FORCE, 1e5)
        .act(4, LENGTH, 5.0).load(1, 3, 1.0).control(1, STEP, NSteps=5)
        .control(2, STEP, NSteps=0).control(3, 9).control(4, RESET, Pose=1, Variant=1)
        .frame('ACT_CMD', {'Act_Seq': 9, 'Act_Mode_upper': FORCE, 'Act_Setpoint_upper': 1.0},
               flags=4, length=8)
        .frame('ACT_CMD', {'Act_Seq': 10}, flags=1)
        .frame('ACT_CMD', {'Act_Seq': 11}, length=48)
        .frame('UNKNOWN', payload=b'\xff' * 64)
        .frame('ST_POS', payload=b'\x01' * 64)
        .frame(None, raw_id=0x1234567, flags=1, payload=b'\0' * 64)
        .control(5, STEP, NSteps=3),
        # every finite float32 is a value a FAULT may echo (CI's fuzz run, session 5)
        'fault_value_flt_max': S().control(1, RESET).act(1, FORCE, FLT_MAX)
        .act(2, KEEP, 0.0, LENGTH, -FLT_MAX).load(1, 0, FLT_MAX, -FLT_MAX).control(2, STEP, NSteps=2),
        # hil_sim --robot: both legs' frames, the box load, its RESET options, a watchdog per leg
        'robot_reset_step': R().control(1, RESET, ActInit=1).control(2, STEP, NSteps=20).heartbeat(),
        'robot_both_legs': R().control(1, RESET, ActInit=1).act(1, FORCE, 150.0)
        .act(1, LENGTH, 0.7, KEEP, 0.0, leg=1).load(1, 0, 3.0, -20.0, leg=1).load(1, 2, 5.0, 1.0)
        .load(2, 3, 2.0).control(2, STEP, NSteps=30).work(4).act(2, KEEP, 0.0, FORCE, -80.0, leg=1)
        .control(3, STEP, NSteps=20).heartbeat(),
        'robot_reset_options': R().control(1, RESET, ActInit=1, ContactLaw=1, FreeContacts=2,
                                           UseLengths=1, Length_upper=0.62, Length_lower=0.52,
                                           Length_upper_L1=0.63, Length_lower_L1=0.53)
        .control(2, STEP, NSteps=40).heartbeat(),
        'robot_watchdog_per_leg': R().control(1, RESET, ActInit=1, CmdTimeout=5)
        .act(1, LENGTH, 0.6).act(1, LENGTH, 0.6, leg=1).control(2, STEP, NSteps=3)
        .act(2, LENGTH, 0.6).control(3, STEP, NSteps=3).act(3, LENGTH, 0.6)
        .control(4, STEP, NSteps=3).heartbeat().act(2, LENGTH, 0.6, leg=1).control(5, STEP, NSteps=9),
        'robot_realtime': R().control(1, RESET, ActInit=1, CmdTimeout=5).control(2, START_RT)
        .act(1, FORCE, 10.0).act(1, FORCE, 20.0, leg=1).tick(2).tick(2).act(2, FORCE, 10.0)
        .tick(2).tick(2).heartbeat().control(3, STOP_RT),
        'robot_bad_frames': R().act(1, FORCE, 1.0, leg=1).control(1, RESET, ActInit=1)
        .act(1, FORCE, nan, leg=1).act(2, KEEP, 0.0, LENGTH, inf, leg=1).act(3, FORCE, 1e5, leg=1)
        .act(4, LENGTH, 0.95, leg=1).act(5, 3, 0.6, leg=1).load(1, 1, 1.0, leg=1)
        .load(2, 0, nan, leg=1).act(6, FORCE, 0.0, leg=1).act(6, FORCE, 10.0, leg=1)
        .control(2, RESET, Variant=1).control(3, RESET, ContactLaw=2).control(4, RESET, FreeContacts=4)
        .control(5, RESET, UseLengths=1, Length_upper=0.6, Length_lower=0.5, Length_upper_L1=0.6,
                 Length_lower_L1=0.2)
        .frame('ACT_CMD_L1', {'Act_Seq': 9, 'Act_Mode_upper': FORCE}, flags=4, length=8)
        .frame('ST_BOX', payload=b'\x01' * 64).frame('ST_CONTACT_L1', payload=b'\x02' * 64)
        .frame('ST_STATUS_L1', payload=b'\x03' * 64).control(6, STEP, NSteps=5),
    }


def hexapod_seeds(db):
    """hil_sim --hexapod (models/hexapod.toml: strokes [0.40, 0.80] and [0.35, 0.70] m, max_force
    1500 N; rowing [-0.6, 0.6] rad, max_torque 30 N m): the RESET's options, each slot in its own
    mode, the held pose, a watchdog per leg, real time, bad frames."""
    X = lambda: Seq(db, HEXAPOD_BUS)  # noqa: E731
    nan, inf = math.nan, math.inf
    SERVO = LENGTH
    stand = dict(HexBoxHeight=1.0, HexStance=63)
    return {
        'hex_reset_step': X().control(1, RESET, ActInit=1, **stand).control(2, STEP, NSteps=16)
        .control(3, STEP, NSteps=16).heartbeat(),
        'hex_mixed_slots': X().control(1, RESET, ActInit=1, **stand)
        .hex(0, 1, None, (FORCE, 300.0, 0.0), None).hex(1, 1, None, None, (FORCE, 5.0, 0.0))
        .hex(2, 1, (SERVO, 0.6, 50.0), (FORCE, -200.0, 0.0), (SERVO, 0.1, 1.0))
        .control(2, STEP, NSteps=16).hex(0, 2, None, (SERVO, 0.5, 100.0), (FORCE, -3.0, 0.0))
        .hex(3, 1, (FORCE, 0.0, 0.0), (FORCE, 0.0, 0.0), (FORCE, 0.0, 0.0)).control(3, STEP, NSteps=16),
        'hex_force_free_fall': X().control(1, RESET, ActInit=0, HexBoxHeight=1.3, HexStance=0, Integrator=1)
        .hex(4, 1, (FORCE, 100.0, 0.0), (SERVO, 0.5, 0.0), None).control(2, STEP, NSteps=16)
        .control(3, STEP, NSteps=16).work(2).heartbeat(),
        'hex_held_pose': X().hex(0, 1, (SERVO, 0.62, 10.0), (SERVO, 0.52, -10.0), (SERVO, 0.05, 0.5))
        .hex(5, 1, None, (SERVO, 0.5, 0.0), None).hex(5, 2, (FORCE, 50.0, 0.0), None, None)
        .control(1, RESET, ActInit=1, UseLengths=1, **stand).control(2, STEP, NSteps=8),
        'hex_watchdog_per_leg': X().control(1, RESET, ActInit=1, CmdTimeout=4, **stand)
        .hex(0, 1).hex(1, 1, None, (FORCE, 100.0, 0.0)).control(2, STEP, NSteps=2).hex(0, 2)
        .control(3, STEP, NSteps=3).hex(0, 3).control(4, STEP, NSteps=3).heartbeat()
        .hex(1, 2, (SERVO, 0.6, 0.0)).control(5, STEP, NSteps=6),
        'hex_realtime': X().control(1, RESET, ActInit=1, CmdTimeout=5, **stand)
        .control(2, START_RT, RtStepsPerTick=2, RtDecimation=2).hex(2, 1, (FORCE, 10.0, 0.0))
        .tick(2).tick(2).hex(2, 2, (FORCE, 20.0, 0.0)).tick(3).tick(3).heartbeat().control(3, STOP_RT),
        'hex_bad_frames': X().control(1, STEP, NSteps=2).control(1, RESET, ActInit=1, **stand)
        .hex(0, 1, (3, 0.6, 0.0)).hex(0, 2, None, (FORCE, 0.0, 0.0), (255, 0.0, 0.0))
        .hex(1, 1, (SERVO, nan, 0.0)).hex(1, 2, (SERVO, 0.6, inf)).hex(1, 3, (SERVO, 0.85, 0.0))
        .hex(2, 1, None, (FORCE, 1500.5, 0.0)).hex(2, 2, None, None, (SERVO, 0.61, 0.0))
        .hex(2, 3, None, None, (FORCE, -30.5, 0.0)).hex(3, 1, (SERVO, 0.6, 1600.0)).hex(3, 1)
        .hex(4, 1, (FORCE, FLT_MAX, 0.0)).hex(4, 2, (FORCE, 1.0, -FLT_MAX))
        .frame('HEX_CMD_H5', {'Hc_Seq': 9}, flags=4, length=8).frame('HEX_CMD_H5', {'Hc_Seq': 10}, length=48)
        .frame('HEX_CMD_H5', {'Hc_Seq': 11}, flags=1)
        .act(1, FORCE, 1.0).load(1, 0, 1.0).frame('START_CMD', {'Start_Seq': 1})
        .control(2, RESET, Variant=1, **stand).control(3, RESET, Pose=1, **stand)
        .control(4, RESET, HexBoxHeight=0.0).control(5, RESET, HexBoxHeight=nan)
        .control(6, RESET, ContactLaw=1, **stand).control(7, RESET, FreeContacts=1, **stand)
        .control(8, RESET, HexBoxHeight=0.01, HexStance=0)
        .frame('HEX_BOX_POSE', payload=b'\x01' * 64).frame('HEX_LEG_H2', payload=b'\x02' * 64)
        .frame('ST_STATUS', payload=b'\x03' * 64).frame('UNKNOWN', payload=b'\xff' * 64)
        .control(9, STEP, NSteps=3),
    }


def deep_keys(outdir, parts):
    key = '.'.join(['a'] * parts)
    files = {
        'model_dotted_key_50000.toml': f'name = "x"\n{key} = 1\n',
        'model_dotted_table_50000.toml': f'name = "x"\n[{key}]\nz = 1\n',
        'scene_dotted_key_50000.toml': f'analysis = "statics"\n{key} = 1\n',
        'scene_dotted_table_50000.toml': f'analysis = "statics"\n[{key}]\nz = 1\n',
    }
    for name, text in files.items():
        sub = os.path.join(outdir, name.split('_', 1)[0])
        os.makedirs(sub, exist_ok=True)
        write_if_changed(os.path.join(sub, name), text.encode())


TOML_TOKENS = ['=', '[', ']', '[[', ']]', '{', '}', ',', '.', '"', "'", '"""', "'''", '#', '\n',
               'true', 'false', 'inf', '-inf', 'nan', '+nan', '0x', '0o', '0b', '1e300', '-1e300',
               '1e-320', '5e-324', '1e9', '1e10', '2147483648', '9223372036854775807',
               '-9223372036854775808', '1979-05-27T07:32:00Z', '\\u00e9', '\u00e9']


def dict_entry(word):
    """A libFuzzer dictionary line: printable ASCII as is, the rest as \\xNN."""
    out = []
    for b in word.encode():
        c = chr(b)
        out.append(c if 0x20 <= b < 0x7f and c not in '"\\' else f'\\x{b:02x}')
    return '"' + ''.join(out) + '"'


def toml_dict(out, files):
    import tomllib
    words = set(TOML_TOKENS)

    def walk(v):
        if isinstance(v, dict):
            for k, x in v.items():
                words.add(k)
                walk(x)
        elif isinstance(v, list):
            for x in v:
                walk(x)
        elif isinstance(v, str) and len(v) <= 32:
            words.add(v)

    for path in files:
        try:
            with open(path, 'rb') as f:
                walk(tomllib.load(f))
        except (OSError, ValueError, RecursionError):  # TOMLDecodeError, UnicodeDecodeError
            pass  # fixtures that are bad on purpose
    words.discard('')
    write_if_changed(out, ('\n'.join(dict_entry(w) for w in sorted(words)) + '\n').encode())


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest='cmd', required=True)
    c = sub.add_parser('can-seeds')
    c.add_argument('dbc')
    c.add_argument('outdir')
    t = sub.add_parser('toml-dict')
    t.add_argument('out')
    t.add_argument('files', nargs='+')
    d = sub.add_parser('deep-keys')
    d.add_argument('outdir')
    d.add_argument('--parts', type=int, default=50000)
    args = ap.parse_args()
    if args.cmd == 'can-seeds':
        import cantools
        db = cantools.database.load_file(args.dbc, strict=True)
        os.makedirs(args.outdir, exist_ok=True)
        for name, seq in can_seeds(db).items():
            write_if_changed(os.path.join(args.outdir, name + '.bin'), bytes(seq.out))
        # the hexapod's in a folder of their own (fuzz_can_hexapod_seeds); read by the others too
        os.makedirs(os.path.join(args.outdir, 'hexapod'), exist_ok=True)
        for name, seq in hexapod_seeds(db).items():
            write_if_changed(os.path.join(args.outdir, 'hexapod', name + '.bin'), bytes(seq.out))
    elif args.cmd == 'toml-dict':
        toml_dict(args.out, args.files)
    else:
        deep_keys(args.outdir, args.parts)
    return 0


if __name__ == '__main__':
    sys.exit(main())
