"""Worker processes that ignore Ctrl-C from their first instruction.

A terminal's Ctrl-C reaches the whole process group. A worker started with the ``spawn`` method
is a fresh interpreter: while it imports ``site`` and its modules it has Python's own SIGINT
handler, so a Ctrl-C then prints ``Fatal Python error: init_import_site`` or a
``KeyboardInterrupt`` traceback into the user's terminal, or leaves a worker dead half-way through
its start. The process that started the workers is the one to handle the interrupt (stop them,
keep or drop what they made, say one line).

Of a signal's dispositions only an ignored one is passed on through fork and exec: a blocked
mask and a Python handler are not (``_posixsubprocess`` starts the child with both reset, seen in
``/proc/<pid>/status``). So the workers are started through a two-line program that ignores
SIGINT and execs this Python, while this process keeps handling Ctrl-C.
"""

from __future__ import annotations

import contextlib
import os
import shlex
import signal
import sys
import threading
from collections.abc import Iterator
from pathlib import Path


@contextlib.contextmanager
def spawned_workers_ignore_ctrl_c(folder: str | os.PathLike[str]) -> Iterator[None]:
    """Processes spawned by :mod:`multiprocessing` inside this block start with SIGINT ignored.

    ``folder`` holds the two-line program (``trap '' INT; exec python "$@"``) for the block's
    life; the caller owns it (a temporary folder). The spawn executable is global to the
    process, so it is set only from the main thread and put back on the way out; elsewhere the
    block changes nothing. Where ``folder`` cannot hold a program (a ``noexec`` mount) this
    process ignores SIGINT itself while inside, as the workers' only way to inherit it: a Ctrl-C
    in that window is lost, one after it is handled as usual. A worker that wants Ctrl-C back
    sets its own handler once it has started."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    import multiprocessing
    from multiprocessing import spawn

    if os.statvfs(folder).f_flag & getattr(os, "ST_NOEXEC", 0):
        previous_handler = signal.signal(signal.SIGINT, signal.SIG_IGN)
        try:
            yield
        finally:
            signal.signal(signal.SIGINT, previous_handler)
        return
    program = Path(folder) / "python-ignoring-ctrl-c"
    # sh's ``trap '' INT`` is an ignored SIGINT, which ``exec`` keeps; a Ctrl-C before the trap
    # ends the shell silently (a default disposition prints nothing)
    program.write_text(f"#!/bin/sh\ntrap '' INT\nexec {shlex.quote(sys.executable)} \"$@\"\n")
    program.chmod(0o700)
    previous = spawn.get_executable()
    multiprocessing.set_executable(str(program))
    try:
        yield
    finally:
        multiprocessing.set_executable(os.fsdecode(previous))
