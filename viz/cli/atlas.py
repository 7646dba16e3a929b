"""``mechviz atlas``: maps of where methods fail and where the hoop turns chaotic, on Dask.

``mechviz atlas stability|chaos|accuracy`` computes the map chunk by chunk on a Dask cluster (by
default a ``distributed.LocalCluster`` on this machine's cores; ``--scheduler ADDRESS`` for an
existing one), writing each chunk into ``OUT/atlas.zarr`` (an xarray Dataset) as it finishes,
and when complete draws ``OUT/KIND.png`` and ``OUT/KIND.svg``. Ctrl-C (SIGTERM, SIGHUP) cancels
the cluster's work and keeps the chunks already written; ``--resume`` continues the same run (the
same flags: the store's run key must match), verifying every chunk it keeps; ``--fresh`` starts
it again. Everything is checked before any work, each refusal one line naming the flag: the cost
(``--max-steps``), the memory the grid needs, the scheduler's address, and flags the map does not
take. ``--bench OUT`` measures the atlas's costs instead and writes
``OUT/atlas-bench.json``. Needs the ``atlas`` extra (``pip install 'mechviz-lab[atlas]'``).
"""

from __future__ import annotations

import argparse
import math
import os
import re
import sys
from dataclasses import fields
from pathlib import Path

from mechviz.dynamics.atlas.grid import SYSTEM_NAMES
from mechviz.dynamics.params import parse_number
from mechviz.dynamics.systems import SYSTEMS

from .errors import command, number

#: Default of ``--max-steps``: the most compiled member-steps an atlas may take, some 500 times
#: the default chaos map (128 x 128 starts and their twins, 60 s at 0.01 s) and above the
#: 1024 x 1024 one a cluster draws (1.3e10): about 3 core-hours of RK4.
DEFAULT_MAX_STEPS = 1e11
#: The largest end an axis may have: far beyond any motion these systems make sense of, and far
#: from the largest double, so the spacing and the states stay representable.
MAX_AXIS_END = 1e6
#: Memory [bytes] one LocalCluster worker needs (an interpreter with numpy, numba's compiled
#: methods and Dask): what ``--workers`` is capped by, beside the cores.
WORKER_BYTES = 600 * 2**20
#: Bytes per cell and variable the command holds at once (the empty dataset written, the map
#: read back, the picture drawn from it): the grid is refused past half the available memory.
COPIES_IN_MEMORY = 4


def _count(text: str) -> int:
    """A whole number typed in ASCII digits (no sign, no underscores: the one rule for typed
    numbers, :func:`mechviz.dynamics.params.parse_number`, for counts)."""
    t = text.strip()
    if not re.fullmatch(r"[0-9]+", t):
        raise ValueError(text)
    return int(t)


def _axis_text(text: str) -> tuple[float, float, int, str]:
    """argparse type for ``START:STOP:N`` or ``START:STOP:N:log``."""
    parts = text.split(":")
    if len(parts) not in (3, 4) or (len(parts) == 4 and parts[3] not in ("log", "linear")):
        raise argparse.ArgumentTypeError(f"expected START:STOP:N or START:STOP:N:log, got {text!r}")
    try:
        start, stop = (parse_number("value", v) for v in parts[:2])
        n = _count(parts[2])
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected numbers in START:STOP:N, got {text!r}"
        ) from None
    if n < 1:
        raise argparse.ArgumentTypeError(f"needs N >= 1, got {text!r}")
    if n > 1_000_000:
        raise argparse.ArgumentTypeError(f"N is at most 1000000, got {n}")
    if not math.isfinite(stop - start) or max(abs(start), abs(stop)) > MAX_AXIS_END:
        raise argparse.ArgumentTypeError(
            f"the ends must lie within +-{MAX_AXIS_END:g}, got {text!r}"
        )
    return start, stop, n, parts[3] if len(parts) == 4 else "linear"


