"""The one Runge-Kutta runner and its pairs: DOP853 through it takes the steps of the loop once
written for DOP853 alone, to the last bit; each pair's tableau meets the order conditions of its
orders; each pair converges at its order and its error estimate follows its true error."""

import itertools

import numpy as np
import pytest

from mechviz.bench import dop853_before as before
from mechviz.dynamics import Cyclotron, Hoop, ReleasedDisk, hoop
from mechviz.dynamics.integrators import exact, rk

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


# Order conditions --------------------------------------------------------------------------
VERNER = {"vern6": 6, "vern7": 7, "vern8": 8, "vern9": 9}


def _trees(max_order):
    """Every rooted tree up to ``max_order`` nodes, each a sorted tuple of its subtrees (a leaf is
    ``()``), with its order and density ``gamma``; listed by order."""
    by_order = {1: [()]}
    for n in range(2, max_order + 1):
        found = set()

        def children(left, smallest, chosen, n=n, found=found):
            # multisets of subtrees of total order `left`, in nondecreasing (order, index) order
            if left == 0:
                found.add(tuple(sorted(chosen)))
                return
            for m in range(1, left + 1):
                for k, t in enumerate(by_order[m]):
                    if (m, k) >= smallest:
                        children(left - m, (m, k), [*chosen, t])

        children(n - 1, (0, 0), [])
        by_order[n] = sorted(found)
    return by_order


def _order(t):
    return 1 + sum(_order(u) for u in t)


def _gamma(t):
    g = _order(t)
    for u in t:
        g *= _gamma(u)
    return g


TREES = _trees(9)


def test_the_trees_are_counted_as_in_the_literature():
    """1, 1, 2, 4, 9, 20, 48, 115, 286 rooted trees of order 1 ... 9 (OEIS A000081): the order
    conditions below check every one."""
    assert [len(TREES[n]) for n in range(1, 10)] == [1, 1, 2, 4, 9, 20, 48, 115, 286]


def _exact_tableau(name):
    """The pair's coefficients as 60-digit numbers: ``(A, b, b_hat, b(x) coefficients, n_all)``."""
    import importlib

    import mpmath

    mod = importlib.import_module(f"mechviz.dynamics.integrators.{name}")
    n = mod.PAIR.n_stages
    n_all = mod.PAIR.n_all
    ex = exact.exact
    with mpmath.workdps(exact.EXACT_DIGITS):
        A = mpmath.zeros(n_all, n_all)
        for (i, j), v in mod.A.items():
            A[i, j] = ex(v)
        b = [mpmath.mpf(0)] * n_all
        for j, v in mod.B.items():
            b[j] = ex(v)
            A[n, j] = b[j]
        b_hat = [mpmath.mpf(0)] * n_all
        for j, v in mod.B_HAT.items():
            b_hat[j] = ex(v)
        interp = {j: [ex(v) for v in coefs] for j, coefs in mod.INTERPOLANT.items()}
    return A, b, b_hat, interp, n_all


def _residuals(A, weights, n_all, max_order, x=1):
    """For each order up to ``max_order``, the largest |sum_i w_i Phi_i(t) - x^|t| / gamma(t)|
    over its trees (``weights`` a list, or a function of the stage giving b_i(x))."""
    import mpmath

    with mpmath.workdps(exact.EXACT_DIGITS):
        g = {}  # tree -> A Phi(tree)
        worst = {}
        for order in range(1, max_order + 1):
            worst[order] = mpmath.mpf(0)
            for t in TREES[order]:
                phi = [mpmath.mpf(1)] * n_all
                for u in t:
                    gu = g[u]
                    phi = [p * q for p, q in zip(phi, gu, strict=True)]
                g[t] = [mpmath.fsum(A[i, j] * phi[j] for j in range(i)) for i in range(n_all)]
                lhs = mpmath.fsum(w * p for w, p in zip(weights, phi, strict=True))
                r = abs(lhs - mpmath.mpf(x) ** order / _gamma(t))
                worst[order] = max(worst[order], r)
    return worst


