"""What the maps are drawn against: the start each amplitude means, and the lines theory predicts.

Amplitude, per system (the x axis of the stability and accuracy maps):

- hoop: both normal modes displaced by ``A`` [rad], at rest (``hoop.mode_state(p, (A, A))``), so
  the faster mode, the one that limits the step, is always present;
- cyclotron: speed ``A`` [m/s] across the field from the origin (``vy = A``);
- free-body: the released disk with an extra spin ``(A, 0, A)`` [rad/s] in the disk's frame.

Lines: the linear stability limit ``dt = x_max / omega_fast`` of each fixed-step method
(:mod:`mechviz.dynamics.stability`), the hoop's two normal-mode lines in its start plane at rest
(``theta2 = theta1`` and ``theta2 = -(M + m)/m theta1``), and where the nonlinear mode 1 (the whole
body swinging as one pendulum, ``theta1 = theta2 = A``) is unstable to the bead's motion:
the Floquet multipliers of its period map. That map is symplectic with two trivial multipliers
(along the orbit and across the energy shells), so the transverse pair is stable exactly when
``|trace(J) - 2| <= 2``; ``J`` is found by central differences of tight DOP853 runs over one
period ``hoop.mode1_period(p, A)``.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from .. import hoop, stability
from ..hoop import HoopParams
from ..simulation import REFERENCE_ATOL, REFERENCE_TOL, Simulation
from ..systems import SYSTEMS, Hoop


def make_system(name: str, params: dict[str, float]):
    """The system adapter ``name`` (:data:`mechviz.dynamics.systems.SYSTEMS`) with the parameter fields
    ``params`` (defaults otherwise)."""
    try:
        cls = SYSTEMS[name]
    except KeyError:
        raise ValueError(f"unknown system {name!r}") from None
    try:
        return cls(cls.Params(**params))
    except TypeError as exc:  # an unknown field name
        raise ValueError(f"params: {exc}") from None


def amplitude_unit(name: str) -> str:
    """The unit of the amplitude axis of system ``name``."""
    return SYSTEMS[name].amplitude[0]


def amplitude_label(name: str) -> str:
    """The label of the amplitude axis of system ``name``."""
    return SYSTEMS[name].amplitude[1]


def start_states(system, amplitudes: np.ndarray) -> np.ndarray:
    """(N, d) start states for ``amplitudes`` (module docstring)."""
    return np.stack([system.amplitude_state(float(x)) for x in np.asarray(amplitudes, float)])


def fastest_period(spec) -> float:
    """The period [s] of the fastest linear motion at the largest amplitude of ``spec``."""
    system = spec.make_system()
    state = start_states(system, [max(abs(spec.x.start), abs(spec.x.stop))])[0]
    return 2.0 * math.pi / system.fastest_frequency(state)


def linear_limit_dt(system, method: str, amplitudes: np.ndarray) -> np.ndarray:
    """Largest linearly stable step [s] per amplitude: ``inf`` for no limit, 0 for none."""
    x = stability.limit_omega_dt(method, system)
    if x is None:
        return np.full(len(amplitudes), np.inf)
    states = start_states(system, amplitudes)
    return np.array([x / system.fastest_frequency(s) for s in states])


def normal_mode_slopes(p: HoopParams) -> tuple[float, float]:
    """Slopes ``theta2 / theta1`` of the two normal-mode lines in the start plane at rest."""
    _, shapes = hoop.normal_modes(p)
    return float(shapes[0, 1] / shapes[0, 0]), float(shapes[1, 1] / shapes[1, 0])


def mode1_transverse_trace(p: HoopParams, amplitude: float, eps: float = 1e-6) -> float:
    """``trace(J) - 2`` of the period map ``J`` of mode 1 at ``amplitude`` [rad]: the transverse
    Floquet pair is stable for values in [-2, 2]."""
    y0 = np.array([amplitude, amplitude, 0.0, 0.0])
    states = [y0]
    for j in range(4):
        for sign in (1.0, -1.0):
            s = y0.copy()
            s[j] += sign * eps
            states.append(s)
    sim = Simulation(
        Hoop(p),
        "dop853",
        rtol=REFERENCE_TOL,
        atol=REFERENCE_ATOL,
        state=np.array(states),
        reference=None,
    )
    sim.advance_to(hoop.mode1_period(p, amplitude))
    end = sim.state
    jac = np.stack([(end[1 + 2 * j] - end[2 + 2 * j]) / (2 * eps) for j in range(4)], axis=1)
    return float(np.trace(jac) - 2.0)


@functools.lru_cache(maxsize=16)
def mode1_unstable_intervals(p: HoopParams, n: int = 64, top: float = 3.0) -> tuple:
    """Amplitudes ``(lo, hi)`` [rad] in (0, ``top``] over which mode 1 is unstable, each end found
    by bisection between ``n`` scanned amplitudes (to 1e-6 rad)."""

    def excess(a: float) -> float:
        return abs(mode1_transverse_trace(p, a)) - 2.0

    grid = np.linspace(top / n, top, n)
    signs = [excess(a) > 0.0 for a in grid]
    ends = []
    for i in range(1, n):
        if signs[i] != signs[i - 1]:
            lo, hi = grid[i - 1], grid[i]
            while hi - lo > 1e-6:
                mid = 0.5 * (lo + hi)
                if (excess(mid) > 0.0) == signs[i - 1]:
                    lo = mid
                else:
                    hi = mid
            ends.append((0.5 * (lo + hi), signs[i]))
    intervals, start = [], (grid[0] if signs[0] else None)
    for a, unstable in ends:
        if unstable:
            start = a
        elif start is not None:
            intervals.append((float(start), float(a)))
            start = None
    if start is not None:
        intervals.append((float(start), float(top)))
    return tuple(intervals)
