"""The peers in their fastest documented form, each a solver reused across problems.

- **heyoka.py**: ``taylor_adaptive`` in two forms, each built with and without
  ``fast_math=True`` (its documented option for speed): the parameters as runtime parameters
  (``hy.par``), so that one compiled integrator serves every case of a system and tolerance, as
  heyoka's documentation advises for problems solved many times (:class:`HeyokaSolver`); and one
  parameter set's constants built into the expressions, an integrator compiled per case
  (:class:`HeyokaBuiltinSolver`, whose construction is timed). A solve sets time, state (and
  parameters) and calls ``propagate_until``.
- **CyRK**: ``nbsolve2_ivp`` called inside a numba ``njit`` function (the form CyRK's
  documentation shows for speed: no Python between the caller and the C++ solver), with a
  numba ``cfunc`` right-hand side that reads the parameters from its ``args`` pointer;
  methods DOP853, Vern8 and Vern7.
- **scipy**: ``odeint`` (LSODA in Fortran; the loop stays in Fortran and only the right-hand
  side calls back into Python, which makes it scipy's fastest here), the right-hand side the
  product's generated one inside an ``njit`` function (:func:`odeint_rhs`) or called from a
  Python function as the product calls it (:func:`odeint_closure`, the faster of the two).

Every solver answers ``solve(y0, params, t_end, tol) -> (final state, steps)`` with
``rtol = atol = tol``; a failed solve raises. The benchmark measures each one's error against
the same references as ours (:mod:`mechviz.bench.fastest`).
"""

from __future__ import annotations

import time
from functools import cache

import numpy as np

from .peer_equations import heyoka_equations
from .peers import _cyrk_rhs, _sizes, not_importable

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


def _empty_heyoka_cache(hy) -> None:
    """Empty heyoka's in-memory cache of compiled code, so that building an integrator again
    compiles it again, as a new parameter set would (a rebuild of the same one is a cache hit)."""
    clear = getattr(getattr(hy, "llvm_state", None), "clear_memcache", None)
    if clear is not None:
        clear()


class HeyokaBuiltinSolver:
    """One compiled ``taylor_adaptive`` per parameter set, tolerance and ``fast_math``, the
    constants of :func:`~.peer_equations.heyoka_pars` built into its expressions; reset per
    solve. ``construction_s``: the wall seconds ``taylor_adaptive`` took to build it (Taylor
    decomposition and LLVM compilation, heyoka's cache of compiled code emptied first); the
    expressions are made before the clock starts (a user writes them once, as a function of the
    constants)."""

    def __init__(self, sys_id: int, constants: np.ndarray, dim: int, tol: float, fast_math: bool):
        import heyoka as hy

        self.sys_id = sys_id
        eqs = heyoka_equations(sys_id, constants)
        _empty_heyoka_cache(hy)
        t0 = time.perf_counter()
        self.ta = hy.taylor_adaptive(eqs, np.zeros(dim), tol=tol, fast_math=fast_math)
        self.construction_s = time.perf_counter() - t0

    def solve(self, y0: np.ndarray, t_end: float) -> tuple[np.ndarray, int]:
        ta = self.ta
        ta.time = 0.0
        ta.state[:] = y0
        out = ta.propagate_until(t_end)
        if int(out[0].value) != 0 and str(out[0]) != "taylor_outcome.time_limit":
            raise RuntimeError(f"heyoka: {out[0]}")
        return ta.state.copy(), int(out[3])


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
@cache
def odeint_rhs(sys_id: int):
    """The right-hand side as odeint calls it, ``f(y, t, p) -> y'`` (``p`` the kernel
    parameters, passed as odeint's ``args``): an ``njit`` function around the product's
    generated right-hand side (:data:`mechviz.dynamics.integrators.kernels.RHS`). Compiled,
    odeint's callback costs 2-3x less than the same right-hand side in plain Python over
    ``math``; one compiled function serves every case of a system (the parameters are an
    argument, not captured)."""
    from mechviz.dynamics._jit import njit
    from mechviz.dynamics.integrators.kernels import RHS

    rhs = RHS[sys_id]

    @njit
    def f(y, t, p):
        out = np.empty_like(y)
        rhs(y, p, out)
        return out

    return f


def odeint_closure(sys_id: int, params: np.ndarray):
    """The right-hand side as the product hands it to scipy (``Simulation``'s scipy methods):
    a Python function ``f(y, t)`` calling the compiled right-hand side, the parameters bound.
    Measured against :func:`odeint_rhs` on the hoop and the disk at 1e-9 (``odeint``, and
    ``solve_ivp``'s DOP853 and LSODA), it is the faster by 4-10 %: a call from Python into an
    ``njit`` function that returns a new array costs about 0.15 us more (boxing the array) than
    a Python call into one that fills an array given to it."""
    from mechviz.dynamics.integrators.kernels import RHS

    rhs = RHS[sys_id]
    p = np.ascontiguousarray(params, dtype=np.float64)
    d = _sizes(sys_id)[0]

    def f(y, t):
        out = np.empty(d)
        rhs(y, p, out)
        return out

    return f


def odeint_solve(
    sys_id: int,
    y0: np.ndarray,
    params: np.ndarray,
    t_end: float,
    tol: float,
    fun=None,
) -> tuple[np.ndarray, int]:
    """``odeint`` from ``y0`` to ``t_end``, its right-hand side :func:`odeint_rhs` (the
    parameters passed as its ``args``) or ``fun(y, t)`` (:func:`odeint_closure`)."""
    from scipy.integrate import odeint

    if fun is None:
        fun, args = odeint_rhs(sys_id), (np.ascontiguousarray(params, dtype=np.float64),)
    else:
        args = ()
    y, info = odeint(
        fun,
        y0,
        [0.0, t_end],
        args=args,
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
