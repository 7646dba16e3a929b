"""Videos of recordings: what a person gets from ``mechviz record --video`` and ``mechviz video``.

The browser tests film short, small recordings (1-2 s at 10 fps, 320x180) so they stay cheap in
software WebGL; they check the frame count, frame rate and duration the file declares, that
the frames move, that the words are drawn in, and that nothing half-written is left behind.
"""

from __future__ import annotations

import itertools
import shutil

import browser
import numpy as np
import pytest
from commands import mechviz

from mechviz.viz import record as rec
from mechviz.viz import video

SIZE = (320, 180)


# --------------------------------------------------------------------------- no browser
def test_gif_delays_add_up_to_the_exact_duration_at_any_frame_rate():
    for fps in (10, 24, 25, 30, 50):
        delays = video.gif_delays_ms(3 * fps, fps)
        assert len(delays) == 3 * fps
        assert sum(delays) == 3000
        assert all(d % 10 == 0 and d >= 20 for d in delays)


@pytest.mark.parametrize(
    ("argv", "flag"),
    [
        (["record", "helix", "--out", "OUT", "--video", "mp4", "--size", "10x"], "--size"),
        (["record", "helix", "--out", "OUT", "--video", "mp4", "--size", "641x360"], "--size"),
        (["record", "helix", "--out", "OUT", "--video", "avi"], "--video"),
        (["record", "helix", "--out", "OUT", "--size", "640x360"], "--size"),
        (["record", "helix", "--out", "OUT", "--video", "gif", "--fps", "120"], "--fps"),
        (["video", "MISSING.viser"], "MISSING.viser"),
        (["video", "MISSING.viser", "--size", "x"], "--size"),
    ],
)
def test_bad_video_input_is_one_line_naming_the_flag_and_exit_status_2(
    capsys, tmp_path, argv, flag
):
    argv = [a.replace("OUT", str(tmp_path / "out")) for a in argv]
    argv = [a.replace("MISSING", str(tmp_path / "no")) for a in argv]
    status, _, err = mechviz(*argv)
    assert status == 2
    assert len(err.strip().splitlines()) == 1, err
    assert flag.replace("MISSING", "no") in err
    assert not (tmp_path / "out").exists()


def test_without_chromium_one_line_says_how_to_get_it_and_exit_status_is_2(
    capsys, tmp_path, monkeypatch
):
    monkeypatch.setattr(video, "find_chromium", lambda: None)
    out = tmp_path / "out"
    status, _, err = mechviz("record", "helix", "--out", str(out), "--video", "mp4")
    assert status == 2
    assert len(err.strip().splitlines()) == 1
    assert "chromium" in err.lower() and "install" in err
    assert not out.exists(), "nothing is recorded when the video cannot be made"


def test_a_file_that_is_not_a_recording_is_refused(capsys, tmp_path):
    fake = tmp_path / "fake.viser"
    fake.write_bytes(b"\x00" * 64)
    status, _, err = mechviz("video", str(fake))
    assert status == 2
    assert "not a viser recording" in err
    assert not (tmp_path / "fake.mp4").exists()


def test_a_recording_with_the_shadows_turned_off_first_plays_the_same_messages_and_data(tmp_path):
    from mechviz.viz import recording_edit

    res = rec.record(rec.load_demo("helix").with_overrides(duration=0.5, fps=10), tmp_path)
    page = res.paths[".html"].read_bytes()
    edited = recording_edit.page_for_video(page, environment=True)
    head, buffers = recording_edit.read(video.recording_of_page(page))
    head2, buffers2 = recording_edit.read(video.recording_of_page(edited))
    assert head2["messages"][0] == [head["messages"][0][0], recording_edit.NO_SHADOWS]
    assert head2["messages"][1:] == head["messages"]
    assert buffers2 == buffers and len(buffers) > 5
    assert head2["durationSeconds"] == head["durationSeconds"]
    with pytest.raises(ValueError, match="not a viser recording"):
        recording_edit.page_for_video(b"<html></html>")


