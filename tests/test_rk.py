"""The one Runge-Kutta runner and its pairs: DOP853 through it takes the steps of the loop once
written for DOP853 alone, to the last bit; each pair's tableau meets the order conditions of its
orders; each pair converges at its order and its error estimate follows its true error."""

import itertools

import numpy as np
import pytest

from mechviz.bench import dop853_before as before
from mechviz.dynamics import Cyclotron, Hoop, ReleasedDisk, hoop
from mechviz.dynamics.integrators import rk

SYSTEMS = {
    "charge": (Cyclotron(), np.array([1.0, -0.5, 0.2, 0.3, 1.0, 0.1])),
    "hoop": (Hoop(), hoop.mode_state(Hoop().params, (0.5, 0.2))),
    "disk": (ReleasedDisk(), None),
}


def _start(name, members=3):
    system, y0 = SYSTEMS[name]
    if y0 is None:
        y0 = np.asarray(system.default_state(), dtype=float)
    spread = 1e-2 * np.arange(members)[:, None] * np.maximum(np.abs(y0), 1.0)
    return system, y0 + spread


@pytest.mark.parametrize("name", list(SYSTEMS))
def test_dop853_through_the_generic_runner_repeats_its_own_loop_bit_for_bit(name):
    """Sampled at uneven times (each a kept step and an interpolation), then landed on a final
    time: the same states and the same counts of evaluations, steps and rejections."""
    system, Y0 = _start(name)
    n, d = Y0.shape
    sys_id, p = system.sys_id, system.kernel_params()
    pair = rk.load_pair("dop853")
    times = [0.0, 0.37, 0.4, 1.9, 2.0, 5.3]

    def arrays():
        return Y0.copy(), np.zeros(n), np.zeros((n, d)), np.zeros((n, 3), np.int64)

    Ya, Ha, Fa, Sa = arrays()
    Yb, Hb, Fb, Sb = arrays()
    ca, cb = before.Dop853Carry(n, d), rk.RKCarry(n, d, pair)
    status = np.zeros(4, dtype=np.int64)
    for k, (t0, t1) in enumerate(itertools.pairwise(times)):
        land = k == len(times) - 2
        before.run_dop853(sys_id, Ya, p, t0, t1, 1e-9, 1e-9, Ha, Fa, Sa, status, ca, land)
        rk.run_rk(pair, sys_id, Yb, p, t0, t1, 1e-9, 1e-9, Hb, Fb, Sb, status, cb, land)
        assert np.array_equal(Ya, Yb), (t1, np.max(np.abs(Ya - Yb)))
        assert np.array_equal(Sa, Sb)
        assert np.array_equal(Ha, Hb)
    assert Sa[:, 1].min() > 5  # the run took steps
