"""What a system is, written once: its parameters, its start, its methods and default step.

A :class:`SystemSpec` describes one system as a person meets it: the physical parameters (with
units, the label a panel shows and the rule that checks them), the settings of its start (the
cyclotron's speed, the hoop's mode amplitudes, the disk's motion and extra spin), the default
method and step, and how to build the driver's system and initial state from them. The command
line's flags, the Python API's keyword arguments, the demo files' keys and the viewer's panels
are generated from it, so one default and one range hold everywhere.

:meth:`SystemSpec.setup` turns settings (any subset; the rest default) into a :class:`Setup`: the
system, its initial state, the method and its step control, all checked, or a
:class:`mechviz.dynamics.params.SettingError` naming the setting (a parameter's name, ``initial.<name>``
for a start setting, ``method``, ``dt``, ``rtol``, ``atol``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, fields, replace
from typing import Any

import numpy as np

from . import params as _v
from .integrators.base import Method, get_method, methods_for
from .steps import Step, step_control


@dataclass(frozen=True)
class Setting:
    """One setting a person can give: ``name`` (a Python identifier: the API's keyword, the demo
    key, the flag ``--name-with-dashes``), ``label`` and ``unit`` (what a panel shows),
    ``default``, and ``rule(name, value)`` that returns the checked value or raises
    :class:`mechviz.dynamics.params.SettingError` naming ``name``."""

    name: str
    label: str
    unit: str
    default: Any
    rule: Callable[[str, Any], Any]
    help: str = ""
    #: Names of a tuple setting's components where each may be given alone (``wx``, ``wy``, ``wz``).
    components: tuple[str, ...] = ()
    #: The values a word setting takes (``motion``: driven, released).
    choices: tuple[str, ...] = ()
    #: ``(setting, value)``: given, this setting only means something when that other start
    #: setting has that value (the disk's ``extra_spin`` needs ``motion = "released"``).
    needs: tuple[str, Any] | None = None
    #: ``(lo, hi)``: the values a live exhibit of the system stays meaningful at (the viewer's
    #: panel refuses others: with a mass of 1e300 nothing moves, with a radius of 1e6 the
    #: exhibit leaves the screen); the API and the command line take whatever ``rule`` allows.
    span: tuple[float, float] | None = None

    @property
    def flag(self) -> str:
        return "--" + self.name.replace("_", "-")

    @property
    def panel_label(self) -> str:
        return f"{self.label} [{self.unit}]" if self.unit else self.label

    def check(self, value: Any) -> Any:
        return self.rule(self.name, value)


def param(
    name: str, label: str, unit: str, help: str = "", span: tuple[float, float] | None = None
) -> Setting:
    """The :class:`Setting` of the physical parameter ``name``: its default and its check are
    the parameter dataclass's own (one default, one rule), bound by the :class:`SystemSpec` that
    lists it; ``help`` defaults to the label with its unit; ``span`` is the range a live exhibit
    takes (:attr:`Setting.span`)."""
    help = help or f"{label[:1].lower()}{label[1:]} [{unit}]"
    return Setting(name, label, unit, None, _unbound, help, span=span)


def _unbound(name: str, value: Any) -> Any:  # pragma: no cover - replaced by SystemSpec
    raise TypeError(f"{name}: a parameter setting not bound to its dataclass")


def _bound(Params: type, s: Setting) -> Setting:
    default = next(f.default for f in fields(Params) if f.name == s.name)

    def rule(n: str, value: Any) -> Any:
        return getattr(Params(**{n: value}), n)

    return replace(s, default=default, rule=rule)


@dataclass(frozen=True)
class Setup:
    """Everything a run starts from: the driver's system, its initial state, method and step."""

    spec: SystemSpec
    params: Any  # the system's parameter dataclass
    start: dict[str, Any]  # the checked start settings, defaults filled in
    system: Any  # a mechviz.dynamics.systems adapter
    state: np.ndarray
    method: Method
    step: Step


