"""Code generated from the equations written once (:mod:`mechviz.dynamics.codegen`) agrees with
the hand-written kernels to round-off, on random states and parameters other than the defaults."""

from __future__ import annotations

import numpy as np
import pytest

from mechviz.dynamics.codegen.equations import EQUATIONS
from mechviz.dynamics.codegen.rhs import generated_rhs
from mechviz.dynamics.integrators.kernels import RHS

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
    files = list(build.generated_dir().glob(f"*_rhs_{eq.name}_{eq.key()}.py"))
    assert len(files) == 1
    assert "def rhs(y, p, out)" in files[0].read_text()