def test_a_video_draws_the_recording_with_a_sky_light_for_the_viewers_environment(tmp_path):
    from mechviz.viz import recording_edit as edit

    res = rec.record(rec.load_demo("helix").with_overrides(duration=0.5, fps=10), tmp_path)
    page = res.paths[".html"].read_bytes()
    head, _ = edit.read(video.recording_of_page(page))
    t0 = head["messages"][0][0]

    def messages(p: bytes) -> list:
        return edit.read(video.recording_of_page(p))[0]["messages"]

    drawn = messages(edit.page_for_video(page))
    first = [edit.NO_SHADOWS, edit.NO_ENVIRONMENT, edit.SKY_LIGHT]
    assert drawn == [[t0, m] for m in first] + head["messages"]
    assert edit.page_for_video(page, shadows=True, environment=True) == page
    # a recording that chose its environment itself (here: none) keeps it, and gets no light
    own = edit.page_with_messages_first(page, [edit.NO_ENVIRONMENT])
    assert edit.sets_environment(own) and not edit.sets_environment(page)
    assert messages(edit.page_for_video(own))[0] == [t0, edit.NO_SHADOWS]
    assert messages(edit.page_for_video(own))[1:] == messages(own)


# --------------------------------------------------------------------------- browser
def _mp4_frames(path) -> tuple[dict, list[np.ndarray]]:
    import imageio_ffmpeg

    gen = imageio_ffmpeg.read_frames(str(path))
    meta = next(gen)
    W, H = meta["size"]
    frames = [np.frombuffer(b, np.uint8).reshape(H, W, 3) for b in gen]
    return meta, frames


def _gif_frames(path) -> tuple[list[int], list[np.ndarray]]:
    from PIL import Image

    im = Image.open(path)
    delays, frames = [], []
    for k in range(im.n_frames):
        im.seek(k)
        delays.append(im.info["duration"])
        frames.append(np.asarray(im.convert("RGB")))
    return delays, frames


def _moves(frames: list[np.ndarray]) -> float:
    """Fraction of consecutive frame pairs that differ visibly."""
    diffs = [np.abs(a.astype(int) - b).max() > 40 for a, b in itertools.pairwise(frames)]
    return float(np.mean(diffs))


