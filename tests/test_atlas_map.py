"""The viewer's atlas maps, headless (:mod:`mechviz.viz.model.atlas_map`): the shipped chaos map is the
default hoop's, a map computed in the background process is the one computed here, and a place
on a map and the start it means go both ways.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from waiting import wait_until

from mechviz.dynamics import hoop
from mechviz.dynamics.atlas.grid import AtlasSpec, Axis
from mechviz.dynamics.atlas.kernels import compute_chunk
from mechviz.viz.model.atlas_map import (
    MapWorker,
    chaos_spec,
    compute,
    load_shipped,
    load_shipped_stability,
    shipped_specs,
)


def test_shipped_chaos_map_is_the_default_hoops_map():
    """A few cells run again one at a time (an ensemble's member does not depend on the others)
    give the shipped exponents (stored as float32)."""
    p = hoop.HoopParams()
    shipped = load_shipped(p)
    assert shipped is not None, (
        "assets/atlas/hoop-maps.npz: run python -m mechviz.viz.model.atlas_map"
    )
    spec = chaos_spec(p)
    one = AtlasSpec(**{**spec.__dict__, "chunk": (1, 1)})
    for i, j in ((32, 32), (5, 60), (50, 10)):
        fresh = compute_chunk(one, (0, i, j))["lyapunov"][0, 0]
        assert np.float32(fresh) == np.float32(shipped.lyapunov[i, j]), (i, j)
    # regular near the hanging rest, chaotic for large swings (the map's physics)
    t1, t2 = np.meshgrid(spec.x.values(), spec.y.values())
    reach = np.maximum(abs(t1), abs(t2))
    assert shipped.lyapunov[reach < 0.5].max() < 0.15
    assert np.median(shipped.lyapunov[reach > 2.5]) > 0.4


def test_shipped_stability_maps_are_the_default_hoops_maps():
    """Each fixed-step method's map, a few cells run again one at a time; and RK4's boundary at
    small amplitude on its linear limit, one row of the log-spaced steps either way."""
    p = hoop.HoopParams()
    methods = [name for name in shipped_specs() if name != "chaos"]
    assert {"euler", "rk4", "verlet", "yoshida4", "midpoint"} <= set(methods)
    for name in methods:
        shipped = load_shipped_stability(p, name)
        one = AtlasSpec(**{**shipped.spec.__dict__, "chunk": (1, 1)})
        for i, j in ((0, 0), (20, 7), (39, 19)):
            fresh = compute_chunk(one, (0, i, j))
            assert fresh["bounded"][0, 0] == shipped.bounded[i, j], (name, i, j)
            assert fresh["energy_error"][0, 0] == shipped.energy_error[i, j], (name, i, j)
    rk4 = load_shipped_stability(p, "rk4")
    dts = rk4.spec.y.values()
    edge = int(np.argmin(rk4.bounded[:, 0]))  # the first unbounded step at the smallest swing
    assert rk4.bounded[:edge, 0].all()
    assert dts[edge - 1] <= rk4.linear_limit()[0] <= dts[edge + 1]


def test_other_masses_are_not_served_the_shipped_maps():
    assert load_shipped(hoop.HoopParams(bead_mass=0.2)) is None
    assert load_shipped_stability(hoop.HoopParams(bead_mass=0.2), "rk4") is None


@pytest.mark.slow
def test_background_map_equals_the_map_computed_here():
    spec = AtlasSpec(
        "chaos",
        "hoop",
        ("rk4",),
        Axis("theta2", -2.0, 2.0, 3),
        Axis("theta1", -2.0, 2.0, 4),
        params=(("bead_mass", 0.2),),
        duration=3.0,
        chunk=(3, 4),
    )
    worker = MapWorker()
    try:
        worker.request("chaos", spec)
        got_spec, arrays = wait_until(lambda: worker.poll("chaos"), 120, "the background map")
    finally:
        worker.close()
    assert got_spec == spec
    here = compute(json.dumps(spec.as_dict()))
    assert arrays["lyapunov"].tobytes() == here["lyapunov"].tobytes()


def test_a_place_on_the_chaos_map_and_its_start_go_both_ways():
    m = load_shipped(hoop.HoopParams())
    for angles in ((0.0, 0.0), (1.2, -0.8), (-2.9, 2.95)):
        u, v = m.place_of(*angles)
        assert 0 < u < 1 and 0 < v < 1
        assert m.angles_at(u, v) == pytest.approx(angles, abs=1e-12)
    # the top-left of the picture is the smallest theta1 and the largest theta2
    t1, t2 = m.angles_at(0.0, 0.0)
    assert t1 < -3.0 and t2 > 3.0
    assert m.angles_at(1.5, 0.5) is None
