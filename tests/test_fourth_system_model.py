"""The fourth system (:mod:`spherical`, defined in the test suite only) in the viewer's headless
model (:mod:`spherical_exhibit`: an :class:`~mechviz.viz.model.base.ExhibitModel` of its own,
registered beside the system), run as the viewer and the recorder run a model.

The physics checked: the energy and ``L_z`` kept over a run at the exhibit's step, the swing of
the polar angle measured from the model's samples against its period from the two invariants
(a quadrature between the turning points), and a change of method or of start taking effect.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import spherical_exhibit
from scipy.integrate import quad
from scipy.optimize import brentq
from spherical import NAME, PendulumParams, invariants, start_state

from mechviz.viz.model import MODELS
from mechviz.viz.model.commands import Set


@pytest.fixture(scope="module")
def registered():
    with spherical_exhibit.registered() as reg:
        yield reg


def swing_period(p: PendulumParams, state: np.ndarray) -> float:
    """The period [s] of ``theta`` between its turning points, from ``E`` and ``L_z``:
    ``theta'^2 = 2 (E + g l cos theta) / l^2 - L_z^2 / (l^4 sin^2 theta)``, integrated as
    ``2 int dtheta / theta'`` with ``theta = c + r sin u`` (smooth at the turning points)."""
    energy, lz = invariants(p, state)
    l, g = p.length, p.gravity

    def rate2(th: float) -> float:
        return 2 * (energy + g * l * math.cos(th)) / l**2 - lz**2 / (l**4 * math.sin(th) ** 2)

    # the rate vanishes at the turning points; the conical orbit's tilt lies between them
    inside = brentq(lambda th: g * math.tan(th) * math.sin(th) ** 3 - lz**2 / l**3, 1e-6, 1.56)
    lo = brentq(rate2, 1e-6, inside)
    hi = brentq(rate2, inside, math.pi - 1e-6)
    c, r = 0.5 * (hi + lo), 0.5 * (hi - lo)
    integrand = lambda u: r * math.cos(u) / math.sqrt(max(rate2(c + r * math.sin(u)), 1e-300))  # noqa: E731
    return 2 * quad(integrand, -math.pi / 2, math.pi / 2, epsabs=1e-13, epsrel=1e-12)[0]


def test_the_model_is_found_through_the_registry_and_keeps_both_invariants(registered):
    model = MODELS[NAME]()
    assert model.key == NAME and model.sim.method.name == "rk4"
    start = model.state.copy()
    for _ in range(1200):  # 20 s at 60 frames a second, sampled every third frame
        model.advance(1 / 60, measure=True)
    assert not model.paused and model.t == pytest.approx(20.0)
    p = model.config.physics()
    e0, lz0 = invariants(p, start)
    e1, lz1 = invariants(p, model.state)
    assert abs(e1 - e0) / abs(e0) < 1e-6  # RK4 at 1/120 s
    assert abs(lz1 - lz0) / abs(lz0) < 1e-6
    assert abs(model.measured()["Lz_mean"] - lz0) < 1e-6 * abs(lz0)
    # the error against the driver's DOP853 reference, through the system's own forms
    assert model.sample.error[0] < 1e-5


def test_the_measured_swing_matches_its_period_from_the_invariants(registered):
    model = MODELS[NAME]()
    for _ in range(1800):  # 30 s: about 17 swings of theta
        model.advance(1 / 60)
    measured = model.measured()["swing_frequency"]
    predicted = 2 * math.pi / swing_period(model.config.physics(), model.sim.state0[0])
    assert measured, measured
    assert abs(measured.value - predicted) < 2e-3 * predicted, (measured.value, predicted)


def test_a_new_method_restarts_and_a_new_start_jumps(registered):
    model = MODELS[NAME]()
    model.apply(Set(fields={"method": "taylor", "rtol": 1e-11}))
    assert model.sim.method.name == "taylor" and model.t == 0.0
    model.advance(5.0)
    assert model.sample.error[0] < 1e-8
    model.apply(Set(fields={"tilt": 0.7, "precession": 2.5}))
    assert model.t == pytest.approx(5.0)  # a start setting jumps, the clock goes on
    np.testing.assert_array_equal(model.state, start_state(0.7, model.config.swing, 2.5))
    model.advance(5.0)
    lz = invariants(model.config.physics(), np.stack([model.sim.state0[0], model.state]))[1]
    assert abs(lz[1] - lz[0]) < 1e-10 * abs(lz[0])
