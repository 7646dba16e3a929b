"""Cyclotron motion: a point charge in a uniform, static magnetic field.

Units and conventions (SI throughout)
-------------------------------------
- Charge ``q`` [C] (signed), mass ``m`` [kg], field ``B`` [T] along +z (a negative ``B`` points the
  field along -z). Force ``F = q v x B``; no electric field.
- State ``(x, y, z, vx, vy, vz)`` [m, m/s]. A velocity component along B gives a helix.
- Signed gyrofrequency ``Omega = q B / m`` [rad/s]. The velocity rotates by the angle ``-Omega t``
  about +z: a positive charge in a field along +z turns **clockwise** seen from +z (it gyrates
  left-handedly about B), a negative charge anticlockwise.
- Symmetric gauge ``A = (B/2)(-y, x, 0)``, so the Lagrangian is
  ``L = m v^2/2 + (qB/2)(x vy - y vx)`` and the canonical angular momentum about the z axis,
  ``p_phi = m (x vy - y vx) + (q B / 2)(x^2 + y^2)``, is conserved.
- Energy error: the energy is all kinetic, ``m |v|^2 / 2``, so the relative energy error is
  ``(E - E0) / E0`` (the energy floor is 0, at rest).

Relation to the seed: its Lagrangian (1.1), ``m v^2/2 - (eB/2)(x y' - x' y)``, is ours with
``q B = -e B``: the seed's charge +e turns anticlockwise, which here is a negative charge (or a
positive one in a field along -z). Every formula below reduces to the seed's with ``qB -> -eB``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import params as _v
from ._jit import deferred_njit

STATE_NAMES = ("x", "y", "z", "vx", "vy", "vz")


@dataclass(frozen=True)
class CyclotronParams:
    """Charge ``charge`` [C], mass ``mass`` [kg], field ``field`` [T] along +z."""

    charge: float = 1.0
    mass: float = 1.0
    field: float = 1.0

    def __post_init__(self) -> None:
        _v.coerce(self, {"charge": _v.nonzero, "mass": _v.positive, "field": _v.nonzero})

    def kernel_params(self) -> np.ndarray:
        """The float64 array the compiled kernels read: ``[Omega]``."""
        return np.array([signed_gyrofrequency(self)])


# --------------------------------------------------------------------------- analytic results
def signed_gyrofrequency(p: CyclotronParams) -> float:
    """``Omega = q B / m`` [rad/s]; its sign gives the sense of rotation (module docstring)."""
    return p.charge * p.field / p.mass


def gyrofrequency(p: CyclotronParams) -> float:
    """Orbital angular frequency ``omega = |qB| / m`` [rad/s], independent of energy (seed 1b)."""
    return abs(signed_gyrofrequency(p))


def period(p: CyclotronParams) -> float:
    """Gyro-period ``2 pi / omega`` [s]."""
    return 2.0 * math.pi / gyrofrequency(p)


def orbit_radius(p: CyclotronParams, kinetic_energy: float) -> float:
    """Radius of the circular orbit with transverse kinetic energy ``E`` [J]: ``sqrt(2 m E)/|qB|``."""
    e = _v.finite("kinetic_energy", kinetic_energy)
    if e < 0.0:
        raise ValueError(f"kinetic_energy must be non-negative, got {e}")
    return math.sqrt(2.0 * p.mass * e) / abs(p.charge * p.field)


def larmor_radius(p: CyclotronParams, state: np.ndarray) -> float:
    """Radius ``|v_perp| / omega`` [m] of the orbit through ``state``."""
    return math.hypot(state[3], state[4]) / gyrofrequency(p)


def guiding_centre(p: CyclotronParams, state: np.ndarray) -> np.ndarray:
    """Centre of the gyration circle, ``r + (m / qB^2) v x B`` [m]; its z moves with ``vz``."""
    s = np.asarray(state, dtype=float)
    w = signed_gyrofrequency(p)
    return np.array([s[0] + s[4] / w, s[1] - s[3] / w, s[2]])


def canonical_angular_momentum(p: CyclotronParams, state: np.ndarray) -> np.ndarray:
    """``p_phi = m (x vy - y vx) + (qB/2)(x^2 + y^2)`` [kg m^2/s]; works on (..., 6) arrays."""
    s = np.asarray(state, dtype=float)
    x, y, vx, vy = s[..., 0], s[..., 1], s[..., 3], s[..., 4]
    return p.mass * (x * vy - y * vx) + 0.5 * p.charge * p.field * (x * x + y * y)


def energy(p: CyclotronParams, state: np.ndarray) -> np.ndarray:
    """Kinetic energy ``m |v|^2 / 2`` [J] (the only energy: B does no work)."""
    s = np.asarray(state, dtype=float)
    return 0.5 * p.mass * np.sum(s[..., 3:6] ** 2, axis=-1)


def effective_potential(p: CyclotronParams, r: float, p_phi: float) -> float:
    """``V_eff(r) = p_phi^2/(2 m r^2) - qB p_phi/(2m) + (qB)^2 r^2 / (8 m)`` [J]."""
    qb = p.charge * p.field
    return (p_phi - 0.5 * qb * r * r) ** 2 / (2.0 * p.mass * r * r)


def radial_coordinates(p: CyclotronParams, state: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(r, p_r)``: distance from the field's axis [m] and radial momentum ``m dr/dt``
    [kg m/s] of states (..., 6). With ``p_phi`` conserved the transverse energy splits as
    ``E_perp = p_r^2 / 2m + V_eff(r)``: the radial motion of a particle in the well ``V_eff``."""
    s = np.asarray(state, dtype=float)
    x, y, vx, vy = s[..., 0], s[..., 1], s[..., 3], s[..., 4]
    r = np.hypot(x, y)
    with np.errstate(invalid="ignore", divide="ignore"):
        p_r = p.mass * np.where(r > 0, (x * vx + y * vy) / r, 0.0)
    return r, p_r


