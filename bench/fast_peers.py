"""The peers in their fastest documented form, each a solver reused across problems.

- **heyoka.py**: ``taylor_adaptive`` with the parameters as runtime parameters (``hy.par``), so
  that one compiled integrator serves every case of a system and tolerance, as heyoka's
  documentation advises for problems solved many times; built with and without
  ``fast_math=True`` (its documented option for speed). A solve sets time, state and
  parameters and calls ``propagate_until``.
- **CyRK**: ``nbsolve2_ivp`` called inside a numba ``njit`` function (the form CyRK's
  documentation shows for speed: no Python between the caller and the C++ solver), with a
  numba ``cfunc`` right-hand side that reads the parameters from its ``args`` pointer;
  methods DOP853, Vern8 and Vern7.
- **scipy**: ``odeint`` (LSODA in Fortran; the loop stays in Fortran and only the right-hand
  side calls back into Python, which makes it scipy's fastest here), the right-hand side in
  plain Python over ``math`` (the free body's: :func:`.handwritten.free_derivatives`, called
  from Python).

Every solver answers ``solve(y0, params, t_end, tol) -> (final state, steps)`` with
``rtol = atol = tol``; a failed solve raises. The benchmark measures each one's error against
the same references as ours (:mod:`mechviz.bench.fastest`).
"""

from __future__ import annotations

import math
from functools import cache

import numpy as np

from mechviz.dynamics.integrators.kernels import CYCLOTRON, HOOP

from .peer_equations import heyoka_equations
from .peers import _cyrk_rhs, not_importable

CYRK_METHODS = ("DOP853", "Vern8", "Vern7")


# --------------------------------------------------------------------------- heyoka
class HeyokaSolver:
    """One compiled ``taylor_adaptive`` per system, tolerance and ``fast_math``, reset per solve."""

    def __init__(self, sys_id: int, dim: int, n_pars: int, tol: float, fast_math: bool):
        import heyoka as hy

        self.sys_id = sys_id
        self.ta = hy.taylor_adaptive(
            heyoka_equations(sys_id),
            np.zeros(dim),
            tol=tol,
            pars=np.zeros(n_pars),
            fast_math=fast_math,
        )

    def solve(self, y0: np.ndarray, pars: np.ndarray, t_end: float) -> tuple[np.ndarray, int]:
        ta = self.ta
        ta.time = 0.0
        ta.state[:] = y0
        ta.pars[:] = pars
        out = ta.propagate_until(t_end)
        if int(out[0].value) != 0 and str(out[0]) != "taylor_outcome.time_limit":
            raise RuntimeError(f"heyoka: {out[0]}")
        return ta.state.copy(), int(out[3])


@cache
def heyoka_solver(sys_id: int, dim: int, n_pars: int, tol: float, fast_math: bool):
    return HeyokaSolver(sys_id, dim, n_pars, tol, fast_math)


# --------------------------------------------------------------------------- CyRK
@cache
def cyrk_caller():
    """The ``njit`` function that calls ``nbsolve2_ivp`` and keeps only the final state."""
    import numba as nb
    from CyRK import nbsolve2_ivp

    @nb.njit
    def final_state(addr, t_end, y0, method, tol, args, out):
        sol = nbsolve2_ivp(addr, (0.0, t_end), y0, method=method, rtol=tol, atol=tol, args=args)
        ok = sol.success
        steps = sol.steps_taken
        if ok:
            y = sol.y
            for j in range(out.size):
                out[j] = y[j, y.shape[1] - 1]
        sol.free()
        return steps if ok else -1

    return final_state


class CyrkSolver:
    """CyRK's ``nbsolve2_ivp`` from an ``njit`` caller, one method."""

    def __init__(self, sys_id: int, method: str):
        self.addr = np.uint64(_cyrk_rhs(sys_id).address)
        self.method = method
        self.call = cyrk_caller()

    def solve(
        self, y0: np.ndarray, params: np.ndarray, t_end: float, tol: float
    ) -> tuple[np.ndarray, int]:
        out = np.empty_like(y0)
        steps = self.call(self.addr, float(t_end), y0, self.method, float(tol), params, out)
        if steps < 0:
            raise RuntimeError(f"CyRK {self.method} failed at tol {tol:g}")
        return out, int(steps)


# --------------------------------------------------------------------------- scipy
def odeint_rhs(sys_id: int, params: np.ndarray):
    """The right-hand side as ``f(y, t)``: in plain Python over ``math``, but for the free body,
    whose Python callable is our compiled :func:`.handwritten.free_derivatives`."""
    p = [float(v) for v in params]
    if sys_id == CYCLOTRON:
        w = p[0]

        def f(y, t):
            return [y[3], y[4], y[5], w * y[4], -w * y[3], 0.0]

    elif sys_id == HOOP:
        M, m, ga = p[0], p[1], p[3] / p[2]
        m11, mg = 2.0 * M + m, (M + m) * ga

        def f(y, t):
            th1, th2, w1, w2 = y
            s, c = math.sin(th1 - th2), math.cos(th1 - th2)
            r1 = -m * s * w2 * w2 - mg * math.sin(th1)
            r2 = s * w1 * w1 - ga * math.sin(th2)
            det = m11 - m * c * c
            return [w1, w2, (r1 - m * c * r2) / det, (m11 * r2 - c * r1) / det]

    else:
        from .handwritten import free_derivatives

        i1, i2, i3 = p

        def f(y, t):
            return free_derivatives(*y, i1, i2, i3)

    return f


def odeint_solve(
    sys_id: int, y0: np.ndarray, params: np.ndarray, t_end: float, tol: float
) -> tuple[np.ndarray, int]:
    from scipy.integrate import odeint

    y, info = odeint(
        odeint_rhs(sys_id, params),
        y0,
        [0.0, t_end],
        rtol=tol,
        atol=tol,
        mxstep=10**7,
        full_output=True,
    )
    if info["message"] != "Integration successful.":
        raise RuntimeError(f"odeint: {info['message']}")
    return y[-1].copy(), int(info["nst"][-1])


def available() -> dict[str, str | None]:
    """Per peer package, by its module's name: ``None`` if it imports, else why not."""
    return {name: not_importable(name) for name in ("heyoka", "CyRK")}