@dataclass(frozen=True)
class BenchCase:
    """One benchmark problem of a system (its description says which: :attr:`SystemSpec.bench`):
    the driver's system, its initial state, the span and the methods to compare.

    ``fixed``: our fixed-step methods in the sweep; ``n0``: the fewest steps there (0: no
    sweep); ``floor``: errors below it cannot be resolved against the reference; ``period``: the
    period counted in the long run; ``exact_reference``: the system's own exact flow is the
    reference; ``long_run``: the step [s] and the fixed-step methods of the long energy-drift
    run (none for a case the methods were not tuned on)."""

    key: str
    title: str
    system: Any  # a mechviz.dynamics.systems adapter
    state0: tuple[float, ...]
    t_end: float
    fixed: tuple[str, ...]
    n0: int
    floor: float
    period: float
    exact_reference: bool
    long_run: tuple[float, tuple[str, ...]] | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "state0", tuple(float(x) for x in self.state0))
        if len(self.state0) != len(self.system.state_names):
            raise ValueError(f"{self.key}: state0 must have {len(self.system.state_names)} values")
        if not (self.t_end > 0 and self.period > 0 and self.n0 >= 0):
            raise ValueError(f"{self.key}: t_end and period must be positive, n0 not negative")
        for name in self.fixed + (self.long_run[1] if self.long_run else ()):
            get_method(name)  # an unknown method raises, naming it

    @property
    def y0(self) -> np.ndarray:
        return np.array(self.state0, dtype=float)

    def error(self, y: np.ndarray, ref: np.ndarray) -> float:
        """The system's error metric of ``y`` against ``ref`` (one state each)."""
        return float(np.asarray(self.system.error(np.atleast_2d(y), np.atleast_2d(ref)))[0])


