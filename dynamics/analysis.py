"""The seed's analytic results for each system, as a JSON-ready dict, with every derived number
checked to be representable.

:func:`analyze` is what ``mechviz analyze`` prints and what :func:`mechviz.dynamics.api.analyze` returns:
cyclotron gyrofrequency, period, radius for a transverse ``speed``, canonical momentum and the
effective potential's minimum; disk inertia tensors, principal moments and axes, bearing forces;
hoop normal-mode frequencies, periods and shapes.

A value that is valid on its own can still have consequences a double cannot hold (a
gyrofrequency that overflows, a kinetic energy that underflows to 0). :func:`analyze` refuses
those with a :class:`mechviz.dynamics.params.SettingError` whose ``fields`` are the settings to blame:
those given whose default alone makes every result representable (else every setting given).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from .params import TINY, SettingError, blamed
from .registry import SPECS

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
    "initial_energy",
    "angular_momentum_norm",
    "axle_force_amplitude",
    "net_bearing_force_amplitude",
}


def unrepresentable(result: Mapping[str, Any], prefix: str = "") -> str | None:
    """The first derived number in ``result`` that is not a finite, normal double (or 0 where it
    cannot be), said in words; None if all are fine. ``parameters`` are not derived."""
    for key, value in result.items():
        if key == "parameters":
            continue
        name = f"{prefix}{key}"
        if isinstance(value, dict):
            found = unrepresentable(value, f"{name}.")
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
            if x == 0.0 and key in _NONZERO:
                return f"{name} would underflow to 0"
    return None


def check_representable(
    compute: Callable[[dict[str, Any]], Mapping[str, Any]], given: Mapping[str, Any]
) -> None:
    """Raise :class:`SettingError` if ``compute(given)`` holds a number that is not
    representable; its ``fields`` are the settings blamed (see the module docstring)."""

    def problem(values: Mapping[str, Any]) -> str | None:
        with np.errstate(all="ignore"):
            return unrepresentable(compute(dict(values)))

    found = problem(given)  # a bad setting raises its own SettingError here
    if found is None:
        return
    alone = blamed(given, lambda k: problem({n: v for n, v in given.items() if n != k}) is None)
    fields = tuple(alone or given) or ("parameters",)
    raise SettingError(fields[0], found, fields=fields)


def analyze(system: str, values: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """The analytic results of ``system`` (a name in :data:`mechviz.dynamics.registry.SPECS`) for
    ``values``: its parameters by name, and the start settings its analysis takes
    (:attr:`mechviz.dynamics.spec.SystemSpec.analysis_start`; the cyclotron's ``speed`` [m/s]); the rest
    default. :class:`SettingError` names a bad or unknown setting, or those whose consequences
    are not representable."""
    spec = SPECS[system]
    given = dict(values or {})
    check_representable(lambda v: spec.analyze(v), given)
    return spec.analyze(given)
