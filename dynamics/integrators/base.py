"""The integrator interface: a method is data (name, order, structure, what it applies to) plus
a step. The driver (:mod:`mechviz.dynamics.simulation`) owns time and counts the work.

Implementers add a :class:`Method` to :data:`METHODS`:

- ``backend="numba"``, ``adaptive=False``: ``kernel`` names the step in
  :mod:`mechviz.dynamics.integrators.kernels` (see :func:`step_functions`); the driver calls
  ``run_fixed`` with it.
- ``backend="numba"``, ``adaptive=True``: with ``pair`` naming an embedded Runge-Kutta pair (a
  module of this package defining its tableau, listed in :data:`.rk.PAIRS`), the one compiled
  runner :func:`.rk.run_rk`; with ``kernel="taylor"`` Taylor's method
  (:mod:`mechviz.dynamics.integrators.taylor`).
- ``backend="scipy"``: ``scipy_name`` is a ``solve_ivp`` method or ``"odeint"``; the driver calls
  :func:`mechviz.dynamics.integrators.scipy_ivp.advance_scipy` with the same compiled right-hand side.
- ``backend="exact"``: the system's closed-form flow.

What the driver gives every method for free: validation of the step size or tolerance, the time
bookkeeping, evaluation and step counts, and an :class:`IntegrationError` (naming the method, the
step size and the time) when a state turns non-finite or an implicit step fails to converge.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any, Literal

from ..forms import SystemForms, forms_needed
from ..taylor_order import STEP_COST, order_for
from . import codes as _c
from . import limits as _lim

Structure = Literal["symplectic", "symmetric", "volume-preserving", "norm-preserving"]


class IntegrationError(RuntimeError):
    """A run that cannot go on: non-finite state, failed implicit solve, step-size collapse."""

    def __init__(self, method: str, step: str, t: float, reason: str):
        self.method, self.step, self.t, self.reason = method, step, t, reason
        super().__init__(f"{method} with {step}: {reason} at t = {t:.6g} s")


#: What each failure code of the compiled loops (``status[0]``) means, in words.
REASONS = {
    _c.NONFINITE: "state became non-finite (the method blew up)",
    _c.NO_CONVERGENCE: "implicit solve did not converge",
    _c.TOO_SMALL_STEP: "step size fell below round-off",
}


def integration_error(method: str, step: str, t: float, code: int) -> IntegrationError:
    """The :class:`IntegrationError` for a compiled loop's failure ``code`` at time ``t`` [s]."""
    return IntegrationError(method, step, t, REASONS.get(int(code), f"failure code {code}"))


