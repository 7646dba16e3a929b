"""The geometric structure a fixed-step method's one-step map keeps on a system, measured.

A label such as "symplectic" is a property of a method *applied in particular variables*: the
implicit midpoint rule is symplectic in canonical variables (and on any linear flow), but the
hoop's state is ``(theta, theta')`` and the free body's ``(omega, q)``, not canonical ones, and
there it is not. So each (method, system) pair's label is checked against the map itself:

- charge and hoop: the symplecticity defect ``max |D^T J D - J|`` of the step's Jacobian ``D``
  in canonical variables (the charge's ``(x, m v + q A)`` in the symmetric gauge
  ``A = B (-y, x, 0) / 2``, the hoop's ``(theta, M(theta) theta')``), by central differences;
- released disk: the Lie-Poisson defect of the step's map of the body angular momentum
  ``L = I omega`` (Euler's equations do not involve the attitude),
  ``max |D B(L0) D^T - B(L1)| / |L0|`` with ``B(L)`` the matrix of ``L x``.

A map that keeps the structure leaves only the differences' noise (about 1e-9 here); one that
does not leaves a defect that grows as a power of the step (the midpoint rule's ``h^3``).
:data:`SYMPLECTIC_NOISE` separates the two; ``tests/test_structure.py`` checks every label.
"""

from __future__ import annotations

import numpy as np

from .integrators import kernels
from .integrators.base import Method, step_functions

#: A defect below this is the central differences' noise (about 1e-9 at the steps used): the
#: map keeps the structure. Measured defects of maps that do not are 1e-5 and above at h = 0.05.
SYMPLECTIC_NOISE = 1e-7


def one_step(method: Method, system, state: np.ndarray, h: float) -> np.ndarray:
    """``state`` (d,) advanced by one step of ``h`` of ``method`` (its compiled step)."""
    step, inner = step_functions(method, system.sys_id)
    Y = np.array(state, dtype=float).reshape(1, -1)
    status = np.zeros(3, dtype=np.int64)
    p = system.kernel_params()
    if inner is None:
        kernels.run_direct(step, Y, p, h, 1, status)
    else:
        kernels.run_composed(step, inner, Y, p, h, 1, status)
    if status[0] != kernels.OK:
        raise RuntimeError(f"{method.name} failed on {system.name} at h = {h}")
    return Y[0]


def symplecticity_defect(
    method: Method, system, state: np.ndarray, h: float, eps: float = 1e-6
) -> float:
    """The structure defect of one step of ``method`` on ``system`` from ``state`` (module
    docstring): symplecticity in canonical variables for the charge and the hoop, Lie-Poisson
    for the released disk."""
    state = np.asarray(state, dtype=float)
    if system.structure_check == "lie-poisson":
        return _lie_poisson_defect(method, system, state, h, eps)
    to_c, from_c = system.canonical_maps()
    z0 = to_c(state)
    n = len(z0)
    D = np.empty((n, n))
    for j in range(n):
        dz = np.zeros(n)
        dz[j] = eps * max(1.0, abs(z0[j]))
        plus = to_c(one_step(method, system, from_c(z0 + dz), h))
        minus = to_c(one_step(method, system, from_c(z0 - dz), h))
        D[:, j] = (plus - minus) / (2.0 * dz[j])
    k = n // 2
    J = np.block([[np.zeros((k, k)), np.eye(k)], [-np.eye(k), np.zeros((k, k))]])
    return float(np.max(np.abs(D.T @ J @ D - J)))


def _cross_matrix(L: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -L[2], L[1]], [L[2], 0.0, -L[0]], [-L[1], L[0], 0.0]])


def _lie_poisson_defect(method: Method, system, state, h, eps) -> float:
    moments = system.kernel_params()

    def momentum_map(L):
        y = state.copy()
        y[:3] = L / moments
        return moments * one_step(method, system, y, h)[:3]

    L0 = moments * state[:3]
    scale = float(np.linalg.norm(L0))
    D = np.empty((3, 3))
    for j in range(3):
        dL = np.zeros(3)
        dL[j] = eps * scale
        D[:, j] = (momentum_map(L0 + dL) - momentum_map(L0 - dL)) / (2.0 * dL[j])
    L1 = momentum_map(L0)
    return float(np.max(np.abs(D @ _cross_matrix(L0) @ D.T - _cross_matrix(L1)))) / scale
