"""scipy's solvers behind the same interface as ours, on the same compiled right-hand side.

Each call integrates every ensemble member from ``t0`` to ``t1`` with ``solve_ivp`` (RK45,
DOP853, Radau, LSODA) or ``odeint``. The right-hand side handed to scipy is our compiled one, so
the comparison measures the solvers, not two implementations of the physics; it is called
through a compiled wrapper (:func:`compiled_fun`), so that no Python runs between scipy and the
right-hand side.
"""

from __future__ import annotations

from functools import cache

import numpy as np

from .._jit import njit
from ..forms import SystemForms
from .kernels import rhs_of


@cache
def _wrapper(rhs):
    """``fun(t, y, p) -> y'`` compiled around the compiled right-hand side ``rhs(y, p, out)``
    (one per right-hand side and process; not cached on disk, a closure)."""

    # rhs is a free variable, typed once at compilation: a wrapper taking rhs as an argument
    # would make numba type it on every call, several times the right-hand side's own cost.
    @njit
    def fun(t, y, p):
        out = np.empty_like(y)
        rhs(y, p, out)
        return out

    return fun


def compiled_fun(sys_id: int | SystemForms, p: np.ndarray, d: int):
    """The right-hand side as scipy calls it, ``fun(t, y, p) -> y'`` (``p``, the kernel
    parameters, passed through scipy's ``args``; ``tfirst`` for odeint), compiled for a state of
    ``d`` components before scipy's first call. Against a Python function calling the compiled
    right-hand side, one call costs about 0.3 us less, measured on the hoop (PLACEHOLDER)."""
    fun = _wrapper(rhs_of(sys_id))
    fun(0.0, np.zeros(d), p)  # compile (for these argument types) before scipy's first call
    return fun


def advance_scipy(
    name: str,
    sys_id: int | SystemForms,
    p: np.ndarray,
    Y: np.ndarray,
    t0: float,
    t1: float,
    rtol: float,
    atol: float,
) -> tuple[int, int, str | None]:
    """Advance ``Y`` (N, d) in place; returns ``(nfev, steps, failure message or None)``."""
    # Imported here: scipy.integrate takes about 0.1 s to import, which a process that never
    # calls scipy's solvers need not pay before its first answer.
    from scipy.integrate import odeint, solve_ivp

    n, d = Y.shape
    p = np.ascontiguousarray(p, dtype=np.float64)
    fun = compiled_fun(sys_id, p, d)
    nfev = steps = 0
    for i in range(n):
        if name == "odeint":
            sol, info = odeint(
                fun,
                Y[i],
                [t0, t1],
                args=(p,),
                rtol=rtol,
                atol=atol,
                tfirst=True,
                full_output=True,
                mxstep=10**7,
            )
            nfev += int(info["nfe"][-1])
            steps += int(info["nst"][-1])
            if info["message"] != "Integration successful.":
                return nfev, steps, f"odeint: {info['message']}"
            Y[i] = sol[-1]
        else:
            sol = solve_ivp(
                fun,
                (t0, t1),
                Y[i],
                method=name,
                args=(p,),
                rtol=rtol,
                atol=atol,
                t_eval=None,
                dense_output=False,
            )
            nfev += int(sol.nfev)
            steps += len(sol.t) - 1
            if sol.status != 0:
                return nfev, steps, f"solve_ivp {name}: {sol.message}"
            Y[i] = sol.y[:, -1]
        if not np.all(np.isfinite(Y[i])):
            return nfev, steps, "state became non-finite"
    return nfev, steps, None
