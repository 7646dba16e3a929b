"""The fourth system (:mod:`spherical`, defined in the test suite only) recorded: a demo naming
it, run by the recorder through its registered model and view (:mod:`spherical_view`), written
as the five files of a recording and read back through the API, every file checked against its
manifest.

The physics checked in what was written: the traces' ``L_z`` kept, their energy error within
the tolerance, their last state the tableau runner's (the registry plays no part there), and
the recorded figure of ``L_z`` against its start.
"""

from __future__ import annotations

import numpy as np
import pytest
import spherical_view
from spherical import NAME, START, PendulumParams, invariants, start_state
from test_fourth_system_registered import tableau_run

from mechviz.dynamics import api
from mechviz.viz.record import parse_demo, record


@pytest.fixture(scope="module")
def registered():
    with spherical_view.registered() as reg:
        yield reg


def test_a_recording_of_the_fourth_system_keeps_its_invariants(registered, tmp_path):
    raw = {"exhibit": NAME, "duration": 3.0, "fps": 10, "method": "taylor", "rtol": 1e-11}
    demo = parse_demo(raw, name="pendulum")
    result = record(demo, tmp_path)
    assert result.frames == 31
    rec = api.read_recording(tmp_path / "pendulum")
    assert rec.manifest["exhibit"] == NAME and rec.manifest["parameters"] == {
        "length": 1.3,
        "gravity": 9.81,
    }
    assert (tmp_path / "pendulum.viser").stat().st_size > 0
    cols = rec.columns()
    main = cols["run"] == cols["run"][0]
    t = cols["t"][main]
    states = np.stack([cols[n][main] for n in ("theta", "phi", "omega", "nu")], axis=-1)
    assert t[0] == 0.0 and t[-1] == pytest.approx(3.0)
    p = PendulumParams()
    _, lz = invariants(p, states)
    assert np.max(np.abs(lz - lz[0])) < 1e-9 * abs(lz[0])
    assert np.max(np.abs(cols["energy_error"][main])) < 1e-9
    # the system's own quantity, as the CSV writes it (ten significant digits)
    np.testing.assert_allclose(cols["Lz"][main], lz, rtol=1e-9)
    np.testing.assert_allclose(states[0], start_state(*START))
    assert np.max(np.abs(states[-1] - tableau_run(3.0, 1e-13))) < 1e-8
    lz_figure = next(f for f in rec.manifest["figures"] if f["name"] == "L_z at the end")
    assert abs(lz_figure["measured"] - lz_figure["predicted"]) < 1e-9 * abs(lz[0])
