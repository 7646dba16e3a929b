"""The reference's own error is measured in every run, not assumed: on a chaotic hoop start the
error bar a run reports covers the reference's true error against a 30-digit integration."""

from __future__ import annotations

import mpmath as mp
import numpy as np
import pytest

from mechviz.dynamics import Hoop, Simulation, api
from mechviz.dynamics.simulation import RESOLVED_FACTOR, error_verdict

#: At rest with large angles of opposite sign: a start in the chaotic part of the chaos map.
CHAOTIC = (1.3, -0.8, 0.0, 0.0)
TIMES = (30.0, 45.0, 60.0)


def _hoop_rhs(p):
    M, m, a, g = (mp.mpf(repr(float(x))) for x in p.kernel_params())
    ga = g / a

    def f(y):
        th1, th2, w1, w2 = y
        s, c = mp.sin(th1 - th2), mp.cos(th1 - th2)
        r1 = -m * s * w2 * w2 - (M + m) * ga * mp.sin(th1)
        r2 = s * w1 * w1 - ga * mp.sin(th2)
        det = 2 * M + m - m * c * c
        return [w1, w2, (r1 - m * c * r2) / det, ((2 * M + m) * r2 - c * r1) / det]

    return f


def _gragg(f, y, H, n):
    """Gragg's smoothed modified midpoint rule: ``n`` substeps over ``H``."""
    h = H / n
    z0, z1 = y, [a + h * b for a, b in zip(y, f(y), strict=True)]
    for _ in range(n - 1):
        z0, z1 = z1, [a + 2 * h * b for a, b in zip(z0, f(z1), strict=True)]
    return [(a + b + h * c) / 2 for a, b, c in zip(z0, z1, f(z1), strict=True)]


def _bulirsch_stoer(f, y0, t_marks, H, tol):
    """The state at each of ``t_marks`` (multiples of ``H``): Gragg's rule extrapolated in h^2
    until two diagonal entries agree to ``tol`` (a step that does not converge fails)."""
    y, t, out = list(y0), mp.mpf(0), []
    for mark in t_marks:
        while t < mark - H / 2:
            table = []
            for k in range(1, 25):
                row = [_gragg(f, y, H, 2 * k)]
                for j in range(1, k):
                    r = (mp.mpf(k) / (k - j)) ** 2
                    row.append(
                        [
                            a + (a - b) / (r - 1)
                            for a, b in zip(row[j - 1], table[-1][j - 1], strict=True)
                        ]
                    )
                if (
                    k > 1
                    and max(abs(a - b) for a, b in zip(row[-1], table[-1][-1], strict=True)) < tol
                ):
                    break
                table.append(row)
            else:
                raise AssertionError("the extrapolation did not converge")
            y, t = row[-1], t + H
        out.append(np.array([float(v) for v in y]))
    return out


@pytest.mark.slow
def test_the_reference_error_bar_covers_its_true_error_on_a_chaotic_start():
    system = Hoop()
    sim = Simulation(system, "rk4", dt=0.01, state=np.array(CHAOTIC))
    samples = []
    for t in TIMES:
        sim.advance_to(t)
        samples.append(sim.sample())
    with mp.workdps(30):
        truth = _bulirsch_stoer(
            _hoop_rhs(system.params),
            [mp.mpf(repr(x)) for x in CHAOTIC],
            TIMES,
            mp.mpf(1) / 20,
            mp.mpf(10) ** -24,
        )
    true_errors = []
    for smp, exact in zip(samples, truth, strict=True):
        assert smp.reference_kind == "reference"
        true_error = float(system.error(smp.reference[0], exact))
        bar = float(smp.reference_accuracy[0])
        assert true_error <= bar, (smp.t, true_error, bar)
        true_errors.append(true_error)
    # chaotic indeed: the reference's own error grows by over a hundredfold from 30 s to 60 s,
    # far past the 5e-13 it keeps on the exact motions
    assert true_errors[-1] > 100 * true_errors[0] and true_errors[-1] > 1e-10


def test_a_run_reports_its_error_with_the_reference_error_and_whether_it_is_resolved():
    tight = api.simulate(
        "hoop", method="dop853", rtol=1e-12, t_end=60.0, samples=3, state=np.array(CHAOTIC)
    )
    loose = api.simulate(
        "hoop", method="rk4", dt=0.01, t_end=30.0, samples=3, state=np.array(CHAOTIC)
    )
    for run in (tight, loose):
        s = run.summary()
        assert s["reference_error"] == pytest.approx(float(run.reference_error[-1]))
        assert s["reference_error"] > 0.0
        assert s["error_resolved"] == (
            s["error_vs_reference"] >= RESOLVED_FACTOR * s["reference_error"]
        )
    assert loose.summary()["error_resolved"]
    assert "not resolved" in error_verdict(1e-12, 1e-12)
    assert "reference good to" in error_verdict(1e-9, 1e-12)