@pytest.mark.parametrize("name", list(VERNER))
def test_verner_tableaus_meet_the_order_conditions_of_both_orders(name):
    """The propagated weights meet every condition up to the pair's order p and the embedded
    ones up to p - 1, to the 60 digits carried (the step's coefficients are exact fractions);
    each fails some condition one order higher, so the check can tell orders apart."""
    p = VERNER[name]
    A, b, b_hat, _, n_all = _exact_tableau(name)
    main = _residuals(A, b, n_all, min(p + 1, 9))
    emb = _residuals(A, b_hat, n_all, p)
    for order in range(1, p + 1):
        assert main[order] < 1e-45, (order, main[order])
    for order in range(1, p):
        assert emb[order] < 1e-45, (order, emb[order])
    assert emb[p] > 1e-8
    if p + 1 <= 9:
        assert main[p + 1] > 1e-8


@pytest.mark.parametrize("name", list(VERNER))
def test_verner_interpolants_meet_the_order_conditions_inside_the_step(name):
    """At x = 0.3 and 0.8 of a step, the interpolant's weights b_i(x) meet every condition
    sum b_i(x) Phi_i(t) = x^|t| / gamma(t) up to its stated order (6(5)'s exactly, the others'
    to double-precision round-off: their source gives those coefficients as decimals good to
    about 16 digits), miss some of the next order, and at x = 1 are b."""
    import mpmath

    pair = rk.load_pair(name)
    q = pair.dense_order
    A, b, _, interp, n_all = _exact_tableau(name)
    bound = 1e-45 if name == "vern6" else 1e-11
    for x in (mpmath.mpf(3) / 10, mpmath.mpf(8) / 10):
        with mpmath.workdps(exact.EXACT_DIGITS):
            w = [
                mpmath.fsum(c * x ** (k + 1) for k, c in enumerate(interp.get(j, [])))
                for j in range(n_all)
            ]
        worst = _residuals(A, w, n_all, min(q + 1, 9), x)
        for order in range(1, q + 1):
            assert worst[order] < bound, (float(x), order, worst[order])
        if q + 1 <= 9:
            assert worst[q + 1] > 1e-9
    with mpmath.workdps(exact.EXACT_DIGITS):
        at_end = [mpmath.fsum(interp.get(j, [0])) for j in range(n_all)]
    assert max(abs(e - bb) for e, bb in zip(at_end, b, strict=True)) < 1e-30


# Convergence and the error estimate, measured ---------------------------------------------
def _stages(pair, rhs, p, y0, h):
    """The stages ``K`` (n_all, d) of one step of ``pair`` from ``y0``, the dense output's
    included, from the pair's float64 tableau."""
    K = np.zeros((pair.n_all, y0.size))
    out = np.empty(y0.size)
    for s in range(pair.n_all):
        rhs(np.ascontiguousarray(y0 + h * (pair.A[s, :s] @ K[:s])), p, out)
        K[s] = out
    return K


def _slope(hs, errs):
    return float(np.polyfit(np.log(hs), np.log(errs), 1)[0])


def _kepler_exact(t, e):
    """Kepler's orbit of eccentricity ``e`` (mu = 1, semi-major axis 1) from perihelion at time
    ``t``: (q, p) as long doubles, from Kepler's equation solved in 40 digits."""
    import mpmath

    with mpmath.workdps(40):
        e, E = mpmath.mpf(e), mpmath.mpf(t)
        for _ in range(60):
            E -= (E - e * mpmath.sin(E) - t) / (1 - e * mpmath.cos(E))
        s, den = mpmath.sqrt(1 - e * e), 1 - e * mpmath.cos(E)
        y = (mpmath.cos(E) - e, s * mpmath.sin(E), -mpmath.sin(E) / den, s * mpmath.cos(E) / den)
        return np.array([np.longdouble(mpmath.nstr(v, 30)) for v in y])


