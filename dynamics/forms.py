"""A system's compiled forms handed to the integrators, rather than looked up by a compiled id.

The shipped systems' compiled forms sit in tables indexed by their compiled id
(:mod:`mechviz.dynamics.ids`, :mod:`mechviz.dynamics.integrators.kernels`), and the adaptive
loops are compiled once per id and cached on disk. A system registered at run time
(:func:`mechviz.dynamics.registry.register`) cannot take a place in those tables without editing
them, so its adapter carries a :class:`SystemForms` as its ``sys_id`` instead: the compiled
functions themselves, generated from its :class:`~mechviz.dynamics.codegen.equations.Equations`
(:meth:`SystemForms.from_equations`). Every place that reads a compiled form by id asks
:func:`rhs_of` and its kin, which answer from the tables for an id and from the forms otherwise;
numba specialises the fixed-step drivers and the Runge-Kutta runner on a function argument (as
it does for the shipped ones), and Taylor's method runs the given expansion
(:func:`mechviz.dynamics.integrators.taylor.run_taylor_given`). Loops given a function are
compiled once per process (about 0.3-3 s each) and never cached on disk
(:mod:`mechviz.dynamics.integrators.kernels` says why).

Importable without numba (as :mod:`mechviz.dynamics.taylor_order`, which reads the Taylor cost
model from here, must be): the compiled functions are only held, never called, here.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # sympy only where the forms are generated
    from .codegen.equations import Equations

#: The Taylor cost model [ns] a registered system takes unless it measures its own: one step as
#: ``c0 + c1 p + c2 p^2`` at order ``p``, between the shipped hoop's and free body's
#: (:data:`mechviz.dynamics.ids.COMPILED`); only the ratios choose the order.
TAYLOR_COST = (60.0, 8.0, 1.0)


@dataclass(frozen=True, eq=False)
class SystemForms:
    """The compiled forms of one system of ``dim`` state components, as the integrators call
    them (:mod:`mechviz.dynamics.integrators.kernels` gives the calling conventions):

    - ``rhs(y, p, out)``: the right-hand side (Euler, implicit midpoint, the Runge-Kutta pairs,
      scipy's solvers, the reference runs);
    - ``rk4(y, p, h) -> 4``: the classical RK4 step in scalar locals;
    - ``expand(A, p, order)`` and ``rows``: the Taylor coefficients' recurrences and the rows of
      the array they fill (None, 0: Taylor's method does not apply);
    - ``symmetric2(y, p, h) -> evals``: the system's own symmetric second-order step, which
      Yoshida's method composes (None: none; the adapter's ``symmetric_step`` names it);
    - ``exact_step(y, p, h) -> 0``: the compiled exact flow, for a closed-form system run at a
      fixed step (None: none);
    - ``taylor_cost`` [ns]: one Taylor step as ``c0 + c1 p + c2 p^2`` at order ``p``, the cost
      model from which Taylor's method picks its order (:func:`~mechviz.dynamics.taylor_order.
      order_for`; default :data:`TAYLOR_COST`); ``entire``: its solutions are entire with
      coefficients falling as ``1/k!``.

    Compared and hashed by identity: two forms are the same only if they are one object (a
    loop compiled for one is not reused for another)."""

    name: str
    dim: int
    rhs: Callable[..., Any]
    rk4: Callable[..., Any]
    expand: Callable[..., Any] | None = None
    rows: int = 0
    symmetric2: Callable[..., Any] | None = None
    exact_step: Callable[..., Any] | None = None
    taylor_cost: tuple[float, float, float] = TAYLOR_COST
    entire: bool = False

    def __post_init__(self) -> None:
        if self.dim < 1:
            raise ValueError(f"{self.name}: the state has at least one component, got {self.dim}")
        if not (callable(self.rhs) and callable(self.rk4)):
            raise TypeError(f"{self.name}: rhs and rk4 must be compiled functions")
        if (self.expand is None) != (self.rows == 0) or (self.rows and self.rows < self.dim):
            raise ValueError(
                f"{self.name}: an expansion comes with its rows (at least the state's {self.dim})"
            )
        cost = tuple(float(c) for c in self.taylor_cost)
        if len(cost) != 3 or not all(math.isfinite(c) and c >= 0 for c in cost) or sum(cost) <= 0:
            raise ValueError(f"{self.name}: taylor_cost is three non-negative costs [ns]")
        object.__setattr__(self, "taylor_cost", cost)

    @classmethod
    def from_equations(
        cls,
        eq: Equations,
        *,
        symmetric2: Callable[..., Any] | None = None,
        exact_step: Callable[..., Any] | None = None,
        taylor_cost: tuple[float, float, float] = TAYLOR_COST,
        entire: bool = False,
    ) -> SystemForms:
        """Every form the generator makes from ``eq`` (:mod:`mechviz.dynamics.codegen`: the
        right-hand side, the RK4 step, the Taylor recurrences), written and imported once per
        equations (compiled on first call), plus the hand-written steps given."""
        from .codegen.rhs import generated_rhs
        from .codegen.series import generated_expand
        from .codegen.steps import generated_rk4

        expand, rows = generated_expand(eq)
        return cls(
            eq.name,
            eq.dim,
            generated_rhs(eq),
            generated_rk4(eq),
            expand,
            rows,
            symmetric2,
            exact_step,
            taylor_cost,
            entire,
        )


def is_given(sys_id: Any) -> bool:
    """Whether ``sys_id`` (an adapter's) is a system's own :class:`SystemForms` rather than a
    compiled id of the kernels' tables."""
    return type(sys_id) is SystemForms


def forms_needed(sys_id: Any, form: str, value: Any) -> Any:
    """``value`` (the form ``form`` of ``sys_id``'s), or :class:`ValueError` saying the system
    has no such form (a method asked of a system that did not give what it needs)."""
    if value is None:
        raise ValueError(f"{sys_id.name}: no compiled {form} was given for this system")
    return value
