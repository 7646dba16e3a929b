"""``mechviz analyze`` and ``mechviz simulate``: the dynamics from the command line, headless.

Registered on the ``mechviz`` parser by :mod:`mechviz.viz.cli`; nothing here imports viser.

Bad input is one line naming the flag, exit status 2: a value that is not a finite number, and
also one whose *consequences* are not representable (a gyrofrequency that overflows, a kinetic
energy that underflows to 0, a step count beyond ``--max-steps``). ``simulate`` estimates its work
before it starts (:meth:`mechviz.dynamics.Simulation.estimated_steps`), shows progress on a terminal for
runs longer than a few seconds, and stops within about a second on Ctrl-C (exit 130), even inside
numba's compiler.
``--json`` is always valid JSON: a number that is not finite is ``null``, and ``null_reasons``
says why.
"""

from __future__ import annotations

import argparse
import copy
import dataclasses
import json
import math
import os
import re
import sys
from typing import Any

import numpy as np

from mechviz.dynamics import analysis
from mechviz.dynamics.files import json_safe
from mechviz.dynamics.integrators import METHODS, IntegrationError
from mechviz.dynamics.params import TINY, SettingError, blamed
from mechviz.dynamics.registry import SPECS
from mechviz.dynamics.simulation import (
    EXACT_FLOW,
    MIN_COMPARED_TOL,
    REFERENCE_RUN,
    REFERENCE_TOL,
    RESOLVED_FACTOR,
    Simulation,
    reference_description,
)
from mechviz.dynamics.spec import Setup, SystemSpec, checked_state
from mechviz.dynamics.steps import Fixed
from mechviz.dynamics.systems import SYSTEMS
from mechviz.viz.interrupts import ctrl_c_within_a_second

from ..progress import add_option as add_progress_option
from ..progress import progress_bar
from .errors import CliError, number, whole

#: The most samples ``simulate --samples`` keeps.
MAX_SAMPLES = 100_000
#: Default of ``simulate --max-steps``: the most steps a run may take (ensemble and reference
#: included); about 1 s of the cheapest compiled method, a few minutes of the dearest.
DEFAULT_MAX_STEPS = 1e8
#: Runs estimated above this many steps show a progress line on a terminal.
PROGRESS_STEPS = 2e6


def flag_for(field: str) -> str:
    """The command-line flag of a setting (:class:`mechviz.dynamics.params.SettingError` ``field``):
    ``bead_mass`` -> ``--bead-mass``, ``initial.speed`` -> ``--speed``."""
    return "--" + field.removeprefix("initial.").replace("_", "-")


def setting_error(exc: SettingError, args: argparse.Namespace | None = None) -> CliError:
    """The one line for a refused setting, naming its flag (and the value given, if any)."""
    shown = []
    for f in exc.fields:
        value = getattr(args, f.removeprefix("initial.").replace(".", "_"), None) if args else None
        flag = flag_for(f)
        shown.append(f"{flag} {value:g}" if isinstance(value, float) else flag)
    return CliError(f"{', '.join(shown)}: {exc}")


def _given(args: argparse.Namespace, names) -> dict[str, Any]:
    return {n: getattr(args, n) for n in names if getattr(args, n, None) is not None}


def _add_params(p: argparse.ArgumentParser, spec: SystemSpec, start: tuple[str, ...]) -> None:
    """The flags of ``spec``'s parameters and of the start settings named in ``start``, each
    with its unit and default, from the system's description."""
    p._negative_number_matcher = _NEGATIVE_NUMBER  # type: ignore[attr-defined]
    # a start setting of several numbers (a centre, mode amplitudes) has flags of its own
    settings = [
        *spec.params,
        *(s for s in map(spec.setting, start) if not isinstance(s.default, tuple)),
    ]
    for s in settings:
        kind: dict[str, Any] = {"choices": s.choices} if s.choices else {"type": number}
        p.add_argument(
            s.flag,
            dest=s.name,
            default=None,
            help=f"{s.help} (default {_default_text(s.default)})",
            **kind,
        )


def _default_text(value) -> str:
    if value is None:  # the one parameter whose default follows from another
        return "5/4 of the disk mass, as in the seed"
    return f"{value:g}" if isinstance(value, float) else str(value)


