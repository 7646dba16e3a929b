"""Each system's equations, written once: ``y' = f(t, y; p)`` as sympy expressions.

An :class:`Equations` holds the state's symbols (in the order of the state vector), the
parameters' symbols (in the order of the float64 array ``p`` the compiled code reads, the
system's ``kernel_params()``) and one expression per component of ``y'``. Every compiled form
the code generator makes (:mod:`.rhs`, the right-hand side; :mod:`.series`, the Taylor
coefficients' recurrences) is derived from these expressions; a system defined anywhere else
(a test's, say) is an :class:`Equations` too.

A mechanical system's equations may be given as a mass-matrix system: the rates of the last
``n`` state components (the velocities' accelerations ``a``) solve ``M(y) a = f(y)``, with
``M`` an ``n x n`` matrix and ``f`` the ``n`` forces as expressions (the hoop's Euler-Lagrange
equations). The right-hand side is then that solution (Cramer's rule: the adjugate over the
determinant), and the Taylor recurrences solve the series of the system itself
(:mod:`.series`), which costs a fraction of the solved form's quotients.

Units: SI, as each system's module documents (:mod:`mechviz.dynamics.cyclotron`,
:mod:`mechviz.dynamics.hoop`, :mod:`mechviz.dynamics.disk`). The equations are autonomous (no
``t``), as every system here is; a driven system would carry its phase as a state component.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass

import sympy as sp

from ..ids import CYCLOTRON, FREE_BODY, HOOP, NAMES


@dataclass(frozen=True)
class Equations:
    """``y' = f(y; p)``: ``state`` and ``params`` symbols, ``rhs`` one expression per state
    component. ``name`` is a system's name, letters, digits, ``_`` and ``-`` (it names the
    generated module on disk, with ``-`` as ``_``).

    With a ``mass`` matrix (``n x n``, rows of expressions) and ``force`` (``n`` expressions),
    ``rhs`` gives the rates of the first ``d - n`` components only; the last ``n`` rates solve
    ``mass @ y'[d - n:] = force`` and are appended to ``rhs`` (module docstring)."""

    name: str
    state: tuple[sp.Symbol, ...]
    params: tuple[sp.Symbol, ...]
    rhs: tuple[sp.Expr, ...]
    mass: tuple[tuple[sp.Expr, ...], ...] = ()
    force: tuple[sp.Expr, ...] = ()

    def __post_init__(self) -> None:
        if not self.name.replace("-", "_").isidentifier():
            raise ValueError(f"the name {self.name!r}: letters, digits, _ and - only")
        n = len(self.mass)
        if len(self.force) != n or any(len(row) != n for row in self.mass):
            raise ValueError(f"{self.name}: the mass matrix is n x n, with n forces")
        if len(self.rhs) + n != len(self.state):
            raise ValueError(
                f"{self.name}: one right-hand side per state component"
                + (f", but for the last {n}, which solve the mass matrix's system" if n else "")
            )
        known = set(self.state) | set(self.params)
        mass = tuple(tuple(sp.sympify(e) for e in row) for row in self.mass)
        force = tuple(sp.sympify(e) for e in self.force)
        for e in (*self.rhs, *force, *(e for row in mass for e in row)):
            stray = sp.sympify(e).free_symbols - known
            if stray:
                raise ValueError(f"{self.name}: unknown symbols {sorted(map(str, stray))}")
        rhs = tuple(sp.sympify(e) for e in self.rhs)
        if n:
            matrix = sp.Matrix(mass)
            # Cramer's rule, division-free up to the one quotient by the determinant
            solved = matrix.adjugate() * sp.Matrix(force) / matrix.det(method="berkowitz")
            rhs += tuple(solved)
        object.__setattr__(self, "rhs", rhs)
        object.__setattr__(self, "mass", mass)
        object.__setattr__(self, "force", force)

    @property
    def dim(self) -> int:
        """The state's dimension."""
        return len(self.state)

    def key(self) -> str:
        """A digest of the equations (their exact expression trees): names the generated code,
        so an edited equation never runs stale code."""
        exprs = [*self.rhs, *self.force, *(e for row in self.mass for e in row)]
        text = repr(
            (self.name, self.state, self.params, len(self.mass), list(map(sp.srepr, exprs)))
        )
        return hashlib.sha256(text.encode()).hexdigest()[:16]


def charge() -> Equations:
    """A charge in a uniform field along z: ``r' = v``, ``v' = Omega (vy, -vx, 0)``, with
    ``p = [Omega]`` (the signed gyrofrequency ``qB/m`` [rad/s])."""
    x, y, z, vx, vy, vz = sp.symbols("x y z vx vy vz", real=True)
    w = sp.Symbol("Omega", real=True)
    return Equations(
        NAMES[CYCLOTRON], (x, y, z, vx, vy, vz), (w,), (vx, vy, vz, w * vy, -w * vx, 0)
    )


def hoop() -> Equations:
    """The hoop and bead (:mod:`mechviz.dynamics.hoop`): the Euler-Lagrange equations as a mass
    matrix system for the accelerations ``(th1'', th2'')``, ``p = [M, m, a, g]``. The matrix is
    the Lagrangian's divided by ``a^2`` and its second row by ``m``:
    ``[[2M + m, m cos u], [cos u, 1]]`` with ``u = th1 - th2``; the forces
    ``-m sin(u) w2^2 - (M + m)(g/a) sin th1`` and ``sin(u) w1^2 - (g/a) sin th2`` [1/s^2]."""
    th1, th2, w1, w2 = sp.symbols("theta1 theta2 omega1 omega2", real=True)
    M, m, a, g = sp.symbols("M m a g", positive=True)
    ga = g / a
    s, c = sp.sin(th1 - th2), sp.cos(th1 - th2)
    r1 = -m * s * w2**2 - (M + m) * ga * sp.sin(th1)
    r2 = s * w1**2 - ga * sp.sin(th2)
    return Equations(
        NAMES[HOOP],
        (th1, th2, w1, w2),
        (M, m, a, g),
        (w1, w2),
        mass=((2 * M + m, m * c), (c, 1)),
        force=(r1, r2),
    )


def free_body() -> Equations:
    """The free rigid body in its principal frame: Euler's equations for ``w`` [rad/s] and the
    attitude quaternion's ``q' = q (0, w) / 2``, with ``p = [I1, I2, I3]`` [kg m^2]."""
    w1, w2, w3, q0, q1, q2, q3 = sp.symbols("w1 w2 w3 q0 q1 q2 q3", real=True)
    i1, i2, i3 = sp.symbols("I1 I2 I3", positive=True)
    half = sp.Rational(1, 2)
    return Equations(
        NAMES[FREE_BODY],
        (w1, w2, w3, q0, q1, q2, q3),
        (i1, i2, i3),
        (
            (i2 - i3) / i1 * w2 * w3,
            (i3 - i1) / i2 * w3 * w1,
            (i1 - i2) / i3 * w1 * w2,
            half * (-q1 * w1 - q2 * w2 - q3 * w3),
            half * (q0 * w1 + q2 * w3 - q3 * w2),
            half * (q0 * w2 + q3 * w1 - q1 * w3),
            half * (q0 * w3 + q1 * w2 - q2 * w1),
        ),
    )


#: The product's systems' equations by their compiled id (:mod:`mechviz.dynamics.ids`).
EQUATIONS = {CYCLOTRON: charge, HOOP: hoop, FREE_BODY: free_body}
