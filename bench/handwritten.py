"""The hand-written compiled right-hand sides, RK4 steps and Taylor expansions that the
generated ones replaced.

The product's right-hand sides and classical RK4 steps are generated from the equations written
once (:mod:`mechviz.dynamics.codegen`; :data:`mechviz.dynamics.integrators.kernels.RHS` and
``RK4``; the hoop's Taylor recurrences, :mod:`mechviz.dynamics.integrators.taylor`). These are
the forms written by hand before, kept for two uses: the generated-cost
benchmark (:mod:`.generated_cost`) times the product's forms against them, and the tests check
the generated forms against them to round-off (an independent writing of the same equations).
The peers' right-hand sides no longer use them: theirs are generated too (:mod:`.peers`,
:mod:`.fast_peers`, :mod:`.peer_equations`).

Conventions: ``rhs(y, p, out)`` writes ``dy/dt`` into ``out``; ``rk4_step(y, p, h)`` advances
``y`` by ``h`` [s] in place and returns the evaluations used (4). ``p`` is the system's
``kernel_params()``: the charge's ``[Omega]`` (the signed gyrofrequency ``qB/m`` [rad/s]), the
hoop's ``[M, m, a, g]`` (kg, kg, m, m/s^2), the free body's ``[I1, I2, I3]`` [kg m^2]. The RK4
steps are written out in scalar locals: with stage arrays the same step costs 3-4x as much.

Not cached on disk (``njit`` without ``cache``): the benchmark keeps no kernel in the cache,
whose folder is keyed on the sources of :mod:`mechviz.dynamics` alone.
"""

from __future__ import annotations

import math

from mechviz.dynamics._jit import njit
from mechviz.dynamics.ids import CYCLOTRON, FREE_BODY, HOOP
from mechviz.dynamics.integrators import taylor


# --------------------------------------------------------------------------- the charge
@njit
def charge_acceleration(vx, vy, w):
    """Transverse acceleration ``(q/m) v x B = Omega (vy, -vx)``; none along B."""
    return w * vy, -w * vx


@njit
def charge_rhs(y, p, out):
    """``dy/dt`` in place: ``r' = v``, ``v' = Omega (vy, -vx, 0)`` with ``p = [Omega]``."""
    out[0] = y[3]
    out[1] = y[4]
    out[2] = y[5]
    out[3], out[4] = charge_acceleration(y[3], y[4], p[0])
    out[5] = 0.0


@njit
def charge_rk4_step(y, p, h):
    """One classical RK4 step in scalar locals, in place; returns the 4 evaluations.

    Written out rather than generic: with stage arrays the same step costs 3-4x as much here.
    """
    w = p[0]
    x0, y0, z0, u0, v0, vz = y[0], y[1], y[2], y[3], y[4], y[5]
    a1u, a1v = charge_acceleration(u0, v0, w)
    u1, v1 = u0 + 0.5 * h * a1u, v0 + 0.5 * h * a1v
    a2u, a2v = charge_acceleration(u1, v1, w)
    u2, v2 = u0 + 0.5 * h * a2u, v0 + 0.5 * h * a2v
    a3u, a3v = charge_acceleration(u2, v2, w)
    u3, v3 = u0 + h * a3u, v0 + h * a3v
    a4u, a4v = charge_acceleration(u3, v3, w)
    c = h / 6.0
    y[0] = x0 + c * (u0 + 2.0 * (u1 + u2) + u3)
    y[1] = y0 + c * (v0 + 2.0 * (v1 + v2) + v3)
    y[2] = z0 + h * vz
    y[3] = u0 + c * (a1u + 2.0 * (a2u + a3u) + a4u)
    y[4] = v0 + c * (a1v + 2.0 * (a2v + a3v) + a4v)
    return 4


# --------------------------------------------------------------------------- the hoop and bead
@njit
def hoop_acceleration(th1, th2, w1, w2, M, m, ga):
    """Angular accelerations from the 2x2 mass-matrix solve (``ga = g / a``)."""
    s = math.sin(th1 - th2)
    c = math.cos(th1 - th2)
    r1 = -m * s * w2 * w2 - (M + m) * ga * math.sin(th1)
    r2 = s * w1 * w1 - ga * math.sin(th2)
    m11 = 2.0 * M + m
    det = m11 - m * c * c
    return (r1 - m * c * r2) / det, (m11 * r2 - c * r1) / det


