"""``mechviz analyze`` and ``mechviz simulate``: the dynamics from the command line, headless.

Registered on the ``mechviz`` parser by :mod:`viz.cli`; nothing here imports viser.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from typing import Any

import numpy as np

from . import cyclotron, disk, hoop
from .integrators import METHODS, IntegrationError, get_method
from .simulation import Simulation
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


class CliError(Exception):
    """A bad flag or value: reported as one line, exit status 2."""


def number(text: str) -> float:
    """argparse type: a finite real number."""
    try:
        x = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not math.isfinite(x):
        raise argparse.ArgumentTypeError(f"must be finite, got {text}")
    return x


def _add_params(p: argparse.ArgumentParser, system: str) -> None:
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
        flag = next((f for f, n in PARAM_FLAGS[system].items() if n == field), field)
        raise CliError(f"{flag}: {exc}") from None


def _speed(args: argparse.Namespace) -> float:
    """``--speed`` (default 1 m/s), which must be positive."""
    speed = 1.0 if args.speed is None else args.speed
    if speed <= 0:
        raise CliError(f"--speed: must be positive, got {speed}")
    return speed


# --------------------------------------------------------------------------- analyze
def analyze(system: str, args: argparse.Namespace) -> dict[str, Any]:
    """The seed's analytic results for ``system`` as a JSON-ready dict."""
    p = _params(args, system)
    if system == "cyclotron":
        speed = _speed(args)
        ke = 0.5 * p.mass * speed**2
        state = cyclotron.circular_orbit_state(p, speed)
        p_phi = float(cyclotron.canonical_angular_momentum(p, state))
        return {
            "system": "cyclotron",
            "parameters": {"charge": p.charge, "mass": p.mass, "field": p.field, "speed": speed},
            "gyrofrequency": cyclotron.gyrofrequency(p),
            "signed_gyrofrequency": cyclotron.signed_gyrofrequency(p),
            "rotation_seen_from_plus_z": "clockwise"
            if cyclotron.signed_gyrofrequency(p) > 0
            else "anticlockwise",
            "period": cyclotron.period(p),
            "kinetic_energy": ke,
            "radius": cyclotron.orbit_radius(p, ke),
            "canonical_angular_momentum": p_phi,
            "effective_potential_minimum_radius": cyclotron.effective_potential_minimum(p, p_phi),
            "radial_oscillation_frequency": cyclotron.radial_oscillation_frequency(p, p_phi),
        }
    if system == "disk":
        moments, axes = disk.principal_axes(p)
        moments_cm, axes_cm = disk.principal_axes_cm(p)
        return {
            "system": "disk",
            "parameters": {
                "disk_mass": p.disk_mass,
                "radius": p.radius,
                "bead_mass": p.bead_mass,
                "omega": p.omega,
            },
            "inertia_tensor": disk.inertia_tensor(p).tolist(),
            "inertia_tensor_disk": disk.inertia_tensor_disk(p).tolist(),
            "inertia_tensor_bead": disk.inertia_tensor_bead(p).tolist(),
            "principal_moments": moments.tolist(),
            "principal_axes": axes.tolist(),
            "centre_of_mass": disk.centre_of_mass(p).tolist(),
            "angular_momentum": disk.angular_momentum(p).tolist(),
            "required_torque": disk.required_torque(p).tolist(),
            "axle_force_amplitude": disk.axle_force_amplitude(p),
            "bearing_force_a_amplitude": float(np.linalg.norm(disk.bearing_force_a(p))),
            "net_bearing_force_amplitude": float(np.linalg.norm(disk.net_bearing_force(p))),
            "principal_moments_cm": moments_cm.tolist(),
            "principal_axes_cm": axes_cm.tolist(),
        }
    freqs, shapes = hoop.normal_modes(p)
    return {
        "system": "hoop",
        "parameters": {
            "hoop_mass": p.hoop_mass,
            "bead_mass": p.bead_mass,
            "radius": p.radius,
            "gravity": p.gravity,
        },
        "mode_frequencies": freqs.tolist(),
        "mode_periods": (2 * math.pi / freqs).tolist(),
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


def simulate(system: str, args: argparse.Namespace) -> dict[str, Any]:
    sysm, state = _system_and_state(system, args)
    try:
        method = get_method(args.method)
    except ValueError as exc:
        raise CliError(f"--method: {exc}") from None
    if not method.applies_to(sysm.name):
        choices = ", ".join(m.name for m in METHODS.values() if m.applies_to(sysm.name))
        raise CliError(f"--method: {method.name} does not apply to {sysm.name}; choose {choices}")
    if args.t_end <= 0:
        raise CliError(f"--t-end: must be positive, got {args.t_end}")
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
        # Land exactly on --t-end: the largest step <= --dt that divides it.
        dt = args.t_end / math.ceil(args.t_end / dt - 1e-9)
    if args.rtol is not None and not 0 < args.rtol < 1:
        raise CliError(f"--rtol: must lie in (0, 1), got {args.rtol}")
    sim = Simulation(sysm, method, dt=dt, rtol=args.rtol, state=state)
    try:
        traj = sim.run(args.t_end, n_samples=args.samples)
    except IntegrationError as exc:
        raise CliError(str(exc)) from None
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
    if sysm.name == "driven-disk":
        out["bearing_force_b"] = disk.bearing_force_b(sysm.params, traj.t[-1]).tolist()
        out["bearing_force_a"] = disk.bearing_force_a(sysm.params, traj.t[-1]).tolist()
    return out


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
            help="samples along the run for the energy error (default 201)",
        )
        p.add_argument("--json", action="store_true", help="print JSON")
        p.set_defaults(func=_run_simulate)


def _emit(result: dict[str, Any], as_json: bool) -> None:
    if as_json:
        json.dump(result, sys.stdout, indent=2)
        print()
    else:
        _print_table(result)


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
    if args.samples < 2:
        raise CliError(f"--samples: must be at least 2, got {args.samples}")
    _emit(simulate(args.system, args), args.json)
    return 0