def effective_potential_minimum(p: CyclotronParams, p_phi: float) -> float:
    """Radius ``r0 = sqrt(2 |p_phi| / |qB|)`` [m] where ``V_eff`` is least for this ``p_phi``.

    Since ``p_phi = (qB/2)(R^2 - rho^2)`` for an orbit of radius ``rho`` whose centre is ``R``
    from the z axis, ``r0^2 = |R^2 - rho^2| = r_min r_max``: the geometric mean of the orbit's
    closest and farthest distances from the axis. It is the orbit's own radius only for an orbit
    centred on the axis (``R = 0``).

    The seed writes ``sqrt(2 p_theta / eB)`` and restricts itself to ``p_theta > 0`` (orbits that
    enclose the origin); ``V_eff`` has the same minimum for either sign, hence the modulus.
    """
    return math.sqrt(2.0 * abs(p_phi) / abs(p.charge * p.field))


def radial_oscillation_frequency(p: CyclotronParams, p_phi: float) -> float:
    """``sqrt(V_eff''(r0) / m)`` [rad/s]; equals ``omega`` for every ``p_phi != 0`` (seed 1c)."""
    r0 = effective_potential_minimum(p, p_phi)
    qb = p.charge * p.field
    curvature = 3.0 * p_phi * p_phi / (p.mass * r0**4) + qb * qb / (4.0 * p.mass)
    return math.sqrt(curvature / p.mass)


def radial_kick(
    p: CyclotronParams, state: np.ndarray, dv: float
) -> tuple[np.ndarray, np.ndarray, float]:
    """Add ``dv`` [m/s] of velocity along the outward radius of the current orbit.

    Returns ``(new_state, new_centre, new_radius)``: the circle moves by ``dv / Omega`` at right
    angles to the kick (``delta R = (m / qB^2) dv x B``) and its radius becomes
    ``sqrt(v_perp^2 + dv^2) / omega``. This is the exact, finite-kick form of the seed's result
    that a radial perturbation oscillates at the orbital frequency and so shifts the circle.
    """
    s = np.array(state, dtype=float)
    c = guiding_centre(p, s)
    d = s[:2] - c[:2]
    rho = math.hypot(d[0], d[1])
    if rho == 0.0:
        raise ValueError("state has no transverse velocity: the radial direction is undefined")
    s[3:5] += dv * d / rho
    return s, guiding_centre(p, s), larmor_radius(p, s)


def circular_orbit_state(p: CyclotronParams, speed: float, centre=(0.0, 0.0), vz: float = 0.0):
    """State on the circle of transverse ``speed`` [m/s] about ``centre``, started on its +x side."""
    v = _v.positive("speed", speed)
    w = signed_gyrofrequency(p)
    rho = v / abs(w)
    # At the +x point of the circle the velocity is -y for clockwise (Omega > 0) gyration.
    return np.array([centre[0] + rho, centre[1], 0.0, 0.0, -math.copysign(v, w), vz])


