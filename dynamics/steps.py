"""Step control as one value: a fixed step, a tolerance, or the closed-form flow.

A run is integrated with one of

- :class:`Fixed` ``(dt)``: steps of exactly ``dt`` [s] (the explicit and implicit fixed-step
  methods, and the exact flow taken in steps of ``dt``);
- :class:`Tolerance` ``(rtol, atol)``: an adaptive method keeps its local error estimate below
  ``atol + rtol |y|`` per component; ``atol`` defaults to ``rtol``, which makes it an *absolute*
  tolerance of ``rtol`` on components near 0 (a hoop swinging 0.01 rad then errs by up to about
  ``rtol / 0.01`` relative: give a smaller ``atol`` for small motions);
- :class:`Exact`: the closed form, evaluated at the times asked for.

:func:`step_control` validates the settings once, for every front end, and raises a
:class:`mechviz.dynamics.params.SettingError` naming the field (``dt``, ``rtol``, ``atol``).
"""

from __future__ import annotations

from dataclasses import dataclass

from . import params as _v
from .integrators.base import Method

#: The tolerance of an adaptive run when none is given.
DEFAULT_RTOL = 1e-9


@dataclass(frozen=True)
class Fixed:
    """Steps of exactly ``dt`` [s]."""

    dt: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "dt", _v.positive("dt", self.dt))

    def label(self) -> str:
        return f"dt={self.dt:g} s"


@dataclass(frozen=True)
class Tolerance:
    """Relative tolerance ``rtol`` and absolute ``atol`` (default: ``rtol``), both in (0, 1)."""

    rtol: float = DEFAULT_RTOL
    atol: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "rtol", _v.below_one("rtol", self.rtol))
        atol = self.rtol if self.atol is None else self.atol
        object.__setattr__(self, "atol", _v.below_one("atol", atol))

    def label(self) -> str:
        return f"rtol={self.rtol:g}, atol={self.atol:g}"


@dataclass(frozen=True)
class Exact:
    """The closed-form flow, evaluated at the times asked for."""

    def label(self) -> str:
        return "exact flow"


Step = Fixed | Tolerance | Exact


def step_control(
    method: Method, dt: float | None = None, rtol: float | None = None, atol: float | None = None
) -> Step:
    """The step control ``method`` takes from the settings given: a tolerance for an adaptive
    method (``rtol`` default :data:`DEFAULT_RTOL`), a fixed step for a fixed-step method (``dt``
    required), and for the exact flow a fixed step if ``dt`` is given, else :class:`Exact`.
    Settings the method does not take are ignored: callers that hold both a step and a tolerance
    (the viewer, a demo) let the method choose. :class:`mechviz.dynamics.params.SettingError` names the
    field that is missing or out of range."""
    if method.adaptive:
        return Tolerance(DEFAULT_RTOL if rtol is None else rtol, atol)
    if dt is None:
        if method.closed_form:
            return Exact()
        raise _v.SettingError("dt", f"dt is required for the fixed-step method {method.name}")
    return Fixed(dt)