@njit
def hoop_rhs(y, p, out):
    """``dy/dt`` in place; ``p = [M, m, a, g]``."""
    out[0] = y[2]
    out[1] = y[3]
    out[2], out[3] = hoop_acceleration(y[0], y[1], y[2], y[3], p[0], p[1], p[3] / p[2])


@njit
def hoop_rk4_step(y, p, h):
    """One classical RK4 step in scalar locals, in place; returns the 4 evaluations."""
    M, m, ga = p[0], p[1], p[3] / p[2]
    q1, q2, u1, u2 = y[0], y[1], y[2], y[3]
    a1, b1 = hoop_acceleration(q1, q2, u1, u2, M, m, ga)
    hh = 0.5 * h
    u1b, u2b = u1 + hh * a1, u2 + hh * b1
    a2, b2 = hoop_acceleration(q1 + hh * u1, q2 + hh * u2, u1b, u2b, M, m, ga)
    u1c, u2c = u1 + hh * a2, u2 + hh * b2
    a3, b3 = hoop_acceleration(q1 + hh * u1b, q2 + hh * u2b, u1c, u2c, M, m, ga)
    u1d, u2d = u1 + h * a3, u2 + h * b3
    a4, b4 = hoop_acceleration(q1 + h * u1c, q2 + h * u2c, u1d, u2d, M, m, ga)
    c = h / 6.0
    y[0] = q1 + c * (u1 + 2.0 * (u1b + u1c) + u1d)
    y[1] = q2 + c * (u2 + 2.0 * (u2b + u2c) + u2d)
    y[2] = u1 + c * (a1 + 2.0 * (a2 + a3) + a4)
    y[3] = u2 + c * (b1 + 2.0 * (b2 + b3) + b4)
    return 4


# --------------------------------------------------------------------------- the free body
@njit
def _free_rates(w1, w2, w3, q0, q1, q2, q3, k1, k2, k3):
    """:func:`free_derivatives` with the Euler coefficients ``k1 = (I2 - I3) / I1`` (cyclic)
    given: a caller that computes them once saves three divisions per evaluation."""
    return (
        k1 * w2 * w3,
        k2 * w3 * w1,
        k3 * w1 * w2,
        0.5 * (-q1 * w1 - q2 * w2 - q3 * w3),
        0.5 * (q0 * w1 + q2 * w3 - q3 * w2),
        0.5 * (q0 * w2 + q3 * w1 - q1 * w3),
        0.5 * (q0 * w3 + q1 * w2 - q2 * w1),
    )


@njit
def free_derivatives(w1, w2, w3, q0, q1, q2, q3, i1, i2, i3):
    """Euler's equations in the principal frame and ``q' = q (0, w) / 2`` (scalar form)."""
    k1, k2, k3 = (i2 - i3) / i1, (i3 - i1) / i2, (i1 - i2) / i3
    return _free_rates(w1, w2, w3, q0, q1, q2, q3, k1, k2, k3)


@njit
def free_rhs(y, p, out):
    """``dy/dt`` in place for the free body; ``p = [I1, I2, I3]``."""
    d = free_derivatives(y[0], y[1], y[2], y[3], y[4], y[5], y[6], p[0], p[1], p[2])
    for j in range(7):
        out[j] = d[j]


