"""``mechviz analyze`` and ``mechviz simulate``: the dynamics from the command line, headless.

Registered on the ``mechviz`` parser by :mod:`viz.cli`; nothing here imports viser.

Bad input is one line naming the flag, exit status 2: a value that is not a finite number, and
also one whose *consequences* are not representable (a gyrofrequency that overflows, a kinetic
energy that underflows to 0, a step count beyond ``--max-steps``). ``simulate`` estimates its work
before it starts (:meth:`dynamics.Simulation.estimated_steps`), shows progress on a terminal for
runs longer than a few seconds, and stops within about a second on Ctrl-C (exit 130), even inside
numba's compiler.
``--json`` is always valid JSON: a number that is not finite is ``null``, and ``null_reasons``
says why.
"""

from __future__ import annotations

import argparse
import contextlib
import copy
import json
import math
import os
import re
import sys
import time
from typing import Any

import numpy as np

from . import cyclotron, disk, hoop
from .files import json_safe
from .integrators import METHODS, IntegrationError, get_method
from .interrupt import ctrl_c_within_a_second
from .simulation import (
    MIN_COMPARED_TOL,
    REFERENCE_ACCURACY,
    REFERENCE_ATOL,
    REFERENCE_TOL,
    Simulation,
)
from .systems import Cyclotron, DrivenDisk, Hoop, ReleasedDisk

# flag -> (dataclass field) for each system; defaults come from the dataclasses.
PARAM_FLAGS = {
    "cyclotron": {"--charge": "charge", "--mass": "mass", "--field": "field"},
    "disk": {
        "--disk-mass": "disk_mass",
        "--radius": "radius",
        "--bead-mass": "bead_mass",
        "--omega": "omega",
    },
    "hoop": {
        "--hoop-mass": "hoop_mass",
        "--bead-mass": "bead_mass",
        "--radius": "radius",
        "--gravity": "gravity",
    },
}
PARAM_HELP = {
    "charge": "charge q [C] (signed, nonzero)",
    "mass": "mass m [kg]",
    "field": "field B [T] along +z (nonzero)",
    "disk_mass": "disk mass M [kg]",
    "radius": "radius [m]",
    "bead_mass": "bead mass [kg]",
    "omega": "spin rate about the axle [rad/s]",
    "hoop_mass": "hoop mass M [kg]",
    "gravity": "gravity g [m/s^2]",
}
STATE_FLAGS = {
    "cyclotron": ("x", "y", "z", "vx", "vy", "vz"),
    "hoop": ("theta1", "theta2", "omega1", "omega2"),
    "disk": ("wx", "wy", "wz"),
}


#: Default of ``simulate --max-steps``: the most steps a run may take (ensemble and reference
#: included); about 1 s of the cheapest compiled method, a few minutes of the dearest.
DEFAULT_MAX_STEPS = 1e8
#: The most samples ``simulate --samples`` keeps.
MAX_SAMPLES = 100_000
#: Runs estimated above this many steps show a progress line on a terminal.
PROGRESS_STEPS = 2e6
TINY = sys.float_info.min  # the smallest normal double, 2.2e-308


class CliError(Exception):
    """A bad flag or value: reported as one line, exit status 2."""


def number(text: str) -> float:
    """argparse type: a finite real number, not so close to 0 that it loses precision (a
    subnormal double)."""
    try:
        x = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not math.isfinite(x):
        raise argparse.ArgumentTypeError(f"must be finite, got {text}")
    if 0.0 < abs(x) < TINY:
        raise argparse.ArgumentTypeError(
            f"{text} is below the smallest normal double ({TINY:.3g}); use 0 or a larger value"
        )
    return x


# --------------------------------------------------------------------------- representability
# Derived quantities that are nonzero for every valid input: 0 means they underflowed.
_NONZERO = {
    "gyrofrequency",
    "period",
    "kinetic_energy",
    "radius",
    "effective_potential_minimum_radius",
    "radial_oscillation_frequency",
    "principal_moments",
    "principal_moments_cm",
    "mode_frequencies",
    "mode_periods",
    "canonical_angular_momentum",
    "time_scale",
    "energy_scale",
}
# ... and these too when the disk spins (omega != 0).
_NONZERO_SPINNING = {"angular_momentum_norm", "axle_force_amplitude", "net_bearing_force_amplitude"}


