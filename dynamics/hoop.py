"""Bead on a hanging hoop: a hoop swinging in its own plane about a pivot on its rim, with a bead
sliding on it without friction.

Units and conventions (SI throughout)
-------------------------------------
- Hoop mass ``M`` [kg] (a thin ring), radius ``a`` [m]; bead mass ``m`` [kg]; gravity ``g``
  [m/s^2] along -y. The pivot is the origin; everything moves in the x-y plane.
- ``theta1`` [rad]: angle of the hoop's centre from the downward vertical at the pivot.
  ``theta2`` [rad]: *absolute* angle of the bead from the downward vertical through the hoop's
  centre (as in the seed). Both increase anticlockwise (towards +x from straight down).
- State ``(theta1, theta2, omega1, omega2)`` with ``omega_i = d theta_i / dt`` [rad/s].
- Hoop centre ``a (sin theta1, -cos theta1)``; bead at the centre plus ``a (sin theta2, -cos theta2)``.
- Energy: the potential's zero is at the pivot's height, so the energy hanging at rest is
  ``-(M + 2m) g a``; the relative energy error is that of the energy above that floor,
  evaluated directly (:func:`energy_above_rest`), the energy that oscillates.

Lagrangian (hoop inertia about the pivot ``2 M a^2``, parallel-axis theorem)::

    L = (M + m/2) a^2 w1^2 + (m a^2 / 2) w2^2 + m a^2 cos(th1 - th2) w1 w2
        + (M + m) g a cos th1 + m g a cos th2

Mass matrix ``a^2 [[2M + m, m c], [m c, m]]`` with ``c = cos(th1 - th2)``. Euler-Lagrange::

    (2M + m) th1'' + m c th2'' = -m s w2^2 - (M + m)(g/a) sin th1
          c  th1'' +     th2'' =  s w1^2  -        (g/a) sin th2        (s = sin(th1 - th2))

The seed prints the second equation with ``+ cos(th1 - th2) th1''`` on its right-hand side; the
Lagrangian gives ``- cos(...) th1''`` (its matrix (3.2) and mode frequencies use the right sign).

Normal modes (linearised): ``omega_1 = sqrt(g / 2a)`` with shape (1, 1), and
``omega_2 = sqrt((1 + m/M) g / a)`` with shape ``(m, -(M + m))``. Mode 1 is also an exact invariant
set of the nonlinear equations: with ``th1 = th2`` the bead sits rigidly opposite the pivot and
the whole body is a pendulum obeying ``th'' = -(g / 2a) sin th`` at any amplitude, solved in
closed form with Jacobi elliptic functions (:func:`mode1_exact_solution`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import params as _v
from ._jit import deferred_njit

STATE_NAMES = ("theta1", "theta2", "omega1", "omega2")


@dataclass(frozen=True)
class HoopParams:
    """Hoop mass ``hoop_mass`` [kg], bead mass ``bead_mass`` [kg], radius [m], gravity [m/s^2]."""

    hoop_mass: float = 1.0
    bead_mass: float = 0.5
    radius: float = 1.0
    gravity: float = 9.81

    def __post_init__(self) -> None:
        _v.coerce(self, dict.fromkeys(("hoop_mass", "bead_mass", "radius", "gravity"), _v.positive))

    def kernel_params(self) -> np.ndarray:
        """``[M, m, a, g]`` for the compiled kernels."""
        return np.array([self.hoop_mass, self.bead_mass, self.radius, self.gravity])


# --------------------------------------------------------------------------- structure
def mass_matrix(p: HoopParams, theta1: float, theta2: float) -> np.ndarray:
    """``a^2 [[2M + m, m cos(th1 - th2)], [m cos(th1 - th2), m]]`` [kg m^2]."""
    M, m, a = p.hoop_mass, p.bead_mass, p.radius
    c = math.cos(theta1 - theta2)
    return a * a * np.array([[2 * M + m, m * c], [m * c, m]])


def positions(p: HoopParams, state: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Hoop centre and bead, each (..., 2) in the swing plane [m]."""
    s = np.asarray(state, dtype=float)
    a = p.radius
    centre = a * np.stack([np.sin(s[..., 0]), -np.cos(s[..., 0])], axis=-1)
    bead = centre + a * np.stack([np.sin(s[..., 1]), -np.cos(s[..., 1])], axis=-1)
    return centre, bead


