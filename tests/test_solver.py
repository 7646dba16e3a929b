"""The reusable compiled problem: one Solver, many starts and parameter sets, each answer the one
a Simulation built for that problem gives; and the charge's closed-form series."""

from __future__ import annotations

import math

import numba
import numpy as np
import pytest

from mechviz.dynamics import Cyclotron, Hoop, ReleasedDisk, Simulation
from mechviz.dynamics.cyclotron import CyclotronParams
from mechviz.dynamics.disk import DiskParams
from mechviz.dynamics.hoop import HoopParams
from mechviz.dynamics.integrators import taylor_linear
from mechviz.dynamics.solver import Solver, solve_taylor

CASES = [
    (Cyclotron(), Cyclotron(CyclotronParams(charge=-2.0, mass=1.5, field=0.7))),
    (Hoop(), Hoop(HoopParams(hoop_mass=0.7, bead_mass=1.3, radius=0.6))),
    (
        ReleasedDisk(DiskParams(omega=1.0), (0.3, 0.0, 0.2)),
        ReleasedDisk(DiskParams(radius=0.8, bead_mass=0.4, omega=1.5), (0.3, 0.0, 0.2)),
    ),
]


@pytest.mark.parametrize(("first", "other"), CASES)
def test_one_solver_answers_other_starts_and_parameters_as_a_fresh_simulation(first, other):
    """A solver built for one system, handed another start and another system's parameters,
    lands on the same bits as a Simulation built for that other problem."""
    solver = Solver(first, rtol=1e-10)
    state = other.default_state() * 1.01
    got = solver.solve(4.0, state, other.kernel_params()).copy()
    sim = Simulation(other, "taylor", rtol=1e-10, atol=1e-10, state=state, reference=None)
    sim.advance_to(4.0)
    np.testing.assert_array_equal(got, sim.state[0])
    assert solver.steps == sim.steps
    again = solver.solve(4.0)  # its own start and parameters again
    ref = Simulation(first, "taylor", rtol=1e-10, atol=1e-10, reference=None)
    ref.advance_to(4.0)
    np.testing.assert_array_equal(again, ref.state[0])


def test_a_wrong_start_or_parameters_is_refused_and_a_blow_up_reported():
    solver = Solver(Hoop())
    with pytest.raises(ValueError, match="state"):
        solver.solve(1.0, [0.1, 0.2])
    with pytest.raises(ValueError, match="params"):
        solver.solve(1.0, None, [1.0, np.nan, 1.0, 9.81])
    with pytest.raises(FloatingPointError):
        solver.solve(1.0, [0.1, 0.2, 1e308, 1e308])


def test_the_compiled_solve_can_be_called_from_njit_code():
    """No Python between solves: an njit caller runs a parameter scan through solve_taylor."""
    solver = Solver(Cyclotron())

    @numba.njit
    def scan(y0, fields, order, a, out):
        x = np.empty(fields.size)
        for i in range(fields.size):
            p = np.array([fields[i]])
            solve_taylor(0, y0, p, math.pi / abs(fields[i]), 1e-12, 1e-12, order, a, out)
            x[i] = out[0]
        return x

    y0 = np.array([1.0, 0.0, 0.0, 0.0, 1.0, 0.0])
    fields = np.array([0.5, 1.0, 2.0])
    xs = scan(y0, fields, solver.order, solver.a, np.empty(6))
    # half a gyration: x goes from 1 to 1 + 2 v / Omega
    np.testing.assert_allclose(xs, 1.0 + 2.0 / fields, rtol=1e-11)


@pytest.mark.parametrize("order", [3, 4, 9, 40])
def test_the_closed_form_sums_are_the_truncated_series(order):
    """C, S, C1, S1 are the cosine's and sine's Taylor polynomials of order p (and of p - 1
    divided by the next factorial), as the generic recurrences give them."""
    for theta in (0.1, 1.3, 4.0):
        c, s, c1, s1 = taylor_linear._series(theta, order)

        def term(k, extra=0, theta=theta):
            return (-1) ** (k // 2) * theta**k / math.factorial(k + extra)

        assert c == pytest.approx(sum(term(k) for k in range(0, order + 1, 2)), rel=1e-14)
        assert s == pytest.approx(sum(term(k) for k in range(1, order + 1, 2)), rel=1e-14)
        assert c1 == pytest.approx(sum(term(k, 1) for k in range(0, order, 2)), rel=1e-14)
        assert s1 == pytest.approx(sum(term(k, 1) for k in range(1, order, 2)), rel=1e-14)


def test_the_charge_lands_on_the_exact_helix_from_any_start():
    """The closed-form steps follow the exact solution over many gyrations, at either sign of
    the charge."""
    for q in (1.0, -3.0):
        system = Cyclotron(CyclotronParams(charge=q, mass=0.7, field=1.3))
        y0 = np.array([0.3, -1.0, 0.2, 1.5, -0.4, 0.3])
        T = 50 * 2 * math.pi * 0.7 / abs(q * 1.3)
        got = Solver(system, rtol=1e-12).solve(T, y0)
        exact = system.exact(y0, T)
        assert float(system.error(got[None], np.asarray(exact)[None])[0]) < 1e-11


@pytest.mark.parametrize("theta", [0.3, -0.9, 2.5, 5.7, -11.0])
def test_a_long_phase_is_summed_as_substeps_that_land_on_the_rotation(theta):
    """Beyond a phase of 1 the series are those of 2^n substeps, composed: at order 40 that is
    the rotation and its integral to round-off (the plain sums at 5.7 lose two digits)."""
    c, s, c1, s1 = taylor_linear.series_at(theta, 40)
    exact = (
        math.cos(theta),
        math.sin(theta),
        math.sin(theta) / theta,
        (1.0 - math.cos(theta)) / theta,
    )
    np.testing.assert_allclose((c, s, c1, s1), exact, rtol=0, atol=4e-16 * max(1.0, abs(theta)))
    if abs(theta) <= 1.0:
        assert (c, s, c1, s1) == taylor_linear._series(theta, 40)
