"""The checks of ``mechviz atlas``'s flags, all made before any work: each value read by the
one rule for typed numbers, the flags a map kind takes, the cost (``--max-steps``), the memory the
grid needs, the workers the machine can hold and the scheduler's address; each refusal is one line
naming the flag (:mod:`.atlas` runs the command)."""

from __future__ import annotations

import argparse
import math
import os
import re

from mechviz.dynamics.atlas.grid import chaos_systems, system_names
from mechviz.dynamics.params import parse_number

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
            if args.system in chaos_systems():
                continue
            raise ValueError(
                f"system {args.system}: the chaos map is of the {', '.join(chaos_systems())} only"
            )
        which = " and ".join(kinds)
        raise ValueError(f"{name}: the {which} map's flag; the {args.kind} map takes none")
    if args.kind == "accuracy" and args.dt is not None and args.rtol is not None:
        raise ValueError("rtol: give --dt (fixed-step methods) or --rtol (adaptive), not both")


def build_spec(args: argparse.Namespace):
    """The :class:`mechviz.dynamics.atlas.AtlasSpec` the flags describe (``ValueError`` naming the flag)."""
    from mechviz.dynamics import SYSTEMS, methods_for
    from mechviz.dynamics.atlas.grid import AtlasSpec, Axis
    from mechviz.dynamics.atlas.theory import make_system, start_states

    check_flags_apply(args)
    if args.kind == "chaos":
        system_name = args.system or chaos_systems()[0]
    else:
        system_name = args.system or system_names()[0]
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
