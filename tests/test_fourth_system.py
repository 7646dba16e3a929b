"""A fourth system defined in the test suite only, by its equations (:class:`~mechviz.dynamics.
codegen.equations.Equations`): the spherical pendulum (:mod:`spherical` has its equations and
physics). Every compiled form comes from the generator, and it runs through the product's
integrators directly: the tableau runner's pairs, the fixed-step drivers (Euler, implicit
midpoint, a generated RK4) and Taylor's method with generated recurrences. The physics checked:
energy and ``L_z`` kept to the tolerance, orders of convergence, and the methods agreeing with
one another. (Through the registry and the product's front doors: :mod:`test_fourth_system_registered`.)
"""

from __future__ import annotations

import numpy as np
import pytest
from spherical import EQ

from mechviz.dynamics.codegen.rhs import generated_rhs
from mechviz.dynamics.codegen.series import generated_expand
from mechviz.dynamics.codegen.steps import generated_rk4
from mechviz.dynamics.integrators import kernels, rk, taylor

P = np.array([1.3, 9.81])  # l [m], g [m/s^2]
Y0 = np.array([1.0, 0.2, 0.3, 1.7])  # a tilted, precessing swing: theta between ~0.6 and ~1.6


def invariants(Y: np.ndarray) -> np.ndarray:
    """``(E, L_z)`` [J/kg, m^2/s] of each state (rows)."""
    l, g = P
    th, om, nu = Y[..., 0], Y[..., 2], Y[..., 3]
    s = np.sin(th)
    energy = 0.5 * l**2 * (om**2 + s**2 * nu**2) - g * l * np.cos(th)
    return np.stack([energy, l**2 * s**2 * nu], axis=-1)


def _drift(Y: np.ndarray) -> float:
    start = invariants(Y0)
    return float(np.max(np.abs(invariants(Y) - start) / np.abs(start)))


def run_pair(name: str, T: float, tol: float) -> np.ndarray:
    """The tableau runner with pair ``name`` and the generated right-hand side."""
    pair = rk.load_pair(name)
    Y = Y0[None].copy()
    stats, status = np.zeros((1, 3), np.int64), np.zeros(3, np.int64)
    carry = rk.RKCarry(1, EQ.dim, pair)
    args = (Y, P, 0.0, T, tol, tol, np.zeros(1), np.zeros((1, EQ.dim)), stats, status)
    rk.run_rk(pair, generated_rhs(EQ), *args, carry, land=True)
    assert status[0] == kernels.OK
    return Y[0]


def run_taylor(T: float, tol: float) -> np.ndarray:
    """Taylor's method with the generated recurrences."""
    expand, rows = generated_expand(EQ)
    order, a = taylor.order_for(tol, tol)
    Y = Y0[None].copy()
    stats, status = np.zeros((1, 3), np.int64), np.zeros(3, np.int64)
    taylor.run_taylor_with(expand, rows, Y, P, 0.0, T, tol, tol, order, a, stats, status)
    assert status[0] == kernels.OK
    return Y[0]


T = 10.0  # about five swings


@pytest.fixture(scope="module")
def reference() -> np.ndarray:
    return run_pair("dop853", T, 1e-13)


@pytest.mark.parametrize("name", rk.PAIRS)
def test_every_pair_of_the_tableau_runner_keeps_energy_and_lz_and_agrees(name, reference):
    y = run_pair(name, T, 1e-10)
    assert _drift(y) < 1e-7
    assert np.max(np.abs(y - reference)) < 1e-6


def test_taylors_method_with_generated_recurrences_keeps_energy_and_lz_to_round_off(reference):
    y = run_taylor(T, 1e-13)
    assert _drift(y) < 1e-11
    assert np.max(np.abs(y - reference)) < 1e-9


@pytest.mark.parametrize("order", [4, 7])
def test_the_generated_series_errs_as_h_to_the_order_plus_one(order):
    """One step of the series truncated at ``order`` against the series to order 30."""
    expand, rows = generated_expand(EQ)

    def step(p: int, h: float) -> np.ndarray:
        A = np.zeros((rows, 31))
        A[: EQ.dim, 0] = Y0
        expand(A, P, p)
        out = np.empty(EQ.dim)
        taylor._horner(A, EQ.dim, p, h, out)
        return out

    hs = [0.1 / 2**k for k in range(4)]
    errs = [np.max(np.abs(step(order, h) - step(30, h))) for h in hs]
    slope = np.polyfit(np.log(hs), np.log(errs), 1)[0]
    assert abs(slope - (order + 1)) < 0.3, (slope, errs)


FIXED = {  # method: (order, how one run of n steps of h is made)
    "euler": (
        1,
        lambda Y, h, n, st: kernels.run_composed(
            kernels.euler_step, generated_rhs(EQ), Y, P, h, n, st
        ),
    ),
    "midpoint": (
        2,
        lambda Y, h, n, st: kernels.run_composed(
            kernels.midpoint_step, generated_rhs(EQ), Y, P, h, n, st
        ),
    ),
    "rk4": (4, lambda Y, h, n, st: kernels.run_direct(generated_rk4(EQ), Y, P, h, n, st)),
}


@pytest.mark.parametrize("method", sorted(FIXED))
def test_the_fixed_step_methods_converge_at_their_order(method, reference):
    """Errors at ``t = 2`` s for halved steps fall by ``2^order`` (measured: within 0.08)."""
    order, run = FIXED[method]
    t_end = 2.0
    exact = run_pair("dop853", t_end, 1e-13)
    errs = []
    for n in (800, 1600, 3200) if order == 1 else (100, 200, 400):
        Y = Y0[None].copy()
        status = np.zeros(3, np.int64)
        run(Y, t_end / n, n, status)
        assert status[0] == kernels.OK
        errs.append(np.max(np.abs(Y[0] - exact)))
    rates = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    assert np.all(np.abs(rates - order) < 0.15), (rates, errs)
