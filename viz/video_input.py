"""What ``mechviz video`` accepts: a recording (and the manifest beside it) read and checked, so
that a crafted or damaged file is refused with one line instead of failing midway.

:func:`read_clip` wraps :func:`mechviz.viz.video.clip_from_file`: a path the system cannot use (too long,
unreadable), a recording whose numbers are not a playback (``durationSeconds = 1e308``, a frame
rate of 0, a value of the wrong kind in the manifest, JSON nested too deeply) raises
``ValueError`` naming the file and what is wrong; so does a clip of more than
:data:`MAX_FRAMES` frames, the most a demo may hold.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from . import video
from .printable import printable

MAX_FRAMES = 100_000  # as many as a demo may record (mechviz.viz.record.demo.MAX_FRAMES)
MAX_FPS = 240


def read_clip(path: Path, fps: int | None = None) -> video.Clip:
    """The clip of the recording at ``path`` (``fps`` overrides its frame rate), checked."""
    name = printable(str(path))
    try:
        clip = video.clip_from_file(path, fps=fps)
        seconds = _declared_seconds(path)
    except ValueError as exc:
        text = str(exc)
        raise ValueError(text if text.startswith(str(path)) else f"{name}: {text}") from None
    except OSError as exc:
        raise ValueError(f"{name}: {exc.strerror or exc}") from None
    except OverflowError:
        raise ValueError(
            f"{name}: its duration is too long to film (the limit is {MAX_FRAMES} frames)"
        ) from None
    except (TypeError, KeyError, ZeroDivisionError, AttributeError, RecursionError) as exc:
        raise ValueError(
            f"{name}: the recording or the manifest beside it holds a value that is not a "
            f"playback ({type(exc).__name__})"
        ) from None
    if not (math.isfinite(seconds) and seconds >= 0):
        raise ValueError(f"{name}: durationSeconds = {seconds:g} is not a length of playback")
    check_clip(clip, name)
    return clip


def _declared_seconds(path: Path) -> float:
    """The playback length the recording itself declares (``durationSeconds``)."""
    data = path.read_bytes()
    recording = data if path.suffix == ".viser" else video.recording_of_page(data)
    return video.recording_duration(recording)


def check_clip(clip: video.Clip, name: str) -> None:
    """``ValueError`` if ``clip`` cannot be filmed in bounded work."""
    if not (isinstance(clip.fps, int) and 1 <= clip.fps <= MAX_FPS):
        raise ValueError(f"{name}: a frame rate from 1 to {MAX_FPS} is needed, got {clip.fps!r}")
    if not (isinstance(clip.frames, int) and 1 <= clip.frames <= MAX_FRAMES):
        raise ValueError(f"{name}: {clip.frames:.3g} frames to film; the limit is {MAX_FRAMES}")
    if not (isinstance(clip.speed, float | int) and math.isfinite(clip.speed)):
        raise ValueError(f"{name}: the manifest's speed must be a finite number")
    for f in clip.figures:
        if not (
            isinstance(f, dict)
            and isinstance(f.get("name"), str)
            and all(_number_or_none(f.get(k)) for k in ("measured", "predicted", "until"))
            and _number_or_none(f.get("since", 0.0))
        ):
            raise ValueError(f"{name}: the manifest's figures are not figures ({str(f)[:60]})")
    if clip.scene is not None:
        try:
            for key in ("bounds", "view"):
                box = np.asarray(clip.scene[key], dtype=float)
                if box.shape != (2, 3) or not np.all(np.isfinite(box)):
                    raise ValueError
        except (KeyError, TypeError, ValueError):
            raise ValueError(
                f"{name}: the manifest's scene needs bounds and view, two points each"
            ) from None


def _number_or_none(x) -> bool:
    return x is None or (isinstance(x, int | float) and math.isfinite(x))
