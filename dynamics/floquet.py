"""Mode 1's stability on the hoop at finite amplitude: the monodromy of its swing and the Floquet
multiplier of a departure from it, computed by running the full equations (kept apart from
:mod:`.hoop`, whose equations the driver compiles: this module drives the driver)."""

from __future__ import annotations

import math

import numpy as np

from . import params as _v
from .hoop import HoopParams, mode1_period
from .simulation import Simulation
from .systems import Hoop


def mode1_monodromy(p: HoopParams, amplitude: float, eps: float = 1e-6) -> np.ndarray:
    """The monodromy matrix (4, 4) of the mode-1 swing of ``amplitude`` [rad], released at rest:
    how a small departure ``d`` of the state at the turning point comes back after one period,
    ``d -> D d``, from central differences of the flow over :func:`mode1_period` (a DOP853 run
    at rtol 1e-13 of the full equations, each of the eight displaced starts beside the others).
    Its eigenvalues are 1, 1 (along the swing, and to a neighbouring amplitude) and the Floquet
    multipliers of the departure from mode 1, ``l`` and ``1/l`` (the flow keeps volume)."""
    A = _v.finite("amplitude", amplitude)
    if not 0.0 < abs(A) < math.pi:
        raise _v.SettingError("amplitude", f"amplitude must lie in (0, pi) rad, got {A!r}")
    start = np.array([A, A, 0.0, 0.0])
    starts = np.repeat(start[None, :], 8, axis=0)
    for j in range(4):
        starts[2 * j, j] += eps
        starts[2 * j + 1, j] -= eps
    sim = Simulation(Hoop(p), "dop853", rtol=1e-13, atol=1e-15, state=starts, reference=None)
    sim.advance_to(mode1_period(p, abs(A)), final=True)
    end = sim.state
    return np.column_stack([(end[2 * j] - end[2 * j + 1]) / (2.0 * eps) for j in range(4)])


#: Mode 1's tangent directions (theta1 = theta2, omega1 = omega2) and the departures from it.
_ALONG_ACROSS = np.array(
    [[1.0, 0.0, 1.0, 0.0], [1.0, 0.0, -1.0, 0.0], [0.0, 1.0, 0.0, 1.0], [0.0, 1.0, 0.0, -1.0]]
)


def mode1_floquet_multiplier(p: HoopParams, amplitude: float) -> float:
    """The largest |Floquet multiplier| of a departure from the mode-1 swing of ``amplitude``
    [rad] (:func:`mode1_monodromy`): 1 where a departure stays small (it only turns), ``l`` above
    1 where it grows ``l``-fold each period, so that one from round-off (1e-16) reaches 0.1 rad
    after about ``ln(1e15) / ln(l)`` periods. On the default hoop about 38 at 2 rad: under ten
    periods (35 s); a hoop with a bead of a tenth of its mass keeps mode 1 stable at 2 rad.

    Mode 1 is an invariant set, so the monodromy maps its tangent directions among themselves,
    and the departures' multipliers are those of the block of the departures (the pair ``l``,
    ``1/l``), apart from the pair along the swing (1 and 1, but a Jordan block that differences
    split by the square root of their error)."""
    D = mode1_monodromy(p, amplitude)
    B = _ALONG_ACROSS
    across = np.linalg.solve(B, D @ B)[2:, 2:]
    return float(np.max(np.abs(np.linalg.eigvals(across))))
