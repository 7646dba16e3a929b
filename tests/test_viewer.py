"""The live viewer, headless: the app on port 0 without its loop thread, driven frame by frame.

Checks that the scene nodes exist and sit where :mod:`dynamics` puts the bodies at the same
time, that GUI commands (pause, step, method change, invalid parameter, kick) act as they should,
and that a blown-up method pauses only its own exhibit. The physics the exhibits show, the
themes and the framing: :mod:`test_viewer_shows`.
"""

from __future__ import annotations

import math
import urllib.request

import numpy as np
import pytest

from mechviz import dynamics
from mechviz.dynamics import cyclotron as cy
from mechviz.dynamics import disk as dk
from mechviz.dynamics import hoop as hp

viser = pytest.importorskip("viser")


from viewer_steps import FRAME, enter, frames  # noqa: E402  (tests/viewer_steps.py)

from mechviz.viz import geometry as geo  # noqa: E402
from mechviz.viz.app_commands import Camera, Pause, Play, ResetAll, Speed, Stage, Step  # noqa: E402
from mechviz.viz.model import HoopConfig  # noqa: E402
from mechviz.viz.model.commands import Kick, Reset, Set  # noqa: E402
from mechviz.viz.scene import DiskExhibit, HoopExhibit  # noqa: E402
from mechviz.viz.scene.disk import LIFT, P  # noqa: E402

# every test here starts the viewer's server
pytestmark = [pytest.mark.slow, pytest.mark.usefixtures("warm_viewer")]


def same_rotation(q1, q2, tol=1e-9) -> bool:
    q1, q2 = np.asarray(q1, float), np.asarray(q2, float)
    return min(np.abs(q1 - q2).max(), np.abs(q1 + q2).max()) < tol


# --------------------------------------------------------------------------- serving
def test_app_serves_the_client_page_on_the_port_it_reports(app):
    assert app.port > 0
    assert app.url == f"http://127.0.0.1:{app.port}/"
    with urllib.request.urlopen(app.url, timeout=10) as r:
        assert r.status == 200
        assert b"<html" in r.read(2000).lower()


def test_every_exhibit_has_its_scene_nodes(app):
    names = set(app.server.scene._handle_from_node_name)  # viser 1.1 has no public lookup
    for name in (
        "/floor",
        "/cyclotron/charges",
        "/cyclotron/field",
        "/cyclotron/theory_circle",
        "/cyclotron/label",
        "/disk/body",
        "/disk/body/disk",
        "/disk/body/bead",
        "/disk/body/centre_of_mass",
        "/disk/body/principal_axes",
        "/disk/axle",
        "/disk/bearing_A",
        "/disk/bearing_B",
        "/disk/bearing_forces",
        "/disk/vectors",
        "/disk/label",
        "/hoop/rings",
        "/hoop/beads",
        "/hoop/pivot",
        "/hoop/label",
    ):
        assert name in names, name
    frames(app, 5)
    assert any(n.startswith("/cyclotron/trail/") for n in app.server.scene._handle_from_node_name)


# --------------------------------------------------------------------------- poses = dynamics
def test_charge_is_drawn_on_the_exact_helix_at_the_simulated_time(app):
    frames(app, 90)
    ex = app.exhibits["cyclotron"]
    p = ex.model.params
    exact = cy.exact_solution(p, ex.model.config.initial_state(), ex.model.t)
    drawn = ex.bodies.batched_positions[0]  # viser stores batched positions as float32
    np.testing.assert_allclose(drawn[:2], exact[:2], atol=1e-6)
    assert drawn[2] == pytest.approx(exact[2] % ex.model.config.height, abs=1e-6)
    # the theory circle is centred on the guiding centre with the radius sqrt(2 m E)/(|q| B)
    centre = cy.guiding_centre(p, exact)
    np.testing.assert_allclose(ex.ring.position[:2], centre[:2], atol=1e-9)
    assert ex._ring_radius == pytest.approx(cy.larmor_radius(p, exact), rel=1e-9)


def test_driven_disk_pose_and_bearing_forces_equal_dynamics(app):
    frames(app, 75)
    ex = app.exhibits["disk"]
    p, t = ex.model.params, ex.model.sample.t
    assert t == pytest.approx(75 * FRAME * app.speed)
    rot = dk.rotation_about_axle(p.omega * t)
    assert same_rotation(ex.body.wxyz, geo.quat_from_matrix(P @ rot))
    np.testing.assert_allclose(ex.body.position, LIFT, atol=1e-12)
    a, b = dk.axle_points(p)
    arrows = ex.forces.points.astype(float)
    for k, (pt, force) in enumerate(((a, dk.bearing_force_a(p, t)), (b, dk.bearing_force_b(p, t)))):
        np.testing.assert_allclose(arrows[k, 0], LIFT + P @ pt, atol=1e-6)
        np.testing.assert_allclose(
            arrows[k, 1] - arrows[k, 0], P @ force * ex.force_scale, atol=1e-5
        )
    # the measured amplitude (dL/dt of the sampled motion) agrees with m R omega^2 / 2
    assert ex.model.measured()["bearing_force"].value == pytest.approx(
        dk.axle_force_amplitude(p), rel=1e-3
    )


