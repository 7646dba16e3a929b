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


#: The step controls already made, by (method, dt, rtol, atol) given as plain floats or ``None``:
#: a step control is frozen and was validated when first made, so a new run at the same settings
#: (a scan of starts, a benchmark building one per solve) takes it as it is instead of checking
#: it again. Keyed by the method's identity (its fields are many and slow to hash); the entry
#: holds the method, so that identity is not reused while it is stored.
_STEPS: dict[tuple, tuple[Method, Step]] = {}
_PLAIN = (float, type(None))


def shared_step_control(
    method: Method, dt: float | None = None, rtol: float | None = None, atol: float | None = None
) -> Step:
    """:func:`step_control`, made once per method and settings (settings other than floats or
    ``None``, a string or a NumPy scalar, are checked every time)."""
    if type(dt) not in _PLAIN or type(rtol) not in _PLAIN or type(atol) not in _PLAIN:
        return step_control(method, dt, rtol, atol)
    key = (id(method), dt, rtol, atol)
    entry = _STEPS.get(key)
    if entry is not None and entry[0] is method:
        return entry[1]
    step = step_control(method, dt, rtol, atol)  # raises, naming the field, before storing
    if len(_STEPS) >= 4096:  # a long scan over tolerances: keep the table bounded
        _STEPS.clear()
    _STEPS[key] = (method, step)
    return step
