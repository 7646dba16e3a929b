"""A child Python process killed (SIGKILL) right after its n-th call of chosen ``os`` functions:
how the tests stop a write at every step of its commit, as a power cut or ``kill -9`` would."""

from __future__ import annotations


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