@njit
def free_rk4_step(y, p, h):
    """One classical RK4 step in scalar locals, in place; returns the 4 evaluations.

    The coefficients ``(I2 - I3)/I1`` etc. are formed once per step rather than once per
    evaluation (12 divisions become 3; results change only at round-off).
    """
    i1, i2, i3 = p[0], p[1], p[2]
    k1, k2, k3 = (i2 - i3) / i1, (i3 - i1) / i2, (i1 - i2) / i3
    a0, a1, a2, a3, a4, a5, a6 = y[0], y[1], y[2], y[3], y[4], y[5], y[6]
    hh = 0.5 * h
    b0, b1, b2, b3, b4, b5, b6 = _free_rates(a0, a1, a2, a3, a4, a5, a6, k1, k2, k3)
    c0, c1, c2, c3, c4, c5, c6 = _free_rates(
        a0 + hh * b0,
        a1 + hh * b1,
        a2 + hh * b2,
        a3 + hh * b3,
        a4 + hh * b4,
        a5 + hh * b5,
        a6 + hh * b6,
        k1,
        k2,
        k3,
    )
    d0, d1, d2, d3, d4, d5, d6 = _free_rates(
        a0 + hh * c0,
        a1 + hh * c1,
        a2 + hh * c2,
        a3 + hh * c3,
        a4 + hh * c4,
        a5 + hh * c5,
        a6 + hh * c6,
        k1,
        k2,
        k3,
    )
    e0, e1, e2, e3, e4, e5, e6 = _free_rates(
        a0 + h * d0,
        a1 + h * d1,
        a2 + h * d2,
        a3 + h * d3,
        a4 + h * d4,
        a5 + h * d5,
        a6 + h * d6,
        k1,
        k2,
        k3,
    )
    c = h / 6.0
    y[0] = a0 + c * (b0 + 2.0 * (c0 + d0) + e0)
    y[1] = a1 + c * (b1 + 2.0 * (c1 + d1) + e1)
    y[2] = a2 + c * (b2 + 2.0 * (c2 + d2) + e2)
    y[3] = a3 + c * (b3 + 2.0 * (c3 + d3) + e3)
    y[4] = a4 + c * (b4 + 2.0 * (c4 + d4) + e4)
    y[5] = a5 + c * (b5 + 2.0 * (c5 + d5) + e5)
    y[6] = a6 + c * (b6 + 2.0 * (c6 + d6) + e6)
    return 4