KEPLER_STEPS = {
    "vern6": (45, 64, 90, 128, 181),
    "vern7": (64, 90, 128, 181, 256),
    "vern8": (16, 23, 32, 45, 64),
    "vern9": (16, 23, 32, 45),
}


@pytest.mark.skipif(np.finfo(np.longdouble).eps > 1e-18, reason="needs 80-bit long double")
@pytest.mark.parametrize("name", list(VERNER))
def test_verner_pairs_converge_at_their_order_on_keplers_orbit(name):
    """Kepler's problem (e = 0.2, to t = 3, where its exact flow is known) at fixed steps T / n,
    in long double with the exact coefficients, over the step counts where each pair's error
    lies between about 1e-9 and 1e-16 (above the long double's round-off): the slope of
    log(error) against log(h) is the pair's order p, within -0.4 ... +1.

    Not the charge's helix: it is linear, so only the conditions of the tall trees show (the
    6(5) pair gives 7.06 there). Verner chose these pairs for small leading error coefficients,
    so before the asymptotic regime the slope runs above p (9.8 for 9(8) here); in 50-digit
    arithmetic at n = 4096 on Kepler's orbit with e = 0.5 it is 6.79, 7.94 and 9.05 for 6(5),
    8(7) and 9(8), still nearing p. A wrong digit in one coefficient drops the order to a few."""
    import importlib

    import mpmath

    mod = importlib.import_module(f"mechviz.dynamics.integrators.{name}")
    n_s, p = mod.PAIR.n_stages, mod.PAIR.order
    L = np.longdouble
    A, b = np.zeros((n_s, n_s), dtype=L), np.zeros(n_s, dtype=L)
    with mpmath.workdps(exact.EXACT_DIGITS):
        for (i, j), v in mod.A.items():
            if i < n_s:
                A[i, j] = L(mpmath.nstr(exact.exact(v), 30))
        for j, v in mod.B.items():
            b[j] = L(mpmath.nstr(exact.exact(v), 30))

    def f(y):
        r3 = (y[0] ** 2 + y[1] ** 2) ** L(1.5)
        return np.array([y[2], y[3], -y[0] / r3, -y[1] / r3])

    T, y0 = 3, _kepler_exact(0, 0.2)
    y_exact = _kepler_exact(T, 0.2)
    hs, errs = [], []
    for n in KEPLER_STEPS[name]:
        y, h = y0.copy(), L(T) / n
        for _ in range(n):
            K = np.zeros((n_s, 4), dtype=L)
            for s in range(n_s):
                K[s] = f(y + h * (A[s, :s] @ K[:s]))
            y = y + h * (b @ K)
        hs.append(float(h))
        errs.append(float(np.linalg.norm((y - y_exact).astype(float))))
    assert min(errs) > 1e-17, errs  # above the long double's round-off
    slope = _slope(hs, errs)
    assert p - 0.4 < slope < p + 1.0, (slope, errs)


def _kepler_rhs(y, p, out):
    r3 = (y[0] ** 2 + y[1] ** 2) ** 1.5
    out[:] = y[2], y[3], -y[0] / r3, -y[1] / r3


@pytest.mark.parametrize("name", list(VERNER))
def test_verner_interpolants_converge_inside_a_step(name):
    """One step on Kepler's orbit (e = 0.7, from t = 0.3), the interpolant at 0.7 of it against
    the exact flow, at steps where its error is resolved (above 5e-11: the interpolants'
    coefficients reach 1.2e5 (6(5)) and 1.4e6 (8(7)), and the source gives those of 7(6), 8(7)
    and 9(8) to double precision only): the local error falls at least as h^(q - 0.6), q the
    interpolant's order.

    An interpolant of order q errs by O(h^(q + 1)) inside a step, but in double precision these
    slopes are still pre-asymptotic (measured: 7.35, 7.11, 7.69 and 8.48 for the 6(5) ... 9(8)
    pairs, q = 6, 6, 8, 9); the order conditions above are the exact check. A broken
    coefficient gives a slope of a few."""
    pair = rk.load_pair(name)
    t0, e, x = 0.3, 0.7, 0.7
    y0 = _kepler_exact(t0, e).astype(float)
    hs, errs = [], []
    for k in range(8):
        h = 0.4 / 2 ** (k / 2)
        K = _stages(pair, _kepler_rhs, None, y0, h)
        weights = sum(pair.P[j] * x ** (j + 1) for j in range(pair.P.shape[0]))
        err = float(np.linalg.norm(y0 + h * (weights @ K) - _kepler_exact(t0 + x * h, e)))
        if err > 5e-11:
            hs.append(h)
            errs.append(err)
    assert len(hs) >= 4, errs
    assert _slope(hs, errs) > pair.dense_order - 0.6, (_slope(hs, errs), errs)