@dataclass(frozen=True)
class Method:
    """One integration method, described as data.

    ``order`` is the order of a fixed-order method; for a variable one (``variable_order``) the
    highest it uses, which only the driver's work estimate reads. ``counts`` says what the
    driver's evaluation count (``nfev``, the CLI's ``rhs_evaluations``) counts for this method:
    not every method's unit of work is one right-hand side."""

    name: str
    title: str
    order: int
    structure: tuple[Structure, ...]
    adaptive: bool
    implicit: bool
    #: What a system must have for this method to apply: ``"rhs"`` a compiled right-hand side,
    #: ``"closed-form"`` its exact flow from every state, ``"symmetric"`` a symmetric
    #: second-order step of its own (which the method composes), or that step's name (the
    #: method *is* that system's own step). Systems state theirs (:mod:`mechviz.dynamics.systems`).
    needs: str
    backend: Literal["numba", "scipy", "exact"]
    kernel: str | None = None
    scipy_name: str | None = None
    stability: str = ""
    variable_order: bool = False
    counts: str = "right-hand-side evaluations"

    #: The embedded Runge-Kutta pair this method runs (:mod:`.rk`), by its module's name.
    pair: str | None = None
    #: On the test oscillation (:mod:`mechviz.dynamics.stability`): the amplification factor of
    #: one step as a function of ``x = omega h``, the largest stable ``x`` (``None``: any step;
    #: 0.0: none) and why, in words. A method without ``limit_reason`` (an adaptive one, whose
    #: step control sets ``h``) has no fixed-step limit.
    amplification: Callable[[float], float] | None = None
    limit_omega_dt: float | None = None
    limit_reason: str = ""
    #: Rough cost [ns] of one compiled step of one member on one core: sizes the atlas's chunks
    #: (its benchmark measures the real figures).
    step_cost_ns: float = 2000.0
    #: The benchmark's lists this method is in: ``"sweep"`` (our adaptive methods in the
    #: work-precision sweeps), ``"scipy"`` (the scipy side of the speed ratios), ``"fastest"``
    #: (ours against the peers in their fastest forms), ``"first-answer"`` (timed from a fresh
    #: process).
    bench: tuple[str, ...] = ()
    #: Its colour in the benchmark's charts (a matplotlib colour).
    chart_color: str | None = None
    #: The oscillation the benchmark measures its amplification on (``"gyration"``: the charge's
    #: transverse speed; ``"mode 2"``: the hoop's faster normal mode; :mod:`mechviz.bench.experiments`);
    #: None: not measured.
    stability_probe: str | None = None

    @property
    def closed_form(self) -> bool:
        """Whether it evaluates the system's exact flow (no step, no truncation error)."""
        return self.backend == "exact"

    @property
    def series(self) -> bool:
        """Whether its steps are Taylor series (:mod:`.taylor`: the order follows the tolerance)."""
        return self.kernel == "taylor"

    def structure_on(self, system: Any) -> tuple[Structure, ...]:
        """The structure this method keeps on ``system`` (an adapter or its class): its own,
        unless the system says that the method applied in its variables keeps less (a label
        belongs to a method applied in particular variables; the system knows its variables,
        :attr:`mechviz.dynamics.systems._Adapter.method_structure`). Each pair is measured
        (:mod:`mechviz.dynamics.structure`)."""
        return getattr(system, "method_structure", {}).get(self.name, (self.structure, ""))[0]

    def applies_to(self, system: Any) -> bool:
        """Whether this method can advance ``system`` (a :mod:`mechviz.dynamics.systems` adapter or its
        class)."""
        if self.needs == "closed-form":
            return system.closed_form
        if system.sys_id is None:
            return False
        if self.needs == "rhs":
            return True
        if self.needs == "symmetric":
            return system.symmetric_step is not None
        return system.symmetric_step == self.needs

    def step_options(self, dt: float | None, rtol: float | None) -> dict[str, float]:
        """Of a step size ``dt`` [s] and a tolerance ``rtol``, the one this method takes, as
        keyword arguments for :class:`mechviz.dynamics.Simulation`: ``rtol`` when adaptive, ``dt`` when it
        takes fixed steps, nothing for the closed-form flow (evaluated at the times asked for).
        Callers that hold both settings (the viewer, the recorder) let the method choose."""
        if self.adaptive:
            return {} if rtol is None else {"rtol": rtol}
        if self.backend == "exact":
            return {}
        return {} if dt is None else {"dt": dt}

    def step_text(self, dt: float | None, rtol: float | None) -> str:
        """The step setting in words: ``"dt = 0.01 s"``, ``"rtol = 1e-09"`` or ``"exact flow"``."""
        opts = self.step_options(dt, rtol)
        if "dt" in opts:
            return f"dt = {opts['dt']:g} s"
        if "rtol" in opts:
            return f"rtol = {opts['rtol']:g}"
        return "exact flow" if self.backend == "exact" else "adaptive"

    def order_text(self) -> str:
        """The order in words: ``"order 4"``; for Taylor's method the orders its rule
        (:func:`mechviz.dynamics.integrators.taylor.order_for`) picks, from the rule itself."""
        if self.kernel == "taylor":

            def picked(tol: float) -> str:
                ps = sorted({order_for(tol, tol, s)[0] for s in STEP_COST})
                return f"{ps[0]}" if len(ps) == 1 else f"{ps[0]}-{ps[-1]}"

            lo = min(order_for(0.5, 0.5, s)[0] for s in STEP_COST)
            hi = max(order_for(1e-300, 1e-300, s)[0] for s in STEP_COST)
            return (
                f"order from min(rtol, atol): {picked(1e-3)} at 1e-3, {picked(1e-9)} at 1e-9, "
                f"{picked(1e-12)} at 1e-12 (by system), {lo}-{hi} over all tolerances"
            )
        if self.variable_order:
            return f"variable order (at most {self.order})"
        return "no truncation error" if self.backend == "exact" else f"order {self.order}"

    def order_at(self, rtol: float, atol: float, sys_id: int | None = None) -> int | None:
        """The order a run at these tolerances uses: Taylor's from its rule (for the system
        ``sys_id``, or over all), ``None`` for a variable order (LSODA's), else ``order``."""
        if self.kernel == "taylor":
            return (
                order_for(rtol, atol, sys_id)[0] if sys_id is not None else order_for(rtol, atol)[0]
            )
        return None if self.variable_order else self.order

    def steps_per_period(self, rtol: float) -> float:
        """Roughly the steps an adaptive method of order p takes per period of the fastest
        motion: ``2 rtol^(-1/p)`` (Taylor's method: p the order it chooses for ``rtol``; a
        variable order: its highest)."""
        order = self.order_at(rtol, rtol) or self.order
        return 2.0 * rtol ** (-1.0 / max(order, 1))

    def describe(self, systems: Iterable[Any] = ()) -> str:
        """One line on the method; with ``systems`` (adapters or their classes), where its
        structure there differs from its label, and why."""
        if self.adaptive:
            kind = "adaptive"
        else:
            kind = "closed-form flow" if self.backend == "exact" else "fixed step"
        props = ", ".join(self.structure) or "no geometric structure"
        for system in systems:
            structure, why = getattr(system, "method_structure", {}).get(self.name, (None, ""))
            if structure is not None:
                props += f"; on {system.name} {', '.join(structure) or 'no geometric structure'}"
                props += f" ({why})"
        imp = ", implicit" if self.implicit else ""
        return (
            f"{self.title}: {self.order_text()}, {kind}{imp}, {props}; evaluations: {self.counts}"
        )