def test_hoop_and_bead_are_drawn_where_an_identical_dynamics_run_puts_them(app):
    ex = app.exhibits["hoop"]
    c = ex.model.config
    twin = dynamics.Simulation(
        dynamics.Hoop(c.physics()), c.method, dt=c.dt, state=c.initial_state()
    )
    for _ in range(50):
        app.step_frame()
        twin.advance(FRAME * app.speed)
    state = twin.sample().state[0]
    np.testing.assert_array_equal(ex.model.sample.state[0], state)
    centre, bead = hp.positions(ex.model.params, state)
    pivot = ex.pivot_local
    rings, beads = ex.rings.batched_positions, ex.beads.batched_positions  # float32 in viser
    np.testing.assert_allclose(rings[0], pivot + [centre[0], 0, centre[1]], atol=1e-6)
    np.testing.assert_allclose(beads[0], pivot + [bead[0], 0, bead[1]], atol=1e-6)
    q = ex.rings.batched_wxyzs[0]
    assert same_rotation(q, geo.quat_about_axis((0.0, -1.0, 0.0), state[0]), tol=1e-6)
    # the ghost follows the linear theory from the same start
    ghost = hp.linear_solution(ex.model.params, c.initial_state(), twin.t)
    _, gbead = hp.positions(ex.model.params, ghost)
    np.testing.assert_allclose(beads[1], pivot + [gbead[0], 0, gbead[1]], atol=1e-6)


def test_released_disk_is_drawn_with_the_free_body_pose(server):
    ex = DiskExhibit(server)
    ex.model.apply(Set(fields={"mode": "released", "follow_cm": False}))
    for _ in range(40):
        ex.model.advance(FRAME)
    ex.draw()
    smp = ex.model.sample
    rot, a = dk.released_pose(ex.model.params, smp.state[0], smp.t, ex.model.config.extra_spin)
    assert same_rotation(ex.body.wxyz, geo.quat_from_matrix(P @ rot))
    np.testing.assert_allclose(ex.body.position, LIFT + P @ a, atol=1e-12)


# --------------------------------------------------------------------------- GUI commands
def test_pause_stops_simulated_time_and_step_advances_one_frame(app):
    frames(app, 3)
    app.enqueue("app", Pause())
    frames(app, 1)
    t = {k: ex.model.t for k, ex in app.exhibits.items()}
    frames(app, 10)
    assert {k: ex.model.t for k, ex in app.exhibits.items()} == t
    assert app.w["play"].label == "Play"
    app.enqueue("app", Step())
    frames(app, 1)
    assert app.exhibits["disk"].model.t == pytest.approx(t["disk"] + FRAME * app.speed)
    app.enqueue("app", Play())
    frames(app, 2)
    assert app.exhibits["disk"].model.t > t["disk"] + FRAME
    assert app.w["play"].label == "Pause"


def test_speed_scales_simulated_time_per_frame(app):
    app.w["speed_track"].value = (3.0,)  # as the slider's track does
    frames(app, 1)  # applies the speed
    t0 = app.exhibits["disk"].model.t
    frames(app, 6)
    assert app.exhibits["disk"].model.t - t0 == pytest.approx(6 * 3.0 * FRAME)


def test_method_change_from_the_dropdown_switches_the_integrator_and_readout(app):
    frames(app, 5)
    assert "`rk4`" in app.exhibits["hoop"].readout()
    app.w["hoop.method"].value = "verlet"  # fires the callback as a browser would
    frames(app, 3)
    ex = app.exhibits["hoop"]
    assert ex.model.sim.method.name == "verlet"
    assert "`verlet`" in ex.readout()
    assert "Stormer-Verlet" in app.w["hoop.about"].content