def _unrepresentable(result: dict[str, Any], prefix: str = "") -> str | None:
    """The first derived number in ``result`` that is not a finite, normal double (or 0 where it
    cannot be), said in words; None if all are fine. ``parameters`` are not derived."""
    nonzero = _NONZERO
    if result.get("parameters", {}).get("omega"):
        nonzero = _NONZERO | _NONZERO_SPINNING
    for key, value in result.items():
        if key == "parameters":
            continue
        name = f"{prefix}{key}"
        if isinstance(value, dict):
            found = _unrepresentable(value, f"{name}.")
            if found:
                return found
            continue
        values = np.ravel(np.asarray(value, dtype=object)) if isinstance(value, list) else [value]
        for x in values:
            if not isinstance(x, float | int | np.floating) or isinstance(x, bool):
                continue
            x = float(x)
            if math.isnan(x):
                return f"{name} is not representable (its formula overflows or divides by 0)"
            if not math.isfinite(x):
                return f"{name} would be {x} (beyond the largest double)"
            if 0.0 < abs(x) < TINY:
                return f"{name} would underflow to {x:.3g} (below the smallest normal double)"
            if x == 0.0 and key in nonzero:
                return f"{name} would underflow to 0"
    return None


def _problem(compute, args: argparse.Namespace) -> str | None:
    """What is not representable in ``compute(args)`` (a dict), or None."""
    with np.errstate(all="ignore"):
        return _unrepresentable(compute(args))


def _check_representable(compute, args: argparse.Namespace, flags: dict[str, str]) -> None:
    """Raise :class:`CliError` naming the flag(s) if ``compute(args)`` has a number that is not
    representable. ``flags``: option -> attribute of ``args``. The flags blamed are those given
    whose default alone makes the result representable (else every flag given)."""
    problem = _problem(compute, args)
    if problem is None:
        return
    given = [f for f, a in flags.items() if getattr(args, a, None) is not None]
    blamed = []
    for f in given:
        trial = copy.copy(args)
        setattr(trial, flags[f], None)
        try:
            if _problem(compute, trial) is None:
                blamed.append(f)
        except CliError:
            pass
    shown = ", ".join(f"{f} {getattr(args, flags[f]):g}" for f in (blamed or given))
    raise CliError(f"{shown or 'the parameters'}: {problem}")


def _flags(system: str) -> dict[str, str]:
    out = dict(PARAM_FLAGS[system])
    if system == "cyclotron":
        out["--speed"] = "speed"
    return out


