"""Every fixed-step method's structure label on every system is what its one-step map does there:
symplectic (Lie-Poisson on the free body) where the measured defect is the differences' noise,
not where it grows with the step; symmetric where a step back undoes a step; volume-preserving
where the Jacobian's determinant is 1; norm-preserving where |L| is kept."""

from __future__ import annotations

import numpy as np
import pytest

from mechviz.dynamics import SYSTEMS
from mechviz.dynamics.integrators import methods_for
from mechviz.dynamics.structure import SYMPLECTIC_NOISE, one_step, symplecticity_defect

#: Starts away from every symmetry, and two steps per system (a few tenths of its fastest
#: period's radian): where a defect that grows with the step stands clear of the noise.
CASES = {
    "cyclotron": (np.array([0.3, -0.2, 0.1, 0.7, 0.4, 0.2]), (0.2, 0.4)),
    "hoop": (np.array([0.9, -0.6, 0.4, -0.7]), (0.1, 0.2)),
    "free-body": (None, (0.1, 0.2)),
}


def _start(name):
    state, steps = CASES[name]
    system = SYSTEMS[name]()
    if state is None:
        state = system.default_state() + np.array([0.3, 0.1, -0.2, 0, 0, 0, 0])
    return system, state, steps


PAIRS = [(name, m.name) for name in CASES for m in methods_for(SYSTEMS[name]) if not m.adaptive]


@pytest.mark.parametrize(("system_name", "method_name"), PAIRS)
def test_each_structure_label_is_what_the_one_step_map_keeps(system_name, method_name):
    system, state, steps = _start(system_name)
    method = next(m for m in methods_for(system) if m.name == method_name)
    labels = method.structure_on(system)
    defects = [symplecticity_defect(method, system, state, h) for h in steps]
    if "symplectic" in labels:
        assert max(defects) < SYMPLECTIC_NOISE, defects
    else:
        assert min(defects) > SYMPLECTIC_NOISE, defects
        assert defects[1] > 2 * defects[0]  # it grows with the step: not noise
    h = steps[0]
    back = one_step(method, system, one_step(method, system, state, h), -h)
    undone = float(np.max(np.abs(back - state)))
    if "symmetric" in labels:
        assert undone < 1e-12, undone
    else:
        assert undone > 1e-8, undone
    if "norm-preserving" in labels or (system_name == "free-body" and method_name == "midpoint"):
        moments = system.kernel_params()
        after = one_step(method, system, state, h)
        L0, L1 = (np.linalg.norm(moments * s[:3]) for s in (state, after))
        assert abs(L1 / L0 - 1) < 1e-13
    if "volume-preserving" in labels:
        eps, n = 1e-6, len(state)
        D = np.empty((n, n))
        for j in range(n):
            d = np.zeros(n)
            d[j] = eps
            D[:, j] = (
                one_step(method, system, state + d, h) - one_step(method, system, state - d, h)
            ) / (2 * eps)
        assert abs(np.linalg.det(D) - 1) < 1e-8


def test_exact_is_a_closed_form_flow_not_a_fixed_step_and_verlet_counts_what_it_evaluates():
    from mechviz.dynamics.integrators import get_method

    exact = get_method("exact").describe()
    assert "fixed step" not in exact and "closed-form flow" in exact
    counts = get_method("verlet").counts
    assert "no force" in counts and "drift" in counts
