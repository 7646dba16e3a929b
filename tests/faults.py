"""Faults the tests inject into a write: a child process killed (SIGKILL) right after its n-th
call of chosen ``os`` functions, as a power cut or ``kill -9`` would stop it at every step of its
commit; a disk that fills at the n-th ``fsync``."""

from __future__ import annotations

import errno
import os


def disk_full_at_nth_fsync(monkeypatch, n: int) -> None:
    """The n-th ``os.fsync`` from now raises ENOSPC ("No space left on device"), the earlier ones
    sync as usual: the disk fills during the write."""
    real = os.fsync
    calls = 0

    def fsync(fd: int) -> None:
        nonlocal calls
        calls += 1
        if calls == n:
            raise OSError(errno.ENOSPC, "No space left on device")
        real(fd)

    monkeypatch.setattr(os, "fsync", fsync)


def killed_after_nth_call(names: tuple[str, ...], body: str) -> str:
    """Python source for ``python -c``: ``sys.argv[1]`` is n; every call of ``os.<name>`` for
    ``names`` is counted and the n-th kills the process once it has returned; then ``body`` runs
    (its arguments from ``sys.argv[2:]``; ``count`` holds the calls so far)."""
    return (
        "import os, signal, sys\n"
        "kill_at, count = int(sys.argv[1]), 0\n"
        "def counted(real):\n"
        "    def op(*args, **kwargs):\n"
        "        global count\n"
        "        result = real(*args, **kwargs)\n"
        "        count += 1\n"
        "        if count == kill_at:\n"
        "            os.kill(os.getpid(), signal.SIGKILL)\n"
        "        return result\n"
        "    return op\n"
        f"for name in {tuple(names)!r}:\n"
        "    setattr(os, name, counted(getattr(os, name)))\n" + body
    )
