"""legsim-bench: run scenes against hil_sim over CAN and check them against the bench's model.

    legsim-bench scenes                         the shipped scenes (scenes/)
    legsim-bench run SCENE... [--start-hil]     record + check in one process (bus here)
    legsim-bench record SCENE... [--start-hil]  only drive the bus and write recording.json
    legsim-bench check RECORDING...             reference model, checks, table, CSV/JSON/PNG
    legsim-bench check --log TRACE [--scene S]  a raw CAN trace decoded into a recording, checked
    legsim-bench demo [--build] [--all]         build, vcan0 (here or in the VM), hil_sim,
                                                record, check, then the hexapod's walk: the
                                                README's main command
    legsim-bench hexapod [--turn R] [--periods N]  the hexapod walking (in process), checked,
                                                with its plot and 3D animation (--slope-deg D:
                                                on a slope)
    legsim-bench workprecision|options|stress|mcu|robot-peers|hexapod-peers|block-peers   the benchmarks (their own options; results
                                                in out/bench-results/, --update-results for
                                                the committed bench/results/)

SCENE is a path or a shipped scene's name ("demo" = the scene marked demo = true).
Bus: --interface/--channel, else python-can's configuration (CAN_INTERFACE/CAN_CHANNEL,
can.rc, ~/.canrc), else socketcan on vcan0; `record` and `run` print which bus they opened.
Raw CAN trace: `record` and `run` log every session's frames beside its recording.json
(trace.log, candump format) or to --log PATH (.log candump, .asc, .blf by the suffix);
`check --log PATH` replays one into a recording and checks it (hil/trace.py).
Exit status: 0 every check passed, 1 a check failed or a run did not complete, 2 usage,
scene or setup error (no repository, no hil_sim, no bus).

Imports are lazy: `record` loads python-can, cantools and numpy (for can_link) and nothing
else, since it runs inside the QEMU VM where imports are slow.
"""
from __future__ import annotations

import argparse
import contextlib
import os
import shlex
import subprocess
import sys
import time
import tomllib
from pathlib import Path

from .scene import RootNotFound, SceneError, find_root, is_hexapod_scene, load_scene, shipped_scenes

EXIT_OK, EXIT_FAIL, EXIT_SETUP = 0, 1, 2
DEFAULT_TIMEOUT_S = 5.0   # the link's answer timeout (s) unless --timeout

# lazily registered benchmark commands: name -> (module, help)
BENCHMARKS = {
    "workprecision": ("legsim_bench.benchmarks.workprecision", "work-precision diagrams of the integrators"),
    "options": ("legsim_bench.benchmarks.options_cost", "cost of the solver options"),
    "stress": ("legsim_bench.benchmarks.stress", "stress runs"),
    "mcu": ("legsim_bench.benchmarks.mcu_cost", "Cortex-M images under QEMU: flash, RAM, instructions per step"),
    "robot-peers": ("legsim_bench.benchmarks.peers.robot_results",
                    "the two-leg robot in legsim, MuJoCo and Siconos: errors against the bench's reference and cost"),
    "hexapod-peers": ("legsim_bench.benchmarks.peers.hexapod_results",
                      "the hexapod in legsim and MuJoCo: errors against the bench's reference and cost"),
    "block-peers": ("legsim_bench.benchmarks.peers.block_peers",
                    "a block on an incline in legsim and MuJoCo: errors against the closed forms and cost"),
}


class SetupError(RuntimeError):
    pass


def _err(msg: str) -> None:
    print(f"legsim-bench: {msg}", file=sys.stderr)


def _root(args) -> Path:
    if getattr(args, "root", None):
        os.environ["LEGSIM_ROOT"] = str(Path(args.root).resolve())
    return find_root()


def _out_base(args, root: Path) -> Path:
    return Path(args.out) if getattr(args, "out", None) else root / "out" / "bench"


