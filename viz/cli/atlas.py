"""``mechviz atlas``: maps of where methods fail and where the hoop turns chaotic, on Dask.

``mechviz atlas stability|chaos|accuracy`` computes the map chunk by chunk on a Dask cluster (by
default a ``distributed.LocalCluster`` on this machine's cores; ``--scheduler ADDRESS`` for an
existing one), writing each chunk into ``OUT/atlas.zarr`` (an xarray Dataset) as it finishes,
and when complete draws ``OUT/KIND.png`` and ``OUT/KIND.svg``. Ctrl-C cancels the cluster's work
and keeps the chunks already written; ``--resume`` continues the same run (the same flags: the
store's run key must match). ``--bench OUT`` measures the atlas's costs instead and writes
``OUT/atlas-bench.json``. Needs the ``atlas`` extra (``pip install 'mechviz-lab[atlas]'``).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
from dataclasses import fields
from pathlib import Path

from mechviz.dynamics.atlas.grid import SYSTEM_NAMES
from mechviz.dynamics.systems import SYSTEMS

from .errors import command


def _axis_text(text: str) -> tuple[float, float, int, str]:
    """argparse type for ``START:STOP:N`` or ``START:STOP:N:log``."""
    parts = text.split(":")
    if len(parts) not in (3, 4) or (len(parts) == 4 and parts[3] not in ("log", "linear")):
        raise argparse.ArgumentTypeError(f"expected START:STOP:N or START:STOP:N:log, got {text!r}")
    try:
        start, stop, n = float(parts[0]), float(parts[1]), int(parts[2])
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected numbers in START:STOP:N, got {text!r}"
        ) from None
    if not (math.isfinite(start) and math.isfinite(stop)) or n < 1:
        raise argparse.ArgumentTypeError(f"needs finite ends and N >= 1, got {text!r}")
    if n > 1_000_000:
        raise argparse.ArgumentTypeError(f"N is at most 1000000, got {n}")
    return start, stop, n, parts[3] if len(parts) == 4 else "linear"


def _chunk_text(text: str) -> tuple[int, int]:
    try:
        rows, cols = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected ROWSxCOLUMNS, got {text!r}") from None
    if rows < 1 or cols < 1:
        raise argparse.ArgumentTypeError(f"rows and columns must be at least 1, got {text!r}")
    return rows, cols


def _param_text(text: str) -> tuple[str, float]:
    name, sep, value = text.partition("=")
    try:
        return name.strip(), float(value) if sep else float("nan")
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected NAME=NUMBER, got {text!r}") from None


_FIELDS = (
    "methods",
    "dt",
    "rtol",
    "amplitude",
    "theta1",
    "theta2",
    "omega1",
    "omega2",
    "section",
    "periods",
    "threshold",
    "duration",
    "step",
    "renormalise",
    "separation",
    "chunk",
    "system",
    "axes",
    "y axis",
)


def _as_flag(message: str) -> str:
    """A message of :class:`AtlasSpec` naming a field, worded with the field's flag."""
    if message.startswith("params:"):
        return "--param" + message[len("params") :]
    for name in _FIELDS:
        if message.startswith(name) and not message.startswith("--"):
            flag = {"axes": "the axes", "y axis": "--dt/--rtol"}.get(name, f"--{name}")
            return flag + message[len(name) :]
    return message


