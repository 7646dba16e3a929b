"""What a :class:`~mechviz.dynamics.simulation.Simulation` takes from its settings alone, made
once and kept, and the driver's numba side, imported when a run first needs it.

A run built per solve (a scan of starts, a benchmark, a shooting method) is mostly the same
system, method and tolerance again: what follows from them alone (the method looked up and
checked against the system, the step control, the kernel parameters) is checked when first
made and then taken as it is (:func:`plan`), so that building the run costs little more than
checking its start. Importable without numba.
"""

from __future__ import annotations

from .integrators.base import Method, get_method, methods_for
from .params import SettingError
from .steps import Fixed, Step, Tolerance, shared_step_control
from .systems import _FROZEN_KINDS, System, shared_kernel_params

__all__ = ["compiled", "plan"]


class _Compiled:
    """numba's side of the driver (the fixed-step loops, the Runge-Kutta pairs, scipy's
    methods), imported when a run first needs it: a Taylor run of a shipped system may be
    answered without numba (:mod:`.integrators.taylor_carry`)."""

    def __getattr__(self, name: str):
        from .integrators import kernels, rk, scipy_ivp  # (numba)

        vars(self).update(
            kernels=kernels,
            RKCarry=rk.RKCarry,
            load_pair=rk.load_pair,
            run_rk=rk.run_rk,
            advance_scipy=scipy_ivp.advance_scipy,
        )
        return vars(self)[name]


compiled = _Compiled()

#: What a Simulation takes from its system, method and step settings alone, checked when first
#: made: ``(system, method, method given, step, dt, rtol, atol, kernel parameters)``, by
#: (system, method, dt, rtol, atol) given as plain values (a frozen adapter of the shipped kinds,
#: a method by name or object, floats or ``None``). A run built per solve of a system and
#: settings already seen takes it as it is. Keyed by identities; the entry holds the system and
#: the method, so that neither identity is reused while it is stored.
_PLANS: dict[tuple, tuple] = {}
_PLAIN = (float, type(None))


def plan(system: System, method: str | Method, dt, rtol, atol, step: Step | None) -> tuple:
    """The plan (see :data:`_PLANS`), looked up or made; ``SettingError`` naming the field."""
    cached = (
        step is None
        and type(system) in _FROZEN_KINDS
        and type(dt) in _PLAIN
        and type(rtol) in _PLAIN
        and type(atol) in _PLAIN
    )
    if cached:
        key = (id(system), method if type(method) is str else id(method), dt, rtol, atol)
        entry = _PLANS.get(key)
        # (a name is compared by the key; a Method object by identity)
        if entry is not None and entry[0] is system and (type(method) is str or entry[2] is method):
            return entry
    m = method if isinstance(method, Method) else get_method(method)
    if not m.applies_to(system):
        raise SettingError(
            "method",
            f"method {m.name!r} does not apply to {system.name}; "
            f"choose one of {', '.join(x.name for x in methods_for(system))}",
        )
    if step is None:
        step = shared_step_control(m, dt, rtol, atol)
    fixed, tol = isinstance(step, Fixed), isinstance(step, Tolerance)
    entry = (
        system,
        m,
        method,
        step,
        step.dt if fixed else None,
        step.rtol if tol else None,
        step.atol if tol else None,
        shared_kernel_params(system),  # read only, as the kernels do
    )
    if cached:
        if len(_PLANS) >= 1024:  # a scan over settings or systems: keep the table bounded
            _PLANS.clear()
        _PLANS[key] = entry
    return entry
