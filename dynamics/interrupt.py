"""Ending a command on Ctrl-C, SIGTERM or SIGHUP: promptly, and with its clean-up done.

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
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
from collections.abc import Iterator

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
