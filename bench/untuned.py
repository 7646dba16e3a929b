"""Cases nobody tuned for: problems drawn at random from a seed, with their references.

Each system gets the same share of the cases. What is drawn (uniformly, signs at random where
marked with +-):

=========  =================================================================================
charge     charge +-[0.3, 3] C, mass [0.3, 3] kg, field +-[0.3, 3] T; position in [-2, 2]^3 m,
           velocity in [-2, 2]^3 m/s; span 10-300 gyro-periods
hoop       hoop mass [0.2, 3] kg, bead mass [0.1, 3] kg, radius [0.3, 2] m, g = 9.81; angles in
           [-1.5, 1.5] rad, rates in [-0.5, 0.5] sqrt(g/a); span 5-30 s
disk       disk mass [0.3, 3] kg, radius [0.3, 2] m, bead mass [0.05, 3] kg, spin +-[0.3, 5]
           rad/s, extra spin per axis in [-0.5, 0.5] of the spin; span 10-100 s
=========  =================================================================================

The same seed gives the same cases (:func:`draw`). References: the exact helix for the charge;
heyoka's Taylor integrator in 80-bit long double at ``tol = 1e-19`` for the others, checked
against a second solve in double at ``1e-15``: a case whose two answers differ by ``c`` (a
sensitive trajectory magnifies round-off) cannot resolve targets below ``100 c``, and those
are reported as unresolved, not as a result (:func:`reference`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mechviz.dynamics.cyclotron import CyclotronParams
from mechviz.dynamics.disk import DiskParams
from mechviz.dynamics.hoop import HoopParams
from mechviz.dynamics.systems import DISK, HOOP, Cyclotron, Hoop, ReleasedDisk

from .problems import LONG_DOUBLE_TOL, Problem

KINDS = ("charge", HOOP.name, DISK.name)
CHECK_TOL = 1e-15
RESOLVE_FACTOR = 100.0


@dataclass(frozen=True)
class Reference:
    """A case's reference final state, how it was made, and the smallest error it resolves."""

    state: np.ndarray
    kind: str
    resolves: float


def _signed(rng: np.random.Generator, lo: float, hi: float) -> float:
    return float(rng.uniform(lo, hi) * rng.choice((-1.0, 1.0)))


def _charge(rng: np.random.Generator, key: str) -> Problem:
    q, m, b = _signed(rng, 0.3, 3.0), float(rng.uniform(0.3, 3.0)), _signed(rng, 0.3, 3.0)
    system = Cyclotron(CyclotronParams(charge=q, mass=m, field=b))
    state = tuple(float(v) for v in np.concatenate([rng.uniform(-2, 2, 3), rng.uniform(-2, 2, 3)]))
    periods = int(rng.integers(10, 301))
    period = 2.0 * math.pi * m / abs(q * b)
    title = f"charge q={q:.3g} m={m:.3g} B={b:.3g}, {periods} gyro-periods"
    return Problem(key, title, system, state, periods * period, (), 0, 1e-13, period, True)


def _hoop(rng: np.random.Generator, key: str) -> Problem:
    M, m, a = float(rng.uniform(0.2, 3.0)), float(rng.uniform(0.1, 3.0)), float(rng.uniform(0.3, 2))
    system = Hoop(HoopParams(hoop_mass=M, bead_mass=m, radius=a))
    rate = math.sqrt(9.81 / a)
    state = tuple(
        float(v)
        for v in np.concatenate([rng.uniform(-1.5, 1.5, 2), rate * rng.uniform(-0.5, 0.5, 2)])
    )
    span = float(rng.uniform(5.0, 30.0))
    title = f"hoop M={M:.3g} m={m:.3g} a={a:.3g}, {span:.1f} s"
    return Problem(key, title, system, state, span, (), 0, 1e-13, 2 * math.pi / rate, False)


def _disk(rng: np.random.Generator, key: str) -> Problem:
    M, R, m = (
        float(rng.uniform(0.3, 3.0)),
        float(rng.uniform(0.3, 2.0)),
        float(rng.uniform(0.05, 3)),
    )
    w = _signed(rng, 0.3, 5.0)
    extra = tuple(float(v) for v in abs(w) * rng.uniform(-0.5, 0.5, 3))
    system = ReleasedDisk(DiskParams(disk_mass=M, radius=R, bead_mass=m, omega=w), extra_spin=extra)
    span = float(rng.uniform(10.0, 100.0))
    title = f"disk M={M:.3g} R={R:.3g} bead={m:.3g} spin={w:.3g}, {span:.1f} s"
    state = tuple(float(v) for v in system.default_state())
    return Problem(key, title, system, state, span, (), 0, 1e-13, 2 * math.pi / abs(w), False)


_DRAW = {"charge": _charge, HOOP.name: _hoop, DISK.name: _disk}


def draw(seed: int, n: int) -> dict[str, Problem]:
    """``n`` cases from ``seed``, the systems in turn (``random-<k>-<system>``)."""
    rng = np.random.default_rng(seed)
    out: dict[str, Problem] = {}
    for k in range(n):
        kind = KINDS[k % len(KINDS)]
        key = f"random-{k:02d}-{kind}"
        out[key] = _DRAW[kind](rng, key)
    return out


def reference(problem: Problem) -> Reference:
    """The reference final state of ``problem`` (module docstring)."""
    if problem.exact_reference:
        exact = np.asarray(problem.system.exact(problem.y0, problem.t_end), dtype=float)
        return Reference(exact, "exact", 0.0)
    from .fast_peers import heyoka_solver
    from .peer_equations import heyoka_pars
    from .problems import _long_double_final

    ref, _ = _long_double_final(problem)
    sid = problem.system.sys_id
    pars = heyoka_pars(sid, problem.system.kernel_params())
    check, _ = heyoka_solver(sid, len(ref), len(pars), CHECK_TOL, False).solve(
        problem.y0, pars, problem.t_end
    )
    c = problem.error(check, ref)
    kind = (
        f"heyoka taylor_adaptive, long double, tol={LONG_DOUBLE_TOL:g}; "
        f"double at {CHECK_TOL:g} lands {c:.1e} from it"
    )
    return Reference(ref, kind, RESOLVE_FACTOR * c)
