"""``mechviz video``: a recording (``.viser``, or a recorded ``.html`` page such as the live
viewer's downloaded session) filmed into an MP4 or a GIF; and the ``--video`` / ``--size`` of
``mechviz record``.

Registered on the ``mechviz`` parser by :mod:`viz.cli`; playwright and the encoders are
imported only when a video is made. Bad input exits with status 2 and one line naming the
flag; a failure with status 1; Ctrl-C with 130. No half-written video is ever left behind.
"""

from __future__ import annotations

import argparse
import logging
import os
import signal
import sys
import threading
from pathlib import Path

from .. import video
from ..interrupts import exit_status
from ..printable import printable
from ..video_input import read_clip
from .errors import CliError


def size_type(text: str) -> tuple[int, int]:
    """argparse type for ``--size WxH``."""
    try:
        return video.size_arg(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def add_commands(sub) -> None:
    p = sub.add_parser(
        "video",
        help="film a recording (.viser or recorded .html) into an MP4 or a GIF",
        description="Draw every frame of a recording in headless Chromium (viser's own player) "
        "and encode it as H.264 MP4 (yuv420p: browsers, PowerPoint, Keynote) or GIF, with the "
        "title, caption and measured-against-predicted readouts drawn in. A demo manifest beside "
        "the file (FILE.json, as mechviz record writes it) gives the duration, fps and words; "
        "otherwise the whole recording is filmed. The video is written atomically.",
    )
    p.add_argument("file", help="a .viser recording or a recorded .html page")
    p.add_argument(
        "--out", metavar="PATH", help="the video file (default: FILE with .mp4 or .gif, beside it)"
    )
    p.add_argument(
        "--format", choices=video.FORMATS, help="mp4 or gif (default: from --out, else mp4)"
    )
    p.add_argument(
        "--size",
        type=size_type,
        metavar="WxH",
        help=f"frame size in pixels, even numbers (default {video.DEFAULT_SIZE[0]}x{video.DEFAULT_SIZE[1]})",
    )
    p.add_argument(
        "--fps",
        type=int,
        metavar="N",
        help=f"frames per second, up to {video.MAX_FPS} (default: the demo's, else 30)",
    )
    p.set_defaults(func=run_video)


def _flag_error(exc: ValueError, flags: dict[str, str]) -> CliError:
    """A ``ValueError`` from :func:`viz.video.check_request` as a one-line error naming the flag."""
    msg = str(exc)
    key, _, rest = msg.partition(": ")
    if key in flags:
        return CliError(f"{flags[key]}: {rest}")
    return CliError(msg)


def _progress(label: str):
    from ..progress import ProgressBar

    return ProgressBar(label)


def _film(clip: video.Clip, path: Path, fmt: str, size, flags: dict[str, str]) -> int:
    try:
        video.check_request(fmt, size, clip.fps)
        video.require_chromium()
    except video.NoChromium as exc:
        raise CliError(str(exc)) from None
    except ValueError as exc:
        raise _flag_error(exc, flags) from None
    # Ctrl-C reaches Chromium and playwright's driver too (one process group), which may fail
    # before Python sees the KeyboardInterrupt: remember it, so either way it reads as one.
    interrupted = threading.Event()

    def on_sigint(signum, frame):
        interrupted.set()
        signal.default_int_handler(signum, frame)

    previous = signal.signal(signal.SIGINT, on_sigint)
    try:
        res = video.write_video(clip, path, fmt=fmt, size=size, progress=_progress(path.name))
    except (video.VideoError, KeyboardInterrupt) as exc:
        _end_line()
        if interrupted.is_set() or isinstance(exc, KeyboardInterrupt):
            logging.getLogger("asyncio").setLevel(logging.CRITICAL)  # the driver's closed pipe
            print(f"mechviz: interrupted; {path} was not written", file=sys.stderr)
            return exit_status(exc) if isinstance(exc, KeyboardInterrupt) else 130
        print(f"mechviz: error: {exc}; {path} was not written", file=sys.stderr)
        return 1
    finally:
        signal.signal(signal.SIGINT, previous)
    print(
        f"{path}: {res.frames} frames, {res.fps} fps, {res.frames / res.fps:g} s, "
        f"{res.size[0]}x{res.size[1]}, {res.bytes / 1e6:.2f} MB "
        f"(page loaded in {res.load_seconds:.1f} s, then {res.ms_per_frame:.0f} ms per frame: "
        f"{1000 * res.render_seconds / res.frames:.0f} drawing, "
        f"{1000 * res.encode_seconds / res.frames:.0f} overlay and encoding)"
    )
    return 0


def _end_line() -> None:
    if sys.stderr.isatty():
        sys.stderr.write("\n")


def run_video(args: argparse.Namespace) -> int:
    src = Path(args.file)
    if args.fps is not None and not 1 <= args.fps <= 240:
        raise CliError(f"--fps: must be a whole number from 1 to 240, got {args.fps}")
    try:
        clip = read_clip(src, fps=args.fps)
    except ValueError as exc:
        raise CliError(str(exc)) from None
    if args.out:
        out = Path(args.out)
        suffix = out.suffix.lstrip(".").lower()
        if args.format is None and suffix not in video.FORMATS:
            raise CliError(
                f"--out: end the name in .mp4 or .gif (or give --format), got {printable(out.name)}"
            )
        fmt = args.format or suffix
    else:
        fmt = args.format or "mp4"
        out = src.with_suffix(f".{fmt}")
    try:
        if out.is_dir():
            raise CliError(f"--out: {printable(str(out))} is a folder; give a file name")
        os.lstat(out.parent / f".{out.name}.{os.getpid()}.partial")  # the name the writer makes
    except FileNotFoundError:
        pass
    except OSError as exc:  # a name too long for the file system, a folder we may not read
        raise CliError(f"--out: {exc.strerror or exc}") from None
    flags = {"video": "--format", "size": "--size", "fps": "--fps"}
    return _film(clip, out, fmt, args.size or video.DEFAULT_SIZE, flags)


# =========================================================================== mechviz record
def add_record_options(p: argparse.ArgumentParser) -> None:
    """``--video`` and ``--size`` on ``mechviz record``."""
    p.add_argument(
        "--video",
        choices=video.FORMATS,
        help="also film the recording into DEMO.mp4 or DEMO.gif (headless Chromium)",
    )
    p.add_argument(
        "--size",
        type=size_type,
        metavar="WxH",
        help=f"video frame size (default {video.DEFAULT_SIZE[0]}x{video.DEFAULT_SIZE[1]})",
    )


def check_record_options(args: argparse.Namespace, demos) -> None:
    """Before anything is recorded: ``CliError`` for a video that cannot be made."""
    if args.size is not None and not args.video:
        raise CliError("--size: only with --video mp4 or --video gif")
    if not args.video:
        return
    flags = {"video": "--video", "size": "--size", "fps": "--fps"}
    try:
        for demo in demos:
            video.check_request(args.video, args.size or video.DEFAULT_SIZE, demo.fps)
        video.require_chromium()
    except video.NoChromium as exc:
        raise CliError(str(exc)) from None
    except ValueError as exc:
        raise _flag_error(exc, flags) from None


def film_record(res, args: argparse.Namespace) -> int:
    """Film a finished recording (:class:`viz.record.RecordResult`) into DEMO.mp4 / DEMO.gif
    beside its other files; the exit status (0 when done)."""
    clip = video.clip_from_manifest(res.paths[".html"].read_bytes(), res.manifest)
    out = res.paths[".html"].with_suffix(f".{args.video}")
    flags = {"video": "--video", "size": "--size", "fps": "--fps"}
    return _film(clip, out, args.video, args.size or video.DEFAULT_SIZE, flags)