def _has_words(frame: np.ndarray) -> bool:
    """Dark ink in the band along the top (the title) and along the bottom (the readouts)."""
    H = frame.shape[0]
    top, bottom = frame[: H // 8], frame[-H // 8 :]
    return all((band.mean(axis=-1) < 90).mean() > 0.005 for band in (top, bottom))


@pytest.mark.browser
@pytest.mark.parametrize("fmt", ["mp4", "gif"])
def test_record_video_has_the_requested_frames_fps_and_duration_and_moves(capsys, tmp_path, fmt):
    browser.require_browser()
    status, out, err = mechviz(
        "record",
        "helix",
        "--out",
        str(tmp_path),
        "--duration",
        "2",
        "--fps",
        "10",
        "--video",
        fmt,
        "--size",
        f"{SIZE[0]}x{SIZE[1]}",
    )
    assert status == 0, err
    path = tmp_path / f"helix.{fmt}"
    assert path.is_file() and str(path) in out
    if fmt == "mp4":
        meta, frames = _mp4_frames(path)
        assert meta["codec"] == "h264" and meta["pix_fmt"].startswith("yuv420p")
        assert meta["fps"] == 10
        assert meta["duration"] == pytest.approx(2.0, abs=0.01)
    else:
        delays, frames = _gif_frames(path)
        assert sum(delays) == 2000 and set(delays) == {100}
    assert len(frames) == 20
    assert frames[0].shape == (SIZE[1], SIZE[0], 3)
    assert _moves(frames) > 0.8, "the charge moves from frame to frame"
    assert _has_words(frames[0]) and _has_words(frames[-1])
    assert not list(tmp_path.glob(".*partial")), "no temporary files left"


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    browser.require_browser()
    out = tmp_path_factory.mktemp("rec")
    rec.record(rec.load_demo("helix").with_overrides(duration=1.0, fps=10), out)
    return out


@pytest.mark.browser
def test_video_converts_a_viser_file_and_a_bare_html_page(capsys, recording, tmp_path):
    # Beside its manifest: the demo's duration and fps.
    target = tmp_path / "clip.mp4"
    status, _, err = mechviz(
        "video",
        str(recording / "helix.viser"),
        "--out",
        str(target),
        "--size",
        f"{SIZE[0]}x{SIZE[1]}",
    )
    assert status == 0, err
    meta, frames = _mp4_frames(target)
    assert (len(frames), meta["fps"]) == (10, 10)
    assert _moves(frames) > 0.5
    # A page without a manifest (as the live viewer downloads a session): the whole recording.
    page = tmp_path / "session.html"
    shutil.copy(recording / "helix.html", page)
    status, _, err = mechviz(
        "video",
        str(page),
        "--format",
        "gif",
        "--fps",
        "5",
        "--size",
        f"{SIZE[0]}x{SIZE[1]}",
    )
    assert status == 0, err
    delays, frames = _gif_frames(tmp_path / "session.gif")
    duration = video.recording_duration(video.recording_of_page(page.read_bytes()))
    assert len(frames) == round(duration * 5)
    assert sum(delays) == pytest.approx(1000 * len(frames) / 5, abs=10)


@pytest.mark.browser
def test_an_interrupted_video_leaves_nothing_behind(recording, tmp_path):
    target = tmp_path / "old.mp4"
    target.write_bytes(b"previous video")
    clip = video.clip_from_file(recording / "helix.viser")

    def interrupt(done, total):
        if done == 3:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        video.write_video(clip, target, size=SIZE, progress=interrupt)
    assert target.read_bytes() == b"previous video"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["old.mp4"]


def _changed(a: np.ndarray, b: np.ndarray) -> int:
    """Pixels that differ visibly (JPEG's noise against a lossless picture stays below)."""
    return int((np.abs(a.astype(int) - b.astype(int)).max(axis=2) > 60).sum())


@pytest.mark.browser
def test_frames_drawn_side_by_side_by_two_pages_are_the_recording_at_their_times(recording):
    """A video's frames are drawn by two copies of the page side by side, each picture taken one
    animation frame after its seek; each must be the picture of that moment drawn on its own
    (after several animation frames), and not of the moment before or after it."""
    from mechviz.viz.player import Player, decode

    clip = video.clip_from_file(recording / "helix.viser")
    times = [t + 1e-6 for t in (0.1, 0.3, 0.4, 0.6, 0.9)]
    size = (640, 360)  # the charge moves a few pixels between the frames at 320x180
    with Player(clip.page, size) as player:
        alone = [decode(player.png(t)) for t in times]  # seeks forward, one at a time
    with Player(clip.page, size, pages=2) as player:
        piped = [decode(j) for j in player.jpegs(times)]
    assert len(piped) == len(times)
    for k, frame in enumerate(piped):
        changed = [_changed(frame, a) for a in alone]
        assert changed[k] <= 5, (k, changed)
        assert all(c > 20 for j, c in enumerate(changed) if j != k), (k, changed)


def _exhibit_rows(frame: np.ndarray, top: int = 0, bottom: int = 0) -> float:
    """Share of the frame's height between its first and last rows that hold the exhibit
    (pixels off the white background) between ``top`` and ``bottom`` rows of words."""
    H = frame.shape[0]
    region = frame[top : H - bottom]
    rows = np.flatnonzero((region.min(axis=2) < 235).sum(axis=1) >= 2)
    return (rows[-1] - rows[0] + 1) / H if len(rows) else 0.0


@pytest.mark.browser
@pytest.mark.parametrize("overlay", [True, False])
def test_the_exhibit_fills_most_of_the_frames_height(capsys, recording, tmp_path, overlay):
    from mechviz.viz.overlay import Overlay

    size = (640, 360)
    target = tmp_path / "framed.mp4"
    argv = ["video", str(recording / "helix.viser"), "--out", str(target), "--size", "640x360"]
    status, _, err = mechviz(*argv, *([] if overlay else ["--no-overlay"]))
    assert status == 0, err
    _, frames = _mp4_frames(target)
    top = bottom = 0
    if overlay:  # measured between the two bands of words
        clip = video.clip_from_file(recording / "helix.viser")
        times = [clip.simulated(t) for t in clip.playback_times()]
        o = Overlay(
            title=clip.title, caption=clip.caption, figures=clip.figures, size=size, times=times
        )
        top, bottom = (round(b * size[1]) + 1 for b in o.band)
    for frame in frames:
        assert _exhibit_rows(frame, top, bottom) >= 0.6


def _text_line_height(frame: np.ndarray) -> int:
    """Height in pixels of the highest line of dark text (the exhibit's title label): dark,
    grey pixels, which nothing else in the cyclotron's scene is."""
    dark = (frame.max(axis=2) < 110) & (np.ptp(frame.astype(int), axis=2) < 30)
    rows = np.flatnonzero(dark.sum(axis=1) >= 2)
    if not len(rows):
        return 0
    run = [rows[0]]
    for r in rows[1:]:
        if r - run[-1] > 2:
            break
        run.append(r)
    return run[-1] - run[0] + 1


@pytest.mark.browser
def test_labels_in_the_scene_grow_with_the_picture(recording, tmp_path):
    """The scene's labels keep their share of the picture: at 960x540 the exhibit's title
    label is at least 2 % of the height (about 11 px; viser draws it 10 px high at any size)."""
    clip = video.clip_from_file(recording / "helix.viser")
    heights = {}
    for size in ((480, 270), (960, 540)):
        path = tmp_path / f"{size[1]}.png"
        video.write_still(clip, path, 0.5, size=size, look=video.Look(overlay=False))
        from PIL import Image

        heights[size[1]] = _text_line_height(np.asarray(Image.open(path).convert("RGB")))
    assert heights[540] >= 0.02 * 540, heights
    assert heights[540] > 1.5 * heights[270], heights


@pytest.mark.browser
def test_the_kicks_figures_appear_on_frames_after_the_kick_only(capsys, tmp_path):
    """radial-kick, filmed at 2 fps: the band of figures holds two lines (gyrofrequency and
    Larmor radius) before the kick at t = 5 s and three (its effects) after."""
    browser.require_browser()
    status, _, err = mechviz(
        *("record", "radial-kick", "--out", str(tmp_path), "--duration", "7", "--fps", "2"),
        *("--video", "mp4", "--size", "640x360"),
    )
    assert status == 0, err
    _, frames = _mp4_frames(tmp_path / "radial-kick.mp4")
    assert len(frames) == 14

    from mechviz.viz.overlay import Overlay

    clip = video.clip_from_file(tmp_path / "radial-kick.viser")
    times = [clip.simulated(t) for t in clip.playback_times()]
    o = Overlay(
        title=clip.title, caption=clip.caption, figures=clip.figures, size=(640, 360), times=times
    )
    y0 = 360 - o.bottom_h + o.pad

    def text_lines(frame) -> int:  # the line slots of the bottom band with ink in their left half
        slots = [frame[y0 + r * o.line_h : y0 + (r + 1) * o.line_h, :320] for r in range(3)]
        return sum(int(((slot.max(axis=2) < 90).sum()) > 20) for slot in slots)

    counts = [text_lines(f) for f in frames]
    assert counts[:10] == [2] * 10, counts  # t = 0 .. 4.5 s
    assert counts[10:] == [3] * 4, counts  # t = 5 .. 6.5 s


@pytest.mark.browser
def test_still_writes_a_3840x2160_png_with_the_exhibit_in_it(capsys, tmp_path):
    from PIL import Image

    browser.require_browser()
    out = tmp_path / "helix.png"
    status, stdout, err = mechviz(
        "still", "helix", "--at", "1.5", "--size", "3840x2160", "--out", str(out)
    )
    assert status == 0, err
    assert str(out) in stdout
    img = Image.open(out)
    assert img.format == "PNG" and img.size == (3840, 2160)
    frame = np.asarray(img.convert("RGB"))
    assert _exhibit_rows(frame, 300, 300) >= 0.5
    assert len(np.unique(frame[::8, ::8].reshape(-1, 3), axis=0)) > 100  # drawn, not blank
    assert sorted(p.name for p in tmp_path.iterdir()) == ["helix.png"]


@pytest.mark.browser
def test_the_sky_light_looks_like_the_viewers_environment_map(recording):
    """Videos swap the viewer's environment map for a hemisphere light (cheaper in software
    WebGL): the exhibit's colours stay close to the environment-lit picture, and the light is
    what keeps them close (without it the lit parts go dark)."""
    from mechviz.viz import recording_edit as edit
    from mechviz.viz.player import Player, decode

    page = video.clip_from_file(recording / "helix.viser").page
    lit = edit.page_with_messages_first(page, [edit.NO_SHADOWS])
    unlit = edit.page_with_messages_first(page, [edit.NO_SHADOWS, edit.NO_ENVIRONMENT])
    pictures = []
    for p in (lit, edit.page_for_video(page), unlit):
        with Player(p, (640, 360), antialias=False) as player:
            pictures.append(decode(player.png(0.5)).astype(int))
    env, sky, dark = pictures
    exhibit = env.min(axis=2) < 235
    assert exhibit.sum() > 500
    sky_off = np.abs(sky - env)[exhibit].mean()
    dark_off = np.abs(dark - env)[exhibit].mean()
    assert sky_off < 12, sky_off
    assert dark_off > 2 * sky_off, (sky_off, dark_off)
