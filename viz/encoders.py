"""The encoders of a video's frames: H.264 MP4 through the ffmpeg that ships in
``imageio-ffmpeg``, and GIF through Pillow.

Both take ``(H, W, 3)`` uint8 frames one at a time (``add``) and write the file on ``close``;
``abort`` drops what was written so far (the caller removes the partial file).
"""

from __future__ import annotations

import contextlib
import itertools
import logging
import zlib
from collections.abc import Iterator
from pathlib import Path

import numpy as np

PRESET = "veryfast"  # x264: the frames are mostly still background; slower presets gain little


def gif_delays_ms(frames: int, fps: int) -> list[int]:
    """Per-frame GIF delays (whole centiseconds) that add up to ``frames / fps`` seconds."""
    edges = [round(k * 100 / fps) * 10 for k in range(frames + 1)]
    return [b - a for a, b in itertools.pairwise(edges)]


class Mp4Writer:
    """H.264 yuv420p MP4, ``+faststart``, frames streamed to the ffmpeg of ``imageio-ffmpeg``."""

    def __init__(self, path: Path, size: tuple[int, int], fps: int):
        import imageio_ffmpeg

        self.gen = imageio_ffmpeg.write_frames(
            str(path),
            size,
            fps=fps,
            codec="libx264",
            pix_fmt_in="rgb24",
            pix_fmt_out="yuv420p",
            quality=None,
            macro_block_size=2,
            ffmpeg_log_level="error",
            output_params=[
                "-crf",
                "20",
                "-preset",
                PRESET,
                "-movflags",
                "+faststart",
                "-f",
                "mp4",
            ],
        )
        self.gen.send(None)

    def add(self, frame: np.ndarray) -> None:
        self.gen.send(np.ascontiguousarray(frame))

    def close(self) -> None:
        self.gen.close()

    def abort(self) -> None:
        log = logging.getLogger("imageio_ffmpeg")
        level = log.level
        log.setLevel(logging.ERROR)  # "no frames have been written": we know, and remove it
        try:
            with contextlib.suppress(Exception):
                self.gen.close()  # ffmpeg exits; the caller removes the partial file
        finally:
            log.setLevel(level)


class GifWriter:
    """Frames share one palette (half from the first frame, half a uniform colour cube), so
    Pillow stores only the part of each frame that changed. Until the file is written, frames
    are kept as compressed palette indices (a 960x540 frame of a mostly blank scene: ~10 kB);
    Pillow's writer then holds every frame uncompressed (W x H bytes each) until it is done."""

    def __init__(self, path: Path, size: tuple[int, int], fps: int):
        self.path, self.size, self.fps = path, size, fps
        self.frames: list[bytes] = []
        self.palette = None

    def add(self, frame: np.ndarray) -> None:
        from PIL import Image

        img = Image.fromarray(frame)
        if self.palette is None:
            first = img.quantize(131, method=Image.Quantize.FASTOCTREE).getpalette()[: 131 * 3]
            cube = [
                c
                for r in range(5)
                for g in range(5)
                for b in range(5)
                for c in (r * 63, g * 63, b * 63)
            ]
            self.palette = Image.new("P", (1, 1))
            self.palette.putpalette(first + cube)
        indices = img.quantize(palette=self.palette, dither=Image.Dither.NONE).tobytes()
        self.frames.append(zlib.compress(indices, 1))

    def _images(self) -> Iterator:
        from PIL import Image

        colours = self.palette.getpalette()
        for data in self.frames:
            img = Image.frombytes("P", self.size, zlib.decompress(data))
            img.putpalette(colours)
            yield img

    def abort(self) -> None:
        self.frames.clear()

    def close(self) -> None:
        images = self._images()
        first = next(images)
        first.save(
            self.path,
            format="GIF",
            save_all=True,
            append_images=images,
            loop=0,
            duration=gif_delays_ms(len(self.frames), self.fps),
            optimize=False,
        )