def energy(p: HoopParams, state: np.ndarray) -> np.ndarray:
    """Total energy ``T + V`` [J] (zero of V at the pivot's height); works on (..., 4) arrays."""
    s = np.asarray(state, dtype=float)
    M, m, a, g = p.hoop_mass, p.bead_mass, p.radius, p.gravity
    th1, th2, w1, w2 = s[..., 0], s[..., 1], s[..., 2], s[..., 3]
    kinetic = a * a * ((M + 0.5 * m) * w1**2 + 0.5 * m * w2**2 + m * np.cos(th1 - th2) * w1 * w2)
    potential = -(M + m) * g * a * np.cos(th1) - m * g * a * np.cos(th2)
    return kinetic + potential


def energy_above_rest(p: HoopParams, state: np.ndarray) -> np.ndarray:
    """Energy above hanging at rest [J], ``energy(state) + (M + 2m) g a``, evaluated without
    cancellation so that it keeps its relative precision at any swing, however small.

    The potential uses ``1 - cos th = 2 sin^2(th / 2)``; the kinetic energy is a sum of squares,
    ``a^2 (M w1^2 + (m/2) |w1 e(th1) + w2 e(th2)|^2)`` with ``e(th) = (cos th, sin th)``, the
    hoop's rotation about the pivot plus the bead's velocity relative to it. ``energy`` takes
    the difference of two terms near ``(M + 2m) g a``, which at a swing ``A`` loses a factor
    ``1 / A^2`` of its relative precision."""
    s = np.asarray(state, dtype=float)
    M, m, a, g = p.hoop_mass, p.bead_mass, p.radius, p.gravity
    th1, th2, w1, w2 = s[..., 0], s[..., 1], s[..., 2], s[..., 3]
    vx = w1 * np.cos(th1) + w2 * np.cos(th2)
    vy = w1 * np.sin(th1) + w2 * np.sin(th2)
    kinetic = a * a * (M * w1 * w1 + 0.5 * m * (vx * vx + vy * vy))
    h1, h2 = np.sin(0.5 * th1), np.sin(0.5 * th2)
    potential = 2.0 * g * a * ((M + m) * h1 * h1 + m * h2 * h2)
    return kinetic + potential


# --------------------------------------------------------------------------- normal modes
def normal_modes(p: HoopParams) -> tuple[np.ndarray, np.ndarray]:
    """Frequencies [rad/s] (ascending) and shapes (rows ``[theta1, theta2]``, largest entry 1).

    ``omega_1 = sqrt(g/2a)``, shape (1, 1): hoop and bead in phase with equal amplitude.
    ``omega_2 = sqrt((1 + m/M) g/a)``, shape ``(m, -(M + m)) / (M + m)``: out of phase, the bead
    swinging wider.
    """
    M, m = p.hoop_mass, p.bead_mass
    freqs = np.array(mode_frequencies(p))
    shapes = np.array([[1.0, 1.0], [m / (M + m), -1.0]])
    return freqs, shapes


def mode_frequencies(p: HoopParams) -> tuple[float, float]:
    """``(omega_1, omega_2)`` [rad/s] of :func:`normal_modes`, as floats: the driver asks for
    the higher one at the start of every adaptive run, where building arrays would cost more
    than the run's own setup."""
    M, m, a, g = p.hoop_mass, p.bead_mass, p.radius, p.gravity
    return math.sqrt(g / (2 * a)), math.sqrt((1 + m / M) * g / a)


def mode_state(p: HoopParams, amplitudes: tuple[float, float]) -> np.ndarray:
    """Initial state at rest with mode ``k`` displaced by ``amplitudes[k]`` [rad].

    The amplitude of a mode is its largest angle (that of the bead in mode 2). A pure mode is
    ``(A, 0)`` or ``(0, A)``; anything else is a mix.
    """
    _, shapes = normal_modes(p)
    amps = np.array([_v.finite("amplitude", x) for x in amplitudes])
    theta = amps @ shapes
    return np.array([theta[0], theta[1], 0.0, 0.0])


def linear_solution(p: HoopParams, state0: np.ndarray, t: np.ndarray | float) -> np.ndarray:
    """Solution of the linearised equations from ``state0`` at times ``t``: shape ``t.shape + (4,)``.

    The small-oscillation motion is a sum of the two modes; their coordinates follow from the
    initial angles and rates by solving with the (non-orthogonal) shape matrix.
    """
    freqs, shapes = normal_modes(p)
    s0 = np.asarray(state0, dtype=float)
    tt = np.asarray(t, dtype=float)[..., None]
    basis = shapes.T  # columns are the shapes
    c = np.linalg.solve(basis, s0[:2])  # modal displacements
    d = np.linalg.solve(basis, s0[2:]) / freqs  # modal velocities / omega
    q = c * np.cos(freqs * tt) + d * np.sin(freqs * tt)
    qdot = freqs * (-c * np.sin(freqs * tt) + d * np.cos(freqs * tt))
    return np.concatenate([q @ shapes, qdot @ shapes], axis=-1)


