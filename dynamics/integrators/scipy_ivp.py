"""scipy's solvers behind the same interface as ours, on the same compiled right-hand side.

Each call integrates every ensemble member from ``t0`` to ``t1`` with ``solve_ivp`` (RK45,
DOP853, Radau, LSODA) or ``odeint``. The right-hand side handed to scipy is our compiled one, so
the comparison measures the solvers, not two implementations of the physics.
"""

from __future__ import annotations

import numpy as np

from ..forms import SystemForms
from .kernels import rhs_of


def _make_fun(sys_id: int | SystemForms, p: np.ndarray, d: int):
    rhs = rhs_of(sys_id)
    rhs(np.zeros(d), p, np.empty(d))  # compile (or load) before scipy's first call

    def fun(t, y):
        # Call the compiled right-hand side's dispatcher directly: a jitted wrapper that takes
        # rhs as an argument makes numba type it on every call, several times the cost of the
        # right-hand side itself, which the benchmark would then charge to scipy.
        out = np.empty(d)
        rhs(np.ascontiguousarray(y, dtype=np.float64), p, out)
        return out

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
    fun = _make_fun(sys_id, p, d)
    nfev = steps = 0
    for i in range(n):
        if name == "odeint":
            sol, info = odeint(
                fun,
                Y[i],
                [t0, t1],
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