def build_spec(args: argparse.Namespace):
    """The :class:`mechviz.dynamics.atlas.AtlasSpec` the flags describe (``ValueError`` naming the flag)."""
    from mechviz.dynamics import SYSTEMS, Hoop, methods_for
    from mechviz.dynamics.atlas.grid import AtlasSpec, Axis
    from mechviz.dynamics.atlas.theory import make_system, start_states

    system_name = Hoop.name if args.kind == "chaos" else args.system
    params = dict(args.param or ())
    for name, value in params.items():
        if not math.isfinite(value):
            raise ValueError(f"--param {name}: not a finite number")
    try:
        system = make_system(system_name, params)
    except ValueError as exc:
        raise ValueError(f"--param: {exc}") from None
    if args.methods:
        methods = tuple(m.strip() for m in args.methods.split(",") if m.strip())
    elif args.kind == "chaos":
        methods = ("rk4",)
    else:
        fixed = [m.name for m in methods_for(system) if m.backend == "numba" and not m.adaptive]
        methods = tuple(fixed)
    lo, hi = SYSTEMS[system_name].amplitude[2]
    amp = Axis("amplitude", *(args.amplitude or (lo, hi, 48, "linear")))
    extra = {}
    from mechviz.dynamics.atlas.grid import CHAOS_SECTIONS

    section = args.section or "rest"
    if args.section and args.kind != "chaos":
        raise ValueError("section: the chaos map's option (stability and accuracy have none)")
    y_name, x_name = CHAOS_SECTIONS[section]
    for name in ("theta1", "theta2", "omega1", "omega2"):
        if not getattr(args, name):
            continue
        if args.kind != "chaos":
            raise ValueError(f"{name}: an axis of the chaos map only")
        if name not in (y_name, x_name):
            raise ValueError(f"{name}: the section {section} has the axes {x_name} and {y_name}")
    if args.kind == "chaos":
        from mechviz.dynamics.hoop import normal_modes

        # rates up to 1.5 times the top of the mode-1 pendulum's separatrix, 2 omega_1
        top = 3.0 * float(normal_modes(system.params)[0][0])
        defaults = {
            "theta": (-math.pi, math.pi, 128, "linear"),
            "omega": (-top, top, 128, "linear"),
        }
        y, x = (
            Axis(name, *(getattr(args, name) or defaults[name[:5]]))
            for name in CHAOS_SECTIONS[section]
        )
        extra = {
            "duration": args.duration or 60.0,
            "step": args.step,
            "renormalise": args.renormalise,
            "separation": args.separation,
        }
    else:
        omega = system.fastest_frequency(start_states(system, [hi])[0])
        x = amp
        if args.kind == "stability":
            y = Axis("dt", *(args.dt or (0.05 / omega, 3.5 / omega, 48, "linear")))
            extra = {"periods": args.periods, "threshold": args.threshold}
        elif args.rtol:
            y = Axis("rtol", *args.rtol)
            extra = {"duration": args.duration or 10.0}
        else:
            y = Axis("dt", *(args.dt or (0.002 / omega, 0.5 / omega, 32, "log")))
            extra = {"duration": args.duration or 10.0}
    return AtlasSpec(
        args.kind,
        system_name,
        methods,
        y,
        x,
        params=tuple(params.items()),
        chunk=args.chunk or (0, 0),
        **extra,
    )


def _run(args: argparse.Namespace) -> int:
    from .errors import CliError

    try:
        import dask  # noqa: F401
        import distributed  # noqa: F401
        import xarray  # noqa: F401
        import zarr  # noqa: F401
    except ImportError as exc:
        raise CliError(
            f"mechviz atlas needs the atlas extra (pip install 'mechviz-lab[atlas]'): {exc}"
        ) from None
    if args.workers is not None and args.workers < 1:
        raise CliError(f"--workers must be at least 1, got {args.workers}")
    if args.bench:
        from mechviz.dynamics.atlas.bench import format_summary, run_bench

        result = run_bench(Path(args.bench), quick=args.quick, progress=not args.no_progress)
        print(format_summary(result))
        return 0
    if args.kind is None:
        raise CliError("give the map to draw: stability, chaos or accuracy (or --bench OUT)")
    if not args.out:
        raise CliError("--out: give the folder to write the atlas into")
    try:
        spec = build_spec(args)
    except ValueError as exc:
        raise CliError(_as_flag(str(exc))) from None
    return run_and_draw(spec, Path(args.out), args)