def _pair(
    name: str, title: str, order: int, step_cost_ns: float, bench: tuple[str, ...], color: str
) -> Method:
    """An embedded explicit Runge-Kutta pair of ``order`` with dense output, run by the
    compiled Runge-Kutta runner from its tableau file ``name``."""
    return Method(
        name,
        title,
        order,
        (),
        True,
        False,
        "rhs",
        "numba",
        stability="step size controlled to rtol, atol",
        counts="right-hand-side evaluations (the dense output's included)",
        pair=name,
        step_cost_ns=step_cost_ns,
        bench=bench,
        chart_color=color,
    )


def _verner(order: int, step_cost_ns: float, bench: tuple[str, ...], color: str) -> Method:
    """Verner's "most efficient" pair of ``order`` (its error estimate one order lower)."""
    title = f"Verner's most efficient {order}({order - 1}) (compiled)"
    return _pair(f"vern{order}", title, order, step_cost_ns, bench, color)


METHODS: dict[str, Method] = {
    m.name: m
    for m in [
        Method(
            "exact",
            "Exact flow",
            0,
            ("symplectic", "symmetric"),
            False,
            False,
            "closed-form",
            "exact",
            kernel="exact",
            stability_probe="gyration",
            stability="exact for any step",
            counts="nothing (the closed form costs no evaluation)",
            amplification=_lim.unit,
            limit_omega_dt=None,
            limit_reason="the exact flow: stable at any step",
            chart_color="tab:gray",
        ),
        Method(
            "euler",
            "Explicit Euler",
            1,
            (),
            False,
            False,
            "rhs",
            "numba",
            kernel="euler",
            stability_probe="gyration",
            stability="on an oscillation |R(i w h)|^2 = 1 + (w h)^2 > 1: unstable at every step",
            amplification=_lim.euler,
            limit_omega_dt=0.0,
            limit_reason="explicit Euler amplifies every oscillation by sqrt(1 + (omega dt)^2) per step",
            step_cost_ns=50.0,
            chart_color="tab:brown",
        ),
        Method(
            "rk4",
            "Classical Runge-Kutta 4",
            4,
            (),
            False,
            False,
            "rhs",
            "numba",
            kernel="rk4",
            stability_probe="gyration",
            stability="oscillation bounded (slowly damped) for w h < 2 sqrt(2)",
            amplification=_lim.rk4,
            limit_omega_dt=_lim.SQRT8,
            limit_reason="RK4 is stable on an oscillation for omega dt <= 2 sqrt 2",
            step_cost_ns=100.0,
            chart_color="tab:blue",
        ),
        Method(
            "midpoint",
            "Implicit midpoint",
            2,
            ("symplectic", "symmetric"),
            False,
            True,
            "rhs",
            "numba",
            kernel="midpoint",
            stability_probe="gyration",
            stability="A-stable; fixed-point solve needs roughly L h < 1",
            counts="right-hand-side evaluations (one per fixed-point iteration)",
            amplification=_lim.unit,
            limit_omega_dt=_lim.MIDPOINT_SOLVE_LIMIT,
            limit_reason=(
                "the implicit midpoint rule's fixed-point solve reaches 1e-14 in 100 sweeps only "
                "for omega dt < 1.449"
            ),
            step_cost_ns=300.0,
            chart_color="tab:purple",
        ),
        Method(
            "boris",
            "Boris pusher",
            2,
            ("symplectic", "symmetric", "volume-preserving"),
            False,
            False,
            "boris",
            "numba",
            kernel="symmetric2",
            stability_probe="gyration",
            stability="unconditionally stable; phase lags by w h - 2 atan(w h / 2) per step",
            counts="force evaluations (one per step)",
            amplification=_lim.unit,
            limit_omega_dt=None,
            limit_reason="Boris rotates the velocity exactly: stable at any step",
            step_cost_ns=50.0,
            chart_color="tab:green",
        ),
        Method(
            "verlet",
            "Stormer-Verlet (generalised leapfrog)",
            2,
            ("symplectic", "symmetric"),
            False,
            True,
            "verlet",
            "numba",
            kernel="symmetric2",
            stability_probe="mode 2",
            stability="linear stability w_max h < 2",
            counts=(
                "partial evaluations: the fixed-point sweeps of the implicit half kick (each a "
                "2x2 velocity solve and a force) and of the implicit drift (a 2x2 velocity solve, "
                "no force), and the explicit closing half kick (a solve and a force)"
            ),
            amplification=_lim.verlet,
            limit_omega_dt=2.0,
            limit_reason="Stormer-Verlet is stable for omega_max dt < 2",
            step_cost_ns=80.0,
            chart_color="tab:green",
        ),
        Method(
            "splitting",
            "Rotation splitting (Strang, exact rotations)",
            2,
            ("symplectic", "symmetric", "norm-preserving"),
            False,
            False,
            "splitting",
            "numba",
            kernel="symmetric2",
            stability="keeps |L| to round-off at any step",
            counts="exact rotations (five per step)",
            amplification=_lim.unit,
            limit_omega_dt=None,
            limit_reason="exact rotations keep |L|: stable at any step",
            step_cost_ns=150.0,
            chart_color="tab:green",
        ),
        Method(
            "yoshida4",
            "Yoshida triple jump of the symmetric 2nd-order step",
            4,
            ("symplectic", "symmetric"),
            False,
            False,
            "symmetric",
            "numba",
            kernel="yoshida4",
            stability_probe="mode 2",
            stability="composition of Boris / Stormer-Verlet / splitting",
            counts="its base steps' units (forces, fixed-point sweeps or rotations)",
            amplification=_lim.yoshida4,
            limit_omega_dt=_lim.YOSHIDA4_LIMIT,
            limit_reason="the Yoshida composition of Verlet steps is stable for omega dt < 1.5734",
            step_cost_ns=400.0,
            chart_color="tab:olive",
        ),
        _pair(
            "dop853",
            "DOP853 (compiled)",
            8,
            2000.0,
            ("sweep", "fastest", "first-answer"),
            "tab:orange",
        ),
        _verner(6, 1500.0, ("sweep",), "goldenrod"),
        _verner(7, 1700.0, ("sweep",), "sienna"),
        _verner(8, 2200.0, ("sweep", "fastest"), "chocolate"),
        _verner(9, 2700.0, ("sweep",), "peru"),
        Method(
            "taylor",
            "Taylor series (compiled)",
            40,
            (),
            True,
            False,
            "rhs",
            "numba",
            kernel="taylor",
            stability="step from the series' radius of convergence (Jorba and Zou)",
            variable_order=True,
            counts="series expansions (one per step)",
            step_cost_ns=2000.0,
            bench=("sweep", "fastest", "first-answer"),
            chart_color="magenta",
        ),
        Method(
            "scipy-rk45",
            "scipy solve_ivp RK45",
            5,
            (),
            True,
            False,
            "rhs",
            "scipy",
            scipy_name="RK45",
            counts="right-hand-side evaluations (scipy's nfev)",
            bench=("scipy",),
            chart_color="tab:pink",
        ),
        Method(
            "scipy-dop853",
            "scipy solve_ivp DOP853",
            8,
            (),
            True,
            False,
            "rhs",
            "scipy",
            scipy_name="DOP853",
            counts="right-hand-side evaluations (scipy's nfev)",
            bench=("scipy",),
            chart_color="tab:red",
        ),
        Method(
            "scipy-radau",
            "scipy solve_ivp Radau IIA",
            5,
            (),
            True,
            True,
            "rhs",
            "scipy",
            scipy_name="Radau",
            counts="right-hand-side evaluations (scipy's nfev: Jacobians' not included)",
            bench=("scipy",),
            chart_color="black",
        ),
        Method(
            "scipy-lsoda",
            "scipy solve_ivp LSODA",
            12,
            (),
            True,
            True,
            "rhs",
            "scipy",
            scipy_name="LSODA",
            variable_order=True,
            counts="right-hand-side evaluations (LSODA's count: Jacobians' included)",
            bench=("scipy",),
            chart_color="tab:cyan",
        ),
        Method(
            "odeint",
            "scipy odeint (Fortran LSODA)",
            12,
            (),
            True,
            True,
            "rhs",
            "scipy",
            scipy_name="odeint",
            variable_order=True,
            counts="right-hand-side evaluations (LSODA's count: Jacobians' included)",
            bench=("scipy",),
            chart_color="darkgoldenrod",
        ),
    ]
}


