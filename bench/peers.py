"""The integrators a numerical-methods user would pick for speed, on our benchmark problems.

- **CyRK** (``pip install CyRK``): compiled Runge-Kutta in C++. ``nbsolve2_ivp`` with a numba
  ``cfunc`` right-hand side (the C callback CyRK calls without Python in the loop), methods DOP853,
  Vern8 and Vern7; and ``pysolve_ivp`` (DOP853) with the same right-hand side as a jitted Python
  callable.
- **heyoka.py** (``pip install heyoka``): Taylor's method compiled with LLVM. ``taylor_adaptive``
  with the equations written in its expression system and the tolerance swept; the integrator is
  built (compiled) once per tolerance, untimed, and each timed run resets time and state and
  calls ``propagate_until(T)``.

Each peer integrates the same equations with the same parameters (the right-hand sides call the
product's generated right-hand side, or are heyoka's expressions generated from the same
equations, :mod:`.peer_equations`), from the same initial state over the same span; errors are
measured against the same references. A peer that
is not installed is reported with the reason instead of run.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from .peer_equations import heyoka_equations, heyoka_pars

if TYPE_CHECKING:  # for annotations only: the problems module imports this one at run time
    from .problems import Problem

PEERS = ("heyoka", "cyrk-dop853", "cyrk-vern8", "cyrk-vern7", "cyrk-py-dop853")


@dataclass
class PeerRun:
    """A prepared peer: ``run()`` integrates the problem once and returns the final state."""

    run: Callable[[], np.ndarray]
    nfev: Callable[[], int]


def not_importable(module: str) -> str | None:
    """``None`` if ``module`` imports, else why not."""
    try:
        __import__(module)
    except Exception as exc:  # not installed, or installed but broken
        return f"{module} not importable ({exc.__class__.__name__}: {exc})"
    return None


def available() -> dict[str, str | None]:
    """Per peer package (as :func:`package_of` names it): ``None`` if it imports, else why not."""
    return {"heyoka": not_importable("heyoka"), "cyrk": not_importable("CyRK")}


def package_of(peer: str) -> str:
    return "heyoka" if peer.startswith("heyoka") else "cyrk"


def versions() -> dict[str, str]:
    out = {}
    for name, module in (("heyoka", "heyoka"), ("CyRK", "CyRK")):
        try:
            out[name] = __import__(module).__version__
        except Exception:
            pass
    return out


# --------------------------------------------------------------------------- heyoka
def heyoka_run(problem: Problem, tol: float, *, fp_type=None) -> PeerRun:
    """heyoka's ``taylor_adaptive`` at ``tol`` (built now; each ``run()`` restarts at t = 0)."""
    import heyoka as hy

    sid = problem.system.sys_id
    y0 = problem.y0
    kw = {}
    if fp_type is not None:
        kw["fp_type"] = fp_type
        y0 = np.array(problem.state0, dtype=fp_type)
        tol = fp_type(tol)
    pars = heyoka_pars(sid, problem.system.kernel_params()).astype(fp_type or float)
    ta = hy.taylor_adaptive(heyoka_equations(sid), y0, tol=tol, pars=pars, **kw)
    t_end = problem.t_end if fp_type is None else fp_type(problem.t_end)
    steps = [0]

    def run() -> np.ndarray:
        ta.time = 0.0 if fp_type is None else fp_type(0)
        ta.state[:] = y0
        out = ta.propagate_until(t_end)
        steps[0] = int(out[3])
        return ta.state.copy()

    return PeerRun(run, lambda: steps[0])


# --------------------------------------------------------------------------- CyRK
_CFUNCS: dict[int, object] = {}


@functools.cache
def _sizes(sys_id: int) -> tuple[int, int]:
    """The state's dimension and the number of kernel parameters of the system ``sys_id``."""
    from mechviz.dynamics.codegen.equations import EQUATIONS

    eq = EQUATIONS[sys_id]()
    return eq.dim, len(eq.params)


