"""Taylor's method on many problems at once (:mod:`mechviz.dynamics.integrators.taylor_batch`):
each member lands where the one-problem solve lands, to round-off, in as many steps; the batch
expansion is generated from the same equations as the one-problem one and agrees with it
coefficient by coefficient; a member that fails spoils no other. No timing here: the speed is
the benchmark's (``mechviz bench --batch``)."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

from mechviz.dynamics import Cyclotron, Hoop, ReleasedDisk
from mechviz.dynamics.codegen.batch import batch_from_series, generated_batch_expand
from mechviz.dynamics.codegen.equations import EQUATIONS, Equations
from mechviz.dynamics.codegen.series import generated_expand, series_source
from mechviz.dynamics.hoop import HoopParams, energy_above_rest
from mechviz.dynamics.ids import FREE_BODY, HOOP, NAMES
from mechviz.dynamics.integrators import taylor, taylor_batch
from mechviz.dynamics.solver import Solver

# A member's state against the one-problem solve's: the expansions' sums are the same but may
# be contracted to fused multiply-adds differently (module docstring of taylor_batch), a few
# ulps per step over some tens of steps.
ROUND_OFF = 1e-12
ORDER = 14


def _hoop_cases(n: int, seed: int = 1):
    """``n`` hoop starts (angles up to 1.2 rad, rates up to 2 rad/s) and parameter rows
    ``[M, m, a, g]``, each member its own."""
    rng = np.random.default_rng(seed)
    y0 = np.column_stack([rng.uniform(-1.2, 1.2, (n, 2)), rng.uniform(-2.0, 2.0, (n, 2))])
    p = np.column_stack(
        [rng.uniform(0.5, 2.0, n), rng.uniform(0.2, 1.0, n), rng.uniform(0.5, 1.5, n)]
    )
    return y0, np.column_stack([p, rng.uniform(5.0, 15.0, n)])


def _free_body_cases(n: int, seed: int = 2):
    """``n`` free-body starts (body rates, a unit quaternion) and principal moments."""
    rng = np.random.default_rng(seed)
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    y0 = np.column_stack([rng.uniform(-2.0, 2.0, (n, 3)), q])
    return y0, rng.uniform(0.5, 2.0, (n, 3))


def _serial(solver: Solver, t_end, y0, p):
    """Each member by :meth:`Solver.solve`: states and steps."""
    out = np.empty_like(y0)
    steps = np.empty(len(y0), np.int64)
    for m in range(len(y0)):
        out[m] = solver.solve(float(t_end[m]), y0[m], p[m])
        steps[m] = solver.steps
    return out, steps


def _close(a, b) -> None:
    scale = 1.0 + np.abs(b)
    assert np.max(np.abs(a - b) / scale) < ROUND_OFF


@pytest.mark.parametrize(
    ("system", "cases"), [(Hoop(), _hoop_cases), (ReleasedDisk(), _free_body_cases)]
)
def test_each_member_lands_where_the_one_problem_solve_lands(system, cases):
    """Every member its own start, parameters and end (one ending at once, one at a short
    time), more members than lanes and not a multiple of them: the states of the one-problem
    solve to round-off, in the same number of steps."""
    n = 3 * taylor_batch.LANES + 5
    y0, p = cases(n)
    t_end = np.random.default_rng(5).uniform(0.5, 3.0, n)
    t_end[3], t_end[7] = 0.0, 1e-3
    solver = Solver(system, rtol=1e-10)
    got = solver.solve_many(t_end, y0, p)
    want, steps = _serial(solver, t_end, y0, p)
    _close(got, want)
    np.testing.assert_array_equal(solver.member_steps, steps)
    np.testing.assert_array_equal(got[3], y0[3])  # no time: the start itself, one expansion
    assert steps[3] == 1


def test_fewer_members_than_lanes_and_shared_parameters():
    """Three members with the system's own parameters and one end time: the solve's states."""
    system = Hoop(HoopParams(hoop_mass=1.3))
    y0, _ = _hoop_cases(3)
    solver = Solver(system)
    got = solver.solve_many(2.0, y0)
    for m in range(3):
        _close(got[m], solver.solve(2.0, y0[m]))
    assert got.shape == (3, 4)
    assert solver.solve_many(1.0, y0[:0]).shape == (0, 4)


def test_the_batch_conserves_the_energy():
    """The hoop's energy above rest after 2 s, each member with its parameters, within a few
    times the tolerance of the start's."""
    n = 40
    y0, p = _hoop_cases(n, seed=9)
    got = Solver(Hoop(), rtol=1e-9).solve_many(2.0, y0, p)
    for m in range(n):
        params = HoopParams(*p[m])
        e0, e1 = energy_above_rest(params, y0[m]), energy_above_rest(params, got[m])
        assert abs(e1 - e0) <= 1e-7 * e0, m