def on_mode1_manifold(state: np.ndarray, tol: float = 1e-12) -> bool:
    """True if ``theta1 = theta2`` and ``omega1 = omega2``: the exact nonlinear mode 1."""
    s = np.asarray(state, dtype=float)
    return abs(s[0] - s[1]) <= tol and abs(s[2] - s[3]) <= tol


def mode1_exact_solution(p: HoopParams, state0: np.ndarray, t: np.ndarray | float) -> np.ndarray:
    """Exact nonlinear motion in mode 1 at any amplitude below the top: shape ``t.shape + (4,)``.

    With ``theta1 = theta2 = theta`` both equations of motion reduce to the pendulum
    ``theta'' = -w0^2 sin theta``, ``w0^2 = g / 2a``. Its solution is
    ``sin(theta/2) = k sn(u0 + w0 t | k^2)``, ``theta' = 2 k w0 cn(u0 + w0 t | k^2)``, with the
    modulus ``k^2 = sin^2(theta0/2) + (theta0' / 2 w0)^2`` fixed by the energy.
    """
    s0 = np.asarray(state0, dtype=float)
    if not on_mode1_manifold(s0):
        raise ValueError("mode-1 exact solution needs theta1 == theta2 and omega1 == omega2")
    w0 = math.sqrt(p.gravity / (2 * p.radius))
    sin_half = math.sin(0.5 * s0[0])
    rate = s0[2] / (2 * w0)
    k2 = sin_half**2 + rate**2
    if k2 >= 1.0:
        raise ValueError("mode-1 motion goes over the top: no libration to solve for")
    tt = np.asarray(t, dtype=float)
    if k2 == 0.0:
        return np.zeros(tt.shape + (4,))
    from scipy import special  # 0.1-0.4 s to import: only the exact mode-1 runs need it

    k = math.sqrt(k2)
    phi0 = math.atan2(sin_half / k, rate / k)  # amplitude: sn = sin(phi0), cn = cos(phi0)
    u0 = float(special.ellipkinc(phi0, k2))
    sn, cn, _, _ = special.ellipj(u0 + w0 * tt, k2)
    theta = 2.0 * np.arcsin(np.clip(k * sn, -1.0, 1.0))
    theta_dot = 2.0 * k * w0 * cn
    return np.stack([theta, theta, theta_dot, theta_dot], axis=-1)


def mode1_period(p: HoopParams, amplitude: float) -> float:
    """Period [s] of mode 1 at finite ``amplitude`` [rad]: ``4 K(k^2) / w0``, ``k = sin(A/2)``."""
    from scipy import special  # deferred, as in mode1_exact_solution

    w0 = math.sqrt(p.gravity / (2 * p.radius))
    return 4.0 * float(special.ellipk(math.sin(0.5 * amplitude) ** 2)) / w0


# --------------------------------------------------------------------------- compiled pieces


@deferred_njit(cache=True)
def _velocities(M, m, a, th1, th2, p1, p2):
    """``theta' = M(theta)^-1 p`` for canonical momenta ``p`` [kg m^2/s]."""
    c = math.cos(th1 - th2)
    det = a * a * m * (2.0 * M + m - m * c * c)
    return (m * p1 - m * c * p2) / det, ((2.0 * M + m) * p2 - m * c * p1) / det


@deferred_njit(cache=True)
def _force(M, m, a, g, th1, th2, w1, w2):
    """``-dH/dtheta`` at given angles and velocities (``H`` is quadratic in ``p``)."""
    k = m * a * a * math.sin(th1 - th2) * w1 * w2
    return -k - (M + m) * g * a * math.sin(th1), k - m * g * a * math.sin(th2)


VERLET_TOL = 1e-14  # relative change at which the fixed-point iterations stop
VERLET_MAX_ITER = 100