def run_and_draw(spec, out: Path, args: argparse.Namespace) -> int:
    from mechviz.dynamics.atlas import store
    from mechviz.dynamics.atlas.driver import AtlasInterrupted, prepare, run_atlas
    from mechviz.dynamics.atlas.maps import save_maps

    from .errors import CliError

    path = out / "atlas.zarr"
    if out.exists() and not out.is_dir():
        raise CliError(f"--out: {out} is not a folder")
    if args.resume and not path.exists() and not store.has_partial(path):
        raise CliError(f"--resume: no atlas at {path}")
    if not args.resume and not args.fresh and path.exists():
        raise CliError(
            f"--out: {path} exists; pass --resume to continue it, --fresh to start it again, "
            "or another --out"
        )
    try:
        out.mkdir(parents=True, exist_ok=True)
        with store.locked(out):
            # before anything is printed: a store this run may not use is one line
            prepared = prepare(spec, path, resume=args.resume, fresh=args.fresh)
            cells = math.prod(spec.shape)
            print(
                f"mechviz atlas: {spec.kind} of the {spec.system}, {cells} cells in "
                f"{len(spec.chunks())} chunks of {spec.chunk[0]}x{spec.chunk[1]}; run key "
                f"{spec.run_key()}",
                file=sys.stderr,
            )
            if prepared.restarted:
                print(
                    f"mechviz atlas: {path} was never completed (a run ended while creating it); "
                    "started afresh",
                    file=sys.stderr,
                )
            if prepared.damaged:
                found = store.Resumed(prepared.done, prepared.damaged).describe_damage()
                print(
                    f"mechviz atlas: {len(prepared.damaged)} damaged chunks (method/row/column) "
                    f"computed again: {found}",
                    file=sys.stderr,
                )
            report = run_atlas(
                spec,
                path,
                scheduler=args.scheduler,
                workers=args.workers,
                progress=not args.no_progress,
                prepared=prepared,
            )
            ds = store.load(path)
            maps = save_maps(ds, out, spec.kind)
    except store.StoreError as exc:
        raise CliError(str(exc)) from None
    except AtlasInterrupted as exc:
        r = exc.report
        kept = len(r.computed) + len(r.skipped)
        print(
            f"mechviz atlas: interrupted; {kept} of {r.total} chunks kept in {path}; "
            "continue with the same flags and --resume",
            file=sys.stderr,
        )
        if getattr(args, "whole_process", False):
            # Everything is written and closed, the workers and their folder gone: the
            # interpreter's teardown of its modules (numba, Dask, xarray) would add a second or
            # more on a busy machine before the process ends.
            sys.stdout.flush()
            sys.stderr.flush()
            os._exit(128 + exc.signum)
        return 128 + exc.signum
    except OSError as exc:  # a full disk, a folder that cannot be made
        where = exc.filename or out
        raise CliError(f"--out {out}: {exc.strerror or exc} ({where})") from None
    print(
        f"mechviz atlas: {len(report.computed)} chunks computed ({len(report.skipped)} kept "
        f"from before) in {report.wall_seconds:.1f} s on {report.workers} workers; "
        f"{path}; {', '.join(str(p) for p in maps)}"
    )
    return 0


ABOUT = """\
maps of stability, chaos and accuracy computed on a Dask cluster (Zarr + PNG/SVG)

Compute the map chunk by chunk on a Dask cluster (this machine's cores, or --scheduler ADDRESS),
writing each chunk into OUT/atlas.zarr as it finishes and, when complete, OUT/KIND.png and
OUT/KIND.svg. Ctrl-C keeps the chunks written; --resume continues the same run.
"""


