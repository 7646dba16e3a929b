"""A compiled problem solved many times: Taylor's method from a start to a time, nothing else.

:class:`~mechviz.dynamics.simulation.Simulation` is a run: it keeps time, counters, energy and the
error against a reference, and builds all of that for each start. A user who solves the same
system from many starts or with many parameter sets (a parameter scan, a shooting method, a
benchmark) needs none of it: :class:`Solver` is built once for a system kind and a tolerance,
and each :meth:`Solver.solve` is one call into compiled code that takes the start and the
parameters as arrays, so changing them costs nothing but passing them. The same compiled
function, :func:`solve_taylor`, can be called from a numba ``njit`` function (no Python between
solves at all).

The steps are :mod:`mechviz.dynamics.integrators.taylor`'s, from ``t = 0`` to ``t_end`` (the last step
evaluated at ``t_end`` by its series): the same final state as a ``Simulation`` advanced to
``t_end`` in one call.
"""

from __future__ import annotations

import math

import numpy as np

from . import params as _v
from ._jit import njit
from .forms import SystemForms, is_given
from .integrators.kernels import OK
from .integrators.taylor import _advance_member, controls, order_for, run_taylor_given
from .params import SettingError
from .spec import checked_state
from .systems import System, shared_kernel_params

__all__ = ["Solver", "solve_taylor"]


@njit(cache=True)
def solve_taylor(sys_id, y0, p, t_end, rtol, atol, order, a, out):
    """``out`` = the state at ``t_end`` from ``y0`` at 0 (kernel parameters ``p``), Taylor's
    method at ``order`` with steps ``rho exp(-a - 0.7 / (order - 1))``; returns the steps taken,
    ``-1`` if the state stopped being finite (``out`` then holds the last state reached), ``-2``
    if ``y0``, ``p`` or ``t_end`` is not finite (``out`` untouched)."""
    d = y0.size
    if not math.isfinite(t_end):
        return -2
    for v in y0:
        if not math.isfinite(v):
            return -2
    for v in p:
        if not math.isfinite(v):
            return -2
    Y = np.empty((1, d))
    for j in range(d):
        Y[0, j] = y0[j]
    stats = np.zeros((1, 3), np.int64)
    carry = (np.empty((1, d, order + 1)), np.zeros(1), np.zeros(1), np.zeros(1), np.empty((1, d)))
    ctl = controls(rtol, atol, order, a)
    code = _advance_member(sys_id, 0, Y, p, 0.0, t_end, order, ctl, stats, carry)
    for j in range(d):
        out[j] = Y[0, j]
    return stats[0, 1] if code == OK else -1


#: What a :class:`Solver` takes from its system and tolerances, by (system, rtol, atol) given
#: as plain floats or ``None``: ``(system, sys_id, rtol, atol, order, a, solve)``, validated when first
#: made. A new Solver of a system and tolerances already seen (a user who builds one per
#: problem) takes it as it is. Keyed by the system's identity; the entry holds the system, so
#: that its identity is not reused while it is stored.
_PLANS: dict[tuple, tuple] = {}
_PLAIN = (float, type(None))


def _plan(system: System, rtol: float | None, atol: float | None) -> tuple:
    """``(system, sys_id, rtol, atol, order, a, solve)``, the settings checked (``SettingError``
    naming the field); ``solve``: :func:`solve_taylor`, or for a registered system (its own
    forms, :class:`~mechviz.dynamics.forms.SystemForms`) :func:`_solve_given`."""
    rtol = 1e-9 if rtol is None else _v.positive("rtol", rtol)
    atol = rtol if atol is None else _v.positive("atol", atol)
    if system.sys_id is None or (is_given(system.sys_id) and system.sys_id.expand is None):
        raise SettingError("method", f"Taylor's method does not apply to {system.name}")
    given = is_given(system.sys_id)
    sys_id = system.sys_id if given else int(system.sys_id)
    order, a = order_for(float(rtol), float(atol), sys_id)
    solve = _solve_given if given else solve_taylor
    return system, sys_id, float(rtol), float(atol), order, a, solve


def _solve_given(forms: SystemForms, y0, p, t_end, rtol, atol, order, a, out) -> int:
    """:func:`solve_taylor` for a registered system, with its own expansion
    (:func:`~mechviz.dynamics.integrators.taylor.run_taylor_given`: the same steps)."""
    if not (math.isfinite(t_end) and np.isfinite(y0).all() and np.isfinite(p).all()):
        return -2
    d = y0.size
    Y = np.array(y0, dtype=np.float64).reshape(1, d)
    stats, status = np.zeros((1, 3), np.int64), np.zeros(3, np.int64)
    carry = (np.empty((1, d, order + 1)), np.zeros(1), np.zeros(1), np.zeros(1), np.empty((1, d)))
    args = (Y, p, 0.0, t_end, rtol, atol, order, a, stats, status, carry)
    run_taylor_given(forms.expand, forms.rows, *args)
    out[:] = Y[0]
    return int(stats[0, 1]) if status[0] == OK else -1


