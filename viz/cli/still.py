"""``mechviz still``: one picture (PNG) of a demo or a recording at a chosen moment, from a chosen
camera, at slide resolution.

A built-in demo (or a demo ``.toml``) is recorded headless up to that moment into a temporary
folder, by the recorder, and the picture is drawn from that recording by the same player as
videos (:func:`mechviz.viz.video.write_still`); a ``.viser`` or recorded ``.html`` is drawn directly.
The PNG is written atomically. Bad input exits with status 2 and one line naming the flag.
"""

from __future__ import annotations

import argparse
import math
import tempfile
from pathlib import Path

from .. import video
from ..printable import printable
from .errors import CliError, command, number
from .video import FLAGS, add_look_options, check_out, flag_error, interruptible, look_of, size_type

RECORDING_SUFFIXES = (".viser", ".html", ".htm")


ABOUT = """\
one PNG of a demo or a recording at a chosen moment (slide resolution)

Draw one picture of a built-in demo (or a demo .toml, recorded headless up to that moment) or of
a recording (.viser or recorded .html) at playback time --at, framed on the exhibit or from
--camera, with the title, caption and the figures true at that moment (or --no-overlay), and
write it as a PNG atomically. Needs Chromium and pip install 'mechviz-lab[video]'.
"""


def add_commands(sub) -> None:
    p = command(sub, "still", ABOUT)
    p.add_argument(
        "source", help="a demo name (mechviz record --list), a demo .toml, or a recording"
    )
    p.add_argument("--at", type=number, required=True, metavar="T", help="seconds of playback")
    p.add_argument(
        "--size",
        type=size_type,
        metavar="WxH",
        help=f"picture size in pixels, even numbers up to {video.MAX_SIDE} "
        f"(default {video.STILL_SIZE[0]}x{video.STILL_SIZE[1]})",
    )
    p.add_argument(
        "--out", metavar="PATH", help="the PNG (default NAME-atT.png; beside a recording)"
    )
    add_look_options(p, part=False)
    p.set_defaults(func=run_still)


def _default_out(source: Path, name: str, at: float, is_file: bool) -> Path:
    stem = f"{name}-at{at:g}s.png"
    return source.with_name(stem) if is_file else Path(stem)


def run_still(args: argparse.Namespace) -> int:
    from ..video_input import read_clip

    size = args.size or video.STILL_SIZE
    at = float(args.at)
    try:
        video.check_size(size)
    except ValueError as exc:
        raise flag_error(exc) from None
    if not (math.isfinite(at) and at >= 0):
        raise CliError(f"--at: must be a number of seconds from 0, got {args.at:g}")
    source = Path(args.source)
    is_file = source.suffix.lower() in RECORDING_SUFFIXES
    out = Path(args.out) if args.out else _default_out(source, source.stem, at, is_file)
    if out.suffix.lower() != ".png":
        raise CliError(f"--out: end the name in .png, got {printable(out.name)}")
    check_out(out)
    look = look_of(args)
    if is_file:
        try:
            clip = read_clip(source)
        except ValueError as exc:
            raise CliError(str(exc)) from None
        return _draw(clip, out, at, size, look)
    return _draw_demo(args.source, out, at, size, look)


def _draw(clip: video.Clip, out: Path, at: float, size, look: video.Look) -> int:
    try:
        length = clip.length if clip.length is not None else clip.duration
        if at > length + 1e-9:
            raise ValueError(f"at: must be from 0 to the recording's {length:g} s, got {at:g}")
        video.camera_for(clip, look, size, None)
        video.require_chromium()
    except video.NoChromium as exc:
        raise CliError(str(exc)) from None
    except ValueError as exc:
        raise flag_error(exc, FLAGS) from None
    status, _ = interruptible(out, lambda: video.write_still(clip, out, at, size=size, look=look))
    if status:
        return status
    print(f"{out}: {size[0]}x{size[1]} PNG at t = {at:g} s of playback")
    return 0


def _draw_demo(name: str, out: Path, at: float, size, look: video.Look) -> int:
    from ..interrupts import ctrl_c_within_a_second

    with ctrl_c_within_a_second():
        from .. import record as rec

    try:
        demo = rec.load_demo(name)
    except ValueError as exc:
        raise CliError(str(exc)) from None
    if at > demo.duration:
        raise CliError(f"--at: must be from 0 to the demo's {demo.duration:g} s, got {at:g}")
    try:  # the camera before anything runs: a position or a preset (a demo frames its exhibit)
        video.require_chromium()
    except video.NoChromium as exc:
        raise CliError(str(exc)) from None
    # Recorded a little past the moment, so that its frame is complete; nothing after it runs.
    duration = min(demo.duration, at + 2.0 / demo.fps)
    with tempfile.TemporaryDirectory(prefix="mechviz-still-") as tmp:
        try:
            with ctrl_c_within_a_second():
                res = rec.record(demo.with_overrides(duration=duration), tmp)
        except rec.RecordingFailed as exc:
            if exc.interrupted:  # Ctrl-C or SIGTERM: main() reports it with its exit status
                cause = exc.__cause__
                raise (
                    cause if isinstance(cause, KeyboardInterrupt) else KeyboardInterrupt()
                ) from None
            raise CliError(f"{printable(name)}: {exc}") from None
        clip = video.clip_from_manifest(res.paths[".html"].read_bytes(), res.manifest)
        return _draw(clip, out, at, size, look)