@pytest.mark.parametrize("name", ["dop853", *VERNER])
@pytest.mark.parametrize("where", ["kepler", "hoop"])
def test_the_error_estimate_tracks_the_embedded_solutions_true_error(name, where):
    """One step from a state: the estimate ``h E K`` the controller reads against the true
    local error of the embedded (lower-order) solution, from the exact flow (Kepler's orbit,
    e = 0.2, from perihelion) or a tight DOP853 reference run (the hoop). Their ratio is within
    10 % of 1 at the smallest step here. DOP853's blended estimate is checked on its
    5th-order part. (Not the charge: on its linear flow the embedded solutions of 8(7) and 9(8)
    are exact to round-off at these steps.)"""
    from mechviz.dynamics import Simulation
    from mechviz.dynamics.integrators import kernels

    pair = rk.load_pair(name)
    if where == "kepler":
        y0, rhs, p = _kepler_exact(0.7, 0.2).astype(float), _kepler_rhs, None
    else:
        system, y0 = SYSTEMS[where]
        rhs, p = kernels.RHS[system.sys_id], system.kernel_params()
    ratios = []
    for h in (0.8, 0.5, 0.3) if where == "kepler" else (0.4, 0.2, 0.1):
        K = _stages(pair, rhs, p, y0, h)
        y_new = y0 + h * (pair.b @ K[: pair.n_stages])
        est = h * (pair.E[0] @ K[: pair.n_stages + 1])
        embedded = y_new - est
        if where == "kepler":
            truth = _kepler_exact(0.7 + h, 0.2).astype(float)
        else:
            ref = Simulation(system, "dop853", rtol=1e-14, atol=1e-16, state=y0, reference=None)
            ref.advance_to(h, final=True)
            truth = ref.state[0]
        true_err = np.linalg.norm(embedded - truth)
        ratios.append(np.linalg.norm(est) / true_err)
        assert true_err > 1e-12, (h, true_err)  # resolved above round-off and the reference
    assert abs(ratios[-1] - 1.0) < 0.1, ratios


@pytest.mark.parametrize("name", list(VERNER))
@pytest.mark.parametrize("where", ["charge", "hoop"])
def test_verner_runs_follow_their_tolerance_against_the_reference(name, where):
    """Whole runs through the driver (sampled 40 times, so through the interpolant too) against
    the exact solution (charge) or the tight DOP853 reference run (hoop): the final error falls
    with the tolerance, by more than 30x for 1e-6 to 1e-9 and stays within 1000x the tolerance;
    the evaluations are those of the pair's steps and its dense output."""
    from mechviz.dynamics import Simulation

    system, y0 = SYSTEMS[where]
    pair = rk.load_pair(name)
    errors = []
    for tol in (1e-6, 1e-9):
        sim = Simulation(system, name, rtol=tol, atol=tol, state=y0)
        for k in range(1, 41):
            sim.advance_to(0.25 * k, final=k == 40)
        err = float(np.max(sim.sample().error))
        errors.append(err)
        assert err < 1e3 * tol, (tol, err)
        steps = sim.steps + sim.rejected
        dense_max = 40 * pair.dense_evaluations
        assert steps * pair.n_stages <= sim.nfev <= steps * pair.n_stages + dense_max + 2
    assert errors[1] < errors[0] / 30, errors
