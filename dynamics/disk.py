"""Spinning disk with a bead: a uniform disk turned about an axle along one of its diameters, with
a bead fixed on the rim at the end of the perpendicular diameter.

Units and conventions (SI throughout)
-------------------------------------
- Disk mass ``M`` [kg], radius ``R`` [m], bead mass ``m`` [kg] (default ``5M/4`` as in the seed),
  spin rate ``omega`` [rad/s] about the axle.
- Disk frame (fixed in the body; equal to the space frame at ``t = 0``): origin at the rim point A,
  axle along +y through A and B = (0, 2R, 0), the disk in the x-y plane with its normal along +z,
  disk centre (0, R, 0), bead at (R, R, 0). The spin is ``omega`` about +y (right-handed).
- Tensors are 3x3 arrays [kg m^2] in that frame, about A unless a name says otherwise.

*Driven* motion: the bearings at A and B hold the axle, the body turns uniformly,
``R(t) = rotation about y by omega t``. Its angular momentum about A, ``L = R(t) I_A omega y``, is
not along the axle, so it turns with the body and the bearings must supply the torque
``N = dL/dt = omega y x L``. Taking moments about A fixes the transverse force at B,
``F_B = -(y x N) / 2R``; the total bearing force is the centripetal force on the off-axle
centre of mass, ``F_A + F_B = -(M + m) omega^2 rho_cm(t)``. Axial forces are not determined (and
gravity is left out, as in the seed). With the bead opposite the axle's midpoint, ``F_A = F_B``,
each of magnitude ``m R omega^2 / 2`` (``5/8 M R omega^2`` for the seed's bead).

*Released* motion: at ``t = 0`` the axle vanishes. The body keeps its spin and its centre of mass
moves off uniformly with velocity ``omega y x r_cm``; about the centre of mass it is a torque-free
rigid body. State ``(w1, w2, w3, q0, q1, q2, q3)``: angular velocity in the principal frame about
the centre of mass [rad/s] and the unit quaternion (scalar first) that turns principal-frame
vectors into space vectors. For the seed's disk the principal moments about the centre of mass are
``(1/4, 29/36, 19/18) M R^2`` along x, y, z: the spin axis y is the *intermediate* axis, so the
released disk tumbles (the tennis-racket instability).

Energy error: with gravity left out the energy is all rotational (``sum I_i w_i^2 / 2``, driven or
released), so the relative energy error is ``(E - E0) / E0`` (the energy floor is 0, at rest).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from fractions import Fraction

import numpy as np

from . import params as _v
from ._jit import deferred_njit

FREE_STATE_NAMES = ("w1", "w2", "w3", "q0", "q1", "q2", "q3")
AXLE = np.array([0.0, 1.0, 0.0])


@dataclass(frozen=True)
class DiskParams:
    """Disk mass [kg], radius [m], bead mass [kg] (``None``: the seed's ``5/4 disk_mass``), spin
    rate ``omega`` [rad/s] about the axle."""

    disk_mass: float = 1.0
    radius: float = 1.0
    bead_mass: float | None = field(default=None)
    omega: float = 2.0

    def __post_init__(self) -> None:
        if self.bead_mass is None:
            bead = 1.25 * _v.positive("disk_mass", self.disk_mass)
            if not math.isfinite(bead):
                raise _v.SettingError(
                    "disk_mass",
                    f"disk_mass {self.disk_mass:g}: the default bead mass 5/4 of it "
                    "is beyond the largest double",
                )
            object.__setattr__(self, "bead_mass", bead)
        _v.coerce(
            self,
            {
                "disk_mass": _v.positive,
                "radius": _v.positive,
                "bead_mass": _v.positive,
                "omega": _v.nonzero,  # without a spin nothing moves and nothing is measured
            },
        )

    @property
    def total_mass(self) -> float:
        return self.disk_mass + self.bead_mass


# --------------------------------------------------------------------------- geometry
def axle_points(p: DiskParams) -> tuple[np.ndarray, np.ndarray]:
    """Bearings A and B in the disk frame [m]."""
    return np.zeros(3), np.array([0.0, 2.0 * p.radius, 0.0])


def disk_centre(p: DiskParams) -> np.ndarray:
    return np.array([0.0, p.radius, 0.0])


def bead_position(p: DiskParams) -> np.ndarray:
    return np.array([p.radius, p.radius, 0.0])


def centre_of_mass(p: DiskParams) -> np.ndarray:
    """``(m R / (M + m), R, 0)`` [m]: on the axle's perpendicular bisector, off the axle."""
    return (p.disk_mass * disk_centre(p) + p.bead_mass * bead_position(p)) / p.total_mass


# --------------------------------------------------------------------------- inertia
def _point_inertia(mass: float, r: np.ndarray) -> np.ndarray:
    return mass * (np.dot(r, r) * np.eye(3) - np.outer(r, r))


def inertia_tensor_disk(p: DiskParams) -> np.ndarray:
    """Disk about A: ``M R^2/4 diag(1, 1, 2)`` about its centre plus the parallel-axis shift,
    ``= M R^2/4 diag(5, 1, 6)``."""
    about_centre = p.disk_mass * p.radius**2 / 4.0 * np.diag([1.0, 1.0, 2.0])
    return about_centre + _point_inertia(p.disk_mass, disk_centre(p))


def inertia_tensor_bead(p: DiskParams) -> np.ndarray:
    """Bead about A: ``m R^2 [[1, -1, 0], [-1, 1, 0], [0, 0, 2]]``."""
    return _point_inertia(p.bead_mass, bead_position(p))


def inertia_tensor(p: DiskParams) -> np.ndarray:
    """Disk plus bead about A (``M R^2 [[5/2, -5/4, 0], [-5/4, 3/2, 0], [0, 0, 4]]`` for the seed)."""
    return inertia_tensor_disk(p) + inertia_tensor_bead(p)


def inertia_tensor_cm(p: DiskParams) -> np.ndarray:
    """About the centre of mass: ``I_A`` minus the parallel-axis term of the total mass."""
    return inertia_tensor(p) - _point_inertia(p.total_mass, centre_of_mass(p))


def _principal(tensor: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    moments, vecs = np.linalg.eigh(tensor)
    axes = vecs.T.copy()  # rows
    for k in range(3):
        # Sign convention: first non-negligible component among (y, z, x) positive; this gives
        # the seed's x' = ((sqrt29 - 2) x + 5 y)/norm, y' = ((-2 - sqrt29) x + 5 y)/norm, z' = z.
        for j in (1, 2, 0):
            if abs(axes[k, j]) > 1e-12:
                if axes[k, j] < 0:
                    axes[k] = -axes[k]
                break
    return moments, axes


def principal_axes(p: DiskParams) -> tuple[np.ndarray, np.ndarray]:
    """Principal moments about A (ascending) [kg m^2] and axes (rows, unit vectors, same order).

    Seed: ``I = (2 - sqrt29/4, 2 + sqrt29/4, 4) M R^2``.
    """
    return _principal(inertia_tensor(p))


def principal_axes_cm(p: DiskParams) -> tuple[np.ndarray, np.ndarray]:
    """Principal moments (ascending) and axes (rows) about the centre of mass."""
    return _principal(inertia_tensor_cm(p))


# --------------------------------------------------------------------------- driven motion
def rotation_about_axle(angle: float | np.ndarray) -> np.ndarray:
    """Rotation matrix (..., 3, 3) about +y by ``angle`` [rad]."""
    ang = np.asarray(angle, dtype=float)
    c, s = np.cos(ang), np.sin(ang)
    out = np.zeros(ang.shape + (3, 3))
    out[..., 0, 0] = c
    out[..., 0, 2] = s
    out[..., 1, 1] = 1.0
    out[..., 2, 0] = -s
    out[..., 2, 2] = c
    return out


def driven_quaternion(p: DiskParams, t: float | np.ndarray) -> np.ndarray:
    """Unit quaternion (w, x, y, z) of the driven disk at time ``t`` [s]: ``omega t`` about +y."""
    half = 0.5 * p.omega * np.asarray(t, dtype=float)
    z = np.zeros_like(half)
    return np.stack([np.cos(half), z, np.sin(half), z], axis=-1)


def angular_momentum(p: DiskParams, t: float | np.ndarray = 0.0) -> np.ndarray:
    """Angular momentum about A [kg m^2/s] of the driven disk at time ``t``: ``R(t) I_A omega y``."""
    body = inertia_tensor(p) @ (p.omega * AXLE)
    return rotation_about_axle(p.omega * np.asarray(t, dtype=float)) @ body


def required_torque(p: DiskParams, t: float | np.ndarray = 0.0) -> np.ndarray:
    """Torque about A [N m] the bearings must supply: ``dL/dt = omega y x L(t)``, perpendicular to
    the axle and turning with the disk. Its component along the axle is zero: no driving torque
    is needed to keep the rate uniform."""
    return np.cross(p.omega * AXLE, angular_momentum(p, t))


def bearing_force_b(p: DiskParams, t: float | np.ndarray = 0.0) -> np.ndarray:
    """Transverse force [N] on the disk from the bearing at B: ``-(y x N) / 2R``.

    Seed: ``F = 5/8 M omega^2 R (-cos omega t x + sin omega t z)``."""
    return -np.cross(AXLE, required_torque(p, t)) / (2.0 * p.radius)


def net_bearing_force(p: DiskParams, t: float | np.ndarray = 0.0) -> np.ndarray:
    """``F_A + F_B = (M + m) a_cm`` [N]: the centripetal force on the off-axle centre of mass."""
    rho = centre_of_mass(p) * np.array([1.0, 0.0, 1.0])  # part perpendicular to the axle
    rot = rotation_about_axle(p.omega * np.asarray(t, dtype=float))
    return -p.total_mass * p.omega**2 * (rot @ rho)


def bearing_force_a(p: DiskParams, t: float | np.ndarray = 0.0) -> np.ndarray:
    """Transverse force [N] from the bearing at A: the net force minus the force at B."""
    return net_bearing_force(p, t) - bearing_force_b(p, t)


def axle_force_amplitude(p: DiskParams) -> float:
    """``|F_B| = |I_xy| omega^2 / 2R`` [N] (``= m R omega^2 / 2``; ``5/8 M R omega^2`` in the seed)."""
    return float(np.linalg.norm(bearing_force_b(p, 0.0)))


def driven_energy(p: DiskParams) -> float:
    """Kinetic energy ``I_yy omega^2 / 2`` [J] of the uniform rotation."""
    return 0.5 * inertia_tensor(p)[1, 1] * p.omega**2


# --------------------------------------------------------------------------- released motion
def _matrix_to_quaternion(r: np.ndarray) -> np.ndarray:
    """Unit quaternion (w, x, y, z) of a proper rotation matrix (Shepperd's method)."""
    tr = np.trace(r)
    k = int(np.argmax([tr, r[0, 0], r[1, 1], r[2, 2]]))
    if k == 0:
        s = 2.0 * math.sqrt(1.0 + tr)
        q = [0.25 * s, (r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s]
    else:
        i = k - 1
        j, l = (i + 1) % 3, (i + 2) % 3
        s = 2.0 * math.sqrt(1.0 + r[i, i] - r[j, j] - r[l, l])
        q = [0.0, 0.0, 0.0, 0.0]
        q[0] = (r[l, j] - r[j, l]) / s
        q[1 + i] = 0.25 * s
        q[1 + j] = (r[j, i] + r[i, j]) / s
        q[1 + l] = (r[l, i] + r[i, l]) / s
    q = np.array(q)
    return q / np.linalg.norm(q) * (1.0 if q[0] >= 0 else -1.0)


def quaternion_to_matrix(q: np.ndarray) -> np.ndarray:
    """Rotation matrices (..., 3, 3) of quaternions (..., 4), scalar first; normalises first."""
    q = np.asarray(q, dtype=float)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    w, x, y, z = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
        ],
        -2,
    )


@functools.lru_cache(maxsize=64)
def _principal_frame_cm(p: DiskParams) -> tuple[np.ndarray, np.ndarray]:
    """Principal moments about the CM and the right-handed matrix whose columns are the axes.

    Cached per parameter set (the eigen-decomposition is most of the 30 us a released disk's
    Simulation took to build); the arrays are read-only, callers copy what they change."""
    moments, axes = principal_axes_cm(p)
    frame = axes.T.copy()
    if np.linalg.det(frame) < 0:
        frame[:, 2] = -frame[:, 2]
    moments.setflags(write=False)
    frame.setflags(write=False)
    return moments, frame


def free_kernel_params(p: DiskParams) -> np.ndarray:
    """``[I1, I2, I3]``, principal moments about the centre of mass, for the compiled kernels."""
    return _principal_frame_cm(p)[0].copy()


def released_initial_state(p: DiskParams, extra_spin=(0.0, 0.0, 0.0)) -> np.ndarray:
    """Free-body state at release: spin ``omega y + extra_spin`` (disk-frame components, rad/s)."""
    _, frame = _principal_frame_cm(p)
    w_space = p.omega * AXLE + np.array(
        [_v.finite(n, x) for n, x in zip("xyz", extra_spin, strict=True)]
    )
    return np.concatenate([frame.T @ w_space, _matrix_to_quaternion(frame)])


def released_pose(
    p: DiskParams, state: np.ndarray, t: float | np.ndarray, extra_spin=(0.0, 0.0, 0.0)
):
    """Disk-frame-to-space rotation (..., 3, 3) and the position of A (..., 3) at time ``t``.

    The centre of mass moves uniformly with its velocity at release, ``w0 x r_cm``; the body
    turns about it: ``x(t) = x_cm(t) + R(t) F^T (r - r_cm)`` for a disk-frame point ``r``, where
    ``F`` holds the principal axes.
    """
    _, frame = _principal_frame_cm(p)
    r_cm = centre_of_mass(p)
    w0 = p.omega * AXLE + np.asarray(extra_spin, dtype=float)
    x_cm = r_cm + np.multiply.outer(np.asarray(t, dtype=float), np.cross(w0, r_cm))
    rot = quaternion_to_matrix(np.asarray(state)[..., 3:7]) @ frame.T
    return rot, x_cm - rot @ r_cm


def free_energy(moments: np.ndarray, state: np.ndarray) -> np.ndarray:
    """Rotational kinetic energy ``sum I_i w_i^2 / 2`` [J] of free-body states (..., 7)."""
    w = np.asarray(state, dtype=float)[..., :3]
    return 0.5 * np.sum(moments * w * w, axis=-1)


def free_angular_momentum_space(moments: np.ndarray, state: np.ndarray) -> np.ndarray:
    """Angular momentum about the centre of mass in the space frame [kg m^2/s], (..., 3)."""
    s = np.asarray(state, dtype=float)
    body = moments * s[..., :3]
    return np.einsum("...ij,...j->...i", quaternion_to_matrix(s[..., 3:7]), body)


def polhode_period(moments: np.ndarray, w: np.ndarray) -> float:
    """The period [s] of the body-frame angular velocity of a torque-free body: the time the
    polhode takes to close, from the Jacobi elliptic solution of Euler's equations (Landau and
    Lifshitz, *Mechanics*, Sec. 37).

    With the moments sorted ``A < B < C`` [kg m^2], ``2E = sum I_i w_i^2`` and
    ``M^2 = sum (I_i w_i)^2``: if ``M^2 > 2EB`` (the polhode circles the axis of the largest
    moment) ``w`` is ``(cn, sn, dn)`` of ``lambda t`` with
    ``lambda^2 = (C - B)(M^2 - 2EA) / ABC`` and ``k^2 = (B - A)(2EC - M^2) / ((C - B)(M^2 - 2EA))``;
    if ``M^2 < 2EB`` (it circles the smallest) ``A`` and ``C`` trade places. ``cn`` and ``sn``
    have the period ``4K(k)``, so the polhode closes after ``T = 4K(k) / lambda``. On the
    separatrix (``M^2 = 2EB``: the spin along the intermediate axis, or a polhode through it) ``T``
    is infinite, and so it is at rest. A spin exactly along the axis of the largest or smallest
    moment gives the limit ``k = 0``: ``2 pi / lambda``, the period of small wobbles about it.
    """
    from scipy import special  # deferred: importing dynamics should not pay for it

    inertia = np.asarray(moments, dtype=float)
    w = np.asarray(w, dtype=float)
    order = np.argsort(inertia)
    # Exact rational arithmetic on the given doubles: near the separatrix ``M^2 - 2EB`` is a
    # small difference of large terms, and ``1 - k^2`` is proportional to it.
    a, b, c = (Fraction(float(x)) for x in inertia[order])
    wa, wb, wc = (Fraction(float(x)) for x in w[order])
    two_e = a * wa * wa + b * wb * wb + c * wc * wc
    m2 = (a * wa) ** 2 + (b * wb) ** 2 + (c * wc) ** 2
    if two_e <= 0 or m2 == two_e * b:
        return math.inf  # at rest, or on the separatrix (k = 1)
    if m2 < two_e * b:  # circles the axis of the smallest moment: swap the roles of A and C
        a, c = c, a
    lam2 = (c - b) * (m2 - two_e * a) / (a * b * c)
    if lam2 <= 0:
        return math.inf
    # 1 - k^2 = (C - A)(M^2 - 2EB) / ((C - B)(M^2 - 2EA)); K from it directly (ellipkm1), which
    # keeps its digits as k -> 1
    k2c = (c - a) * (m2 - two_e * b) / ((c - b) * (m2 - two_e * a))
    if not 0 < k2c <= 1:
        return math.inf
    return 4.0 * float(special.ellipkm1(float(k2c))) / math.sqrt(float(lam2))


def poinsot(moments: np.ndarray, state: np.ndarray) -> dict[str, np.ndarray | float]:
    """Poinsot's construction for a torque-free state (7,): the inertia ellipsoid about the
    centre of mass, ``x^T I x = 1`` (semi-axes ``1/sqrt(I_i)`` along the principal axes),
    carried with the body, rolls without slipping on the invariable plane, normal to the fixed
    ``L`` at the distance ``sqrt(2T)/|L|`` from the centre. The contact point is
    ``w / sqrt(2T)``: on the ellipsoid, where its normal ``I w = L`` is along the plane's.

    Returns ``semi_axes`` (3,) [1/sqrt(kg m^2)], ``rotation`` (principal frame -> space),
    ``contact_body`` and ``contact_space`` (3,), ``normal`` (unit, space), ``distance``; the
    contact traces the polhode on the ellipsoid (body frame) and the herpolhode on the plane.
    """
    s = np.asarray(state, dtype=float)
    w = s[:3]
    rot = quaternion_to_matrix(s[3:7])
    two_t = float(np.sum(moments * w * w))
    L = rot @ (moments * w)
    contact_body = w / math.sqrt(two_t)
    return {
        "semi_axes": 1.0 / np.sqrt(moments),
        "rotation": rot,
        "contact_body": contact_body,
        "contact_space": rot @ contact_body,
        "normal": L / np.linalg.norm(L),
        "distance": math.sqrt(two_t) / float(np.linalg.norm(L)),
    }


# --------------------------------------------------------------------------- compiled pieces


@deferred_njit(cache=True)
def _rotation(angle, lj, lk, ij, ik, q0, qi, qj, qk):
    """Exact flow of the piece ``L_i^2 / 2 I_i`` for the time giving ``angle = w_i h``.

    The body turns about its own axis ``i`` at the rate ``w_i``: the body-frame components
    ``(L_j, L_k)`` (``i, j, k`` cyclic) rotate by ``-angle`` and the orientation quaternion is
    multiplied on the right by the rotation ``+angle`` about ``e_i``. Both are exact, so ``|L|``
    is kept to round-off. Returns the new ``(w_j, w_k, q0, q_i, q_j, q_k)``.
    """
    # Two libm calls instead of four: the whole angle from the half angle by the double-angle
    # formulas (the step is bound by sin/cos; results change only at round-off).
    ch = math.cos(0.5 * angle)
    sh = math.sin(0.5 * angle)
    c = (ch - sh) * (ch + sh)
    s = 2.0 * sh * ch
    return (
        (c * lj + s * lk) / ij,
        (-s * lj + c * lk) / ik,
        ch * q0 - sh * qi,
        ch * qi + sh * q0,
        ch * qj + sh * qk,
        ch * qk - sh * qj,
    )


@deferred_njit(cache=True)
def splitting_step(y, p, h):
    """Symmetric (Strang) splitting into exact rotations about the axes 1, 2, 3, 2, 1.

    Five exact sub-flows (McLachlan 1993; Touma & Wisdom 1994); second order, symplectic and
    symmetric. Returns the number of sub-flows.
    """
    i1, i2, i3 = p[0], p[1], p[2]
    w1, w2, w3, q0, q1, q2, q3 = y[0], y[1], y[2], y[3], y[4], y[5], y[6]
    hh = 0.5 * h
    w2, w3, q0, q1, q2, q3 = _rotation(w1 * hh, i2 * w2, i3 * w3, i2, i3, q0, q1, q2, q3)
    w3, w1, q0, q2, q3, q1 = _rotation(w2 * hh, i3 * w3, i1 * w1, i3, i1, q0, q2, q3, q1)
    w1, w2, q0, q3, q1, q2 = _rotation(w3 * h, i1 * w1, i2 * w2, i1, i2, q0, q3, q1, q2)
    w3, w1, q0, q2, q3, q1 = _rotation(w2 * hh, i3 * w3, i1 * w1, i3, i1, q0, q2, q3, q1)
    w2, w3, q0, q1, q2, q3 = _rotation(w1 * hh, i2 * w2, i3 * w3, i2, i3, q0, q1, q2, q3)
    y[0], y[1], y[2], y[3], y[4], y[5], y[6] = w1, w2, w3, q0, q1, q2, q3
    return 5


def wobble_growth_rate(moments: np.ndarray, w0: np.ndarray) -> float:
    """Linear growth rate [1/s] of a wobble about the intermediate axis of principal moments
    ``I1 < I2 < I3`` for body angular velocity ``w0`` [rad/s]:
    ``|w2| sqrt((I2 - I1)(I3 - I2) / (I1 I3))``."""
    i1, i2, i3 = (float(m) for m in moments)
    return abs(float(w0[1])) * math.sqrt((i2 - i1) * (i3 - i2) / (i1 * i3))


def analysis(p: DiskParams) -> dict:
    """The seed's results, JSON-ready: inertia tensors about A (disk, bead, both), principal
    moments and axes about A and about the centre of mass, the angular momentum and torque of the
    uniform rotation, and the bearing forces' amplitudes. A result a double cannot hold is NaN
    (:func:`mechviz.dynamics.params.guarded`)."""
    g = _v.guarded
    nan3 = (np.full(3, np.nan), np.full((3, 3), np.nan))
    moments, axes = g(lambda: principal_axes(p), nan3)
    moments_cm, axes_cm = g(lambda: principal_axes_cm(p), nan3)
    return {
        "parameters": {
            "disk_mass": p.disk_mass,
            "radius": p.radius,
            "bead_mass": p.bead_mass,
            "omega": p.omega,
        },
        "inertia_tensor": g(lambda: inertia_tensor(p).tolist()),
        "inertia_tensor_disk": g(lambda: inertia_tensor_disk(p).tolist()),
        "inertia_tensor_bead": g(lambda: inertia_tensor_bead(p).tolist()),
        "principal_moments": moments.tolist(),
        "principal_axes": axes.tolist(),
        "centre_of_mass": centre_of_mass(p).tolist(),
        "angular_momentum": g(lambda: angular_momentum(p).tolist()),
        "required_torque": g(lambda: required_torque(p).tolist()),
        "axle_force_amplitude": g(lambda: axle_force_amplitude(p)),
        "bearing_force_a_amplitude": g(lambda: float(np.linalg.norm(bearing_force_a(p)))),
        "net_bearing_force_amplitude": g(lambda: float(np.linalg.norm(net_bearing_force(p)))),
        "principal_moments_cm": moments_cm.tolist(),
        "principal_axes_cm": axes_cm.tolist(),
        "wobble_growth_rate": g(
            lambda: wobble_growth_rate(moments_cm, released_initial_state(p)[:3])
        ),
    }
