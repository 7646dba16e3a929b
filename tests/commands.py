"""``mechviz ARGS`` run in this process, as the tests call the command line: what a shell sees
(exit status and both streams), without the start-up of a new interpreter each time."""

from __future__ import annotations

import contextlib
import io
from typing import NamedTuple


class Ran(NamedTuple):
    """What a command left: its exit status and the text of its two streams."""

    returncode: int
    stdout: str
    stderr: str


def mechviz(*args: str) -> Ran:
    """Run ``mechviz ARGS`` through ``mechviz.viz.cli.main`` (argparse's refusals included)."""
    from mechviz.viz.cli import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main(list(args))
        except SystemExit as exc:  # argparse's refusals
            code = exc.code if isinstance(exc.code, int) else 1
    return Ran(code, out.getvalue(), err.getvalue())
