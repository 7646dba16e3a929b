"""Taylor's method's tolerance levels: a tighter tolerance never gives a worse answer.

The order and the step follow the tolerance by levels (:func:`mechviz.dynamics.taylor_order.levels`):
every tolerance of a level takes the same steps, and from level to level the error falls. Checked
at 33 tolerances from 1e-3 to 1e-12 on every system, with parameters and starts other than the
defaults, against references the test makes with two other methods (the charge: its exact
helix).
"""

import itertools
import math

import numpy as np
import pytest

from mechviz.dynamics import Cyclotron, Hoop, ReleasedDisk, Simulation
from mechviz.dynamics.cyclotron import CyclotronParams
from mechviz.dynamics.disk import DiskParams
from mechviz.dynamics.hoop import HoopParams
from mechviz.dynamics.solver import Solver
from mechviz.dynamics.taylor_order import MAX_ORDER, levels, order_for

TOLS = np.logspace(-3, -12, 33)
RISE = 2.0  # the most an error may exceed the smallest at any looser tolerance
# An error within this factor of the references' disagreement is not judged: it is the
# references' own error as much as the method's.
RESOLVE = 100.0

CASES = {
    "charge": (
        Cyclotron(CyclotronParams(charge=-1.7, mass=0.6, field=2.3)),
        [0.4, -1.1, 0.3, 1.3, 0.5, -0.7],
        40.0,
    ),
    "hoop": (
        Hoop(HoopParams(hoop_mass=1.7, bead_mass=0.8, radius=0.6, gravity=9.81)),
        [1.1, -0.6, 0.8, -1.5],
        15.0,
    ),
    "free body": (
        ReleasedDisk(
            DiskParams(disk_mass=1.4, radius=0.7, bead_mass=0.35, omega=3.1), (0.4, -0.3, 0.2)
        ),
        None,
        30.0,
    ),
}


def _start(system, state):
    return np.asarray(system.default_state() if state is None else state, dtype=np.float64)


def _reference(system, y0, t_end):
    """The final state and how far it can be trusted: the exact flow where there is one, else
    DOP853 and Verner's 9(8) at 1e-14, whose disagreement bounds what the test judges."""
    exact = system.exact(y0, t_end)
    if exact is not None:
        return np.asarray(exact), 1e-15 * max(1.0, np.max(np.abs(exact)))
    ends = []
    for method in ("dop853", "vern9"):
        sim = Simulation(system, method, rtol=1e-14, atol=1e-14, state=y0, reference=None)
        sim.advance_to(t_end)
        ends.append(sim.state[0].copy())
    return ends[0], float(np.max(np.abs(ends[0] - ends[1])))


@pytest.mark.parametrize("name", CASES)
def test_the_error_falls_as_the_tolerance_tightens_at_33_tolerances(name):
    """At every tolerance the error is at most twice the smallest error of any looser tolerance,
    over nine decades of tolerance, and falls by several decades over them."""
    system, state, t_end = CASES[name]
    y0 = _start(system, state)
    ref, spread = _reference(system, y0, t_end)
    errors = []
    for tol in TOLS:
        y = Solver(system, rtol=tol, atol=tol).solve(t_end, y0)
        errors.append(float(np.max(np.abs(y - ref))))
    errors = np.array(errors)
    judged = errors > RESOLVE * spread
    for i in range(1, TOLS.size):
        if judged[i]:
            assert errors[i] <= RISE * errors[:i].min(), (
                f"{name}: error {errors[i]:.2e} at tol {TOLS[i]:.2e}, "
                f"{errors[i] / errors[:i].min():.1f}x the smallest at a looser tolerance"
            )
    if name == "charge":  # one order and step at every tolerance: the round-off of the helix
        assert errors.max() < 1e-12
    else:
        assert errors[0] / errors[judged].min() > 1e5  # the test spans the error's fall


@pytest.mark.parametrize("name", ["hoop", "free body"])
def test_every_tolerance_of_a_level_takes_the_same_steps(name):
    """Inside a level the answer does not depend on the tolerance, to the last bit; one step
    past the level's tight end the order goes up."""
    system, state, t_end = CASES[name]
    y0 = _start(system, state)
    sys_id = system.sys_id
    tiers = levels(sys_id)
    assert tiers[-1] == (MAX_ORDER, math.inf)
    orders = [p for p, _ in tiers]
    assert orders == sorted(set(orders))
    for (p, end), (p_next, _) in itertools.pairwise(tiers[3:8]):
        start = math.exp(-end) * 2.0  # inside the level (levels are more than a decade wide)
        answers = set()
        for tol in (start, math.sqrt(start * math.exp(-end)), math.exp(-end)):
            assert order_for(tol, tol, sys_id)[0] == p
            answers.add(Solver(system, rtol=tol, atol=tol).solve(t_end, y0).tobytes())
        assert len(answers) == 1
        past = math.exp(-end) * 0.999
        assert order_for(past, past, sys_id)[0] == p_next > p


def test_the_step_is_the_levels_tightest_and_meets_the_tolerance():
    """The step ``rho exp(-a)`` at a level is the one for its tightest tolerance: the error
    estimate ``(h / rho)^(p - 1) = exp(-a (p - 1))`` is within every tolerance of the level."""
    for system, _, _ in CASES.values():
        for tol in TOLS:
            p, a = order_for(tol, tol, system.sys_id)
            assert (p - 1) * a >= -math.log(tol) - 1e-9
            tighter = [end for q, end in levels(system.sys_id) if q == p]
            if tighter and tighter[0] != math.inf:
                assert math.isclose((p - 1) * a, tighter[0], rel_tol=1e-12) or a == 1.0


def test_the_order_found_by_descent_is_the_least_work_over_every_order():
    """The work model is unimodal in the order on every system, so the descent the levels use
    finds the order a search over every order would (checked on a fine grid of tolerances)."""
    from mechviz.dynamics.taylor_order import _best_order, _work_model

    for system, _, _ in CASES.values():
        work, _ = _work_model(system.sys_id)
        for L in np.linspace(0.05, 80.0, 4001):
            every = min(range(3, MAX_ORDER + 1), key=lambda p: work(p, L))
            assert _best_order(work, L) == every
            assert _best_order(work, L, every + 5 if every + 5 <= MAX_ORDER else every) == every