def add_commands(sub) -> None:
    p = command(sub, "atlas", ABOUT)
    p.add_argument(
        "kind",
        nargs="?",
        choices=("stability", "chaos", "accuracy"),
        help="the map: stability (bounded or not over step x amplitude), chaos (the "
        "hoop's start plane by Lyapunov exponent), accuracy (error over step x amplitude)",
    )
    p.add_argument("--out", help="folder for atlas.zarr and the maps (KIND.png, KIND.svg)")
    again = p.add_mutually_exclusive_group()
    again.add_argument(
        "--resume",
        action="store_true",
        help="continue the run in --out (same flags): every chunk kept is verified, damaged "
        "ones are computed again",
    )
    again.add_argument(
        "--fresh",
        action="store_true",
        help="replace the atlas in --out by a new run (as after a damaged store)",
    )
    p.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="an existing Dask scheduler (tcp://host:8786); default a LocalCluster",
    )
    p.add_argument(
        "--workers", type=int, help="LocalCluster worker processes (default: one per core)"
    )
    p.add_argument(
        "--system",
        choices=SYSTEM_NAMES,
        default=SYSTEM_NAMES[0],
        help=f"stability and accuracy: the system (chaos: the {SYSTEM_NAMES[0]})",
    )
    p.add_argument(
        "--param",
        type=_param_text,
        action="append",
        metavar="NAME=VALUE",
        help="a system parameter by its field name ("
        + "; ".join(
            f"{n}: {', '.join(f.name for f in fields(SYSTEMS[n].Params))}" for n in SYSTEM_NAMES
        )
        + "); repeat for more",
    )
    p.add_argument(
        "--methods", help="comma-separated methods (default: every fixed-step method; chaos: rk4)"
    )
    p.add_argument("--dt", type=_axis_text, metavar="START:STOP:N[:log]", help="step axis [s]")
    p.add_argument(
        "--rtol",
        type=_axis_text,
        metavar="START:STOP:N[:log]",
        help="accuracy: tolerance axis for adaptive methods",
    )
    p.add_argument(
        "--amplitude",
        type=_axis_text,
        metavar="START:STOP:N[:log]",
        help="amplitude axis ("
        + "; ".join(f"{n}: {SYSTEMS[n].amplitude[1]}" for n in SYSTEM_NAMES)
        + ")",
    )
    p.add_argument(
        "--theta1",
        type=_axis_text,
        metavar="START:STOP:N",
        help="chaos: hoop angle axis [rad] (write --theta1=-3.14:3.14:64 for a negative start)",
    )
    p.add_argument(
        "--theta2",
        type=_axis_text,
        metavar="START:STOP:N",
        help="chaos: bead angle axis [rad] (as --theta2=-3.14:3.14:64)",
    )
    for name, what, angle in (
        ("omega1", "the hoop's", "theta1"),
        ("omega2", "the bead's", "theta2"),
    ):
        p.add_argument(
            f"--{name}",
            type=_axis_text,
            metavar="START:STOP:N",
            help=f"chaos: {what} rate axis [rad/s] of the --section {angle} "
            f"(as --{name}=-6:6:64; default +-3 omega_1)",
        )
    p.add_argument(
        "--section",
        choices=("rest", "theta1", "theta2"),
        help="chaos: the starts mapped; rest: theta1 x theta2, both rates zero (default); "
        "theta1: theta1 x theta1', with theta2 = theta2' = 0 (the bead straight below the "
        "hoop's centre, not turning); theta2: theta2 x theta2', the hoop hanging at rest",
    )
    p.add_argument(
        "--periods",
        type=float,
        default=50.0,
        help="stability: run length in periods of the fastest mode (default 50)",
    )
    p.add_argument(
        "--threshold",
        type=float,
        default=1.0,
        help="stability: unbounded once the relative energy error exceeds this (default 1)",
    )
    p.add_argument(
        "--duration", type=float, help="chaos and accuracy: run length [s] (default 60 and 10)"
    )
    p.add_argument(
        "--step", type=float, default=0.01, help="chaos: the method's step [s] (default 0.01)"
    )
    p.add_argument(
        "--renormalise",
        type=float,
        default=1.0,
        help="chaos: seconds between renormalisations of the twin (default 1)",
    )
    p.add_argument(
        "--separation",
        type=float,
        default=1e-9,
        help="chaos: the twin's distance in state space (default 1e-9)",
    )
    p.add_argument(
        "--chunk",
        type=_chunk_text,
        metavar="ROWSxCOLUMNS",
        help="cells per chunk (default: about a second of work)",
    )
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument(
        "--bench",
        metavar="OUT",
        help="measure cost per cell, parallel efficiency and scheduling overhead; "
        "write OUT/atlas-bench.json",
    )
    p.add_argument("--quick", action="store_true", help="--bench: smaller grids")
    p.set_defaults(func=_run)
