"""Ctrl-C held while libraries import, and delivered as soon as they are done.

Some libraries import their optional parts inside ``try: ... except BaseException:`` (trimesh
does, and viser imports trimesh), so a ``KeyboardInterrupt`` raised during such an import is
swallowed and the program carries on as if Ctrl-C had never been pressed. Blocking SIGINT in
the importing thread (``pthread_sigmask``) keeps the signal pending instead; unblocking it
afterwards delivers it, and the ``KeyboardInterrupt`` is raised at that point, outside the
library's ``try``.
"""

from __future__ import annotations

import contextlib
import importlib
import signal
from collections.abc import Iterator
from types import ModuleType

_CAN_BLOCK = hasattr(signal, "pthread_sigmask")


def hold_sigint() -> set | None:
    """Block SIGINT in this thread; returns the mask to give :func:`release_sigint`."""
    if not _CAN_BLOCK:
        return None
    return signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})


def release_sigint(previous: set | None) -> None:
    """Restore the mask from :func:`hold_sigint`; a Ctrl-C that came meanwhile raises
    ``KeyboardInterrupt`` here (CPython runs the handlers before ``pthread_sigmask`` returns)."""
    if previous is not None:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


@contextlib.contextmanager
def sigint_held() -> Iterator[None]:
    """SIGINT blocked inside the block and delivered at its end."""
    previous = hold_sigint()
    try:
        yield
    finally:
        release_sigint(previous)


def import_holding_sigint(name: str) -> ModuleType:
    """``importlib.import_module(name)`` with SIGINT held (module docstring)."""
    with sigint_held():
        return importlib.import_module(name)