def test_a_failing_member_spoils_no_other():
    """A start that is not finite (row NaN, steps -2, nothing run), parameters that are not
    finite (the same) and a start whose series overflow (steps -1, the last state reached):
    the other members are the one-problem solve's."""
    n = 2 * taylor_batch.LANES + 1
    y0, p = _hoop_cases(n, seed=4)
    y0[2, 1] = np.nan
    p[5, 0] = np.inf
    y0[9, 2] = 1e200  # its square overflows: the series is not finite at the first step
    solver = Solver(Hoop(), rtol=1e-9)
    t_end = np.full(n, 1.5)
    got = solver.solve_many(t_end, y0, p)
    steps = solver.member_steps
    assert steps[2] == steps[5] == -2 and steps[9] == -1
    assert np.isnan(got[2]).all() and np.isnan(got[5]).all()
    good = [m for m in range(n) if m not in (2, 5, 9)]
    want, serial_steps = _serial(solver, t_end[good], y0[good], p[good])
    _close(got[good], want)
    np.testing.assert_array_equal(steps[good], serial_steps)


def test_wrong_shapes_are_refused():
    solver = Solver(Hoop())
    with pytest.raises(ValueError, match="states"):
        solver.solve_many(1.0, np.zeros((2, 3)))
    with pytest.raises(ValueError, match="params"):
        solver.solve_many(1.0, np.zeros((2, 4)), np.ones((3, 4)))
    with pytest.raises(ValueError, match="t_end"):
        solver.solve_many(np.ones(3), np.zeros((2, 4)))


def test_the_charge_falls_back_to_the_one_problem_solve():
    """The charge's steps are taken in closed form, with no batch form: one member after
    another, bit for bit the solve's."""
    system = Cyclotron()
    solver = Solver(system, rtol=1e-9)
    y0 = system.default_state() + np.random.default_rng(0).uniform(-0.1, 0.1, (5, 6))
    got = solver.solve_many(1.0, y0)
    for m in range(5):
        np.testing.assert_array_equal(got[m], solver.solve(1.0, y0[m]))


def _batch_coefficients(expand, rows, y, p, lanes):
    """The batch expansion's state coefficients of members ``y`` (lanes, d), ``p`` (lanes, P)."""
    A = np.full((rows, ORDER + 1, lanes), np.nan)  # what the expansion leaves unwritten shows
    A[: y.shape[1], 0, :] = y.T
    expand(A, np.ascontiguousarray(p.T), ORDER)
    return A[: y.shape[1]]


def _serial_coefficients(expand, rows, y, p):
    A = np.full((rows, ORDER + 1), np.nan)
    A[: y.size, 0] = y
    expand(A, p, ORDER)
    return A[: y.size]


def _compare_expansions(batch_form, one_form, lanes: int, y: np.ndarray, p: np.ndarray) -> None:
    """Member by member, every state coefficient to :data:`ORDER`, on the scale of each
    order's largest (the orders span many decades). ``batch_form``, ``one_form``:
    ``(expand, rows)``."""
    batch = _batch_coefficients(*batch_form, y, p, lanes)
    expand, rows = one_form
    for b in range(lanes):
        one = _serial_coefficients(expand, rows, y[b], p[b])
        assert np.all(np.isfinite(batch[:, :, b]))
        scale = np.max(np.abs(one), axis=0) + 1e-300
        assert np.max(np.abs(batch[:, :, b] - one) / scale) < 1e-12, (b, y[b], p[b])


