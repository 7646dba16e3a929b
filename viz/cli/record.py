"""``mechviz record`` (record built-in demos headless) and ``mechviz play`` (:mod:`mechviz.viz.play`).

Registered on the ``mechviz`` parser by :mod:`mechviz.viz.cli`; viser and matplotlib are imported only
when a command runs.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

from ..interrupts import ctrl_c_within_a_second, exit_status
from ..play import add_command as _add_play
from ..printable import printable
from ..progress import ProgressBar
from ..progress import add_option as add_progress_option
from .errors import CliError, command, number, whole

ABOUT = """\
record a built-in demo headless: .viser, .html, .csv, .png, .json

Run a demo headless, faster than real time, and write DEMO.viser (scene recording), DEMO.html
(plays from file://), DEMO.csv (traces), DEMO.png (chart) and DEMO.json (manifest) into --out.
Files are replaced atomically.
"""


def add_commands(sub) -> None:
    p = command(sub, "record", ABOUT)
    p.add_argument("demo", nargs="?", help="demo name (see --list) or path of a demo .toml file")
    p.add_argument("--list", action="store_true", help="list the built-in demos and exit")
    p.add_argument("--json", action="store_true", help="with --list: print the demos as JSON")
    p.add_argument("--all", action="store_true", help="record every built-in demo")
    p.add_argument("--out", metavar="DIR", help="output folder (created if missing)")
    p.add_argument("--duration", type=number, metavar="S", help="seconds of playback")
    p.add_argument("--fps", type=whole, metavar="N", help="frames per second of playback")
    p.add_argument(
        "--method", metavar="NAME", help="integration method (mechviz simulate --list-methods)"
    )
    p.add_argument("--dt", type=number, metavar="DT", help="step size [s] for fixed-step methods")
    p.add_argument(
        "--plots",
        metavar="FORMATS",
        default="",
        help="the chart also as svg, pdf or svg,pdf (DEMO.svg, DEMO.pdf; PNG is always written)",
    )
    p.add_argument(
        "--theme",
        choices=("light", "dark"),
        default="light",
        help="page of the .html (default light); the scene's colours read on both",
    )
    from .video import add_record_options

    add_record_options(p)  # --video, --size, --camera, --title, --caption, --no-overlay, ...
    add_progress_option(p)
    p.set_defaults(func=run_record)

    _add_play(sub)


# =========================================================================== record
def _option_error(exc: ValueError, args) -> CliError:
    """The one line for an override the demo refused, naming the flag it came from."""
    field = getattr(exc, "field", None)
    if field in ("duration", "fps", "method", "dt") and getattr(args, field) is not None:
        return CliError(f"--{field}: {exc}")
    return CliError(str(exc))


def run_record(args: argparse.Namespace) -> int:
    from mechviz.dynamics.fileset import check_room

    with ctrl_c_within_a_second():  # a Ctrl-C that an import swallows (trimesh's) still counts
        from .. import record as rec
        from ..record import charts

    if args.json and not args.list:
        raise CliError("--json: only with --list (a recording's figures are in DEMO.json)")
    if args.list:
        demos = rec.list_demos()
        if args.json:
            print(json.dumps({"demos": [_demo_entry(d) for d in demos]}, indent=2))
            return 0
        width = max(len(d.name) for d in demos)
        for d in demos:
            print(f"{d.name:<{width}}  {d.description}")
        return 0
    if args.all == bool(args.demo):
        raise CliError("give one DEMO or --all (mechviz record --list shows the demos)")
    if not args.out:
        raise CliError("--out DIR is required")
    names = rec.demo_names() if args.all else [args.demo]
    demos = []
    for name in names:
        try:
            demo = rec.load_demo(name)
        except ValueError as exc:
            raise CliError(str(exc)) from None
        try:
            demos.append(
                demo.with_overrides(
                    duration=args.duration, fps=args.fps, method=args.method, dt=args.dt
                )
            )
        except ValueError as exc:
            raise _option_error(exc, args) from None
    try:
        plots = charts.check_formats(args.plots)
    except ValueError as exc:
        raise CliError(f"--plots: {exc}") from None
    out = Path(args.out)
    try:
        if out.exists() and not out.is_dir():
            raise CliError(f"--out: {printable(str(out))} exists and is not a folder")
        for demo in demos:  # the deepest path the recording makes must be possible
            suffixes = (*rec.SUFFIXES, *(f".{f}" for f in plots))
            check_room(out, demo.name, [f"{demo.name}{s}" for s in suffixes])
        _check_writable(out)
    except OSError as exc:  # a name too long for the file system, a folder we may not read
        raise CliError(f"--out: {exc.strerror or exc}") from None
    from .video import check_record_options, film_record

    check_record_options(args, demos)  # the video's options, before anything is recorded
    for demo in demos:
        try:
            res = rec.record(
                demo,
                out,
                progress=ProgressBar(demo.name),
                theme=args.theme,
                on_wait=_say_waiting,
                interruptible=ctrl_c_within_a_second,
                plots=plots,
            )
        except rec.RecordingFailed as exc:
            if sys.stderr.isatty():
                sys.stderr.write("\n")
            print(f"mechviz: error: {exc}", file=sys.stderr)
            if exc.interrupted:  # 130 for Ctrl-C, 128 + the signal for SIGTERM and SIGHUP
                cause = exc.__cause__
                return exit_status(cause) if isinstance(cause, KeyboardInterrupt) else 130
            return 2 if exc.bad_input else 1
        _report(res)
        if args.video and (status := film_record(res, args)):
            return status
    return 0


def _demo_entry(d) -> dict:
    """One demo as ``record --list --json`` gives it: numbers as numbers."""
    return {
        "name": d.name,
        "title": d.title,
        "description": d.description,
        "exhibit": d.exhibit,
        "motion": d.motion,
        "method": d.method,
        "dt": d.dt,
        "rtol": d.rtol,
        "duration": d.duration,
        "fps": d.fps,
        "frames": d.frames,
        "speed": d.speed,
    }


def _check_writable(out: Path) -> None:
    """``CliError`` unless ``out`` is a folder, or can be made in one, that this user may write."""
    existing = out.absolute()
    while not existing.exists():
        existing = existing.parent
    if not existing.is_dir():
        raise CliError(f"--out: {printable(str(existing))} is not a folder")
    if not os.access(existing, os.W_OK | os.X_OK):
        raise CliError(f"--out: {printable(str(existing))}: permission denied")


def _say_waiting(message: str) -> None:
    if sys.stderr.isatty():
        sys.stderr.write("\n")
    print(f"mechviz: {message}", file=sys.stderr, flush=True)


def _report(res) -> None:
    d, man = res.demo, res.manifest
    size = res.paths[".viser"].stat().st_size
    print(
        f"{d.name}: {res.frames} frames ({d.duration:g} s at {d.fps} fps, "
        f"{man['simulated_time']:.4g} s simulated) in {res.wall_seconds:.2f} s "
        f"({d.duration / res.wall_seconds:.2g}x real time); {d.name}.viser {size / 1e6:.3f} MB"
    )
    print(f"  -> {res.paths['.viser'].parent}/{d.name}.{{viser,html,csv,png,json}}")
    for f in man["figures"]:
        if f["measured"] is None:
            if f.get("not_resolved"):
                print(f"  {f['name']}: not resolved ({f['not_resolved']})")
            continue
        pred = "" if f["predicted"] is None else f", predicted {f['predicted']:.6g}"
        print(f"  {f['name']}: {f['measured']:.6g} {f['unit']}{pred}".rstrip())