def test_tolerance_dropdown_sets_the_adaptive_methods_rtol(app):
    w = app.w["hoop.rtol"]
    # down to 1e-12, the tightest a run is still compared with the reference run at
    assert w.value == "1e-9" and w.options[0] == "1e-3" and w.options[-1] == "1e-12"
    app.enqueue("app", Speed(10.0))  # 1/6 s per frame: several steps each
    app.w["hoop.method"].value = "dop853"
    w.value = "1e-6"  # fires the callback as a browser would
    frames(app, 30)
    ex = app.exhibits["hoop"]
    assert ex.model.config.rtol == 1e-6 and ex.model.sim.rtol == 1e-6
    loose_steps, loose_h = ex.model.sim.steps, ex.model.sim.last_step
    # the readout shows the length of the step DOP853 is in (not cut at the frames)
    assert loose_h is not None and f"h = {loose_h:.2g} s" in ex.readout()
    w.value = "1e-12"
    frames(app, 30)
    assert (
        ex.model.sim.rtol == 1e-12 and ex.model.sim.steps > loose_steps
    )  # tighter: more steps, same time
    assert ex.model.sim.last_step < loose_h
    app.enqueue("hoop", Set(fields={"rtol": 3e-7}))  # a value off the decades (a demo's)
    frames(app, 1)
    assert w.value == "3e-7" and "3e-7" in w.options


def test_invalid_parameter_is_refused_and_the_running_simulation_kept(app):
    frames(app, 20)
    app.enqueue("app", Pause())
    frames(app, 1)
    ex = app.exhibits["cyclotron"]
    sim, state, t, config = ex.model.sim, ex.model.sample.state.copy(), ex.model.t, ex.model.config
    enter(app, "cyclotron.params.mass", "-2")
    frames(app, 1)
    assert ex.model.sim is sim and ex.model.config == config and ex.model.t == t
    np.testing.assert_array_equal(ex.model.sample.state, state)
    _title, body = app.messages[-1]
    assert body.startswith("Mass m [kg] must lie between") and "got -2" in body  # named as labelled
    assert app.w["cyclotron.params.mass"].value == "1"  # the widget shows the value in use
    app.enqueue("app", Play())
    frames(app, 2)
    assert ex.model.t > t


def test_invalid_step_size_is_refused_with_the_field_named(app):
    enter(app, "hoop.dt", "0")
    frames(app, 1)
    assert app.messages[-1][1].startswith("Step dt [s] must be positive")
    assert app.exhibits["hoop"].model.config.dt == pytest.approx(1 / 60)
    assert app.w["hoop.dt"].value == "0.0166667"


@pytest.mark.parametrize(
    ("typed", "applied"), [("2.5e-2", 0.025), ("2.5E-2", 0.025), ("0.001", 1e-3), ("1e-3", 1e-3)]
)
def test_a_step_typed_as_a_person_writes_it_is_applied(app, typed, applied):
    enter(app, "hoop.dt", typed)
    frames(app, 1)
    assert app.exhibits["hoop"].model.config.dt == applied


@pytest.mark.parametrize(
    ("widget", "typed", "message"),
    [
        ("hoop.dt", "abc", "Step dt [s] must be a number, got 'abc'"),
        ("hoop.params.gravity", "1e400", "Gravity g [m/s²] must be finite"),
        ("hoop.th1", "4", "θ1 (custom) [rad] must lie between -3.14 and 3.14"),
        ("cyclotron.kick", "5", "Kick dv [m/s] must lie between -1 and 1"),
        ("speed", "50", "Speed [×] must lie between 0.1 and 10"),
        ("hoop.dt", "50", "Step dt [s] = 50 s is longer than one period"),
        ("hoop.params.bead_mass", "1e300", "Bead mass m [kg] must lie between 0.001 and 1000"),
        ("cyclotron.params.mass", "1e300", "Mass m [kg] must lie between 0.001 and 1000"),
    ],
)
def test_a_value_that_cannot_be_taken_is_refused_by_name_and_the_box_springs_back(
    app, widget, typed, message
):
    before = app.w[widget].value
    speed, configs = app.speed, {k: ex.model.config for k, ex in app.exhibits.items()}
    enter(app, widget, typed)
    frames(app, 2)
    assert app.messages[-1][1].startswith(message), app.messages[-1]
    assert app.w[widget].value == before
    assert app.speed == speed and {k: ex.model.config for k, ex in app.exhibits.items()} == configs


def test_real_time_factor_says_nothing_while_paused_and_starts_afresh_after_a_reset(app):
    frames(app, 10)
    app.enqueue("app", Pause())
    app.enqueue("app", ResetAll())
    frames(app, 3)
    assert app.real_time_factor is None
    app.enqueue("app", Play())
    frames(app, 5)
    assert app.real_time_factor > 0