class Solver:
    """Solve ``system``'s equations with Taylor's method at ``rtol``, ``atol`` (default ``1e-9``
    and ``rtol``), from any start and with any parameters of that system kind.

    ``solve(t_end, state=None, params=None)`` returns the state at ``t_end`` [s] from ``state``
    at 0 (default: the system's ``default_state()``), with ``params`` the system's kernel
    parameters (``System.kernel_params()``; default: ``system``'s). The returned array is this
    solver's own and is overwritten by the next solve (copy it to keep it). ``steps`` is the
    last solve's step count. A start or parameters of the wrong size, or not finite, raise
    ``ValueError``; a solve whose state stops being finite raises ``FloatingPointError``.

    Once a Solver of the same system object and tolerances has been built, building another
    costs under a microsecond: what depends only on them is kept, checked, from the first, and
    its output array is made on the first solve, so a Solver per problem costs little more than
    handing a kept one a new start.
    """

    def __init__(
        self,
        system: System,
        *,
        rtol: float | None = None,
        atol: float | None = None,
    ) -> None:
        if type(rtol) in _PLAIN and type(atol) in _PLAIN:  # hashable, and compared as numbers
            key = (id(system), rtol, atol)
            plan = _PLANS.get(key)
            if plan is None or plan[0] is not system:
                plan = _plan(system, rtol, atol)
                if len(_PLANS) >= 1024:  # a scan over tolerances: keep the table bounded
                    _PLANS.clear()
                _PLANS[key] = plan
        else:
            plan = _plan(system, rtol, atol)
        self.system, self.sys_id, self.rtol, self.atol, self.order, self.a, self._solve = plan

    # What a new Solver starts with, as class attributes (set on the instance when they change),
    # and its output array made on first use: a Solver built per problem pays for neither.
    _state0: np.ndarray | None = None  # the defaults, worked out when first used
    _params: np.ndarray | None = None
    steps = 0
    #: Each member's steps in the last :meth:`solve_many` (replaced, never written in place).
    member_steps = np.zeros(0, np.int64)

    def __getattr__(self, name: str):
        if name != "_out":
            raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")
        self._out = np.empty(len(self.system.state_names))
        return self._out

    @property
    def state0(self) -> np.ndarray:
        """The system's default start (used when ``solve`` is given none)."""
        if self._state0 is None:
            s = checked_state(self.system, self.system.default_state())
            self._state0 = np.ascontiguousarray(s, dtype=np.float64)
        return self._state0

    @property
    def params(self) -> np.ndarray:
        """The system's kernel parameters (used when ``solve`` is given none; shared with every
        run of the same system: read, never write)."""
        if self._params is None:
            self._params = shared_kernel_params(self.system)
        return self._params

    @staticmethod
    def _array(name: str, value, size: int) -> np.ndarray:
        arr = np.ascontiguousarray(value, dtype=np.float64)
        if arr.shape != (size,):
            raise ValueError(f"{name} must be {size} finite numbers; got {value!r}")
        return arr  # finiteness is checked in the compiled solve

    def solve(self, t_end: float, state=None, params=None) -> np.ndarray:
        y0 = self.state0 if state is None else self._array("state", state, self._out.size)
        p = self.params if params is None else self._array("params", params, self.params.size)
        steps = self._solve(
            self.sys_id, y0, p, float(t_end), self.rtol, self.atol, self.order, self.a, self._out
        )
        if steps == -2:
            raise ValueError("state, params and t_end must be finite")
        if steps < 0:
            raise FloatingPointError(f"taylor at rtol {self.rtol:g}: the state is not finite")
        self.steps = int(steps)
        return self._out

    def solve_many(self, t_end, states, params=None) -> np.ndarray:
        """The states at ``t_end`` [s] of many problems: ``states`` (N, d) the starts at 0,
        ``params`` the kernel parameters, ``(N, P)`` one row per problem or ``(P,)`` (default:
        the system's) shared, ``t_end`` one time or ``(N,)`` one per problem. Returns a new
        (N, d) array.

        A member that fails spoils no other: its row is NaN if its start, parameters or end
        are not finite, and the last state reached if its state stopped being finite;
        :attr:`member_steps` (N,) holds each member's steps, ``-2`` and ``-1`` for those. Raises
        ``ValueError`` only for arrays of the wrong shape. The hoop and the free body run
        :data:`~mechviz.dynamics.integrators.taylor_batch.LANES` members at a time
        (:func:`~mechviz.dynamics.integrators.taylor_batch.solve_batch`); the charge (whose
        steps are taken in closed form) and registered systems one after another with
        :meth:`solve`'s compiled solve."""
        d = self._out.size
        y0 = np.ascontiguousarray(states, dtype=np.float64)
        if y0.ndim != 2 or y0.shape[1] != d:
            raise ValueError(f"states must be (N, {d}); got shape {np.shape(states)}")
        n, size = len(y0), self.params.size
        p = self.params if params is None else np.asarray(params, dtype=np.float64)
        if p.shape == (size,):
            p = np.broadcast_to(p, (n, size))
        elif p.shape != (n, size):
            raise ValueError(f"params must be ({size},) or ({n}, {size}); got {p.shape}")
        p = np.ascontiguousarray(p)
        t = np.asarray(t_end, dtype=np.float64)
        if t.shape not in ((), (n,)):
            raise ValueError(f"t_end must be one time or ({n},); got shape {t.shape}")
        t = np.ascontiguousarray(np.broadcast_to(t, (n,)))
        out = np.full((n, d), np.nan)
        steps = np.zeros(n, np.int64)
        from .integrators import taylor_batch  # its generated expansions: loaded when first used

        args = (self.rtol, self.atol, self.order, self.a)
        if taylor_batch.batched(self.sys_id):
            taylor_batch.solve_batch(self.sys_id, y0, p, t, *args, out, steps)
        else:
            for m in range(n):
                steps[m] = self._solve(self.sys_id, y0[m], p[m], float(t[m]), *args, out[m])
        self.member_steps = steps
        return out
