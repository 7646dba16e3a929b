"""What a Taylor run keeps between calls, and the ensembles that run on numba's threads;
importable without numba (which compiled code takes the steps:
:func:`mechviz.dynamics.aot.taylor_runner`)."""

from __future__ import annotations

import os

import numpy as np

from ..taylor_order import MAX_ORDER

# Ensembles of at least PARALLEL_MIN members run their members on numba's threads
# (:func:`.taylor.run_taylor_parallel`, bitwise the serial result). On idle cores that pays from
# small ensembles on, but on cores busy with other jobs a thread that loses its core holds the
# whole loop up, and in short calls the threads wait on each other (``mechviz bench``,
# "Ensembles", has the figures). Hence a threshold at calls long enough for the waiting not to
# matter; ``MECHVIZ_PARALLEL_MIN`` sets it, 0 turns it off.
PARALLEL_MIN = int(os.environ.get("MECHVIZ_PARALLEL_MIN") or 1000) or 1 << 62


class TaylorCarry:
    """What one run keeps between calls: each member's last step (see :mod:`.taylor`)."""

    def __init__(self, n: int, d: int) -> None:
        self.kept = np.zeros((n, d, MAX_ORDER + 1))  # the state's series only: 1 kB a hoop
        self.base = np.zeros(n)
        self.comp = np.zeros(n)  # the base time's compensation: it is base + comp
        self.span = np.zeros(n)
        self.last = np.zeros((n, d))

    @property
    def arrays(self) -> tuple[np.ndarray, ...]:
        """``(kept, base, comp, span, last)``, as the compiled loops take them."""
        return self.kept, self.base, self.comp, self.span, self.last

    def forget(self) -> None:
        """Keep no step: the next call starts a fresh one."""
        self.span.fill(0.0)