def test_kick_moves_the_predicted_circle_at_once_and_the_charge_stays_on_it(app):
    frames(app, 30)
    ex = app.exhibits["cyclotron"]
    p = ex.model.params
    before = ex.model.sample.state[0]
    v = math.hypot(before[3], before[4])
    _expected_state, expected_centre, expected_radius = cy.radial_kick(p, before, 0.5)
    enter(app, "cyclotron.kick", "0.5")
    app.enqueue("cyclotron", Kick(dv=0.5))
    app.enqueue("app", Pause())
    frames(app, 1)
    assert ex.model.theory_radius == pytest.approx(math.hypot(v, 0.5), rel=1e-12)
    np.testing.assert_allclose(ex.model.theory_centre[:2], expected_centre[:2], atol=1e-12)
    assert ex._ring_radius == pytest.approx(expected_radius, rel=1e-9)
    app.enqueue("app", Play())
    frames(app, 120)
    st = ex.model.sample.state[0]
    assert math.hypot(*(st[:2] - expected_centre[:2])) == pytest.approx(expected_radius, rel=1e-9)


def test_the_first_view_a_page_gets_is_the_all_preset_with_everything_in_it(app):
    """The camera a page starts with is the *All* preset of the finished scene (every exhibit
    as it shows at home): a page the app is slow to reframe shows it as is."""
    position, look_at = app.camera_preset("All")
    np.testing.assert_allclose(app.server.initial_camera.position, position, atol=1e-9)
    np.testing.assert_allclose(app.server.initial_camera.look_at, look_at, atol=1e-9)


def test_the_hoops_maps_stand_on_its_stage_only_and_a_stage_set_by_the_app_is_not_echoed(app):
    """At home the configuration square and the chaos map are hidden (between the disk and the
    hoop they would read as part of neither) and the home view is framed without them; on the
    hoop's stage they are shown. The panel's Stage buttons follow the stage the app sets
    without sending it back as a click of their own (a second stage command would frame the
    page again, over a camera moved since, such as "Look at the map")."""
    hoop = app.exhibits["hoop"]
    square, chaos = hoop.config_space.node, hoop.maps_view.node
    try:
        for view, shown in (("Hoop", True), ("Home", False), ("Disk", False), ("Hoop", True)):
            app.enqueue("app", Stage(view))
            frames(app, 1)
            assert (square.visible, chaos.visible) == (shown, shown), view
            assert app.w["stage"].value == view
            assert app.commands.empty(), f"{view}: the Stage buttons sent the stage back"
        home_lo, home_hi = hoop.home_bounds
        lo = hoop.bounds[0]
        assert home_lo[0] > lo[0] + 1.0  # the square, left of the hoop, left out at home
        centre = hoop.world(hoop.maps_view.centre_local)  # the chaos map's, above the square
        assert not np.all((centre >= home_lo) & (centre <= home_hi))
    finally:
        app.enqueue("app", Stage("Home"))
        frames(app, 1)


def test_the_app_takes_only_its_own_typed_commands_and_refuses_the_rest_at_once(app):
    """A dict, an op's name or an exhibit's command sent to the app is refused in the caller's
    thread, naming the commands it takes, and nothing is queued; a typed one is applied."""
    for wrong in ({"op": "pause"}, "pause", Kick(dv=0.1)):
        with pytest.raises(ValueError, match="an app command must be one of Play, Pause"):
            app.enqueue("app", wrong)
        assert app.commands.empty()
    app.enqueue("app", Pause())
    frames(app, 1)
    assert not app.playing
    app.enqueue("app", Play())
    frames(app, 1)
    assert app.playing