def step_functions(method: Method, sys_id: int | SystemForms):
    """``(step, inner)`` for this method on this system; ``inner`` is ``None`` for a direct step
    (``kernels.run_direct``) and the right-hand side or base step for a composed one. ``sys_id``
    is a compiled id (the kernels' tables) or a registered system's own
    :class:`~mechviz.dynamics.forms.SystemForms`."""
    from . import kernels as _k  # numba: only a fixed-step run needs it

    if type(sys_id) is SystemForms:
        return _given_step_functions(method, sys_id)
    kind = method.kernel
    if kind == "rk4":
        return _k.RK4[sys_id], None
    if kind == "symmetric2":
        return _k.SYMMETRIC2[sys_id], None
    if kind == "exact":
        if _k.EXACT[sys_id] is None:
            raise ValueError(f"system {sys_id} has no compiled exact flow")
        return _k.EXACT[sys_id], None
    if kind == "yoshida4":
        return _k.yoshida4_step, _k.SYMMETRIC2[sys_id]
    step = {"euler": _k.euler_step, "midpoint": _k.midpoint_step}[kind]
    return step, _k.RHS[sys_id]


def _given_step_functions(method: Method, forms: SystemForms):
    """:func:`step_functions` from a system's own compiled forms."""
    from . import kernels as _k

    kind = method.kernel
    if kind == "rk4":
        return forms.rk4, None
    if kind == "symmetric2":
        return forms_needed(forms, "symmetric step", forms.symmetric2), None
    if kind == "exact":
        return forms_needed(forms, "exact step", forms.exact_step), None
    if kind == "yoshida4":
        return _k.yoshida4_step, forms_needed(forms, "symmetric step", forms.symmetric2)
    step = {"euler": _k.euler_step, "midpoint": _k.midpoint_step}[kind]
    return step, forms.rhs


def get_method(name: str) -> Method:
    """The method called ``name``; ``ValueError`` listing the choices otherwise."""
    try:
        return METHODS[name]
    except KeyError:
        raise ValueError(f"method must be one of {', '.join(METHODS)}; got {name!r}") from None


def methods_for(system: Any) -> list[Method]:
    """The methods that apply to ``system`` (a :mod:`mechviz.dynamics.systems` adapter or its class; by
    name: ``methods_for(mechviz.dynamics.SYSTEMS[name])``), in the order of :data:`METHODS`."""
    return [m for m in METHODS.values() if m.applies_to(system)]
