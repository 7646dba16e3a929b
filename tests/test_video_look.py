"""How a video or a still is shown, checked without a browser: the camera's framing (by the
projection the player uses), the figures the overlay shows at each moment, the words of the
captions, a live session's camera and title, and bad ``--camera``/``--start``/... values."""

from __future__ import annotations

import math
import types

import numpy as np
import pytest
from commands import mechviz

from mechviz.viz import framing, video
from mechviz.viz import record as rec
from mechviz.viz.overlay import Overlay, true_at
from mechviz.viz.record.run import trace_demo

SIZE = (960, 540)


# --------------------------------------------------------------------------- framing
@pytest.mark.parametrize("direction", [(0.0, -5.2, 2.8), (1.0, 0.0, 0.12), (0.0, -0.002, 1.0)])
@pytest.mark.parametrize("band", [(0.0, 0.0), (0.12, 0.15)])
def test_a_framed_box_fills_the_free_height_and_fits_the_width(direction, band):
    bounds = ((-1.7, -1.7, 0.0), (1.7, 1.7, 2.3))
    cam = framing.frame(bounds, direction, aspect=16 / 9, band=band)
    lo, hi = np.array(bounds[0]), np.array(bounds[1])
    hi[2] += framing.LABEL_ROOM * (hi[2] - lo[2])
    xy = framing.project(cam.position, cam.look_at, cam.fov, 16 / 9, framing.corners(lo, hi))
    free = 1.0 - sum(band)
    height = (xy[:, 1].max() - xy[:, 1].min()) / 2
    width = (xy[:, 0].max() - xy[:, 0].min()) / 2
    assert width <= 0.94 + 1e-6
    assert height <= framing.FILL * free + 1e-6
    assert height >= 0.97 * framing.FILL * free or width >= 0.93  # one of them is the limit
    # centred in the free part: the box's middle at the middle between the bands
    assert (xy[:, 1].max() + xy[:, 1].min()) / 2 == pytest.approx(band[1] - band[0], abs=0.02)
    assert (xy[:, 0].max() + xy[:, 0].min()) / 2 == pytest.approx(0.0, abs=0.02)


def test_camera_text_is_a_preset_or_a_position():
    assert framing.parse_camera("Top").preset == "top"
    req = framing.parse_camera("1,-5,2.5")
    assert req.position == (1.0, -5.0, 2.5) and req.look_at is None
    req = framing.parse_camera("1,-5,2.5:0,0,1")
    assert req.look_at == (0.0, 0.0, 1.0)
    for bad in ("sideways", "1,2", "1,2,3:4", "1,2,3:1,2,3", "nan,0,0", ""):
        with pytest.raises(ValueError):
            framing.parse_camera(bad)


def test_a_position_looks_at_the_exhibits_centre():
    bounds = ((-1.0, -1.0, 0.0), (1.0, 1.0, 2.0))
    cam = framing.resolve(framing.parse_camera("0,-6,1"), bounds=bounds, aspect=16 / 9)
    assert cam.position == (0.0, -6.0, 1.0)
    assert cam.look_at == pytest.approx((0.0, 0.0, 1.0))
    assert "initialCameraPosition" in cam.query() and cam.query()["initialCameraUp"] == "0,0,1"


def test_presets_need_an_exhibit_and_say_so():
    with pytest.raises(ValueError, match="position"):
        framing.resolve(framing.parse_camera("top"), bounds=None, aspect=1.0)


# --------------------------------------------------------------------------- overlay
@pytest.fixture(scope="module")
def kick_figures():
    demo = rec.load_demo("radial-kick").with_overrides(duration=10.0)
    return demo, rec.figures(demo, trace_demo(demo))


def test_no_figure_about_the_kick_is_shown_before_the_kick(kick_figures):
    demo, figs = kick_figures
    kick = demo.events[0].t
    overlay = Overlay(title="", caption="", figures=figs, size=SIZE, times=[0.0, 9.0])
    for t in np.arange(0.0, kick, 0.25):
        assert not any("kick" in line for line in overlay.lines_at(float(t))), t
    for t in np.arange(kick, 10.0, 0.25):
        lines = overlay.lines_at(float(t))
        # the caption: "moves the circle's centre by Δv/Ω; the period is unchanged"
        assert any(line.startswith("circle shift after the kick") for line in lines)
        assert any(line.startswith("gyrofrequency after the kick") for line in lines)
        assert not any(line.startswith("gyrofrequency:") for line in lines)  # before the kick


def test_a_final_error_appears_only_at_the_end():
    demo = rec.load_demo("euler-vs-boris").with_overrides(duration=3.0)
    figs = rec.figures(demo, trace_demo(demo))
    times = [k / demo.fps * demo.speed for k in range(round(demo.duration * demo.fps))]
    end = times[-1]  # a video's last frame comes one frame before the run's last sample
    overlay = Overlay(title="", caption="", figures=figs, size=SIZE, times=times)
    assert not any("final" in line for line in overlay.lines_at(0.5 * end))
    assert sum("final energy error" in line for line in overlay.lines_at(end)) == 2


def test_every_figure_true_at_a_moment_is_shown_and_the_band_holds_them(kick_figures):
    _, figs = kick_figures
    overlay = Overlay(title="T", caption="C", figures=figs, size=SIZE, times=[0.0, 9.0])
    for t in (0.0, 9.0):
        shown = overlay.lines_at(t)
        assert len(shown) == sum(1 for f in figs if true_at(f, t))
    top, bottom = overlay.band
    assert 0 < top < 0.2 and 0 < bottom < 0.2


