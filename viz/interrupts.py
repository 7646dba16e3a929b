"""Ctrl-C, SIGTERM and SIGHUP: every command ends promptly, with its clean-up done, and no
library can swallow the signal (the one place the command line handles signals).

- :func:`signals_end_like_ctrl_c` (around a whole command): SIGTERM and SIGHUP (a closed
  terminal) raise :class:`Terminated`, a ``KeyboardInterrupt``, in the main thread, so every
  clean-up a Ctrl-C runs (``finally`` blocks and context managers that end child processes and
  browsers and remove temporary folders) runs for them too. Their default action would end the
  process at once and leave all that behind.
- :func:`ctrl_c_within_a_second` (around work that writes no files): if the process has not
  ended a second after one of these signals (numba's compiler, which runs Python callbacks from
  C, swallows the exception), it prints the usual line and exits at once; and if the work
  ends within that second although the exception was swallowed, it is raised as the block ends.

A second signal while the first is being handled ends the process at once as well.

- :func:`hold_sigint` / :func:`release_sigint`, :func:`sigint_held`: Ctrl-C held while libraries
  import, and delivered as soon as they are done. Some libraries import their optional parts
  inside ``try: ... except BaseException:`` (trimesh does, and viser imports trimesh), so a
  ``KeyboardInterrupt`` raised during such an import is swallowed and the program carries on as
  if Ctrl-C had never been pressed. Blocking SIGINT in the importing thread
  (``pthread_sigmask``) keeps the signal pending instead; unblocking it afterwards delivers it,
  and the ``KeyboardInterrupt`` is raised at that point, outside the library's ``try``.
"""

from __future__ import annotations

import contextlib
import importlib
import os
import signal
import sys
import threading
from collections.abc import Iterator
from types import ModuleType

# SIGHUP does not exist on Windows.
END_SIGNALS = tuple(getattr(signal, n) for n in ("SIGTERM", "SIGHUP") if hasattr(signal, n))
HARD_EXIT_SECONDS = 1.0


class Terminated(KeyboardInterrupt):
    """SIGTERM or SIGHUP, raised like Ctrl-C; ``signum`` says which (exit status 128 + it)."""

    def __init__(self, signum: int) -> None:
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


def exit_status(exc: KeyboardInterrupt) -> int:
    """The exit status for an interrupt: 128 + the signal (130 for Ctrl-C)."""
    return 128 + getattr(exc, "signum", signal.SIGINT)


def _in_main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()


@contextlib.contextmanager
def signals_end_like_ctrl_c() -> Iterator[None]:
    """SIGTERM and SIGHUP raise :class:`Terminated` in the main thread while inside (handlers
    someone else installed are left alone); a second one exits at once."""
    if not _in_main_thread():
        yield
        return
    seen = threading.Event()

    def on_signal(signum, frame) -> None:
        if seen.is_set():
            os._exit(128 + signum)
        seen.set()
        raise Terminated(signum)

    previous = {}
    for s in END_SIGNALS:
        if signal.getsignal(s) is signal.SIG_DFL:
            previous[s] = signal.signal(s, on_signal)
    try:
        yield
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)


@contextlib.contextmanager
def ctrl_c_within_a_second() -> Iterator[None]:
    """Ctrl-C raises ``KeyboardInterrupt`` as usual (SIGTERM and SIGHUP :class:`Terminated`),
    and if the process has not ended :data:`HARD_EXIT_SECONDS` later, prints the usual line and
    exits with 128 + the signal. Only around work that writes no files (the bench wraps its
    measurements, not its writing)."""
    if not _in_main_thread():
        yield
        return
    done = threading.Event()

    def hard_exit(signum: int) -> None:
        if not done.is_set():
            if sys.stderr.isatty():  # a progress line may be showing: clear it first
                sys.stderr.write("\r\033[K")
            sys.stderr.write("mechviz: interrupted\n")
            sys.stderr.flush()
            os._exit(128 + signum)

    received: list[int] = []

    def on_signal(signum, frame) -> None:
        received.append(signum)
        timer = threading.Timer(HARD_EXIT_SECONDS, hard_exit, args=(signum,))
        timer.daemon = True
        timer.start()
        if signum == signal.SIGINT:
            raise KeyboardInterrupt
        raise Terminated(signum)

    def unraisable(info) -> None:  # the swallowed KeyboardInterrupt is not worth a traceback
        if not issubclass(info.exc_type, KeyboardInterrupt):
            previous_hook(info)

    previous = {s: signal.signal(s, on_signal) for s in (signal.SIGINT, *END_SIGNALS)}
    previous_hook, sys.unraisablehook = sys.unraisablehook, unraisable
    try:
        yield
    finally:
        done.set()
        for s, handler in previous.items():
            signal.signal(s, handler)
        sys.unraisablehook = previous_hook
    if received:  # swallowed on the way (numba's compiler, matplotlib's layout): it counts here
        if received[0] == signal.SIGINT:
            raise KeyboardInterrupt
        raise Terminated(received[0])


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