def _chunk_text(text: str) -> tuple[int, int]:
    try:
        rows, cols = (_count(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected ROWSxCOLUMNS, got {text!r}") from None
    if rows < 1 or cols < 1:
        raise argparse.ArgumentTypeError(f"rows and columns must be at least 1, got {text!r}")
    return rows, cols


def _param_text(text: str) -> tuple[str, float]:
    name, sep, value = text.partition("=")
    try:
        if not sep:
            raise ValueError(text)
        return name.strip(), parse_number("value", value)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected NAME=NUMBER, got {text!r}") from None


def _workers_text(text: str) -> int:
    try:
        return _count(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None


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
    "workers",
    "scheduler",
    "max-steps",
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


#: The flags each map takes (beyond --out, --resume, --fresh, --scheduler, --workers, --chunk,
#: --max-steps, --param, --methods and the progress bar's): any other given is refused.
APPLIES = {
    "system": ("stability", "accuracy"),
    "dt": ("stability", "accuracy"),
    "rtol": ("accuracy",),
    "amplitude": ("stability", "accuracy"),
    "periods": ("stability",),
    "threshold": ("stability",),
    "duration": ("chaos", "accuracy"),
    "step": ("chaos",),
    "renormalise": ("chaos",),
    "separation": ("chaos",),
    "section": ("chaos",),
    "theta1": ("chaos",),
    "theta2": ("chaos",),
    "omega1": ("chaos",),
    "omega2": ("chaos",),
}


def check_flags_apply(args: argparse.Namespace) -> None:
    """Refuse (``ValueError`` naming it) a flag given that the map kind does not use."""
    for name, kinds in APPLIES.items():
        if getattr(args, name, None) is None or args.kind in kinds:
            continue
        if name == "system" and args.kind == "chaos":
            from mechviz.dynamics import Hoop

            if args.system == Hoop.name:
                continue
            raise ValueError(f"system {args.system}: the chaos map is of the {Hoop.name} only")
        which = " and ".join(kinds)
        raise ValueError(f"{name}: the {which} map's flag; the {args.kind} map takes none")
    if args.kind == "accuracy" and args.dt is not None and args.rtol is not None:
        raise ValueError("rtol: give --dt (fixed-step methods) or --rtol (adaptive), not both")


def build_spec(args: argparse.Namespace):
    """The :class:`mechviz.dynamics.atlas.AtlasSpec` the flags describe (``ValueError`` naming the flag)."""
    from mechviz.dynamics import SYSTEMS, Hoop, methods_for
    from mechviz.dynamics.atlas.grid import AtlasSpec, Axis
    from mechviz.dynamics.atlas.theory import make_system, start_states

    check_flags_apply(args)
    system_name = Hoop.name if args.kind == "chaos" else (args.system or SYSTEM_NAMES[0])
    params = dict(args.param or ())
    for name, value in params.items():
        if not math.isfinite(value):
            raise ValueError(f"--param {name}: not a finite number")
    try:
        system = make_system(system_name, params)
    except ValueError as exc:
        raise ValueError(f"--param: {exc}") from None
    if args.methods is not None:
        methods = tuple(m.strip() for m in args.methods.split(",") if m.strip())
        if not methods:
            raise ValueError(f"methods: give at least one method, got {args.methods!r}")
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
    y_name, x_name = CHAOS_SECTIONS[section]
    for name in ("theta1", "theta2", "omega1", "omega2"):
        if getattr(args, name) and name not in (y_name, x_name):
            raise ValueError(f"{name}: the section {section} has the axes {x_name} and {y_name}")
    given = {
        k: getattr(args, k)
        for k in ("periods", "threshold", "duration", "step", "renormalise", "separation")
        if getattr(args, k) is not None
    }
    if args.kind == "chaos":
        from mechviz.dynamics.hoop import normal_modes

        # rates up to 1.5 times the top of the mode-1 pendulum's separatrix, 2 omega_1
        top = 3.0 * float(normal_modes(system.params)[0][0])
        if not math.isfinite(top):
            raise ValueError("--param: the hoop's normal modes are not representable")
        defaults = {
            "theta": (-math.pi, math.pi, 128, "linear"),
            "omega": (-top, top, 128, "linear"),
        }
        y, x = (
            Axis(name, *(getattr(args, name) or defaults[name[:5]]))
            for name in CHAOS_SECTIONS[section]
        )
        extra = {"duration": 60.0} | given
    else:
        omega = system.fastest_frequency(start_states(system, [hi])[0])
        if not (math.isfinite(omega) and omega > 0):
            raise ValueError("--param: the motion's fastest frequency is not representable")
        x = amp
        if args.kind == "stability":
            y = Axis("dt", *(args.dt or (0.05 / omega, 3.5 / omega, 48, "linear")))
            extra = given
        elif args.rtol:
            y = Axis("rtol", *args.rtol)
            extra = {"duration": 10.0} | given
        else:
            y = Axis("dt", *(args.dt or (0.002 / omega, 0.5 / omega, 32, "log")))
            extra = {"duration": 10.0} | given
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


def _axis_flags(spec) -> str:
    return f"--{spec.y.name} and --{spec.x.name}"


def check_memory(spec, available: int | None = None) -> None:
    """Refuse (``ValueError``) a grid whose cells would not fit in half the available memory."""
    import numpy as np

    from mechviz.dynamics.atlas.kernels import VARIABLES

    cells = math.prod(spec.shape)
    per_cell = sum(np.dtype(d).itemsize for d, _fill in VARIABLES[spec.kind].values())
    need = cells * per_cell * COPIES_IN_MEMORY
    free = available_memory() if available is None else available
    if need > free / 2:
        raise ValueError(
            f"{_axis_flags(spec)}: {spec.y.n} x {spec.x.n} cells x {len(spec.methods)} methods "
            f"need about {need / 2**30:.3g} GiB in memory, more than half the "
            f"{free / 2**30:.3g} GiB available"
        )


def available_memory() -> int:
    try:
        import psutil

        return int(psutil.virtual_memory().available)
    except Exception:  # no psutil: the physical memory
        return int(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))


def check_cost(spec, limit: float) -> None:
    """Refuse (``ValueError``) an atlas estimated above ``limit`` steps (``--max-steps``), naming
    the flags that make its cost."""
    from mechviz.dynamics.atlas.grid import estimated_steps, fastest_period_of

    steps = estimated_steps(spec)
    if steps <= limit:
        return
    period = fastest_period_of(spec)
    finest = min(spec.y.start, spec.y.stop)
    if spec.kind == "chaos":
        what = f"--duration {spec.duration:g} / --step {spec.step:g}, the start and its twin"
    elif spec.kind == "stability":
        what = f"--periods {spec.periods:g} at --dt down to {finest:.3g}"
    else:
        what = f"--duration {spec.duration:g} at --{spec.y.name} down to {finest:.3g}"
    cells = math.prod(spec.shape)
    raise ValueError(
        f"max-steps: about {steps:.2g} steps for {cells} cells ({what}; the motion's shortest "
        f"period is {period:.3g} s), above the limit of {limit:.3g} (--max-steps raises it)"
    )


def check_theory(spec) -> None:
    """What the store and the maps draw from theory must be representable for these
    parameters (``ValueError`` naming ``--param``)."""
    import numpy as np

    from mechviz.dynamics.atlas.grid import fastest_period_of
    from mechviz.dynamics.atlas.theory import linear_limit_dt, mode1_unstable_intervals

    period = fastest_period_of(spec)
    shown = ", ".join(f"{k}={v:g}" for k, v in spec.params) or "the defaults"
    if not (math.isfinite(period) and period > 0):
        raise ValueError(f"--param {shown}: the motion's shortest period is not representable")
    system = spec.make_system()
    if not _energies_finite(spec, system):
        raise ValueError(
            f"--param {shown}: the energy of the starts mapped is beyond the largest double"
        )
    try:
        with np.errstate(all="ignore"):
            if spec.kind == "chaos":
                mode1_unstable_intervals(system.params)
            elif spec.kind == "stability":
                for m in spec.methods:
                    linear_limit_dt(system, m, spec.x.values())
    except (ArithmeticError, ValueError) as exc:
        raise ValueError(
            f"--param {shown}: what theory draws over the map is not representable "
            f"({exc.__class__.__name__})"
        ) from None


def _energies_finite(spec, system) -> bool:
    """The energy (and its distance from the floor, what the errors are relative to) of the
    grid's extreme starts are finite numbers."""
    import numpy as np

    from mechviz.dynamics.atlas.grid import HOOP_COORDINATES
    from mechviz.dynamics.atlas.theory import start_states

    if spec.kind == "chaos":
        states = np.zeros((4, 4))
        for i, (y, x) in enumerate([(a, b) for a in (0, 1) for b in (0, 1)]):
            states[i, HOOP_COORDINATES[spec.y.name]] = (spec.y.start, spec.y.stop)[y]
            states[i, HOOP_COORDINATES[spec.x.name]] = (spec.x.start, spec.x.stop)[x]
    else:
        states = start_states(system, np.array([spec.x.start, spec.x.stop]))
    try:
        with np.errstate(all="ignore"):
            e = np.asarray(system.energy(states), dtype=float)
            moving = e - system.energy_floor()
    except (ArithmeticError, ValueError):
        return False
    return bool(np.all(np.isfinite(e)) and np.all(np.isfinite(moving)))


def default_workers(requested: int | None) -> tuple[int, str]:
    """The LocalCluster's worker count: ``requested`` (default: one per core) capped by the cores
    and by the memory (:data:`WORKER_BYTES` each); and a note when capped."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    cores = max(1, cores or 1)
    by_memory = max(1, available_memory() // WORKER_BYTES)
    cap = min(cores, by_memory)
    want = requested or cores
    if want <= cap:
        return want, ""
    why = f"{cores} cores" if cores <= by_memory else f"memory for {by_memory}"
    shown = f"{want}" if want < 10**6 else f"{float(want):.3g}"
    return cap, f"--workers {shown} capped at {cap} (the {why})"


def check_scheduler(address: str) -> None:
    """Refuse (``ValueError``) a ``--scheduler`` that is no address of a known protocol, or where
    nothing answers: at once, rather than after the client's own time limit."""
    import socket

    text = address.strip()
    if not text:
        raise ValueError("scheduler: give an address such as tcp://host:8786")
    from distributed.comm import parse_address, parse_host_port
    from distributed.comm.registry import backends

    try:
        scheme, loc = parse_address(text, strict=True)
    except (ValueError, TypeError):
        raise ValueError(f"scheduler {address}: not an address such as tcp://host:8786") from None
    if scheme not in backends:
        known = ", ".join(sorted(backends))
        raise ValueError(f"scheduler {address}: unknown protocol {scheme} (one of {known})")
    if scheme not in ("tcp", "tls"):
        return
    try:
        host, port = parse_host_port(loc)
        with socket.create_connection((host, port), timeout=5):
            pass
    except (OSError, ValueError, TypeError) as exc:
        why = getattr(exc, "strerror", None) or exc.__class__.__name__
        raise ValueError(f"scheduler {address}: nothing answers there ({why})") from None


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
    if args.quick:
        raise CliError("--quick: a flag of --bench")
    if not args.out:
        raise CliError("--out: give the folder to write the atlas into")
    if not args.max_steps >= 1:
        raise CliError(f"--max-steps: must be at least 1, got {args.max_steps:g}")
    try:
        if args.scheduler is not None:
            if args.workers is not None:
                raise ValueError("workers: sets the cluster started here, not --scheduler's")
            check_scheduler(args.scheduler)
        spec = build_spec(args)
        check_memory(spec)
        check_cost(spec, args.max_steps)
        check_theory(spec)
    except ValueError as exc:
        raise CliError(_as_flag(str(exc))) from None
    note = ""
    if args.scheduler is None:
        args.workers, note = default_workers(args.workers)
    return run_and_draw(spec, Path(args.out), args, note)


def run_and_draw(spec, out: Path, args: argparse.Namespace, note: str = "") -> int:
    from mechviz.dynamics.atlas import store
    from mechviz.dynamics.atlas.driver import AtlasInterrupted, ClusterError, prepare, run_atlas
    from mechviz.dynamics.atlas.maps import save_maps

    from .errors import CliError

    path = out / "atlas.zarr"
    try:
        if out.exists() and not out.is_dir():
            raise CliError(f"--out: {out} is not a folder")
        if args.resume and not path.exists() and not store.has_partial(path):
            raise CliError(f"--resume: no atlas at {path}")
        if not args.resume and not args.fresh and path.exists():
            raise CliError(
                f"--out: {path} exists; pass --resume to continue it, --fresh to start it again, "
                "or another --out"
            )
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
            if note:
                print(f"mechviz atlas: {note}", file=sys.stderr)
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
    except ClusterError as exc:
        raise CliError(str(exc)) from None
    except OSError as exc:  # a full disk, a folder that cannot be made, a name too long
        where = f" ({exc.filename})" if exc.filename and str(exc.filename) != str(out) else ""
        raise CliError(f"--out {_short(out)}: {exc.strerror or exc}{where}") from None
    print(
        f"mechviz atlas: {len(report.computed)} chunks computed ({len(report.skipped)} kept "
        f"from before) in {report.wall_seconds:.1f} s on {report.workers} workers; "
        f"{path}; {', '.join(str(p) for p in maps)}"
    )
    return 0


def _short(path: Path, most: int = 80) -> str:
    text = str(path)
    return text if len(text) <= most else f"{text[: most // 2]}...{text[-most // 2 :]}"


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
        "--workers",
        type=_workers_text,
        help="LocalCluster worker processes (default: one per core; capped by the cores and "
        "the memory)",
    )
    p.add_argument(
        "--max-steps",
        type=number,
        default=DEFAULT_MAX_STEPS,
        help="refuse an atlas estimated to take more compiled steps than this, all its cells "
        f"together (default {DEFAULT_MAX_STEPS:g})",
    )
    p.add_argument(
        "--system",
        choices=SYSTEM_NAMES,
        help=f"stability and accuracy: the system (default and chaos: the {SYSTEM_NAMES[0]})",
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
        type=number,
        help="stability: run length in periods of the fastest mode (default 50)",
    )
    p.add_argument(
        "--threshold",
        type=number,
        help="stability: unbounded once the relative energy error exceeds this (default 1)",
    )
    p.add_argument(
        "--duration", type=number, help="chaos and accuracy: run length [s] (default 60 and 10)"
    )
    p.add_argument("--step", type=number, help="chaos: the method's step [s] (default 0.01)")
    p.add_argument(
        "--renormalise",
        type=number,
        help="chaos: seconds between renormalisations of the twin (default 1)",
    )
    p.add_argument(
        "--separation",
        type=number,
        help="chaos: the twin's distance in state space (default 1e-9; 1e-12 to 1e-3)",
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