@deferred_njit(cache=True)
def verlet_step(y, p, h):
    """One generalised Stormer-Verlet step (Hairer, Lubich & Wanner, GNI, eq. VI.3.4), in place.

    ``H(q, p)`` is not separable (the mass matrix depends on ``th1 - th2``), so the half kick and
    the drift are implicit; both are solved by fixed-point iteration to ``VERLET_TOL``. Returns
    the number of partial evaluations used, or ``-1`` if an iteration did not converge in
    ``VERLET_MAX_ITER`` sweeps or diverged to an overflow (the caller turns that into an error).
    """
    M, m, a, g = p[0], p[1], p[2], p[3]
    th1, th2 = y[0], y[1]
    c = math.cos(th1 - th2)
    a2 = a * a
    p1 = a2 * ((2.0 * M + m) * y[2] + m * c * y[3])
    p2 = a2 * (m * c * y[2] + m * y[3])
    half = 0.5 * h
    evals = 0
    # p_half = p - h/2 dH/dq(q, p_half)
    q1, q2 = p1, p2
    converged = False
    for _ in range(VERLET_MAX_ITER):
        w1, w2 = _velocities(M, m, a, th1, th2, q1, q2)
        f1, f2 = _force(M, m, a, g, th1, th2, w1, w2)
        n1, n2 = p1 + half * f1, p2 + half * f2
        evals += 1
        size = abs(n1) + abs(n2)
        # An iterate that overflowed is no fixed point (inf <= inf would pass): the iteration
        # diverged, which is the failure to report, not a step to a non-finite state.
        if abs(n1 - q1) + abs(n2 - q2) <= VERLET_TOL * (1.0 + size) and size < math.inf:
            q1, q2 = n1, n2
            converged = True
            break
        q1, q2 = n1, n2
    if not converged:
        return -1
    # q_new = q + h/2 (dH/dp(q, p_half) + dH/dp(q_new, p_half))
    v1, v2 = _velocities(M, m, a, th1, th2, q1, q2)
    n_th1, n_th2 = th1 + h * v1, th2 + h * v2
    converged = False
    for _ in range(VERLET_MAX_ITER):
        u1, u2 = _velocities(M, m, a, n_th1, n_th2, q1, q2)
        t1, t2 = th1 + half * (v1 + u1), th2 + half * (v2 + u2)
        evals += 1
        size = abs(t1) + abs(t2)
        if abs(t1 - n_th1) + abs(t2 - n_th2) <= VERLET_TOL * (1.0 + size) and size < math.inf:
            n_th1, n_th2 = t1, t2
            converged = True
            break
        n_th1, n_th2 = t1, t2
    if not converged:
        return -1
    # p_new = p_half - h/2 dH/dq(q_new, p_half): explicit
    u1, u2 = _velocities(M, m, a, n_th1, n_th2, q1, q2)
    f1, f2 = _force(M, m, a, g, n_th1, n_th2, u1, u2)
    q1 += half * f1
    q2 += half * f2
    evals += 1
    y[0], y[1] = n_th1, n_th2
    y[2], y[3] = _velocities(M, m, a, n_th1, n_th2, q1, q2)
    return evals


def analysis(p: HoopParams) -> dict:
    """The seed's results, JSON-ready: the normal-mode frequencies [rad/s], periods [s] and
    shapes (rows). A result a double cannot hold is NaN (:func:`mechviz.dynamics.params.guarded`)."""
    g = _v.guarded
    freqs, shapes = g(lambda: normal_modes(p), (np.full(2, np.nan), np.full((2, 2), np.nan)))
    return {
        "parameters": {
            "hoop_mass": p.hoop_mass,
            "bead_mass": p.bead_mass,
            "radius": p.radius,
            "gravity": p.gravity,
        },
        "mode_frequencies": freqs.tolist(),
        "mode_periods": g(lambda: (2 * np.pi / freqs).tolist()),
        "mode_shapes": shapes.tolist(),
    }


# --------------------------------------------------------------------------- structure check
def canonical_maps(params: HoopParams):
    """``(to_canonical, from_canonical)``: the state ``(theta1, theta2, theta1', theta2')`` to
    the canonical ``(theta, p = M(theta) theta')`` (``M`` the Lagrangian's mass matrix,
    ``p`` the generalized momenta ``dL/dtheta'``) and back."""
    M, m, a = params.hoop_mass, params.bead_mass, params.radius

    def mass(th1, th2):
        c = np.cos(th1 - th2)
        return a * a * np.array([[2 * M + m, m * c], [m * c, m]])

    def to_canonical(y):
        return np.concatenate([y[:2], mass(y[0], y[1]) @ y[2:4]])

    def from_canonical(z):
        return np.concatenate([z[:2], np.linalg.solve(mass(z[0], z[1]), z[2:4])])

    return to_canonical, from_canonical