def test_linear_theory_figures_say_where_the_prediction_comes_from():
    demo = rec.load_demo("hoop-mode1").with_overrides(duration=10.0)
    figs = rec.figures(demo, trace_demo(demo))
    overlay = Overlay(title="", caption="", figures=figs, size=SIZE, times=[0.0])
    line = next(s for s in overlay.lines_at(1.0) if s.startswith("mode 1 frequency"))
    assert "(linear theory " in line
    assert "frequency (linear theory)" not in line  # the measured value is not linear theory


def test_captions_write_their_mathematics_in_unicode():
    ascii_stand_ins = (" pi ", "Omega", "omega", "sqrt", "^2", "dv/")
    for demo in rec.list_demos():
        assert not any(s in demo.description for s in ascii_stand_ins), demo.description
    assert "2π m/|q|B" in rec.load_demo("helix").description
    assert "Δv/Ω" in rec.load_demo("radial-kick").description


def test_the_overlay_draws_only_in_its_two_bands():
    frame = np.full((SIZE[1], SIZE[0], 3), 128, np.uint8)
    overlay = Overlay(title="Title", caption="Caption", figures=[], size=SIZE, times=[0.0])
    out = overlay.apply(frame, 1.0)
    top, bottom = (round(b * SIZE[1]) for b in overlay.band)
    assert np.array_equal(out[top : SIZE[1] - bottom], frame[top : SIZE[1] - bottom])
    assert (out[:top] != 128).any() and (out[SIZE[1] - bottom :] != 128).any()


# --------------------------------------------------------------------------- sessions
def test_a_session_carries_the_viewers_camera_and_the_exhibits_title():
    from mechviz.viz.app import MechvizApp
    from mechviz.viz.live_record import session_info

    app = MechvizApp(port=0, start_loop=False)
    try:
        key = next(iter(app.exhibits))
        ex = app.exhibits[key]
        target = tuple(float(x) for x in np.mean(ex.bounds, axis=0))
        camera = types.SimpleNamespace(position=(1.0, -4.0, 2.0), look_at=target, fov=0.9)
        info = session_info(app, types.SimpleNamespace(camera=camera))
    finally:
        app.stop()
    assert info["title"] == ex.model.title
    page = video.with_session_info(b"<html><head></head><body></body></html>", info)
    assert video.session_info(page) == info
    clip = video.Clip(page=page, fps=30, frames=1, camera=framing.Camera(**info["camera"]))
    clip.scene = info["scene"]
    cam = video.camera_for(clip, video.Look(), SIZE, None)
    assert cam.position == (1.0, -4.0, 2.0) and cam.look_at == pytest.approx(target)
    assert cam.fov == pytest.approx(0.9)


# --------------------------------------------------------------------------- bad values
@pytest.mark.parametrize(
    ("argv", "flag"),
    [
        (["record", "helix", "--out", "OUT", "--video", "mp4", "--camera", "sideways"], "--camera"),
        (["record", "helix", "--out", "OUT", "--video", "mp4", "--camera", "1,2"], "--camera"),
        (["record", "helix", "--out", "OUT", "--camera", "top"], "--camera"),
        (["record", "helix", "--out", "OUT", "--no-overlay"], "--no-overlay"),
        (["record", "helix", "--out", "OUT", "--video", "mp4", "--start", "-1"], "--start"),
        (["record", "helix", "--out", "OUT", "--video", "mp4", "--end", "99"], "--end"),
        (
            ["record", "helix", "--out", "OUT", "--video", "mp4", "--start", "5", "--end", "3"],
            "--end",
        ),
        (["record", "helix", "--out", "OUT", "--video", "mp4", "--title", "a\nb"], "--title"),
        (["still", "helix", "--at", "999", "--out", "OUT.png"], "--at"),
        (["still", "helix", "--at", "-1", "--out", "OUT.png"], "--at"),
        (["still", "helix", "--at", "1", "--size", "5000x5000", "--out", "OUT.png"], "--size"),
        (["still", "helix", "--at", "1", "--out", "OUT.jpg"], "--out"),
        (["still", "helix", "--at", "1", "--camera", "x", "--out", "OUT.png"], "--camera"),
        (["still", "helix", "--out", "OUT.png"], "--at"),
    ],
)
def test_bad_look_values_are_one_line_naming_the_flag_and_exit_status_2(
    capsys, tmp_path, argv, flag
):
    argv = [a.replace("OUT", str(tmp_path / "out")) for a in argv]
    status, _, err = mechviz(*argv)
    assert status == 2, err
    assert len(err.strip().splitlines()) == 1, err
    assert flag in err
    assert list(tmp_path.iterdir()) == []


def test_a_part_outside_the_recording_names_start_or_end():
    clip = video.Clip(page=b"", fps=10, frames=50, length=5.0)
    assert video.window(clip, 1.0, 3.0).frames == 20
    assert video.window(clip, 1.0, 3.0).playback_times()[0] == 1.0
    for start, end, name in ((-1, None, "start"), (5, None, "start"), (2, 1, "end"), (0, 9, "end")):
        with pytest.raises(ValueError, match=f"^{name}:"):
            video.window(clip, start, end)
    assert math.isclose(video.window(clip, None, None).duration, 5.0)
