"""The words drawn on every frame of a video: title, caption, readouts and the simulated time
(Pillow; DejaVu fonts where installed)."""

from __future__ import annotations

import contextlib
import os

import numpy as np


def _font(size: int, bold: bool = False):
    from PIL import ImageFont

    name = "DejaVuSans-Bold.ttf" if bold else "DejaVuSans.ttf"
    for folder in ("/usr/share/fonts/truetype/dejavu", "/usr/share/fonts/dejavu"):
        with contextlib.suppress(OSError):
            return ImageFont.truetype(os.path.join(folder, name), size)
    return ImageFont.load_default(size)


def _wrap(draw, text: str, font, width: float, max_lines: int) -> list[str]:
    words, lines, line = text.split(), [], ""
    for w in words:
        trial = f"{line} {w}".strip()
        if draw.textlength(trial, font=font) <= width or not line:
            line = trial
        else:
            lines.append(line)
            line = w
    if line:
        lines.append(line)
    if len(lines) > max_lines:
        lines = lines[:max_lines]
        lines[-1] = lines[-1].rstrip(".,;") + " ..."
    return lines


class Overlay:
    """The words on every frame: title and caption in a band along the top, the readouts in a
    band along the bottom, and the simulated time at the bottom right. The static part is drawn
    once; only the time changes per frame."""

    def __init__(self, clip, size: tuple[int, int]):
        from PIL import Image, ImageDraw

        W, H = size
        self.size = size
        self.speed = clip.speed
        unit = max(H, 240) / 360
        self.f_title = _font(round(17 * unit), bold=True)
        self.f_text = _font(round(12 * unit))
        pad = round(8 * unit)
        layer = Image.new("RGBA", size, (0, 0, 0, 0))
        d = ImageDraw.Draw(layer)
        band = (255, 255, 255, 215)
        ink = (25, 25, 35, 255)
        # Top: title, caption (at most two lines).
        y = pad
        lines = [(clip.title, self.f_title)] if clip.title else []
        lines += [(s, self.f_text) for s in _wrap(d, clip.caption, self.f_text, W - 2 * pad, 2)]
        if lines:
            h = sum(_line_height(f) for _, f in lines) + 2 * pad
            d.rectangle((0, 0, W, h), fill=band)
            for text, f in lines:
                d.text((pad, y), text, font=f, fill=ink)
                y += _line_height(f)
        # Bottom: readouts, one per line, and room for the time.
        self.line_h = _line_height(self.f_text)
        n = max(1, len(clip.readouts))
        self.bottom = H - n * self.line_h - 2 * pad
        d.rectangle((0, self.bottom, W, H), fill=band)
        y = self.bottom + pad
        for text in clip.readouts:
            d.text((pad, y), text, font=self.f_text, fill=ink)
            y += self.line_h
        self.pad, self.ink = pad, ink
        self.layer = layer

    def apply(self, frame: np.ndarray, k: int, fps: int) -> np.ndarray:
        from PIL import Image, ImageDraw

        img = Image.fromarray(frame).convert("RGBA")
        img.alpha_composite(self.layer)
        d = ImageDraw.Draw(img)
        label = f"t = {k / fps * self.speed:.2f} s"
        W, H = self.size
        w = d.textlength(label, font=self.f_text)
        d.text(
            (W - self.pad - w, H - self.pad - self.line_h), label, font=self.f_text, fill=self.ink
        )
        return np.asarray(img.convert("RGB"))


def _line_height(font) -> int:
    asc, desc = font.getmetrics()
    return round((asc + desc) * 1.2)
