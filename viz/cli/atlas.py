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
import sys
from dataclasses import fields
from pathlib import Path

from mechviz.dynamics.atlas.grid import system_names
from mechviz.dynamics.systems import SYSTEMS

from .atlas_checks import (  # noqa: F401  (the checks, re-exported for the tests)
    _FIELDS,
    APPLIES,
    COPIES_IN_MEMORY,
    DEFAULT_MAX_STEPS,
    MAX_AXIS_END,
    WORKER_BYTES,
    _as_flag,
    _axis_flags,
    _axis_text,
    _chunk_text,
    _count,
    _energies_finite,
    _param_text,
    _workers_text,
    available_memory,
    build_spec,
    check_cost,
    check_flags_apply,
    check_memory,
    check_scheduler,
    check_theory,
    default_workers,
)
from .errors import command, number


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
    names = system_names()  # the registry's now: a system registered at run time too
    p.add_argument(
        "--system",
        choices=names,
        help=f"stability and accuracy: the system (default and chaos: the {names[0]})",
    )
    p.add_argument(
        "--param",
        type=_param_text,
        action="append",
        metavar="NAME=VALUE",
        help="a system parameter by its field name ("
        + "; ".join(f"{n}: {', '.join(f.name for f in fields(SYSTEMS[n].Params))}" for n in names)
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
        help="amplitude axis (" + "; ".join(f"{n}: {SYSTEMS[n].amplitude[1]}" for n in names) + ")",
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
