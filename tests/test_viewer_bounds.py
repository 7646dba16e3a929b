"""A diverging method stays in its own exhibit, headless (the viewer's scene, no browser).

Explicit Euler's energy grows every step: the charge spirals outward, the hoop's angles run away
in its configuration-space square, the released disk's ω and L lengthen. The growth is drawn up to
the exhibit's edge (the lesson), never across a neighbour: every drawn path stays inside the
exhibit's box, and a charge that leaves it pauses its exhibit with the failure message."""

from __future__ import annotations

import numpy as np
import pytest

from mechviz.viz.app import MechvizApp
from mechviz.viz.model.commands import Kick, Set
from mechviz.viz.scene.hoop import CONFIG_SIZE

# every test here starts the viewer's server
pytestmark = [pytest.mark.slow, pytest.mark.usefixtures("warm_viewer")]


@pytest.fixture
def app():
    """The viewer without its GUI panel (only the scene is looked at here)."""
    a = MechvizApp(port=0, start_loop=False, environment_map=False, gui=False)
    yield a
    a.stop()


def _drawn(app, key: str, parts: tuple[str, ...]) -> np.ndarray:
    """World points (N, 3) of the exhibit's line nodes whose name holds one of ``parts`` (the
    trails and paths are children of the exhibit's root: local = world - origin)."""
    ex = app.exhibits[key]
    out = []
    for name, h in app.server.scene._handle_from_node_name.items():
        if name.startswith(ex.root + "/") and any(p in name for p in parts):
            if getattr(h, "visible", True) and hasattr(h, "points"):
                out.append(np.asarray(h.points, float).reshape(-1, 3) + ex.origin)
    return np.concatenate(out) if out else np.zeros((0, 3))


def _inside(points: np.ndarray, box, margin: float = 1e-5) -> np.ndarray:
    lo, hi = box
    return np.all((points >= lo - margin) & (points <= hi + margin), axis=1)


def _euler(app, key: str, frames: int, frame_dt: float, **settings) -> None:
    app.exhibits[key].model.apply(Set(fields={"method": "euler", **settings}))
    for _ in range(frames):
        app.step_frame(frame_dt)
        if app.exhibits[key].model.paused:
            return


def test_eulers_spiral_on_the_cyclotron_grows_to_the_exhibits_edge_and_stops_there(app):
    ex = app.exhibits["cyclotron"]
    _euler(app, "cyclotron", 3000, 0.05, dt=0.05)
    assert ex.model.paused and "the charge left the exhibit" in ex.model.failure
    trail = _drawn(app, "cyclotron", ("/trail/",))
    assert len(trail) > 100
    assert _inside(trail, ex.bounds).all()
    # the spiral was drawn: from the start's circle (radius 1 m) out to near the edge (1.7 m)
    r = np.hypot(*(trail[:, :2] - ex.origin[:2]).T)
    assert r.min() < 1.05 and r.max() > 1.6
    # the charge stopped within a frame's travel of the edge (|v| grew with sqrt(energy))
    lo, hi = ex.bounds
    charge = np.asarray(ex.bodies.batched_positions[0], float) + ex.origin
    assert _inside(charge[None], (lo, hi), margin=0.2).all()


def test_eulers_runaway_in_the_hoops_configuration_space_stays_in_its_square(app):
    ex = app.exhibits["hoop"]
    _euler(app, "hoop", 4000, 1 / 60)
    assert ex.model.paused  # the energy rule: Euler's energy grew 25-fold
    square = ex.config_space
    half = 0.5 * CONFIG_SIZE
    lo = square.centre - (half, 0.0, half) + ex.origin
    hi = square.centre + (half, 0.0, half) + ex.origin
    path = _drawn(app, "hoop", ("/configuration_space/path/", "/configuration_space/ghost_path/"))
    assert len(path) > 100
    assert _inside(path, (lo, hi)).all()
    # the angles themselves ran far beyond the square (theta2 went round the hoop)
    assert np.abs(ex.model.state[:2]).max() * square.scale > 4 * half
    trails = _drawn(app, "hoop", ("/trail/",))
    assert _inside(trails, ex.bounds).all()


def test_the_released_disks_growing_vectors_are_drawn_up_to_its_edge(app):
    ex = app.exhibits["disk"]
    ex.model.apply(Set(fields={"mode": "released"}))
    _euler(app, "disk", 1200, 0.1)
    assert float(ex.model.sample.energy_error[0]) > 1.0  # the energy more than doubled
    arrows = _drawn(app, "disk", ("/vectors",))
    assert _inside(arrows, ex.bounds).all()
    # drawn as long as the box allows: a tip on its edge
    lo, hi = ex.bounds
    assert np.isclose(arrows, hi, atol=1e-3).any() or np.isclose(arrows, lo, atol=1e-3).any()


def test_a_kick_that_sends_the_orbit_past_the_edge_still_draws_all_of_it(app):
    """Bounding the drawing is for runaways: a kick of 1 m/s moves the exact circle 1 m off the
    axis with radius sqrt(2) m, beyond the exhibit's box, and every turn of it is drawn."""
    ex = app.exhibits["cyclotron"]
    ex.model.apply(Kick(dv=1.0))
    centre = ex.model.theory_centre[:2] + ex.origin[:2]
    for _ in range(420):  # a period (2 pi s) and more
        app.step_frame(1 / 60)
    assert not ex.model.paused
    trail = _drawn(app, "cyclotron", ("/trail/",))
    r = np.hypot(*(trail[:, :2] - centre).T)
    after = np.isclose(r, ex.model.theory_radius, rtol=1e-3)
    assert ex.model.theory_radius == pytest.approx(np.sqrt(2.0), rel=1e-9)
    assert not _inside(trail[after], ex.bounds).all()  # it reaches past the exhibit's box
    # the whole circle after the kick: points all round it
    angles = np.arctan2(*(trail[after, :2] - centre).T[::-1])
    assert np.ptp(np.sort(angles)) > 1.9 * np.pi and np.diff(np.sort(angles)).max() < 0.2
