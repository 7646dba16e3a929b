"""What a Taylor run keeps between calls, and which compiled code takes its steps; importable
without numba.

A :class:`~mechviz.dynamics.simulation.Simulation` of a shipped system with ``"taylor"`` is
advanced by the module compiled ahead of time (:mod:`mechviz.dynamics.aot`: the same loop,
:func:`.taylor.run_taylor_compiled`, compiled for this processor) when it is built and
:func:`mechviz.dynamics.aot.enabled`, and by numba's just-in-time code otherwise: a registered
system (its own forms), an ensemble large enough for numba's threads (:data:`PARALLEL_MIN`), or
no module yet, in which case the first such run starts building it in the background. A fresh
process whose run takes the first road imports neither numba nor scipy.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Callable

import numpy as np

from ..taylor_order import MAX_ORDER, order_for

# Ensembles of at least PARALLEL_MIN members run their members on numba's threads
# (:func:`.taylor.run_taylor_parallel`, bitwise the serial result). On idle cores that pays from
# small ensembles on, but on cores busy with other jobs a thread that loses its core holds the
# whole loop up, and in short calls the threads wait on each other (``mechviz bench``,
# "Ensembles", has the figures). Hence a threshold at calls long enough for the waiting not to
# matter; ``MECHVIZ_PARALLEL_MIN`` sets it, 0 turns it off.
PARALLEL_MIN = int(os.environ.get("MECHVIZ_PARALLEL_MIN") or 1000) or 1 << 62
_TAYLOR = __name__.rsplit(".", 1)[0] + ".taylor"


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


def _ahead_of_time(module):
    """:func:`.taylor.run_taylor`'s serial road through the module compiled ahead of time."""
    run = module.run

    def advance(sys_id, Y, p, t0, t1, rtol, atol, stats, status, carry: TaylorCarry) -> int:
        order, a = order_for(rtol, atol, sys_id)
        return run(sys_id, Y, p, t0, t1, rtol, atol, order, a, stats, status, *carry.arrays)

    return advance


#: The runner chosen, by whether the module compiled ahead of time may serve (a shipped system,
#: a serial run): chosen once per process, so that a run built per solve does not ask again.
_CHOSEN: dict[bool, Callable] = {}


def taylor_runner(sys_id, members: int) -> Callable:
    """The function ``f(sys_id, Y, p, t0, t1, rtol, atol, stats, status, carry) -> steps`` that
    advances a run of ``members`` members of system ``sys_id`` (module docstring):
    :func:`.taylor.run_taylor`'s arguments and result, whichever code runs it."""
    taylor = sys.modules.get(_TAYLOR)  # its threshold, which the warm-up and the bench move
    threshold = PARALLEL_MIN if taylor is None else taylor.PARALLEL_MIN
    serial_shipped = type(sys_id) is int and members < threshold
    run = _CHOSEN.get(serial_shipped)
    if run is None:
        run = _CHOSEN[serial_shipped] = _choose(serial_shipped)
    return run


def _choose(serial_shipped: bool) -> Callable:
    from .. import aot

    if serial_shipped and aot.enabled():
        module = aot.load()
        if module is not None and hasattr(module, "run"):
            return _ahead_of_time(module)
    from .taylor import run_taylor  # numba, and the generated expansions written if new

    if serial_shipped and aot.enabled():
        aot.build_in_background()  # numba's start is paid now; the next process need not
    return run_taylor
