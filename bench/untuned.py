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

from dataclasses import dataclass

import numpy as np

from mechviz.dynamics.registry import SPECS

from .problems import LONG_DOUBLE_TOL, Problem

CHECK_TOL = 1e-15
RESOLVE_FACTOR = 100.0


@dataclass(frozen=True)
class Reference:
    """A case's reference final state, how it was made, and the smallest error it resolves."""

    state: np.ndarray
    kind: str
    resolves: float


#: Each system's draw, by the key of its benchmark problem (the registry's order).
_DRAW = {s.bench[0].key: s.bench_draw for s in SPECS.values() if s.bench and s.bench_draw}
KINDS = tuple(_DRAW)


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
