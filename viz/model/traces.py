"""A recorded run: every run's samples at every frame, the events and the measured figures."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np


@dataclass
class Traces:
    """Samples of every run at every frame, by run label (the method's name, or
    ``"<method> (compare)"`` when both runs use one method)."""

    t: np.ndarray  # (K,) frame times (simulated)
    times: dict[str, np.ndarray]  # label -> (K,) time of each sample (fixed step: last step <= t)
    states: dict[str, np.ndarray]  # label -> (K, N, d)
    energy: dict[str, np.ndarray]  # label -> (K, N)
    energy_error: dict[str, np.ndarray]
    error: dict[str, np.ndarray | None]
    reference: dict[str, str | None]
    steps: dict[str, int]
    nfev: dict[str, int]
    runs: dict[str, dict[str, Any]]  # label -> method, title, order, structure, step
    ghost: np.ndarray | None  # (K, 1, d) linear theory (hoop)
    event_log: list[dict[str, Any]] = field(default_factory=list)
    measured: dict[str, Any] = field(default_factory=dict)  # the exhibit's readout figures
    # label -> (K, N) the measured relative error of what ``error`` is against (0: exact)
    reference_error: dict[str, np.ndarray | None] = field(default_factory=dict)

    @property
    def main(self) -> str:
        return next(iter(self.states))
