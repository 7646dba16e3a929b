"""The words drawn on a video's frames and on stills: title, caption, the figures that are true at
that moment, and the simulated time (Pillow; DejaVu fonts where installed, which cover the
Unicode of the captions: π, Ω, Δ, ², √).

A figure (a manifest's measured-against-predicted entry) carries the stretch of simulated time it
is true of (``since`` .. ``until``, seconds): a kick's effects appear at the kick, a final error at
the end, a figure of the motion before a kick leaves with the kick. Every figure true at a moment
is shown (in a second column beyond :data:`COLUMN_LINES`), so the figure a caption speaks of is
never dropped. The predicted value is labelled with what it comes from ("linear theory", ...).
"""

from __future__ import annotations

import contextlib
import os
from typing import Any

import numpy as np

COLUMN_LINES = 4  # readout lines per column
LAYOUT_HEIGHT = 360  # font sizes are given for a picture this high and scale with its height
EPS = 1e-9


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
        lines[-1] = lines[-1].rstrip(".,;") + " …"
    return lines


def figure_line(f: dict[str, Any]) -> str:
    """``name: measured unit   (theory predicted)`` of one figure."""
    unit = f" {f['unit']}" if f.get("unit") else ""
    line = f"{f['name']}: {f['measured']:.6g}{unit}"
    if f.get("predicted") is not None:
        line += f"   ({f.get('theory', 'theory')} {f['predicted']:.6g})"
    return line


def true_at(f: dict[str, Any], t: float) -> bool:
    """Whether figure ``f`` is true at simulated time ``t`` [s] (and has a measured value)."""
    if f.get("measured") is None:
        return False
    since, until = float(f.get("since", 0.0)), f.get("until")
    return since <= t + EPS and (until is None or t < float(until) - EPS)


def figures_at(figures: list[dict[str, Any]], t: float) -> list[dict[str, Any]]:
    """The figures true at simulated time ``t``, in the manifest's order."""
    return [f for f in figures if true_at(f, t)]


def _line_height(font) -> int:
    asc, desc = font.getmetrics()
    return round((asc + desc) * 1.15)


class Overlay:
    """The words on a picture of ``size = (W, H)``: title and caption in a band along the top,
    the figures true at that moment in a band along the bottom with the simulated time at its
    right. ``times`` are the simulated times of the frames to come, so the bottom band is as
    high as the most figures any of them shows (it does not jump). Each set of figures is
    drawn once; only the time changes per frame."""

    def __init__(
        self,
        *,
        title: str,
        caption: str,
        figures: list[dict[str, Any]],
        size: tuple[int, int],
        times,
    ) -> None:
        from PIL import Image, ImageDraw

        W, H = size
        self.size = size
        self.figures = [f for f in figures if f.get("measured") is not None]
        u = H / LAYOUT_HEIGHT
        self.f_title = _font(max(8, round(15 * u)), bold=True)
        self.f_text = _font(max(7, round(10.5 * u)))
        self.pad = max(2, round(5 * u))
        self.line_h = _line_height(self.f_text)
        self.ink = (25, 25, 35, 255)
        self.paper = (255, 255, 255, 205)
        probe = ImageDraw.Draw(Image.new("RGBA", (1, 1)))
        top = [(title, self.f_title)] if title else []
        top += [(s, self.f_text) for s in _wrap(probe, caption, self.f_text, W - 2 * self.pad, 2)]
        self.top_lines = top
        self.top_h = (sum(_line_height(f) for _, f in top) + 2 * self.pad) if top else 0
        times = sorted(float(t) for t in times)
        if times:
            # A figure of the run's last sample (a final error) is shown on the last frame, which
            # may come up to one frame before that sample.
            step = times[-1] - times[-2] if len(times) > 1 else 0.0
            last = times[-1]
            self.figures = [
                {**f, "since": last}
                if last < float(f.get("since", 0.0)) <= last + step + EPS
                else f
                for f in self.figures
            ]
        most = max((len(figures_at(self.figures, t)) for t in times), default=0)
        rows = min(max(most, 1), COLUMN_LINES)
        self.bottom_h = rows * self.line_h + 2 * self.pad
        self._layers: dict[tuple[int, ...], Any] = {}

    @property
    def band(self) -> tuple[float, float]:
        """Shares of the picture's height the top and bottom bands cover (for framing)."""
        H = self.size[1]
        return self.top_h / H, self.bottom_h / H

    def lines_at(self, t: float) -> list[str]:
        """The figure lines shown at simulated time ``t`` [s]."""
        return [figure_line(f) for f in figures_at(self.figures, t)]

    def _layer(self, t: float):
        """The two bands (RGBA images, top and bottom) for the figures true at ``t``."""
        from PIL import Image, ImageDraw

        shown = tuple(i for i, f in enumerate(self.figures) if true_at(f, t))
        layer = self._layers.get(shown)
        if layer is not None:
            return layer
        W = self.size[0]
        top = Image.new("RGBA", (W, max(self.top_h, 1)), (0, 0, 0, 0))
        d = ImageDraw.Draw(top)
        if self.top_lines:
            d.rectangle((0, 0, W, self.top_h), fill=self.paper)
            y = self.pad
            for text, f in self.top_lines:
                d.text((self.pad, y), text, font=f, fill=self.ink)
                y += _line_height(f)
        bottom = Image.new("RGBA", (W, self.bottom_h), self.paper)
        d = ImageDraw.Draw(bottom)
        lines = [figure_line(self.figures[i]) for i in shown]
        columns = [lines[i : i + COLUMN_LINES] for i in range(0, len(lines), COLUMN_LINES)]
        col_w = (W - 2 * self.pad) / max(len(columns), 1)
        for c, col in enumerate(columns):
            for r, text in enumerate(col):
                x = self.pad + c * col_w
                d.text((x, self.pad + r * self.line_h), text, font=self.f_text, fill=self.ink)
        self._layers[shown] = (top, bottom)
        return top, bottom

    def apply(self, frame: np.ndarray, t: float) -> np.ndarray:
        """``frame`` with the words for simulated time ``t`` [s] drawn on it (only the two
        bands are touched)."""
        from PIL import Image, ImageDraw

        W, H = self.size
        out = np.array(frame, copy=True)
        top, bottom = self._layer(t)
        if self.top_h:
            region = Image.fromarray(out[: self.top_h]).convert("RGBA")
            region.alpha_composite(top)
            out[: self.top_h] = np.asarray(region.convert("RGB"))
        region = Image.fromarray(out[H - self.bottom_h :]).convert("RGBA")
        region.alpha_composite(bottom)
        d = ImageDraw.Draw(region)
        label = f"t = {t:.2f} s"
        w = d.textlength(label, font=self.f_text)
        d.text(
            (W - self.pad - w, self.bottom_h - self.pad - self.line_h),
            label,
            font=self.f_text,
            fill=self.ink,
        )
        out[H - self.bottom_h :] = np.asarray(region.convert("RGB"))
        return out