def exact_solution(p: CyclotronParams, state0: np.ndarray, t: np.ndarray | float) -> np.ndarray:
    """Exact state at times ``t`` [s] from ``state0``: rotation of ``v_perp`` by ``-Omega t``.

    Works for ``state0`` of shape (6,) or (N, 6) and scalar or 1-D ``t``; the result has shape
    ``t.shape + state0.shape``.
    """
    s0 = np.asarray(state0, dtype=float)
    tt = np.asarray(t, dtype=float)[(...,) + (None,) * (s0.ndim - 1)]
    w = signed_gyrofrequency(p)
    c, s = np.cos(w * tt), np.sin(w * tt)
    vx0, vy0, vz0 = s0[..., 3], s0[..., 4], s0[..., 5]
    out = np.empty(np.broadcast_shapes(tt.shape, s0[..., 0].shape) + (6,))
    out[..., 0] = s0[..., 0] + (vx0 * s + vy0 * (1.0 - c)) / w
    out[..., 1] = s0[..., 1] + (vx0 * (c - 1.0) + vy0 * s) / w
    out[..., 2] = s0[..., 2] + vz0 * tt
    out[..., 3] = vx0 * c + vy0 * s
    out[..., 4] = -vx0 * s + vy0 * c
    out[..., 5] = vz0
    return out


def error_metric(y: np.ndarray, y_exact: np.ndarray) -> float:
    """Relative 2-norm error, normalised by the transverse part ``(x, y, vx, vy)`` of the exact
    state, so that the secular drift along B does not hide the gyration error."""
    d = np.asarray(y, float) - np.asarray(y_exact, float)
    ref = np.asarray(y_exact, float)[..., [0, 1, 3, 4]]
    return float(np.linalg.norm(d) / np.linalg.norm(ref))


# --------------------------------------------------------------------------- compiled pieces


@deferred_njit(cache=True)
def boris_step(y, p, h):
    """One synchronised Boris step (drift h/2, rotate v, drift h/2), in place; returns 1.

    The rotation angle is ``2 arctan(Omega h / 2)``, so ``|v|`` is kept to round-off at every
    step size and the orbit's centre and radius are exact; only the phase lags.
    """
    t = 0.5 * p[0] * h
    s = 2.0 * t / (1.0 + t * t)
    half = 0.5 * h
    y[0] += half * y[3]
    y[1] += half * y[4]
    y[2] += half * y[5]
    vx, vy = y[3], y[4]
    px = vx + vy * t
    py = vy - vx * t
    vx += py * s
    vy -= px * s
    y[3], y[4] = vx, vy
    y[0] += half * vx
    y[1] += half * vy
    y[2] += half * y[5]
    return 1


@deferred_njit(cache=True)
def exact_step(y, p, h):
    """Advance by ``h`` with the exact flow (the closed-form rotation), in place."""
    w = p[0]
    c = math.cos(w * h)
    s = math.sin(w * h)
    vx, vy = y[3], y[4]
    y[0] += (vx * s + vy * (1.0 - c)) / w
    y[1] += (vx * (c - 1.0) + vy * s) / w
    y[2] += y[5] * h
    y[3] = vx * c + vy * s
    y[4] = -vx * s + vy * c
    return 0


def analysis(p: CyclotronParams, speed: float = 1.0) -> dict:
    """The seed's results for a charge of transverse ``speed`` [m/s], JSON-ready: gyrofrequency
    (and its sign), period, kinetic energy, radius, canonical angular momentum, the effective
    potential's minimum and the radial oscillation frequency about it. A result a double cannot
    hold is NaN (:func:`mechviz.dynamics.params.guarded`)."""
    g = _v.guarded
    ke = g(lambda: 0.5 * p.mass * speed**2)
    state = g(lambda: circular_orbit_state(p, speed), np.full(6, math.nan))
    p_phi = g(lambda: float(canonical_angular_momentum(p, state)))
    w = g(lambda: signed_gyrofrequency(p))
    return {
        "parameters": {"charge": p.charge, "mass": p.mass, "field": p.field, "speed": speed},
        "gyrofrequency": abs(w),
        "signed_gyrofrequency": w,
        "rotation_seen_from_plus_z": "clockwise" if w > 0 else "anticlockwise",
        "period": g(lambda: period(p)),
        "kinetic_energy": ke,
        "radius": g(lambda: orbit_radius(p, ke)),
        "canonical_angular_momentum": p_phi,
        "effective_potential_minimum_radius": g(lambda: effective_potential_minimum(p, p_phi)),
        "radial_oscillation_frequency": g(lambda: radial_oscillation_frequency(p, p_phi)),
    }


# --------------------------------------------------------------------------- structure check
def canonical_maps(params: CyclotronParams):
    """``(to_canonical, from_canonical)``: the state ``(x, v)`` to the canonical ``(x, m v + q A)``
    in the symmetric gauge ``A = B (-y, x, 0) / 2`` and back."""
    q, m, B = params.charge, params.mass, params.field

    def potential(x):
        return 0.5 * B * np.array([-x[1], x[0], 0.0])

    def to_canonical(y):
        return np.concatenate([y[:3], m * y[3:6] + q * potential(y[:3])])

    def from_canonical(z):
        return np.concatenate([z[:3], (z[3:6] - q * potential(z[:3])) / m])

    return to_canonical, from_canonical