# --------------------------------------------------------------------------- Taylor series
# The hoop's hand-written Taylor recurrences, replaced by those generated from its mass matrix's
# system (:mod:`mechviz.dynamics.codegen.series`). Its sums may be reassociated (the order of a
# Cauchy product's terms is arbitrary) and contracted, as the generated ones'.
@njit(fastmath={"reassoc", "contract"})
def hoop_expand(A, p, order):
    """Taylor coefficients of the hoop and bead (:func:`mechviz.dynamics.codegen.equations.hoop`),
    in the convention of :func:`mechviz.dynamics.integrators.taylor.run_taylor_with` (14 rows): with
    ``u = th1 - th2``, ``r1 = -m sin(u) w2^2 - (M + m)(g/a) sin th1``,
    ``r2 = sin(u) w1^2 - (g/a) sin th2``, the accelerations solve the mass-matrix system
    ``(2M + m) w1' + m cos(u) w2' = r1``, ``cos(u) w1' + w2' = r2``.

    The series are taken of that system rather than of its solved form (the quotients by
    ``det = 2M + m - m cos(u)^2``): order ``k`` of each line is the order-``k`` accelerations
    times the matrix at the step's start, plus the products of the higher orders of ``cos u``
    with the lower orders of the accelerations, so order ``k`` is one 2x2 solve with the matrix
    inverted once per step. That takes two Cauchy products per order (``cos(u) w2'``,
    ``cos(u) w1'``) where the quotients took four and the square ``cos(u)^2``: a fifth fewer
    multiply-adds a step.

    Per order three loops, each accumulating several independent sums (the sums are chains of
    dependent additions; interleaving them keeps the floating-point units busy): the three
    sine/cosine pairs; the squares ``w2^2``, ``w1^2`` (over half the terms, by symmetry); the
    products with ``sin u`` and ``cos u``.
    """
    M, m, ga = p[0], p[1], p[3] / p[2]
    m11 = 2.0 * M + m
    mg = (M + m) * ga
    # rows 0-3: th1, th2, w1, w2
    SU, CU, S1, C1, S2, C2, Q1, Q2, A1, A2 = range(4, 14)
    i11 = i12 = i21 = i22 = 0.0  # the inverse of the matrix at the step's start
    for k in range(order):
        if k == 0:
            s1, c1 = math.sin(A[0, 0]), math.cos(A[0, 0])
            s2, c2 = math.sin(A[1, 0]), math.cos(A[1, 0])
            A[S1, 0], A[C1, 0], A[S2, 0], A[C2, 0] = s1, c1, s2, c2
            su = s1 * c2 - c1 * s2  # sin(th1 - th2): two library calls fewer per step
            cu = c1 * c2 + s1 * s2
            A[SU, 0] = su
            A[CU, 0] = cu
            inv_det = 1.0 / (m11 - m * cu * cu)
            i11, i12, i21, i22 = inv_det, -m * cu * inv_det, -cu * inv_det, m11 * inv_det
        else:
            su = cu = s1 = c1 = s2 = c2 = 0.0
            for j in range(1, k + 1):
                t1 = A[2, j - 1]  # j th1^[j] = w1^[j-1]: th1' = w1
                t2 = A[3, j - 1]
                tu = t1 - t2
                i = k - j
                su += tu * A[CU, i]
                cu += tu * A[SU, i]
                s1 += t1 * A[C1, i]
                c1 += t1 * A[S1, i]
                s2 += t2 * A[C2, i]
                c2 += t2 * A[S2, i]
            inv = 1.0 / k
            A[SU, k] = su * inv
            A[CU, k] = -cu * inv
            A[S1, k] = s1 * inv
            A[C1, k] = -c1 * inv
            A[S2, k] = s2 * inv
            A[C2, k] = -c2 * inv
        # squares: (uu)^[k] = 2 sum_{j < k/2} u_j u_(k-j) (+ u_(k/2)^2 for even k)
        q1 = q2 = 0.0
        for j in range((k + 1) // 2):
            i = k - j
            q1 += A[3, j] * A[3, i]
            q2 += A[2, j] * A[2, i]
        q1 *= 2.0
        q2 *= 2.0
        if k % 2 == 0:
            h = k // 2
            q1 += A[3, h] * A[3, h]
            q2 += A[2, h] * A[2, h]
        A[Q1, k] = q1
        A[Q2, k] = q2
        # the terms j = 1 ... k, which use only lower orders of the squares and accelerations
        s1 = s2 = n1 = n2 = 0.0
        for j in range(1, k + 1):
            i = k - j
            su = A[SU, j]
            cu = A[CU, j]
            s1 += su * A[Q1, i]
            s2 += su * A[Q2, i]
            n1 += cu * A[A2, i]
            n2 += cu * A[A1, i]
        s1 += A[SU, 0] * q1
        s2 += A[SU, 0] * q2
        b1 = -m * s1 - mg * A[S1, k] - m * n1
        b2 = s2 - ga * A[S2, k] - n2
        a1 = i11 * b1 + i12 * b2
        a2 = i21 * b1 + i22 * b2
        A[A1, k] = a1
        A[A2, k] = a2
        inv = 1.0 / (k + 1)
        A[0, k + 1] = A[2, k] * inv
        A[1, k + 1] = A[3, k] * inv
        A[2, k + 1] = a1 * inv
        A[3, k + 1] = a2 * inv


#: The hand-written Taylor expansions by system id: the hoop's here, the charge's and the free
#: body's where the product keeps them (:data:`mechviz.dynamics.integrators.taylor.EXPANDS`).
EXPANDS = {
    CYCLOTRON: taylor.charge_expand,
    HOOP: hoop_expand,
    FREE_BODY: taylor.free_body_expand,
}
EXPAND_ROWS = 14  # the rows hoop_expand's array needs (the others need fewer)


# Per system (index = system id), as :data:`mechviz.dynamics.integrators.kernels.RHS` and ``RK4``.
_BY_ID = {
    CYCLOTRON: (charge_rhs, charge_rk4_step),
    HOOP: (hoop_rhs, hoop_rk4_step),
    FREE_BODY: (free_rhs, free_rk4_step),
}
RHS = tuple(_BY_ID[i][0] for i in sorted(_BY_ID))
RK4 = tuple(_BY_ID[i][1] for i in sorted(_BY_ID))