# argparse takes "-1e-3" for an option (its pattern for negative numbers has no exponent).
_NEGATIVE_NUMBER = re.compile(r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$")


def _add_params(p: argparse.ArgumentParser, system: str) -> None:
    p._negative_number_matcher = _NEGATIVE_NUMBER  # type: ignore[attr-defined]
    for flag, name in PARAM_FLAGS[system].items():
        p.add_argument(flag, dest=name, type=number, default=None, help=PARAM_HELP[name])
    if system == "cyclotron":
        p.add_argument(
            "--speed",
            type=number,
            default=None,
            help="speed in the plane normal to B [m/s] (default 1)",
        )


def _params(args: argparse.Namespace, system: str):
    cls = {
        "cyclotron": cyclotron.CyclotronParams,
        "disk": disk.DiskParams,
        "hoop": hoop.HoopParams,
    }[system]
    kwargs = {
        name: getattr(args, name)
        for name in PARAM_FLAGS[system].values()
        if getattr(args, name) is not None
    }
    try:
        return cls(**kwargs)
    except ValueError as exc:
        field = str(exc).split()[0]
        if field not in kwargs:  # a default derived from what was given (the bead from the disk)
            raise CliError(f"{_shown(args, _flags(system))}: {exc}") from None
        flag = next((f for f, n in PARAM_FLAGS[system].items() if n == field), field)
        raise CliError(f"{flag}: {exc}") from None


def _shown(args: argparse.Namespace, flags: dict[str, str]) -> str:
    """The flags of ``flags`` (option -> attribute) given on the command line, with values."""
    given = [f"{f} {getattr(args, a):g}" for f, a in flags.items() if getattr(args, a) is not None]
    return ", ".join(given) or "the defaults"


def _blame(args: argparse.Namespace, flags: dict[str, str], bad) -> str:
    """The given flags whose default alone makes ``bad(args)`` false (else every one given), as
    :func:`_shown` writes them: the fields a refusal names."""
    blamed = {}
    for f, a in flags.items():
        if getattr(args, a, None) is None:
            continue
        trial = copy.copy(args)
        setattr(trial, a, None)
        with contextlib.suppress(CliError, ValueError, ArithmeticError):
            if not bad(trial):
                blamed[f] = a
    return _shown(args, blamed or flags)


def _speed(args: argparse.Namespace) -> float:
    """``--speed`` (default 1 m/s), which must be positive."""
    speed = 1.0 if args.speed is None else args.speed
    if speed <= 0:
        raise CliError(f"--speed: must be positive, got {speed}")
    return speed


# --------------------------------------------------------------------------- analyze
def analyze(system: str, args: argparse.Namespace) -> dict[str, Any]:
    """The seed's analytic results for ``system`` as a JSON-ready dict; :class:`CliError` naming
    the flag if one of them is not a representable number."""
    _check_representable(lambda a: _analyze(system, a), args, _flags(system))
    return _analyze(system, args)


def _q(fn, fallback: Any = math.nan):
    """``fn()``, or ``fallback`` (NaN) if its arithmetic overflows, divides by zero or leaves its
    domain: the NaN is then reported, in order, by :func:`_unrepresentable`."""
    try:
        with np.errstate(all="ignore"):
            return fn()
    except (OverflowError, ZeroDivisionError, ValueError, np.linalg.LinAlgError):
        return fallback  # ValueError: math domain, or a helper's finite-input check


def _analyze(system: str, args: argparse.Namespace) -> dict[str, Any]:
    p = _params(args, system)
    if system == "cyclotron":
        speed = _speed(args)
        ke = _q(lambda: 0.5 * p.mass * speed**2)
        state = _q(lambda: cyclotron.circular_orbit_state(p, speed), np.full(6, math.nan))
        p_phi = _q(
            lambda: float(cyclotron.canonical_angular_momentum(p, state)),
        )
        w = _q(lambda: cyclotron.signed_gyrofrequency(p))
        return {
            "system": "cyclotron",
            "parameters": {"charge": p.charge, "mass": p.mass, "field": p.field, "speed": speed},
            "gyrofrequency": abs(w),
            "signed_gyrofrequency": w,
            "rotation_seen_from_plus_z": "clockwise" if w > 0 else "anticlockwise",
            "period": _q(lambda: cyclotron.period(p)),
            "kinetic_energy": ke,
            "radius": _q(lambda: cyclotron.orbit_radius(p, ke)),
            "canonical_angular_momentum": p_phi,
            "effective_potential_minimum_radius": _q(
                lambda: cyclotron.effective_potential_minimum(p, p_phi),
            ),
            "radial_oscillation_frequency": _q(
                lambda: cyclotron.radial_oscillation_frequency(p, p_phi),
            ),
        }
    if system == "disk":
        nan3 = (np.full(3, math.nan), np.full((3, 3), math.nan))
        moments, axes = _q(lambda: disk.principal_axes(p), nan3)
        moments_cm, axes_cm = _q(lambda: disk.principal_axes_cm(p), nan3)
        return {
            "system": "disk",
            "parameters": {
                "disk_mass": p.disk_mass,
                "radius": p.radius,
                "bead_mass": p.bead_mass,
                "omega": p.omega,
            },
            "inertia_tensor": _q(lambda: disk.inertia_tensor(p).tolist()),
            "inertia_tensor_disk": _q(lambda: disk.inertia_tensor_disk(p).tolist()),
            "inertia_tensor_bead": _q(lambda: disk.inertia_tensor_bead(p).tolist()),
            "principal_moments": moments.tolist(),
            "principal_axes": axes.tolist(),
            "centre_of_mass": disk.centre_of_mass(p).tolist(),
            "angular_momentum": _q(lambda: disk.angular_momentum(p).tolist()),
            "required_torque": _q(lambda: disk.required_torque(p).tolist()),
            "axle_force_amplitude": _q(lambda: disk.axle_force_amplitude(p)),
            "bearing_force_a_amplitude": _q(lambda: float(np.linalg.norm(disk.bearing_force_a(p)))),
            "net_bearing_force_amplitude": _q(
                lambda: float(np.linalg.norm(disk.net_bearing_force(p)))
            ),
            "principal_moments_cm": moments_cm.tolist(),
            "principal_axes_cm": axes_cm.tolist(),
        }
    freqs, shapes = _q(
        lambda: hoop.normal_modes(p), (np.full(2, math.nan), np.full((2, 2), math.nan))
    )
    return {
        "system": "hoop",
        "parameters": {
            "hoop_mass": p.hoop_mass,
            "bead_mass": p.bead_mass,
            "radius": p.radius,
            "gravity": p.gravity,
        },
        "mode_frequencies": freqs.tolist(),
        "mode_periods": _q(lambda: (2 * math.pi / freqs).tolist()),
        "mode_shapes": shapes.tolist(),
    }


def _print_table(result: dict[str, Any]) -> None:
    width = max(len(k) for k in result)
    for key, value in result.items():
        if isinstance(value, list) and value and isinstance(value[0], list):
            rows = [" ".join(f"{x: .6g}" for x in row) for row in value]
            print(f"{key:<{width}}  {rows[0]}")
            for row in rows[1:]:
                print(f"{'':<{width}}  {row}")
        elif isinstance(value, list):
            print(f"{key:<{width}}  " + " ".join(f"{x:.6g}" for x in value))
        elif isinstance(value, dict):
            print(f"{key:<{width}}  " + ", ".join(f"{k}={v:g}" for k, v in value.items()))
        elif isinstance(value, float):
            print(f"{key:<{width}}  {value:.10g}")
        else:
            print(f"{key:<{width}}  {value}")


# --------------------------------------------------------------------------- simulate
def _system_and_state(system: str, args: argparse.Namespace):
    p = _params(args, system)
    if system == "cyclotron":
        speed = _speed(args)
        sysm = Cyclotron(p)
        state = cyclotron.circular_orbit_state(p, speed)
    elif system == "hoop":
        sysm = Hoop(p)
        state = np.zeros(4)
    else:
        spin = tuple(getattr(args, n) or 0.0 for n in STATE_FLAGS["disk"])
        if args.motion == "driven":
            if any(spin):
                raise CliError("--wx/--wy/--wz: only apply to --motion released")
            sysm = DrivenDisk(p)
        else:
            sysm = ReleasedDisk(p, spin)
        return sysm, sysm.default_state()
    for j, name in enumerate(STATE_FLAGS[system]):
        value = getattr(args, name)
        if value is not None:
            state[j] = value
    return sysm, state


def _initial(system: str, args: argparse.Namespace) -> dict[str, Any]:
    """The initial energy, for :func:`_check_representable`."""
    sysm, state = _system_and_state(system, args)
    return {"initial_energy": _q(lambda: float(np.ravel(sysm.energy(state))[0]))}


def simulate(system: str, args: argparse.Namespace) -> dict[str, Any]:
    flags = _flags(system)
    _check_representable(lambda a: _analyze(system, a), args, flags)
    flags |= {f"--{n}": n for n in STATE_FLAGS[system]}
    _check_representable(lambda a: _initial(system, a), args, flags)
    sysm, state = _system_and_state(system, args)
    try:
        method = get_method(args.method)
    except ValueError as exc:
        raise CliError(f"--method: {exc}") from None
    if not method.applies_to(sysm.name):
        choices = ", ".join(m.name for m in METHODS.values() if m.applies_to(sysm.name))
        raise CliError(f"--method: {method.name} does not apply to {sysm.name}; choose {choices}")
    t_end = args.t_end
    if t_end <= 0:
        raise CliError(f"--t-end: must be positive, got {t_end}")
    if t_end / (args.samples - 1) < TINY:
        raise CliError(
            f"--t-end {t_end:g}: {args.samples - 1} sample intervals of it would underflow "
            "(below the smallest normal double)"
        )
    period = sysm.time_scale(state)
    if math.ulp(t_end) > 1e-6 * period:
        def too_coarse(a: argparse.Namespace) -> bool:
            trial_system, trial_state = _system_and_state(system, a)
            return math.ulp(t_end) > 1e-6 * trial_system.time_scale(trial_state)

        params = _blame(args, flags, too_coarse)
        raise CliError(
            f"--t-end {t_end:g}: a double near it resolves time only to {math.ulp(t_end):.2g} s, "
            f"too coarse for the motion's shortest period ({period:.3g} s"
            + ("" if params == "the defaults" else f", set by {params}") + ")"
        )
    if method.adaptive and args.dt is not None:
        raise CliError(f"--dt: {method.name} is adaptive; give --rtol instead")
    if not method.adaptive and args.rtol is not None:
        raise CliError(f"--rtol: {method.name} takes a fixed step; give --dt instead")
    dt = args.dt
    if dt is not None and dt <= 0:
        raise CliError(f"--dt: must be positive, got {dt}")
    if not method.adaptive and method.backend != "exact" and dt is None:
        raise CliError(f"--dt: required for the fixed-step method {method.name}")
    if dt is not None:
        n = t_end / dt
        if not n <= args.max_steps:
            raise CliError(
                f"--t-end {t_end:g} / --dt {dt:g} = {n:.3g} steps, above the limit of "
                f"{args.max_steps:.3g} (--max-steps raises it)"
            )
        # Land exactly on --t-end: the largest step <= --dt that divides it.
        dt = t_end / max(1, math.ceil(n - 1e-9))
    if args.rtol is not None and not 0 < args.rtol < 1:
        raise CliError(f"--rtol: must lie in (0, 1), got {args.rtol}")
    try:
        sim = Simulation(sysm, method, dt=dt, rtol=args.rtol, state=state)
    except ValueError as exc:
        raise CliError(str(exc)) from None
    if sim.reference_note:
        raise CliError(
            f"--rtol {args.rtol:g}: the {sysm.name} has no exact solution here and the reference "
            f"run (DOP853 at rtol {REFERENCE_TOL:g}) must be clearly tighter; choose "
            f"--rtol >= {MIN_COMPARED_TOL:g}"
        )
    steps = sim.estimated_steps(t_end)
    if not steps <= args.max_steps:
        ref = " and the DOP853 reference run" if sim.reference_kind == "reference" else ""
        if not method.adaptive:
            what = f"--dt {dt:g}"
        elif args.rtol is not None:
            what = f"--rtol {sim.rtol:g} ({method.name})"
        else:
            what = f"{method.name} at rtol {sim.rtol:g}"
        raise CliError(
            f"--t-end {t_end:g}: about {steps:.2g} steps of {what}{ref} (the motion's shortest "
            f"period is {period:.3g} s), above the limit of {args.max_steps:.3g} "
            "(--max-steps raises it)"
        )
    progress = _Progress(f"{sysm.name} with {method.name}", t_end, enabled=steps > PROGRESS_STEPS)
    sim.on_chunk = lambda s: progress(s.t)
    try:
        traj = sim.run(t_end, n_samples=args.samples)
    except IntegrationError as exc:
        raise CliError(str(exc)) from None
    finally:
        progress.close()
    final = traj.states[-1, 0]
    out: dict[str, Any] = {
        "system": sysm.name,
        "method": method.name,
        "step": sim.step_label(),
        "t_end": float(traj.t[-1]),
        "final_state": dict(zip(sysm.state_names, map(float, final), strict=True)),
        "energy_drift": float(traj.energy_error[-1, 0]),
        "max_energy_error": float(np.max(np.abs(traj.energy_error))),
        "rhs_evaluations": int(traj.nfev),
        "steps": int(traj.steps),
    }
    if traj.error is not None:
        key = "error_vs_exact" if sim.reference_kind == "exact" else "error_vs_reference"
        out[key] = float(traj.error[-1, 0])
        out["reference"] = (
            "exact solution (round-off only)"
            if sim.reference_kind == "exact"
            else f"DOP853 at rtol = {REFERENCE_TOL:g}, atol = {REFERENCE_ATOL:g}, its own "
            f"relative error below "
            f"{REFERENCE_ACCURACY:g}"
        )
    if sysm.name == "driven-disk":
        out["bearing_force_b"] = disk.bearing_force_b(sysm.params, traj.t[-1]).tolist()
        out["bearing_force_a"] = disk.bearing_force_a(sysm.params, traj.t[-1]).tolist()
    return out


class _Progress:
    """``simulating LABEL: 42% (t = 4.2 of 10 s)`` on stderr when it is a terminal, at most ten
    times a second; silent otherwise or when not ``enabled``."""

    def __init__(self, label: str, t_end: float, *, enabled: bool = True, stream=None) -> None:
        self.stream = stream or sys.stderr
        self.enabled = enabled and self.stream.isatty()
        self.label, self.t_end = label, t_end
        self.last = 0.0
        self.shown = False

    def __call__(self, t: float) -> None:
        now = time.monotonic()
        if not self.enabled or now - self.last < 0.1:
            return
        self.last = now
        pct = 100.0 * t / self.t_end
        self.stream.write(
            f"\rsimulating {self.label}: {pct:5.1f}% (t = {t:.4g} of {self.t_end:g} s)"
        )
        self.stream.flush()
        self.shown = True

    def close(self) -> None:
        if self.shown:
            self.stream.write("\r\033[K")
            self.stream.flush()


# --------------------------------------------------------------------------- parser
def add_commands(sub: argparse._SubParsersAction) -> None:
    """Register ``analyze`` and ``simulate`` on the ``mechviz`` sub-parser set."""
    an = sub.add_parser("analyze", help="print the analytic results of a system")
    an_sub = an.add_subparsers(dest="system", required=True, metavar="{cyclotron,disk,hoop}")
    for system in ("cyclotron", "disk", "hoop"):
        p = an_sub.add_parser(system, help=f"analytic results for the {system}")
        _add_params(p, system)
        p.add_argument("--json", action="store_true", help="print JSON")
        p.set_defaults(func=_run_analyze)

    si = sub.add_parser("simulate", help="integrate a system and report the final state")
    si.add_argument(
        "--list-methods",
        action="store_true",
        help="list the integration methods with their properties",
    )
    si.set_defaults(func=_run_simulate, system=None)
    si_sub = si.add_subparsers(dest="system", metavar="{cyclotron,disk,hoop}")
    for system in ("cyclotron", "disk", "hoop"):
        p = si_sub.add_parser(system, help=f"integrate the {system}")
        _add_params(p, system)
        if system == "disk":
            p.add_argument(
                "--motion",
                choices=("driven", "released"),
                default="driven",
                help="driven: uniform rotation about the axle (exact); released: "
                "the axle removed at t = 0 (free rigid body)",
            )
        for name in STATE_FLAGS[system]:
            p.add_argument(
                f"--{name}",
                type=number,
                default=None,
                help=f"initial {name}"
                + (" (added to the spin) [rad/s]" if system == "disk" else ""),
            )
        p.add_argument("--t-end", type=number, required=True, help="duration [s]")
        p.add_argument("--method", default=None, help="integration method (--list-methods)")
        p.add_argument("--dt", type=number, default=None, help="fixed step size [s]")
        p.add_argument("--rtol", type=number, default=None, help="tolerance of adaptive methods")
        p.add_argument(
            "--samples",
            type=int,
            default=201,
            help=f"samples along the run for the energy error (2 to {MAX_SAMPLES}; default 201)",
        )
        p.add_argument(
            "--max-steps",
            type=number,
            default=DEFAULT_MAX_STEPS,
            help="refuse runs estimated to take more steps than this, ensemble and reference "
            f"run included (default {DEFAULT_MAX_STEPS:g})",
        )
        p.add_argument("--json", action="store_true", help="print JSON")
        p.set_defaults(func=_run_simulate)


def _emit(result: dict[str, Any], as_json: bool) -> None:
    """Print ``result`` as a table or as valid JSON (non-finite numbers become null, listed with
    the reason under ``null_reasons``). A reader that closes the pipe early is not an error."""
    try:
        if as_json:
            reasons: dict[str, str] = {}
            safe = json_safe(result, reasons=reasons)
            if reasons:
                safe["null_reasons"] = reasons
            print(json.dumps(safe, indent=2, allow_nan=False))
        else:
            _print_table(result)
        sys.stdout.flush()
    except BrokenPipeError:
        # Python would complain again when it flushes stdout at exit.
        devnull = open(os.devnull, "w")
        os.dup2(devnull.fileno(), sys.stdout.fileno())


def _run_analyze(args: argparse.Namespace) -> int:
    _emit(analyze(args.system, args), args.json)
    return 0


def _run_simulate(args: argparse.Namespace) -> int:
    if args.list_methods or args.system is None:
        if not args.list_methods:
            raise CliError("simulate: choose a system (cyclotron, disk, hoop) or --list-methods")
        for m in METHODS.values():
            systems = ", ".join(sorted(m.systems))
            print(f"{m.name:13s} {m.describe()}; applies to {systems}")
        return 0
    if args.method is None:
        args.method = "exact" if (args.system == "disk" and args.motion == "driven") else "rk4"
    if not 2 <= args.samples <= MAX_SAMPLES:
        raise CliError(f"--samples: must be from 2 to {MAX_SAMPLES}, got {args.samples}")
    if args.max_steps < 1:
        raise CliError(f"--max-steps: must be at least 1, got {args.max_steps:g}")
    with ctrl_c_within_a_second():
        result = simulate(args.system, args)
    _emit(result, args.json)
    return 0