def _cyrk_rhs(kind: int):
    """The right-hand side as ``f(dy, t, y, args)`` on raw pointers (CyRK's C callback): the
    product's generated right-hand side (:data:`mechviz.dynamics.integrators.kernels.RHS`)
    called on the pointers viewed as arrays, ``args`` the system's kernel parameters. A numba
    ``cfunc``, so it needs numba alone (CyRK only to be called)."""
    if kind in _CFUNCS:
        return _CFUNCS[kind]
    import numba as nb

    from mechviz.dynamics.integrators.kernels import RHS

    rhs = RHS[kind]
    d, n_p = _sizes(kind)

    def f(dy, t, y, args):
        rhs(nb.carray(y, (d,)), nb.carray(args, (n_p,)), nb.carray(dy, (d,)))

    sig = nb.types.void(
        nb.types.CPointer(nb.types.float64),
        nb.types.float64,
        nb.types.CPointer(nb.types.float64),
        nb.types.CPointer(nb.types.float64),
    )
    cf = nb.cfunc(sig)(f)
    _CFUNCS[kind] = cf
    return cf


def cyrk_run(problem: Problem, tol: float, method: str = "DOP853") -> PeerRun:
    """CyRK's ``nbsolve2_ivp`` with a compiled C callback."""
    from CyRK import nbsolve2_ivp

    addr = _cyrk_rhs(problem.system.sys_id).address
    p = np.ascontiguousarray(problem.system.kernel_params(), dtype=np.float64)
    y0 = problem.y0
    span = (0.0, float(problem.t_end))
    steps = [0]

    def run() -> np.ndarray:
        r = nbsolve2_ivp(addr, span, y0, method=method, rtol=tol, atol=tol, args=p)
        try:
            if not r.success:
                raise RuntimeError(f"CyRK {method}: {r.message}")
            steps[0] = int(r.steps_taken)
            return np.array(r.y[:, -1])
        finally:
            r.free()

    return PeerRun(run, lambda: steps[0])


def cyrk_py_run(problem: Problem, tol: float) -> PeerRun:
    """CyRK's ``pysolve_ivp`` (DOP853) with a jitted right-hand side called from C++ via Python."""
    from CyRK import pysolve_ivp

    from mechviz.dynamics.integrators.kernels import RHS

    rhs = RHS[problem.system.sys_id]
    p = np.ascontiguousarray(problem.system.kernel_params(), dtype=np.float64)

    def f(dy, t, y):
        rhs(y, p, dy)

    y0 = problem.y0
    span = (0.0, float(problem.t_end))
    steps = [0]

    def run() -> np.ndarray:
        r = pysolve_ivp(f, span, y0, method="DOP853", rtol=tol, atol=tol, pass_dy_as_arg=True)
        if not r.success:
            raise RuntimeError(f"CyRK pysolve_ivp: {r.message}")
        steps[0] = int(r.steps_taken)
        return np.array(r.y[:, -1])

    return PeerRun(run, lambda: steps[0])


def prepare(peer: str, problem: Problem, tol: float) -> PeerRun:
    if peer == "heyoka":
        return heyoka_run(problem, tol)
    if peer == "cyrk-py-dop853":
        return cyrk_py_run(problem, tol)
    method = {"cyrk-dop853": "DOP853", "cyrk-vern8": "Vern8", "cyrk-vern7": "Vern7"}[peer]
    return cyrk_run(problem, tol, method)


def compile_ahead(problem: Problem) -> None:
    """Compile what the installed peers compile in every process (CyRK's ``nbsolve2_ivp`` is a
    numba function without an on-disk cache), on ``problem``, before anything is timed."""
    if available()["cyrk"] is None:
        cyrk_run(problem, 1e-3).run()


def tolerances(peer: str, settings_tolerances: tuple[float, ...]) -> tuple[float, ...]:
    """The tolerance sweep (the same grid as ours; heyoka's error stays near its tolerance, so
    its sweep stops one decade past the tightest target)."""
    return tuple(t for t in settings_tolerances if t >= 1e-16 and math.isfinite(t))


# Left out of ``--quick`` runs: in full runs neither was the fastest peer at any target.
QUICK_SKIP = ("cyrk-vern7", "cyrk-py-dop853")