@dataclass(frozen=True)
class SystemSpec:
    """One system as a person meets it (see the module docstring).

    ``build(params, start)`` returns the driver's system and the initial state for checked
    settings; ``default_method(start)`` the method a run takes when none is given (the disk's
    depends on its motion); ``analysis(params, **start)`` the seed's analytic results (a
    JSON-ready dict), taking the start settings named in ``analysis_start``. ``bench``: the
    benchmark's problems of this system, the one it was tuned on first, then the ones it was
    not (:class:`BenchCase`)."""

    name: str
    title: str
    Params: type
    params: tuple[Setting, ...]
    start: tuple[Setting, ...]
    build: Callable[[Any, dict[str, Any]], tuple[Any, np.ndarray]]
    default_method: Callable[[dict[str, Any]], str]
    dt: float
    analysis: Callable[..., dict[str, Any]]
    analysis_start: tuple[str, ...] = ()
    #: State variables a command line may set one by one over the default start.
    state_overrides: tuple[str, ...] = ()
    rtol: float = 1e-9
    bench: tuple[BenchCase, ...] = ()
    #: A case of this system drawn at random (``(rng, key) -> BenchCase``) for the benchmark's
    #: untuned cases; None: the system takes no part there.
    bench_draw: Callable[[np.random.Generator, str], BenchCase] | None = None

    def __post_init__(self) -> None:
        names = [f.name for f in fields(self.Params)]
        if [s.name for s in self.params] != names:
            raise TypeError(f"{self.name}: params must describe {names} in order")
        bound = tuple(_bound(self.Params, s) if s.rule is _unbound else s for s in self.params)
        object.__setattr__(self, "params", bound)

    # ------------------------------------------------------------------ settings
    def setting(self, name: str) -> Setting:
        """The parameter or start setting called ``name``."""
        for s in (*self.params, *self.start):
            if s.name == name:
                return s
        raise KeyError(name)

    def default_params(self) -> dict[str, Any]:
        """The parameters a run takes when none is given, by name (as the dataclass fills them)."""
        p = self.Params()
        return {s.name: getattr(p, s.name) for s in self.params}

    def parameters(self, values: Mapping[str, Any] | None = None) -> Any:
        """The checked parameter dataclass for ``values`` (names of :attr:`params`; the rest
        default). An unknown name or a bad value raises :class:`SettingError` naming it."""
        values = dict(values or {})
        known = [s.name for s in self.params]
        for name in values:
            if name not in known:
                raise _v.SettingError(
                    name,
                    f"{name} is not a parameter of the {self.name}; choose from {', '.join(known)}",
                )
        return self.Params(**values)

    def start_values(self, values: Mapping[str, Any] | None = None) -> dict[str, Any]:
        """The checked start settings, defaults filled in (:class:`SettingError` naming
        ``initial.<name>`` otherwise)."""
        values = dict(values or {})
        known = [s.name for s in self.start]
        out = {}
        for name in values:
            if name not in known:
                raise _v.SettingError(
                    f"initial.{name}",
                    f"{name} is not a start setting of the {self.name}; "
                    f"choose from {', '.join(known)}",
                )
        for s in self.start:
            try:
                out[s.name] = s.check(values.get(s.name, s.default))
            except _v.SettingError as exc:
                raise _v.SettingError(f"initial.{s.name}", str(exc)) from None
        for s in self.start:
            if s.needs is not None and s.name in values and out[s.needs[0]] != s.needs[1]:
                other, value = s.needs
                raise _v.SettingError(
                    f"initial.{s.name}",
                    f"{s.name} only applies when {other} is {value!r}, not {out[other]!r}",
                )
        return out

    def analyze(self, values: Mapping[str, Any]) -> dict[str, Any]:
        """``analysis`` for ``values`` (parameters and the start settings it takes, by name),
        with the system's name first; :class:`SettingError` names a bad or unknown setting."""
        values = dict(values)
        start = {k: values.pop(k) for k in self.analysis_start if k in values}
        p = self.parameters(values)
        st = self.start_values(start)
        return {"system": self.name, **self.analysis(p, **{k: st[k] for k in self.analysis_start})}

    def methods(self, start: Mapping[str, Any] | None = None) -> list[Method]:
        """The methods that apply for these start settings."""
        system, _ = self.build(self.parameters(), self.start_values(start))
        return methods_for(system)

    def setup(
        self,
        params: Mapping[str, Any] | None = None,
        start: Mapping[str, Any] | None = None,
        *,
        method: str | None = None,
        dt: float | None = None,
        rtol: float | None = None,
        atol: float | None = None,
        state: Any = None,
    ) -> Setup:
        """Check the settings (any subset; the rest default) and build the run's start. ``dt``
        defaults to :attr:`dt` for a fixed-step method, ``rtol`` to :attr:`rtol` for an adaptive
        one; ``state`` replaces the start settings' initial state."""
        p = self.parameters(params)
        st = self.start_values(start)
        system, s0 = self.build(p, st)
        name = self.default_method(st) if method is None else method
        try:
            m = get_method(name)
        except ValueError as exc:
            raise _v.SettingError("method", str(exc)) from None
        if not m.applies_to(system):
            names = ", ".join(x.name for x in methods_for(system))
            raise _v.SettingError(
                "method",
                f"method {m.name!r} does not apply to the {self.name} here; choose one of {names}",
            )
        if m.closed_form:
            step = step_control(m, dt, None, None)
        else:
            step = step_control(
                m, self.dt if dt is None else dt, self.rtol if rtol is None else rtol, atol
            )
        if state is not None:
            s0 = checked_state(system, state)
        return Setup(self, p, st, system, s0, m, step)


def checked_state(system: Any, state: Any, copy: bool = False) -> np.ndarray:
    """``state`` as a finite float array of shape ``(d,)`` or ``(N, d)`` for ``system``, else
    :class:`SettingError` naming ``state``; ``copy``: always a new array (the caller's own)."""
    d = len(system.state_names)
    try:
        s = np.array(state, dtype=float) if copy else np.asarray(state, dtype=float)
    except (TypeError, ValueError):
        raise _v.SettingError("state", f"state must be numbers, got {state!r}") from None
    if s.shape[-1:] != (d,) or s.ndim not in (1, 2):
        raise _v.SettingError(
            "state",
            f"state must have shape (d,) or (N, d) with d = {d} "
            f"({', '.join(system.state_names)}); got {s.shape}",
        )
    if not all_finite(s):
        raise _v.SettingError("state", "state must be finite")
    return s


def all_finite(s: np.ndarray) -> bool:
    """Whether every entry of ``s`` is finite. One state is checked number by number: NumPy's
    ``isfinite`` costs about 1.5 us a call on a few numbers, three times this loop, and every
    new run and solve checks its start."""
    if s.ndim == 1 and s.size <= 64:
        return all(map(math.isfinite, s.tolist()))
    return bool(np.isfinite(s).all())
