"""Fixtures shared by the headless viewer and recorder tests."""

from __future__ import annotations

import contextlib
import io

import pytest


@pytest.fixture
def server():
    """A headless viser server on a free port (no browser), stopped after the test."""
    import viser

    with contextlib.redirect_stdout(io.StringIO()):
        srv = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    yield srv
    with contextlib.redirect_stdout(io.StringIO()):
        srv.stop()
