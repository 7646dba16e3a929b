"""Code generated from the equations written once (:mod:`mechviz.dynamics.codegen`) agrees with
the hand-written kernels to round-off, on random states and parameters other than the defaults;
the product's right-hand sides and RK4 steps are the generated ones (the hand-written ones they
replaced, :mod:`mechviz.bench.handwritten`, are the check), and load without sympy."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
import sympy as sp

from mechviz.bench.handwritten import EXPANDS, RHS, RK4
from mechviz.dynamics.codegen.equations import EQUATIONS, Equations
from mechviz.dynamics.codegen.rhs import generated_rhs
from mechviz.dynamics.codegen.series import generated_expand
from mechviz.dynamics.codegen.steps import generated_rk4
from mechviz.dynamics.ids import FREE_BODY, HOOP
from mechviz.dynamics.integrators import kernels, taylor

ROUND_OFF = 1e-14  # relative to the size of the right-hand side's terms


def _random_cases(sys_id: int, n: int = 20, seed: int = 0):
    """``n`` random states and parameter arrays (parameters in [0.3, 3], positive as every
    system's are; states of order one, angles over a whole turn)."""
    eq = EQUATIONS[sys_id]()
    rng = np.random.default_rng(seed + sys_id)
    for _ in range(n):
        yield rng.uniform(-3.0, 3.0, eq.dim), rng.uniform(0.3, 3.0, len(eq.params))


@pytest.mark.parametrize("sys_id", sorted(EQUATIONS))
def test_the_generated_right_hand_side_is_the_hand_written_one_to_round_off(sys_id):
    eq = EQUATIONS[sys_id]()
    generated = generated_rhs(eq)
    for y, p in _random_cases(sys_id):
        new, old = np.empty(eq.dim), np.empty(eq.dim)
        generated(y, p, new)
        RHS[sys_id](y, p, old)
        scale = 1.0 + np.max(np.abs(old)) * (1.0 + np.max(np.abs(y)))
        assert np.max(np.abs(new - old)) <= ROUND_OFF * scale, (y, p, new, old)


def test_the_generated_source_is_written_once_and_found_again():
    from mechviz.dynamics.codegen import build

    eq = EQUATIONS[min(EQUATIONS)]()
    generated_rhs(eq)
    files = list(build.generated_dir().glob(f"*_rhs_{eq.name.replace('-', '_')}_{eq.key()}.py"))
    assert len(files) == 1
    assert "def rhs(y, p, out)" in files[0].read_text()


# --------------------------------------------------------------------------- Taylor series
ORDER = 12


def _coefficients(expand, rows: int, y: np.ndarray, p: np.ndarray) -> np.ndarray:
    A = np.full((rows, ORDER + 1), np.nan)  # what the expansion leaves unwritten shows
    A[: y.size, 0] = y
    expand(A, p, ORDER)
    return A[: y.size]


@pytest.mark.parametrize("sys_id", sorted(EQUATIONS))
def test_the_generated_taylor_coefficients_are_the_hand_written_ones_to_round_off(sys_id):
    """Every state coefficient to order 12, at random states and parameters; each order is
    compared on the scale of its largest coefficient (the orders span many decades)."""
    eq = EQUATIONS[sys_id]()
    expand, rows = generated_expand(eq)
    hand = EXPANDS[sys_id]
    for y, p in _random_cases(sys_id, n=10):
        y = 0.5 * y  # the hoop's determinant stays away from 0 (its m cos^2 < 2M + m anyway)
        new = _coefficients(expand, rows, y, p)
        old = _coefficients(hand, taylor.N_ROWS, y, p)
        assert np.all(np.isfinite(new))
        scale = np.max(np.abs(old), axis=0) + 1e-300
        assert np.max(np.abs(new - old) / scale) < 1e-12, (y, p)


def _run(expand, rows, sys_id, Y, p, tol):
    order, a = taylor.order_for(tol, tol, sys_id)
    stats, status = np.zeros((len(Y), 3), np.int64), np.zeros(3, np.int64)
    steps = taylor.run_taylor_with(expand, rows, Y, p, 0.0, 3.0, tol, tol, order, a, stats, status)
    assert status[0] == taylor.OK
    return steps


# the expansion the product's Taylor method uses on each system (both generated)
IN_USE = {
    HOOP: (taylor.hoop_generated, taylor.N_ROWS),
    FREE_BODY: (taylor.free_body_generated, taylor.N_ROWS),
}


@pytest.mark.parametrize("sys_id", [HOOP, FREE_BODY])
def test_taylor_with_generated_coefficients_runs_as_the_hand_written_method(sys_id):
    """The driver given the expansion in use is the product's method bit for bit; given the
    generated and the hand-written expansions it takes the same steps and lands on the same
    state to round-off."""
    eq = EQUATIONS[sys_id]()
    rng = np.random.default_rng(3)
    Y0 = 0.5 * rng.uniform(-1.0, 1.0, (4, eq.dim))
    p = rng.uniform(0.5, 2.0, len(eq.params))
    tol = 1e-12
    product = Y0.copy()
    stats, status = np.zeros((4, 3), np.int64), np.zeros(3, np.int64)
    carry = taylor.TaylorCarry(4, eq.dim)
    n_product = taylor.run_taylor(sys_id, product, p, 0.0, 3.0, tol, tol, stats, status, carry)
    in_use = Y0.copy()
    assert _run(*IN_USE[sys_id], sys_id, in_use, p, tol) == n_product
    np.testing.assert_array_equal(in_use, product)
    hand_run = Y0.copy()
    n_hand = _run(EXPANDS[sys_id], taylor.N_ROWS, sys_id, hand_run, p, tol)
    new_run = Y0.copy()
    n_new = _run(*generated_expand(eq), sys_id, new_run, p, tol)
    assert n_new == n_hand
    assert np.max(np.abs(new_run - hand_run)) < 1e-12 * (1.0 + np.max(np.abs(hand_run)))


@pytest.mark.parametrize("sys_id", [HOOP, FREE_BODY])
def test_the_taylor_expansion_in_use_is_the_generated_one(sys_id):
    """The product's free body and hoop expand with the code generated from their equations (the
    same source text as a test-defined system's would be, so the same coefficients bit for
    bit)."""
    eq = EQUATIONS[sys_id]()
    expand, rows = generated_expand(eq)
    for y, p in _random_cases(sys_id, n=3):
        np.testing.assert_array_equal(
            _coefficients(IN_USE[sys_id][0], rows, y, p), _coefficients(expand, rows, y, p)
        )


def _mass_matrix_system(solved: bool) -> Equations:
    """A made-up 2-DOF system ``M(x, y) (v', w') = f`` with every kind of mass entry (a
    constant plus a square, a product of two series, a polynomial), as a mass-matrix system or
    with its accelerations solved (quotients by the determinant)."""
    x, y, v, w = sp.symbols("x y v w", real=True)
    k = sp.Symbol("k", positive=True)
    mass = sp.Matrix(
        [[2 + sp.cos(x) ** 2, sp.sin(x) * sp.cos(y)], [sp.sin(x) * sp.cos(y), 1 + y**2]]
    )
    force = sp.Matrix([-k * sp.sin(x) - v * w, -y + k * v**2])
    if solved:
        rates = tuple(mass.adjugate() * force / mass.det())
        return Equations("mass-solved", (x, y, v, w), (k,), (v, w, *rates))
    return Equations(
        "mass-matrix",
        (x, y, v, w),
        (k,),
        (v, w),
        mass=tuple(map(tuple, mass.tolist())),
        force=tuple(force),
    )


def test_a_mass_matrix_system_has_the_series_of_its_solved_form():
    """The recurrences solving ``M^[0] a^[k] = f^[k] - sum M^[j] a^[k-j]`` give the coefficients
    the quotients of the solved accelerations give, to round-off; the right-hand side is the
    solved form's."""
    matrix, solved = _mass_matrix_system(False), _mass_matrix_system(True)
    assert [sp.simplify(a - b) for a, b in zip(matrix.rhs, solved.rhs, strict=True)] == [0] * 4
    rng = np.random.default_rng(7)
    for _ in range(10):
        y, p = rng.uniform(-1.5, 1.5, 4), rng.uniform(0.3, 3.0, 1)
        new = _coefficients(*generated_expand(matrix), y, p)
        old = _coefficients(*generated_expand(solved), y, p)
        assert np.all(np.isfinite(new))
        scale = np.max(np.abs(old), axis=0) + 1e-300
        assert np.max(np.abs(new - old) / scale) < 1e-12, (y, p)


def test_a_mass_matrix_must_be_square_with_one_force_a_row():
    x, v = sp.symbols("x v", real=True)
    with pytest.raises(ValueError, match="n x n"):
        Equations("bad", (x, v), (), (v,), mass=((1, 2),), force=(x,))
    with pytest.raises(ValueError, match="mass matrix"):
        Equations("bad", (x, v), (), (v, x), mass=((1,),), force=(x,))


@pytest.mark.parametrize("sys_id", sorted(EQUATIONS))
def test_the_generated_rk4_step_is_the_hand_written_one_to_round_off(sys_id):
    eq = EQUATIONS[sys_id]()
    step = generated_rk4(eq)
    for y, p in _random_cases(sys_id, n=10):
        new, old = 0.5 * y, 0.5 * y
        assert step(new, p, 0.05) == 4 == RK4[sys_id](old, p, 0.05)
        assert np.max(np.abs(new - old)) <= ROUND_OFF * (1.0 + np.max(np.abs(old))), (y, p)


@pytest.mark.parametrize("sys_id", sorted(EQUATIONS))
def test_the_product_right_hand_side_and_rk4_step_are_the_generated_ones(sys_id):
    """The kernels' tables hold the code generated from the equations (the same source text as
    a test-defined system's, so the same numbers bit for bit), not hand-written functions."""
    eq = EQUATIONS[sys_id]()
    for form in (kernels.RHS[sys_id], kernels.RK4[sys_id]):
        assert form.py_func.__module__.startswith("mechviz_generated_"), form
    for y, p in _random_cases(sys_id, n=3):
        product, generated = np.empty(eq.dim), np.empty(eq.dim)
        kernels.RHS[sys_id](y, p, product)
        generated_rhs(eq)(y, p, generated)
        np.testing.assert_array_equal(product, generated)
        product, generated = y.copy(), y.copy()
        assert kernels.RK4[sys_id](product, p, 0.05) == generated_rk4(eq)(generated, p, 0.05)
        np.testing.assert_array_equal(product, generated)


def test_the_product_forms_load_without_sympy_once_written():
    """A process that finds the generated modules written (this one wrote them, importing the
    kernels) imports every integrator without importing sympy (half a second)."""
    code = (
        "import sys\n"
        "from mechviz.dynamics.integrators import base, kernels, rk, scipy_ivp, taylor\n"
        "assert 'sympy' not in sys.modules, sorted(m for m in sys.modules if 'sympy' in m)[:3]\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True, timeout=300)


@pytest.mark.slow
def test_the_cost_benchmark_runs_both_forms_to_the_same_steps_and_states():
    """The benchmark's pairs are the same computation: equal step counts, final states equal to
    round-off (the adaptive methods' to far below their tolerance, 1e-10)."""
    from mechviz.bench.generated_cost import FORMS, generated_cost, missed, report

    result = generated_cost(quick=True, members=4)
    for name, r in result.items():
        for form in FORMS:
            assert r[form]["same_steps"], (name, form)
            assert r[form]["max_state_difference"] < 1e-11, (name, form, r[form])
    assert len(report(result)) == 1 + len(result) * len(FORMS) + len(missed(result))