def _add_bus(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("bus (python-can conventions)")
    g.add_argument("--interface", "-i", help="python-can interface (default: CAN_INTERFACE, can.rc, "
                   "~/.canrc, else socketcan)")
    g.add_argument("--channel", "-c", help="channel (default: CAN_CHANNEL, can.rc, ~/.canrc, else vcan0)")
    g.add_argument("--timeout", type=float, default=DEFAULT_TIMEOUT_S,
                   help=f"seconds to wait for an answer (default {DEFAULT_TIMEOUT_S:g})")
    g.add_argument("--start-hil", action="store_true",
                   help="start hil_sim on the channel for the run (socketcan; binary from "
                   "$LEGSIM_HIL_SIM or build/host/hil_sim/hil_sim)")
    g.add_argument("--hil-sim", metavar="PATH", help="hil_sim binary for --start-hil")


def _progress_flag(args) -> bool | None:
    return False if getattr(args, "no_progress", False) else None


# ---- scenes ----------------------------------------------------------------------------------

def cmd_scenes(args) -> int:
    from .report.tables import scene_table

    root = _root(args)
    rows = []
    for p in shipped_scenes(root, hexapod=True):
        if is_hexapod_scene(p):  # legsim_cli's to run: the scenes' runner drives the planar frames
            try:
                desc = tomllib.loads(p.read_text()).get("description", "")
            except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as e:
                desc = str(e)
            rows.append((p.stem, "legsim_cli", desc))
            continue
        try:
            sc = load_scene(p, root)
            rows.append((sc.name, "demo" if sc.demo else "", sc.description))
        except SceneError as e:
            rows.append((p.stem, "BAD", str(e)))
    if not rows:
        print(f"no scenes in {root / 'scenes'}")
        return EXIT_SETUP
    print(scene_table(rows))
    if args.verbose:
        for p in shipped_scenes(root):
            sc = load_scene(p, root)
            print(f"\n{sc.name} ({p.relative_to(root)}): {sc.summary()}")
            for c in sc.commands:
                if c is not None:
                    print(f"  {c.describe()}")
            for k, v in sc.checks.tolerances().items():
                print(f"  check {k} <= {v:g}")
            for inj in sc.injections:
                print(f"  inject at {sc.t(inj.step):g} s: {inj.label} -> {inj.expect}")
    print(f"\n({len(rows)} scenes in {root / 'scenes'}; run one: legsim-bench run NAME; a hexapod's "
          "(legsim_cli): legsim_cli scenes/NAME.toml)")
    return EXIT_OK


# ---- record ------------------------------------------------------------------------------------

def _load_scenes(specs: list[str], root: Path):
    if specs == ["all"]:
        specs = [str(p) for p in shipped_scenes(root)]
    return [load_scene(s, root) for s in specs]


DEFAULT_TRACE = "trace.log"   # beside recording.json: candump's format, read by can-utils too


def _trace_paths(args, scenes, out_base: Path) -> dict[str, Path | None]:
    """Where each scene's raw CAN trace goes: --log PATH ({scene} in it for several scenes),
    else DIR/<scene>/trace.log; none with --no-log or for a scene that has no frames."""
    from .hil.trace import TraceError, trace_path

    spec = getattr(args, "log", None)
    if spec and len(scenes) > 1 and "{scene}" not in spec:
        raise SetupError(f"--log {spec}: several scenes need {{scene}} in the path "
                         "(e.g. --log 'traces/{scene}.blf')")
    out = {}
    for sc in scenes:
        if getattr(args, "no_log", False) or not sc.over_can:
            out[sc.name] = None
            continue
        p = Path(spec.replace("{scene}", sc.name)) if spec else out_base / sc.name / DEFAULT_TRACE
        try:
            out[sc.name] = trace_path(p)
        except TraceError as e:
            raise SetupError(str(e)) from None
    return out


@contextlib.contextmanager
def _sniffer(path, interface, channel):
    """--sniff PATH: the whole bus as a second listener sees it (every frame of every node, no
    filter, the interface's time stamps) logged by python-can's Notifier and Logger while the
    scenes run, like candump beside the bench (works in the VM, where can-utils may be absent)."""
    if not path:
        yield None
        return
    import can

    from .hil.can_link import bus_config
    from .hil.trace import TraceError, trace_path

    try:
        trace_path(path)
    except TraceError as e:
        raise SetupError(f"--sniff: {e}") from None
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    bus = can.Bus(**bus_config(interface, channel))
    logger = can.Logger(str(path))
    notifier = can.Notifier(bus, [logger], timeout=0.05)
    print(f"sniffer: every frame on the bus -> {path}", flush=True)
    try:
        yield logger
    finally:
        notifier.stop()
        logger.stop()
        bus.shutdown()


def _record_all(args, root: Path, scenes, out_base: Path) -> list[tuple[object, Path | None, dict | None]]:
    """Records every scene on one link (and one hil_sim with --start-hil)."""
    from .hil.runner import HilProcess, record
    from .recording import RecordingError, save_recording

    hil = None
    logs = [opt for opt, value in (("--log", getattr(args, "log", None)), ("--sniff", getattr(args, "sniff", None)))
            if value]
    if logs and getattr(args, "dry_run", False):
        raise SetupError(f"{' and '.join(logs)}: a --dry-run uses no bus (the reference model plays "
                         "hil_sim): there are no frames to log")
    if logs and not any(sc.over_can for sc in scenes):
        raise SetupError(f"{' and '.join(logs)}: no scene given runs over CAN (they run in legsim_cli): "
                         "there are no frames to log")
    if getattr(args, "dry_run", False):
        from .hil.reference_link import ReferenceLink

        out = []
        with ReferenceLink(root) as link:
            for sc in scenes:
                print(f"recording {sc.name} (dry run: the reference model plays hil_sim): {sc.summary()}",
                      flush=True)
                rec = record(sc, link, progress=_progress_flag(args))
                rec["dry_run"] = True
                path = save_recording(rec, out_base / sc.name / "recording.json")
                out.append((sc, path, rec))
        return out
    if not any(sc.over_can for sc in scenes):
        # every scene runs in legsim_cli (analyses, the robot): no bus and no hil_sim needed
        out = []
        for sc in scenes:
            print(f"recording {sc.name} (in legsim_cli, not over CAN): {sc.summary()}", flush=True)
            rec = record(sc, None, progress=_progress_flag(args))
            out.append((sc, save_recording(rec, out_base / sc.name / "recording.json"), rec))
        return out
    traces = _trace_paths(args, scenes, out_base)
    start_origin = {}
    if args.start_hil:
        from .hil.can_link import bus_config, bus_origin

        # hil_sim runs on SocketCAN: the channel from --channel or python-can's configuration
        cfg = bus_config(args.interface, args.channel)
        start_origin = bus_origin(args.interface, args.channel, cfg)
        if cfg["interface"] != "socketcan":
            raise SetupError(f"--start-hil runs hil_sim on socketcan, not on {cfg['interface']} "
                             f"(from {start_origin['interface']})")
        channel = str(cfg["channel"])
        try:
            hil = HilProcess(channel, args.hil_sim, log_path=out_base / "hil_sim.log").__enter__()
        except RecordingError as e:
            raise SetupError(str(e)) from None
        print(f"hil_sim started on {channel} (pid {hil.proc.pid}, log {hil.log_path})", flush=True)
    try:
        t0 = time.monotonic()
        # python-can and cantools: slow in the VM
        from .hil.can_link import HilLink, bus_config, bus_origin, describe_bus
        interface, channel = args.interface, args.channel
        given_by = {}
        if hil is not None:  # --start-hil: socketcan on hil_sim's channel unless named
            if interface is None:
                interface, given_by["interface"] = "socketcan", "--start-hil"
            if channel is None:
                channel = hil.channel
                given_by["channel"] = start_origin["channel"] if start_origin["channel"] != "default" \
                    else "--start-hil"
        try:
            link = HilLink(interface, channel, dbc=root / "can" / "legsim.dbc",
                           timeout=args.timeout, given_by=given_by)
        except Exception as e:  # noqa: BLE001 - python-can raises many kinds
            try:
                cfg = bus_config(interface, channel)
                which = " " + describe_bus(cfg, bus_origin(interface, channel, cfg, given_by))
            except Exception:  # noqa: BLE001 - the configuration itself is what failed
                which = ""
            raise SetupError(f"cannot open the CAN bus{which}: {type(e).__name__}: {e}") from None
        print(f"bus: {link.description}" + (f", open in {time.monotonic() - t0:.1f} s (import "
              "and connect)" if args.verbose else ""), flush=True)
        out = []
        with link, _sniffer(getattr(args, "sniff", None), interface, channel):
            for sc in scenes:
                if hil is not None and sc.over_can and hil.args != sc.hil_args():
                    # the scene's own model file: a hil_sim started with --model FILE
                    hil.stop()
                    hil = HilProcess.for_scene(sc, hil.channel, args.hil_sim, hil.log_path).__enter__()
                print(f"recording {sc.name}: {sc.summary()}", flush=True)
                with link.trace(traces[sc.name]) as trace:
                    rec = record(sc, link, progress=_progress_flag(args),
                                 log=lambda m: print(m, file=sys.stderr))
                if trace is not None:
                    rec["trace"] = str(traces[sc.name])
                    print(f"  trace: {trace.frames} frames -> {traces[sc.name]}", flush=True)
                path = save_recording(rec, out_base / sc.name / "recording.json")
                status = "complete" if rec["complete"] else "INCOMPLETE: " + "; ".join(
                    e["error"] for e in rec["errors"])
                nf = sum(len(s["faults"]) for s in rec["samples"])
                print(f"  {len(rec['samples'])} samples, {nf} faults, {rec['wall_time_s']:.1f} s, "
                      f"{status} -> {path}", flush=True)
                out.append((sc, path, rec))
        return out
    finally:
        if hil is not None:
            rc = hil.stop()
            if rc not in (0, None):
                print(f"hil_sim exited {rc}: {hil.log()[-2000:]}", file=sys.stderr)


def cmd_record(args) -> int:
    root = _root(args)
    scenes = _load_scenes(args.scenes, root)
    out = _record_all(args, root, scenes, _out_base(args, root))
    return EXIT_OK if all(r["complete"] for _, _, r in out) else EXIT_FAIL


# ---- check -------------------------------------------------------------------------------------

def _check_one(rec: dict, out_dir: Path, args, root: Path):
    from .verdict.checks import evaluate
    from .report.tables import format_table, write_outputs

    ev = evaluate(rec, root)
    files = write_outputs(ev, out_dir)
    out = rec.get("cli_output") or {}
    robot = None
    if rec.get("complete") and (out.get("contacts") or rec.get("legs", 1) > 1):
        from .report.tables import write_robot_tables

        robot = _robot_trajectories(rec, ev)   # the robot: its samples.csv, reference.csv
        files.update(write_robot_tables(robot[0], out_dir, reference=robot[1]))
    if not args.no_plots:
        from .report.plots import write_plots
        files.update(write_plots(ev, out_dir))
        if robot is not None:
            files.update(_robot_plots(*robot, out_dir))  # stick figures, time series, animation
    print(format_table(ev, details=not args.brief))
    print(f"  files: {out_dir}/ ({', '.join(sorted(p.name for p in files.values()))})")
    return ev, files


def _robot_trajectories(rec: dict, ev):
    """A robot run as report.robot_plots.RobotTrajectory, from legsim_cli's output or a CAN
    recording, and the verdict's reference (RobotModel, where it applies) as one, or None."""
    from .reference.model_file import read_model_file
    from .reference.robot import RobotModel
    from .report.robot_plots import RobotTrajectory

    scene = ev.scene
    box = tuple(read_model_file(scene.model_path)["box"]["size"])
    if rec.get("cli_output"):
        traj = RobotTrajectory.from_cli_json(rec["cli_output"], box, title=scene.name)
    else:
        import legsim

        traj = RobotTrajectory.from_recording(rec, legsim.Model.from_toml(scene.model_path), box,
                                              title=scene.name, ground=scene.ground)
    ref = ev.reference_run
    if ref is not None:
        from .verdict.analyses import robot_model

        ref = RobotTrajectory.from_reference(robot_model(scene), ref,
                                             title=f"{scene.name} (reference)")
    return traj, ref


def _robot_plots(traj, ref, out_dir: Path) -> dict[str, Path]:
    """A robot run's stick figures, time series (the reference overlaid) and GIF."""
    from .report.robot_plots import plot_snapshots, plot_time_series, write_robot_animation

    span = float(traj.t[-1] - traj.t[0])
    return {"snapshots": plot_snapshots(traj, out_dir / "robot_snapshots.png")[0],
            "time_series": plot_time_series(traj, out_dir / "robot_time_series.png", reference=ref),
            # about 2 s of animation whatever the scene's length
            "animation": write_robot_animation(traj, out_dir / "robot.gif", fps=20,
                                               speed=max(span / 2.0, 1e-3))}


def _recording_paths(specs: list[str]) -> list[Path]:
    paths = []
    for s in specs:
        p = Path(s)
        if p.is_dir():
            if (p / "recording.json").is_file():
                paths.append(p / "recording.json")
            else:
                paths += sorted(p.glob("*/recording.json"))
        else:
            paths.append(p)
    return paths


def _replay_traces(args, root: Path) -> list:
    """check --log: each trace decoded into a recording by replaying its scene on it."""
    from .hil.runner import replay_trace
    from .hil.trace import TraceError
    from .recording import RecordingError, load_recording, save_recording, scene_of

    evs = []
    for spec in args.log:
        trace = Path(spec)
        beside = trace.parent / "recording.json"
        try:
            live = load_recording(beside) if beside.is_file() else None
            if args.scene:
                scene = load_scene(args.scene, root)
            elif live is not None:
                try:
                    scene = scene_of(live, root)
                except SceneError as e:
                    raise SetupError(f"{trace}: the scene of {beside} cannot be run: {e}") from None
            else:
                raise SetupError(f"{trace}: which scene? give --scene (no recording.json beside the "
                                 "trace to take it from)")
            # the live session's answer timeout, unless --timeout says otherwise
            timeout = args.timeout if args.timeout is not None else \
                float((live or {}).get("timeout_s") or DEFAULT_TIMEOUT_S)
            rec = replay_trace(trace, scene, dbc=root / "can" / "legsim.dbc", timeout=timeout)
        except (TraceError, RecordingError) as e:
            raise SetupError(str(e)) from None
        out_dir = Path(args.out) / rec["scene_name"] if args.out else trace.parent / "replay"
        print(f"replayed {trace}: scene {scene.name}, {len(rec['samples'])} samples -> "
              f"{save_recording(rec, out_dir / 'recording.json')}")
        ev, _ = _check_one(rec, out_dir, args, root)
        evs.append(ev)
        print()
    return evs


def cmd_check(args) -> int:
    from .recording import RecordingError, load_recording, save_recording

    root = _root(args)
    paths = _recording_paths(args.recordings)
    if not paths and not getattr(args, "log", None):
        _err("no recording given (a recording.json, or a directory holding */recording.json, "
             "or --log TRACE)")
        return EXIT_SETUP
    evs = _replay_traces(args, root) if getattr(args, "log", None) else []
    for p in paths:
        try:
            rec = load_recording(p)
        except RecordingError as e:
            _err(str(e))
            return EXIT_SETUP
        out_dir = Path(args.out) / rec["scene_name"] if args.out else p.parent
        if args.out:
            save_recording(rec, out_dir / "recording.json")
        ev, _ = _check_one(rec, out_dir, args, root)
        evs.append(ev)
        print()
    return _final(evs)


def _final(evs) -> int:
    if len(evs) > 1:
        w = max(len(e.scene.name) for e in evs)
        print("summary")
        for e in evs:
            print(f"  {e.scene.name.ljust(w)}  {'PASS' if e.passed else 'FAIL'}  "
                  f"{len(e.results) - e.n_failed}/{len(e.results)} checks")
    ok = all(e.passed for e in evs)
    print("ALL PASS" if ok else f"FAILED: {', '.join(e.scene.name for e in evs if not e.passed)}")
    return EXIT_OK if ok else EXIT_FAIL


# ---- run = record + check ----------------------------------------------------------------------

def cmd_run(args) -> int:
    root = _root(args)
    scenes = _load_scenes(args.scenes, root)
    out_base = _out_base(args, root)
    recs = _record_all(args, root, scenes, out_base)
    print()
    evs = []
    for sc, path, rec in recs:
        ev, _ = _check_one(rec, path.parent, args, root)
        evs.append(ev)
        print()
    return _final(evs)


# ---- demo: everything from a clean checkout ------------------------------------------------------

def _sh(cmd: list[str], cwd: Path, env=None) -> int:
    print("+ " + " ".join(shlex.quote(c) for c in cmd), flush=True)
    return subprocess.call(cmd, cwd=cwd, env=env)


# The demo's default: the leg's demo scene and the robot's Fig. 7, both over CAN in one VM run.
DEMO_SCENES = ("demo", "robot_fig7")


def cmd_demo(args) -> int:
    from .hil.runner import hil_sim_path

    root = _root(args)
    if args.build:
        preset = args.preset
        if _sh(["cmake", "--preset", preset], root) != 0:
            raise SetupError(f"cmake --preset {preset} failed")
        if _sh(["cmake", "--build", "--preset", preset], root) != 0:
            raise SetupError(f"cmake --build --preset {preset} failed")
    hil = Path(args.hil_sim) if args.hil_sim else hil_sim_path(root)
    if not hil.is_file():
        raise SetupError(f"hil_sim not found at {hil}: run with --build (or build it: cmake --preset "
                         "host && cmake --build --preset host --target hil_sim)")
    scenes = ["all"] if args.all else (args.scenes or list(DEMO_SCENES))
    names = [s.name for s in _load_scenes(scenes, root)]
    out_base = _out_base(args, root)
    env = dict(os.environ)
    bench_dir = str(Path(__file__).resolve().parents[1])
    env["PYTHONPATH"] = bench_dir + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    env["LEGSIM_ROOT"] = str(root)
    env["LEGSIM_HIL_SIM"] = str(hil.resolve())
    env.setdefault("PYTHONUNBUFFERED", "1")
    rec_cmd = [sys.executable, "-m", "legsim_bench", "record", "--start-hil",
               "--interface", "socketcan", "--channel", "vcan0", "--out", str(out_base), *names]
    print(f"recording {', '.join(names)} against hil_sim on vcan0 (tools/with-vcan: here if this "
          "kernel has vcan, else in a QEMU VM)", flush=True)
    rc = _sh([str(root / "tools" / "with-vcan"), *rec_cmd], root, env)
    if rc in (124, 125):
        raise SetupError(f"tools/with-vcan failed ({rc}: {'timeout' if rc == 124 else 'no vcan0 / VM failed'})")
    paths = [out_base / n / "recording.json" for n in names]
    missing = [p for p in paths if not p.is_file()]
    if missing:
        raise SetupError(f"no recording from the bus run (exit {rc}): {', '.join(map(str, missing))}")
    print()
    args.recordings = [str(p) for p in paths]
    args.out = None
    rc = cmd_check(args)
    # the hexapod walking (in process; its CAN node has its own link: hil/hexapod_link.py)
    from .hexapod_walk import print_rows, run_walk

    print()
    walk_dir = out_base / "hexapod_walk"
    ok, rows, _ = run_walk(root, None if args.no_plots else walk_dir)
    print_rows("the hexapod walking two periods of its tripod gait (models/hexapod.toml, legsim.Hexapod.walk)", rows)
    rc = rc or (0 if ok else 1)
    print("\nplots and data:")
    for d in [*(out_base / n for n in names), walk_dir]:
        pngs = sorted([*d.glob("*.png"), *d.glob("*.gif")])
        print(f"  {d}/  " + (" ".join(p.name for p in pngs) if pngs else "(no plots)"))
    return rc


# ---- the hexapod ---------------------------------------------------------------------------------

def cmd_hexapod(args) -> int:
    from .hexapod_walk import run

    return run(args)


# ---- benchmarks (lazy) ---------------------------------------------------------------------------

def _benchmark(name: str):
    module, help_ = BENCHMARKS[name]

    def handler(args) -> int:
        import importlib

        try:
            mod = importlib.import_module(module)
        except ModuleNotFoundError as e:
            if e.name == module:
                _err(f"'{name}' is not available: module {module} is missing from this installation")
                return EXIT_SETUP
            raise
        p = argparse.ArgumentParser(prog=f"legsim-bench {name}", description=help_)
        mod.configure_parser(p)
        ns = p.parse_args(args.rest)
        return int(mod.run(ns) or 0)

    return handler


# ---- parser --------------------------------------------------------------------------------------

def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="legsim-bench", description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog="Scene schema and examples: bench/README.md")
    p.add_argument("--root", help="the legsim repository (default: $LEGSIM_ROOT, else found from "
                   "the package or the working directory)")
    p.add_argument("-v", "--verbose", action="store_true")
    sub = p.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    _add = sub.add_parser

    def add_parser(name, **kw):
        q = _add(name, **kw)
        if kw.get("add_help", True):
            q.add_argument("-v", "--verbose", action="store_true", default=argparse.SUPPRESS,
                           help="more output")
        return q

    sub.add_parser = add_parser

    s = sub.add_parser("scenes", help="list the shipped scenes")
    s.set_defaults(func=cmd_scenes)

    def out_opts(q, what):
        q.add_argument("--out", "-o", metavar="DIR", help=f"{what} (default: out/bench/ in the repository; "
                       "one subdirectory per scene)")

    def check_opts(q):
        q.add_argument("--no-plots", action="store_true", help="no PNG plots (no matplotlib import)")
        q.add_argument("--brief", action="store_true", help="details of the failing checks only")

    def log_opts(q):
        q.add_argument("--log", metavar="PATH", help="raw CAN trace of the session (.log candump, "
                       ".asc, .blf; {scene} in PATH for several scenes; default DIR/<scene>/trace.log)")
        q.add_argument("--no-log", action="store_true", help="no raw CAN trace")
        q.add_argument("--sniff", metavar="PATH", help="also log the whole bus as another listener "
                       "sees it (all nodes, no filter; .log, .asc, .blf), as candump would")

    s = sub.add_parser("run", help="run scenes on a live hil_sim: record + check")
    s.add_argument("scenes", nargs="+", metavar="SCENE", help="scene file or shipped name ('all', 'demo')")
    _add_bus(s)
    log_opts(s)
    out_opts(s, "output directory")
    check_opts(s)
    s.add_argument("--no-progress", action="store_true", help="no progress bar")
    s.add_argument("--dry-run", action="store_true",
                   help="no bus: the reference model plays hil_sim (tries the scene, the checks, "
                   "the report and the plots; says nothing about the core; no stroke stops)")
    s.set_defaults(func=cmd_run)

    s = sub.add_parser("record", help="only drive the bus and write the raw recording (for the VM)")
    s.add_argument("scenes", nargs="+", metavar="SCENE")
    _add_bus(s)
    log_opts(s)
    out_opts(s, "where recordings go: DIR/<scene>/recording.json")
    s.add_argument("--no-progress", action="store_true")
    s.set_defaults(func=cmd_record)

    s = sub.add_parser("check", help="check recordings: reference model, table, CSV/JSON/PNG")
    s.add_argument("recordings", nargs="*", metavar="RECORDING",
                   help="recording.json, or a directory with recording.json or */recording.json")
    s.add_argument("--log", action="append", default=[], metavar="TRACE",
                   help="a raw CAN trace (.log, .asc, .blf) of a session: replayed into a recording "
                   "and checked (outputs in TRACE's directory/replay/ unless --out); repeatable")
    s.add_argument("--scene", help="the scene of --log (default: the one in the recording.json beside it)")
    s.add_argument("--timeout", type=float, default=None, help="the session's answer timeout, s "
                   f"(default: the live one, from the recording.json beside the trace, else {DEFAULT_TIMEOUT_S:g})")
    s.add_argument("--out", "-o", metavar="DIR", help="write outputs to DIR/<scene>/ (default: beside "
                   "the recording)")
    check_opts(s)
    s.set_defaults(func=cmd_check)

    s = sub.add_parser("demo", help="build, bring up vcan0 (here or in the VM), start hil_sim, run "
                       "the demo scene, check it, print the table and where the plots are")
    s.add_argument("scenes", nargs="*", metavar="SCENE", help="scenes (default: the demo scene and robot_fig7)")
    s.add_argument("--all", action="store_true", help="every shipped scene (one VM boot)")
    s.add_argument("--build", action="store_true", help="configure and build first (cmake --preset, "
                   "cmake --build --preset)")
    s.add_argument("--preset", default="host", help="cmake preset for --build (default host)")
    s.add_argument("--hil-sim", metavar="PATH", help="hil_sim binary (default $LEGSIM_HIL_SIM or "
                   "build/host/hil_sim/hil_sim)")
    out_opts(s, "output directory")
    check_opts(s)
    s.set_defaults(func=cmd_demo)

    s = sub.add_parser("hexapod", help="the hexapod walking on its tripod gait (in process: no bus), checked, "
                       "with its plot and 3D animation")
    s.add_argument("--step-length", type=float, default=0.12, help="m a step (default 0.12)")
    s.add_argument("--turn", type=float, default=0.0, help="rad a step about the box's z (default 0)")
    s.add_argument("--periods", type=int, default=2, help="gait periods of 1.2 s (default 2)")
    s.add_argument("--slope-deg", type=float, default=0.0,
                   help="the ground's slope (deg, default 0: level); the box stays level")
    s.add_argument("--uphill-deg", type=float, default=0.0,
                   help="the direction the slope rises toward, about z from the walk's heading (deg; default 0: "
                        "up the fall line, 90: across it)")
    s.add_argument("--box-height", type=float, default=None,
                   help="m over the ground below the box (default 1.0; 15 deg across needs 0.85)")
    s.add_argument("--out", "-o", metavar="DIR", default=None,
                   help="output directory (default out/hexapod_walk under the repository)")
    s.add_argument("--no-plots", action="store_true", help="no GIF, no PNG")
    s.set_defaults(func=cmd_hexapod)

    for name, (module, help_) in BENCHMARKS.items():
        s = sub.add_parser(name, help=f"{help_} ({module}; its options: legsim-bench {name} --help)",
                           add_help=False)
        s.set_defaults(func=_benchmark(name), rest=[])
    return p


def main(argv: list[str] | None = None) -> int:
    p = build_parser()
    args, extra = p.parse_known_args(argv)
    if args.command in BENCHMARKS:
        args.rest = extra  # the benchmark's own options, parsed by its module
    elif extra:
        p.error(f"unrecognized arguments: {' '.join(extra)}")
    try:
        return args.func(args)
    except (SceneError, RootNotFound, SetupError) as e:
        _err(str(e))
        return EXIT_SETUP
    except KeyboardInterrupt:
        _err("interrupted")
        return 130


if __name__ == "__main__":
    sys.exit(main())
