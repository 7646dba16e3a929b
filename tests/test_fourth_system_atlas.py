"""The fourth system (:mod:`spherical`, defined in the test suite only) in a small atlas map: its
stability over (step, amplitude) for RK4, the implicit midpoint rule and explicit Euler, computed
through Dask into a Zarr store and, the same map, in this process; and an accuracy map of its
adaptive methods.

The workers are threads of this process: a system registered at run time is known to the process
that registered it (worker processes would each have to register it too).

The physics checked: the energy error after ten swings falls as RK4's fourth power of the step
(measured slopes 4.3 to 4.7 over these steps) and as the midpoint rule's second power (1.9 to
2.2), Euler's grows without bound at steps where both others keep it to 1e-5, and Taylor's and
DOP853's errors after 5 s follow their tolerances.
"""

from __future__ import annotations

import logging

import numpy as np
import pytest
import spherical
from spherical import NAME

from mechviz.dynamics.atlas import store
from mechviz.dynamics.atlas.driver import compute_serial, run_atlas
from mechviz.dynamics.atlas.grid import AtlasSpec, Axis, system_names


@pytest.fixture(scope="module")
def registered():
    with spherical.registered() as reg:
        yield reg


@pytest.fixture(scope="module")
def client(registered):
    from distributed import Client, LocalCluster

    cluster = LocalCluster(
        n_workers=1,
        threads_per_worker=2,
        processes=False,
        dashboard_address=None,
        silence_logs=logging.CRITICAL,
    )
    c = Client(cluster)
    yield c
    c.close()
    cluster.close()


def stability_spec() -> AtlasSpec:
    return AtlasSpec(
        "stability",
        NAME,
        ("rk4", "midpoint", "euler"),
        Axis("dt", 0.005, 0.0125, 2),
        Axis("amplitude", 0.3, 1.0, 3),
        periods=10,
        chunk=(1, 2),
    )


def test_the_atlas_knows_a_registered_system_only_while_it_is_registered():
    assert NAME not in system_names()
    with spherical.registered():
        assert NAME in system_names()
        stability_spec()
    with pytest.raises(ValueError, match="system must be one of"):
        stability_spec()


def test_a_stability_map_of_the_fourth_system(client, tmp_path):
    spec = stability_spec()
    report = run_atlas(spec, tmp_path / "s.zarr", client=client)
    assert report.complete and sorted(report.computed) == spec.chunks()
    ds = store.load(tmp_path / "s.zarr")
    serial = compute_serial(spec)
    for name in ("energy_error", "escape_time", "bounded"):
        a, b = ds[name].values, serial[name].values
        assert a.tobytes() == b.tobytes(), name  # the distributed map is the serial one
    # (method, dt, amplitude), the methods in the spec's order
    err, bounded = ds["energy_error"].values, ds["bounded"].values.astype(bool)
    rk4, mid, euler = (spec.methods.index(m) for m in ("rk4", "midpoint", "euler"))
    slope = np.log(np.abs(err[rk4, 1] / err[rk4, 0])) / np.log(2.5)
    assert np.all((3.5 < slope) & (slope < 5.5)), slope
    assert bounded[rk4].all() and np.abs(err[rk4]).max() < 1e-6
    slope = np.log(np.abs(err[mid, 1] / err[mid, 0])) / np.log(2.5)
    assert np.all((1.5 < slope) & (slope < 2.6)), slope
    assert bounded[mid].all() and np.abs(err[mid]).max() < 2e-5
    assert not bounded[euler, :, :2].any()  # the smaller swings blow up within ten
    assert np.all(np.isinf(err[euler, :, :2]))


def test_an_accuracy_map_of_its_adaptive_methods(registered):
    spec = AtlasSpec(
        "accuracy",
        NAME,
        ("taylor", "dop853"),
        Axis("rtol", 1e-10, 1e-6, 3, "log"),
        Axis("amplitude", 0.3, 1.0, 2),
        duration=5.0,
        chunk=(3, 2),
    )
    err = compute_serial(spec)["error"].values  # (method, rtol, amplitude)
    assert np.all(err > 0) and np.all(err[:, 0] < 1e-10) and np.all(err[:, -1] < 1e-6)
    assert np.all(
        err[:, -1] / err[:, 0] > 1e3
    )  # four decades of tolerance, at least three of error