# argparse takes "-1e-3" for an option (its pattern for negative numbers has no exponent).
_NEGATIVE_NUMBER = re.compile(r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$")


# --------------------------------------------------------------------------- analyze
def analyze(system: str, args: argparse.Namespace) -> dict[str, Any]:
    """The seed's analytic results for ``system`` as a JSON-ready dict
    (:func:`mechviz.dynamics.analysis.analyze`); :class:`CliError` naming the flag otherwise."""
    spec = SPECS[system]
    given = _given(args, [s.name for s in spec.params] + list(spec.analysis_start))
    try:
        return analysis.analyze(system, given)
    except SettingError as exc:
        raise setting_error(exc, args) from None


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
def _component_flags(spec: SystemSpec) -> tuple[str, ...]:
    """``simulate``'s flags for single components of the start: the state's own variables
    where the description says so (``--theta1``, ``--vx``), and the named components of tuple
    start settings (the disk's ``--wx``); names that are start settings already are left out."""
    own = {s.name for s in spec.start}
    names = spec.state_overrides + tuple(c for s in spec.start for c in s.components)
    return tuple(n for n in names if n not in own)


def _component_help(spec: SystemSpec, name: str) -> str:
    for s in spec.start:
        if name in s.components:
            i = s.components.index(name)
            return f"{name}: component {i + 1} of {s.help} (default {s.default[i]:g})"
    return f"initial {name} (default: the default start's)"


def _setup(spec: SystemSpec, args: argparse.Namespace) -> Setup:
    """The run's start from the flags given (the rest from the system's description)."""
    start = _given(args, [s.name for s in spec.start])
    for s in spec.start:
        given = [getattr(args, c, None) for c in s.components]
        if any(v is not None for v in given):
            if s.name == "extra_spin" and spec.start_values(start)["motion"] != "released":
                raise CliError("--wx/--wy/--wz: only apply to --motion released")
            base = list(s.default)
            start[s.name] = tuple(b if v is None else v for b, v in zip(base, given, strict=True))
    setup = spec.setup(
        _given(args, [x.name for x in spec.params]),
        start,
        method=args.method,
        dt=args.dt,
        rtol=args.rtol,
        atol=getattr(args, "atol", None),
    )
    overrides = {
        n: getattr(args, n) for n in spec.state_overrides if getattr(args, n, None) is not None
    }
    if overrides:
        state = setup.state.copy()
        names = list(setup.system.state_names)
        for n, v in overrides.items():
            state[names.index(n)] = v
        setup = dataclasses.replace(setup, state=checked_state(setup.system, state))
    return setup


def _start_flags(spec: SystemSpec) -> list[str]:
    """Every flag's attribute that shapes the start: parameters, start settings, components."""
    return [s.name for s in (*spec.params, *spec.start)] + list(_component_flags(spec))


def _blame(spec: SystemSpec, args: argparse.Namespace, bad) -> str:
    """The flags given (with their values) whose default alone makes ``bad(setup)`` false, else
    every one given: what a refusal of a consequence of several flags names."""
    given = [n for n in _start_flags(spec) if getattr(args, n, None) is not None]

    def fixed_without(name: str) -> bool:
        trial = copy.copy(args)
        setattr(trial, name, None)
        return not bad(_setup(spec, trial))

    alone = blamed(given, fixed_without, (CliError, ValueError, ArithmeticError))
    shown = [
        f"{flag_for(n)} {getattr(args, n):g}"
        if isinstance(getattr(args, n), float)
        else flag_for(n)
        for n in (alone or given)
    ]
    return ", ".join(shown)


def _energy_overflows(setup: Setup) -> bool:
    with np.errstate(all="ignore"):
        return not math.isfinite(float(np.ravel(setup.system.energy(setup.state))[0]))


def simulate(system: str, args: argparse.Namespace) -> dict[str, Any]:
    """Run ``system`` as the flags say and report its end (see ``mechviz simulate --help``)."""
    spec = SPECS[system]
    given = _given(args, [s.name for s in spec.params] + list(spec.analysis_start))
    try:
        analysis.check_representable(spec.analyze, given)
        setup = _setup(spec, args)
    except SettingError as exc:
        raise setting_error(exc, args) from None
    sysm, state, method = setup.system, setup.state, setup.method
    if _energy_overflows(setup):
        shown = _blame(spec, args, _energy_overflows) or "the start"
        raise CliError(f"{shown}: the initial energy is beyond the largest double")
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
        shown = _blame(spec, args, lambda s: math.ulp(t_end) > 1e-6 * s.system.time_scale(s.state))
        by = f", set by {shown}" if shown else ""
        raise CliError(
            f"--t-end {t_end:g}: a double near it resolves time only to {math.ulp(t_end):.2g} s, "
            f"too coarse for the motion's shortest period ({period:.3g} s{by})"
        )
    step = setup.step
    if method.adaptive and args.dt is not None:
        raise CliError(f"--dt: {method.name} is adaptive; give --rtol instead")
    for flag, tol in (("--rtol", args.rtol), ("--atol", getattr(args, "atol", None))):
        if not method.adaptive and tol is not None:
            raise CliError(f"{flag}: {method.name} takes a fixed step; give --dt instead")
    if isinstance(step, Fixed):
        n = t_end / step.dt
        if not n <= args.max_steps:
            raise CliError(
                f"--t-end {t_end:g} / --dt {step.dt:g} = {n:.3g} steps, above the limit of "
                f"{args.max_steps:.3g} (--max-steps raises it)"
            )
        # Land exactly on --t-end: the largest step <= dt that divides it.
        step = Fixed(t_end / max(1, math.ceil(n - 1e-9)))
    sim = Simulation(sysm, method, step=step, state=state)
    if sim.reference_note:
        raise CliError(
            f"{'--atol' if sim.atol < sim.rtol else '--rtol'} {min(sim.rtol, sim.atol):g}: the "
            f"{spec.name} has no exact solution here and the reference run (DOP853 at rtol "
            f"{REFERENCE_TOL:g}) must be clearly tighter; choose --rtol and --atol >= "
            f"{MIN_COMPARED_TOL:g}"
        )
    steps = sim.estimated_steps(t_end)
    if not steps <= args.max_steps:
        if not method.adaptive:
            what = f"--dt {sim.dt:g}"
        elif args.rtol is not None:
            what = f"--rtol {sim.rtol:g} ({method.name})"
        else:
            what = f"{method.name} at rtol {sim.rtol:g}"
        ref = " and the DOP853 reference run" if sim.reference_kind == "reference" else ""
        raise CliError(
            f"--t-end {t_end:g}: about {steps:.2g} steps of {what}{ref} (the motion's shortest "
            f"period is {period:.3g} s), above the limit of {args.max_steps:.3g} "
            "(--max-steps raises it)"
        )
    progress = progress_bar(
        f"simulating {spec.name} with {method.name}",
        t_end,
        enabled=steps > PROGRESS_STEPS,
        bar_format="{desc}: {percentage:5.1f}% (t = {n:.4g} of {total:g} s)",
    )
    sim.on_chunk = lambda s: progress.update(min(s.t, t_end) - progress.n)
    try:
        traj = sim.run(t_end, n_samples=args.samples)
    except IntegrationError as exc:
        raise CliError(str(exc)) from None
    finally:
        progress.close()
    final = traj.states[-1, 0]
    out: dict[str, Any] = {
        "system": spec.name,
        **({"motion": setup.start["motion"]} if "motion" in setup.start else {}),
        "method": method.name,
        "step": sim.step_label(),
        **step_numbers(sim.step),
        "parameters": dataclasses.asdict(setup.params),
        "t_end": float(traj.t[-1]),
        "initial_state": dict(zip(sysm.state_names, map(float, traj.states[0, 0]), strict=True)),
        "final_state": dict(zip(sysm.state_names, map(float, final), strict=True)),
        "energy_drift": float(traj.energy_error[-1, 0]),
        "max_energy_error": float(np.max(np.abs(traj.energy_error))),
        "rhs_evaluations": int(traj.nfev),
        "rhs_evaluations_count": method.counts,
        "steps": int(traj.steps),
        "samples": int(len(traj.t)),
        "members": int(traj.states.shape[1]),
    }
    if traj.error is not None:
        key = "error_vs_exact" if sim.reference_kind == EXACT_FLOW else "error_vs_reference"
        out[key] = float(traj.error[-1, 0])
        out["reference"] = reference_description(sim.reference_kind)
        if sim.reference_kind == REFERENCE_RUN and traj.reference_error is not None:
            bar = float(traj.reference_error[-1, 0])
            out["reference_error"] = bar
            out["error_resolved"] = out[key] >= RESOLVED_FACTOR * bar
    out.update(sysm.report(traj.t[-1]))
    return out


# --------------------------------------------------------------------------- parser
def add_commands(sub: argparse._SubParsersAction) -> None:
    """Register ``analyze`` and ``simulate`` on the ``mechviz`` sub-parser set, one sub-command
    per system, their flags generated from the systems' descriptions (:data:`SPECS`)."""
    names = "{" + ",".join(SPECS) + "}"
    an = sub.add_parser("analyze", help="print the analytic results of a system")
    an_sub = an.add_subparsers(dest="system", required=True, metavar=names)
    for spec in SPECS.values():
        p = an_sub.add_parser(spec.name, help=f"analytic results: {spec.title.lower()}")
        _add_params(p, spec, spec.analysis_start)
        p.add_argument("--json", action="store_true", help="print JSON")
        p.set_defaults(func=_run_analyze)

    si = sub.add_parser("simulate", help="integrate a system and report the final state")
    si.add_argument(
        "--list-methods",
        action="store_true",
        help="list the integration methods with their properties",
    )
    si.add_argument("--json", action="store_true", help="with --list-methods: print JSON")
    si.set_defaults(func=_run_simulate, system=None)
    si_sub = si.add_subparsers(dest="system", metavar=names)
    for spec in SPECS.values():
        p = si_sub.add_parser(spec.name, help=f"integrate: {spec.title.lower()}")
        _add_params(p, spec, tuple(x.name for x in spec.start))
        for name in _component_flags(spec):
            p.add_argument(f"--{name}", type=number, default=None, help=_component_help(spec, name))
        p.add_argument("--t-end", type=number, required=True, help="duration [s]")
        p.add_argument(
            "--method",
            default=None,
            help="integration method (--list-methods; default the system's)",
        )
        p.add_argument(
            "--dt", type=number, default=None, help=f"fixed step size [s] (default {spec.dt:.4g})"
        )
        p.add_argument(
            "--rtol",
            type=number,
            default=None,
            help=f"relative tolerance of adaptive methods (default {spec.rtol:g})",
        )
        p.add_argument(
            "--atol",
            type=number,
            default=None,
            help="absolute tolerance of adaptive methods, in the state's units (default: --rtol); "
            "a motion much smaller than 1 (a swing of 0.01 rad) is then held to atol, not to "
            "rtol of itself, and its relative error is larger than rtol by about that ratio",
        )
        p.add_argument(
            "--samples",
            type=whole,
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
        add_progress_option(p)
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


def step_numbers(step) -> dict[str, Any]:
    """The step control as numbers, beside its words (``step``): ``dt`` [s] of a fixed step,
    ``rtol`` and ``atol`` of an adaptive one, each ``null`` where the method takes none."""
    return {
        "dt": getattr(step, "dt", None),
        "rtol": getattr(step, "rtol", None),
        "atol": getattr(step, "atol", None),
    }


def method_list() -> list[dict[str, Any]]:
    """Every integration method as ``simulate --list-methods --json`` gives it."""
    return [
        {
            "name": m.name,
            "title": m.title,
            "description": m.describe(SYSTEMS.values()),
            "order": m.order,
            "variable_order": m.variable_order,
            "adaptive": m.adaptive,
            "implicit": m.implicit,
            "structure": [str(getattr(x, "value", x)) for x in m.structure],
            "backend": m.backend,
            "counts": m.counts,
            "applies_to": sorted(n for n, cls in SYSTEMS.items() if m.applies_to(cls)),
        }
        for m in METHODS.values()
    ]


def _run_analyze(args: argparse.Namespace) -> int:
    _emit(analyze(args.system, args), args.json)
    return 0


def _run_simulate(args: argparse.Namespace) -> int:
    if args.list_methods or args.system is None:
        if not args.list_methods:
            raise CliError(f"simulate: choose a system ({', '.join(SPECS)}) or --list-methods")
        if args.json:
            _emit({"methods": method_list()}, True)
            return 0
        for m in METHODS.values():
            systems = ", ".join(sorted(n for n, cls in SYSTEMS.items() if m.applies_to(cls)))
            print(f"{m.name:13s} {m.describe(SYSTEMS.values())}; applies to {systems}")
        return 0
    if not 2 <= args.samples <= MAX_SAMPLES:
        raise CliError(f"--samples: must be from 2 to {MAX_SAMPLES}, got {args.samples}")
    if args.max_steps < 1:
        raise CliError(f"--max-steps: must be at least 1, got {args.max_steps:g}")
    with ctrl_c_within_a_second():
        result = simulate(args.system, args)
    _emit(result, args.json)
    return 0
