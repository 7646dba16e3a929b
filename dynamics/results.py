"""What a run reports: its samples (:class:`Sample`, :class:`Trajectory`) and the tight DOP853
reference the error is measured against where there is no exact solution, with its own measured
error (kept apart from the driver, :mod:`.simulation`, which fills them)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: The reference run's rtol and atol. Its steps are not cut at each frame (dense output), so the
#: tolerance alone sets its error: at rtol = atol = 1e-14 it reached 6e-12 on the hoop's mode 1 at
#: 0.05 rad, where atol dominates the small state. These keep it below REFERENCE_ACCURACY with
#: fewer steps than one per frame.
REFERENCE_TOL = 3e-15
#: The method the reference run (and its check run) takes.
REFERENCE_METHOD = "dop853"
REFERENCE_ATOL = 1e-17
#: The reference run's own relative error on the exact motions (the cyclotron's helix, the hoop's
#: mode 1), measured over 100 s in 1/60 s frames. Not a bound on other motions: on a chaotic one
#: the error grows exponentially, which is why every run measures it (CHECK_TOL).
REFERENCE_ACCURACY = 5e-13
#: The tolerances of the check run advanced beside the reference: ten times looser, so that the
#: two runs' difference is dominated by the check's error and bounds the reference's from above.
CHECK_TOL = 10 * REFERENCE_TOL
CHECK_ATOL = 10 * REFERENCE_ATOL
#: An error against the reference is resolved (a figure about the method) only where it is at
#: least this many times the reference's measured error bar.
RESOLVED_FACTOR = 10.0
#: What a run's error is measured against (:attr:`Simulation.reference_kind`): the system's exact
#: flow, or the tight reference run. Named here because the first is spelt as the exact method
#: is, and a comparison with the word would read as a branch on that method.
EXACT_FLOW, REFERENCE_RUN = "exact", "reference"


def reference_description(kind: str | None) -> str | None:
    """What a run's ``error`` is measured against, in words (``kind``: ``"exact"``,
    ``"reference"`` or ``None``, as :attr:`Simulation.reference_kind`)."""
    if kind is None:
        return None
    if kind == EXACT_FLOW:
        return "exact solution (round-off only)"
    return (
        f"DOP853 at rtol = {REFERENCE_TOL:g}, atol = {REFERENCE_ATOL:g}; its own relative error "
        f"(reference_error) measured by a DOP853 run at rtol = {CHECK_TOL:g}, atol = "
        f"{CHECK_ATOL:g} advanced beside it: their difference"
    )


def error_verdict(error: float, reference_error: float | None) -> str:
    """An error against the reference in words with the reference's own: ``"3e-11, reference
    good to 2e-12"``, or ``"not resolved by the reference"`` where the error is not at least
    :data:`RESOLVED_FACTOR` times the reference's (``reference_error`` None or 0: the exact
    solution)."""
    if not reference_error:
        return f"{error:.2e}"
    if error >= RESOLVED_FACTOR * reference_error:
        return f"{error:.2e}, reference good to {reference_error:.1e}"
    return f"{error:.2e}: not resolved by the reference (good to {reference_error:.1e})"


#: An adaptive run is compared with the reference only if its rtol and atol are at least this
#: (over 100 times REFERENCE_TOL).
MIN_COMPARED_TOL = 1e-12
#: Target wall time [s] of one call into compiled code; Ctrl-C is seen between calls.
CHUNK_SECONDS = 0.1


@dataclass(frozen=True)
class Sample:
    """One moment of a run. Arrays have the ensemble on the leading axis."""

    t: float
    state: np.ndarray  # (N, d)
    energy: np.ndarray  # (N,)
    energy_error: np.ndarray  # (N,) relative: (E - E0) / (E0 - E_floor), see the module docstring
    error: np.ndarray | None  # (N,) against the exact solution or the tight reference
    reference: np.ndarray | None  # (N, d) the state it was measured against
    nfev: int
    steps: int
    invariants: dict[str, np.ndarray] | None = None  # the system's conserved quantities, by name
    # What ``error`` is measured against ("exact", "reference" or None) and that reference's own
    # relative error (N,) as measured now (zeros for the exact solution: round-off only; for the
    # DOP853 reference its difference from the check run, Simulation.reference_error).
    reference_kind: str | None = None
    reference_accuracy: np.ndarray | None = None


@dataclass(frozen=True)
class Trajectory:
    """Samples of a run stacked in time: ``t`` (K,) [s], ``states`` (K, N, d), ``energy`` [J]
    and ``energy_error`` (K, N), ``error`` (K, N) or None, ``invariants`` by name (K, N, ...);
    ``nfev`` and ``steps`` of the whole run."""

    t: np.ndarray
    states: np.ndarray
    energy_error: np.ndarray
    error: np.ndarray | None
    nfev: int
    steps: int
    energy: np.ndarray | None = None
    invariants: dict[str, np.ndarray] | None = None
    # (K, N) the measured relative error of what ``error`` is against (Sample.reference_accuracy)
    reference_error: np.ndarray | None = None