@pytest.mark.parametrize("lanes", [4, 8])
@pytest.mark.parametrize("sys_id", [HOOP, FREE_BODY])
def test_the_batch_expansion_is_the_one_problem_expansion_member_by_member(sys_id, lanes):
    """Generated from the same equations: each lane's coefficients are the one-problem
    expansion's at that lane's state and parameters, to round-off."""
    eq = EQUATIONS[sys_id]()
    rng = np.random.default_rng(sys_id + lanes)
    y = 0.5 * rng.uniform(-3.0, 3.0, (lanes, eq.dim))
    p = rng.uniform(0.3, 3.0, (lanes, len(eq.params)))
    one = (taylor.hoop_generated if sys_id == HOOP else taylor.free_body_generated, taylor.N_ROWS)
    if lanes == taylor_batch.LANES:  # the forms in use (the others generated here alike)
        in_use = taylor_batch.hoop_batch if sys_id == HOOP else taylor_batch.free_body_batch
        batch = (in_use, taylor_batch.ROWS)
    else:
        batch = generated_batch_expand(eq, lanes)
    _compare_expansions(batch, one, lanes, y, p)


def test_every_kind_of_node_has_its_batch_form():
    """A made-up system with quotients, an exponential, a square root, a power and a sine:
    the batch form of its generated expansion agrees with the one-problem form."""
    x, v = sp.symbols("x v", real=True)
    k = sp.Symbol("k", positive=True)
    rhs = (v, -k * sp.sin(x) + sp.exp(-(x**2)) / (2 + v**2) + sp.sqrt(1 + x**2) * (1 + v**2) ** k)
    eq = Equations("batch-kinds", (x, v), (k,), rhs)
    rng = np.random.default_rng(11)
    y, p = rng.uniform(-1.0, 1.0, (4, 2)), rng.uniform(0.3, 1.5, (4, 1))
    _compare_expansions(generated_batch_expand(eq, 4), generated_expand(eq), 4, y, p)


def test_the_batch_source_is_the_series_source_per_member():
    """Each statement of the one-problem expansion that reads a coefficient is in the batch
    source once per member, indexed by its lane; the loops and tests over the order once."""
    serial = series_source(EQUATIONS[HOOP]())
    batch = batch_from_series(serial, 4)
    assert batch.count("for k in range(order):") == 1
    assert "A[8, 0, 3] = math.sin(A[0, 0, 3])" in batch
    assert "A[8, 0, 4]" not in batch
    with pytest.raises(ValueError, match="lanes"):
        batch_from_series(serial, 0)


def test_the_batch_benchmark_measures_every_contender_on_the_same_problems():
    """A small run of ``mechviz bench --batch`` without heyoka: every contender of ours lands
    on the batch mode's states; the verdict flags only a loss to heyoka (no time asserted)."""
    from mechviz.bench import batch

    row = batch.measure_system(NAMES[HOOP], n=20, rounds=1, heyoka=False)
    assert set(row["us_per_problem"]) == {
        batch.OURS,
        "ours Solver loop",
        "ours solve_taylor njit loop",
    }
    assert max(row["max_difference_from_ours"].values()) < ROUND_OFF
    assert row["failed"] == 0 and row["ours_at_most_heyoka"] is None
    name = NAMES[HOOP]
    assert batch.missed({"systems": {name: row}}) == []
    lost = dict(row, ours_at_most_heyoka=False, heyoka_fastest="ours Solver loop")
    assert len(batch.missed({"systems": {name: lost}})) == 1
    settings = {"problems": 20, "t_end_s": 2.0, "rtol": 1e-9, "seed": 0}
    table = batch.markdown({"settings": settings, "lanes": 8, "systems": {name: row}})
    assert "| ours batch |" in table
