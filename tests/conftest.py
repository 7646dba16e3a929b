"""Shared by the tests: the live viewer driven frame by frame and a headless viser server
(fixtures), and the rule that a test run leaves the
checkout as it was: ``git status --porcelain`` is compared before and after the session, and a
change fails the run (pictures and tables under ``docs/`` are refreshed only by ``make
screenshots`` and ``make bench-docs``). Not checked outside a git checkout or under
``MECHVIZ_WRITE_DOCS=1``."""

from __future__ import annotations

import contextlib
import io
import os
import signal
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

# Taylor runs go through numba here, and nothing is compiled ahead of time in the background
# behind the tests' backs: the tests of mechviz.dynamics.aot turn it on in their own processes.
os.environ.setdefault("MECHVIZ_AOT", "0")


@pytest.fixture(scope="session")
def warm_viewer():
    """The viewer's compiled kernels loaded (or compiled) once for the session."""
    from mechviz.viz.app import warm_up

    warm_up("defaults")


@pytest.fixture
def app(warm_viewer):
    """The live viewer on a free port without its loop thread (environment map off), driven
    frame by frame with ``app.step_frame()``; stopped after the test."""
    from mechviz.viz.app import MechvizApp

    a = MechvizApp(port=0, start_loop=False, environment_map=False)
    yield a
    a.stop()


@pytest.fixture
def server():
    """A headless viser server on a free port (no browser), stopped after the test."""
    import viser

    with contextlib.redirect_stdout(io.StringIO()):
        srv = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    yield srv
    with contextlib.redirect_stdout(io.StringIO()):
        srv.stop()


def _status() -> str | None:
    try:
        out = subprocess.run(
            ["git", "status", "--porcelain", "--untracked-files=all"],
            cwd=ROOT,
            capture_output=True,
            text=True,
            timeout=60,
        )
    except (OSError, subprocess.SubprocessError):
        return None
    return out.stdout if out.returncode == 0 else None


def pytest_sessionstart(session: pytest.Session) -> None:
    # A run started in the background (``make test &``, nohup) inherits SIGINT and SIGHUP
    # ignored, and so would every process a test starts: the tests of Ctrl-C and of a closed
    # terminal need them as a terminal gives them.
    if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)
    if hasattr(signal, "SIGHUP") and signal.getsignal(signal.SIGHUP) is signal.SIG_IGN:
        signal.signal(signal.SIGHUP, signal.SIG_DFL)
    session.config._git_status_before = (  # type: ignore[attr-defined]
        None if os.environ.get("MECHVIZ_WRITE_DOCS") == "1" else _status()
    )


def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> None:
    before = getattr(session.config, "_git_status_before", None)
    if before is None:
        return
    after = _status()
    if after is not None and after != before:
        changed = sorted(set(after.splitlines()) ^ set(before.splitlines()))
        print(f"\nthe tests changed the checkout (git status): {'; '.join(changed)}")
        session.exitstatus = pytest.ExitCode.TESTS_FAILED