def test_each_stage_frames_its_exhibit_to_three_quarters_of_the_height_or_the_free_width(app):
    """Below (or beside) the stage's words and chart, left of the panel: 75 % of the page's
    height, or 90 % of the width the panel leaves when the exhibit is wide; the words, the
    chart and the exhibit's box apart."""
    from mechviz.viz.scene import framing
    from mechviz.viz.views import CHART_MIN, STAGE_TEXT, label_px

    for size in ((1280, 800), (1440, 900), (1920, 1080)):
        free = size[0] - framing.PANEL_PX
        for view, key in (("Cyclotron", "cyclotron"), ("Disk", "disk"), ("Hoop", "hoop")):
            position, target, words, chart = app.stage_view(key, *size)
            text, (x, y), anchor, *_ = words
            share, x0, x1, y0, y1 = framing.share(
                *app.exhibits[key].bounds, position, target, *size
            )
            assert share >= 0.75 or x1 - x0 >= 0.9 * free, (view, size, share)
            assert 0 <= x0 and x1 <= free and 0 <= y0 and y1 <= size[1], (view, size)
            w, h = label_px(text, STAGE_TEXT)
            if anchor == "top-center":  # a band above the exhibit
                assert y + h <= y0 and x - w / 2 >= 0 and x + w / 2 <= free, (view, size)
                box = (x - w / 2, y, x + w / 2, y + h)
            else:  # a column right of it, or the left of a band above it
                assert (x >= x1 or y + h <= y0) and x + w <= free, (view, size)
                box = (x, y, x + w, y + h)
            c0, cy0, c1, cy1 = chart
            assert c1 - c0 >= CHART_MIN[0] - 1 and cy1 - cy0 >= CHART_MIN[1] - 1, (view, size)
            assert 0 <= c0 and c1 <= free and 0 <= cy0 and cy1 <= size[1], (view, size, chart)
            for other in ((x0, y0, x1, y1), box):  # the chart clear of the exhibit and words
                apart = c1 <= other[0] or other[2] <= c0 or cy1 <= other[1] or other[3] <= cy0
                assert apart, (view, size, chart, other)
    position, target = app.camera_preset("Top")  # straight down on the orbit
    down = np.subtract(target, position)
    assert down[2] < 0 and np.hypot(*down[:2]) < 0.02 * abs(down[2])
    app.enqueue("app", Camera("Hoop"))  # no client: nothing to move, no error
    frames(app, 1)


# --------------------------------------------------------------------------- failures
def test_diverging_euler_pauses_only_the_charge_and_reset_recovers(app):
    enter(app, "cyclotron.dt", "0.5")
    app.w["cyclotron.method"].value = "euler"
    enter(app, "speed", "10")
    frames(app, 2)
    ex = app.exhibits["cyclotron"]
    assert ex.model.sim.method.name == "euler"
    for _ in range(300):
        app.step_frame()
        if ex.model.paused:
            break
    assert ex.model.paused
    assert "euler" in ex.model.failure and "dt=0.5" in ex.model.failure
    assert any("euler" in body for _, body in app.messages)
    t_cyc, t_hoop = ex.model.t, app.exhibits["hoop"].model.t
    frames(app, 5)
    assert ex.model.t == t_cyc
    assert app.exhibits["hoop"].model.t > t_hoop
    app.enqueue("cyclotron", Reset())
    frames(app, 3)
    assert not ex.model.paused and ex.model.failure is None and ex.model.t > 0


def test_a_step_beyond_the_stability_limit_pauses_the_hoop_with_the_step_named(server):
    ex = HoopExhibit(server, HoopConfig(method="rk4", dt=0.9, amplitude=0.3))
    for _ in range(400):
        ex.model.advance(0.5)
        if ex.model.paused:
            break
    assert ex.model.paused
    assert "rk4" in ex.model.failure and "dt=0.9" in ex.model.failure
    title, _body = ex.model.events[-1]
    assert "Hoop" in title
    ex.model.apply(Reset())
    assert not ex.model.paused and ex.model.t == 0.0


def test_the_step_control_shows_the_stability_limit_theory_gives(app):
    """Under each step control: RK4's limit 2 sqrt 2 / omega_2 on the hoop, Stormer-Verlet's
    2 / omega_2 after a method change, the gyrofrequency's after a field change, and a warning
    once dt is beyond the limit."""
    w = app.w["hoop.limit"]
    omega2 = hp.normal_modes(app.exhibits["hoop"].model.params)[0][1]
    assert f"dt < {2 * math.sqrt(2) / omega2:.4g} s" in w.content
    app.enqueue("hoop", Set(fields={"method": "verlet", "dt": 0.01}))
    frames(app, 1)
    assert f"dt < {2 / omega2:.4g} s" in w.content and "⚠" not in w.content
    app.enqueue("hoop", Set(fields={"dt": 0.6}))  # beyond 2 / omega_2 = 0.521 s
    frames(app, 1)
    assert "⚠" in w.content and "beyond" in w.content

    c = app.w["cyclotron.limit"]
    assert "exact" in c.content  # the default: the exact flow, any step
    app.enqueue("cyclotron", Set(fields={"method": "rk4", "dt": 0.05}))
    app.enqueue("cyclotron", Set(params={"field": 4.0}))  # omega = qB/m = 4 rad/s
    frames(app, 1)
    assert f"dt < {2 * math.sqrt(2) / 4.0:.4g} s" in c.content
    app.enqueue("cyclotron", Set(fields={"method": "euler"}))
    frames(app, 1)
    assert "Unstable at every dt" in c.content
    app.enqueue("cyclotron", Set(fields={"method": "boris"}))
    frames(app, 1)
    assert "any dt" in c.content
