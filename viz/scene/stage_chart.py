"""An exhibit's chart drawn in the scene, on its stage, at the stage's text size.

viser has no 2-D overlay over the scene, and the panel's charts are 300 px wide: from the back
of a hall neither reads. So the stage shows the exhibit's main series against time on a flat
panel in the scene beside the exhibit (:class:`StageChart`): the panel a light quad facing the
camera, the axes and grid line segments, the tick and axis labels scene labels of the stage's
size, and the data one line-segments node whose points are the only thing a frame updates.

The series are the exhibit's own quantities (:meth:`mechviz.viz.scene.base.Exhibit.stage_plot`,
names of :meth:`~mechviz.viz.model.base.ExhibitModel.plot_variables`) over the chart window,
from the same samples the panel's plot draws (the model's trace), ending at the moment shown:
scrubbed back with Rewind, the chart ends there too.

Where the panel goes on the page is the stage's business (:mod:`mechviz.viz.views`): it gives
:meth:`StageChart.place` the camera and a page rectangle, and the chart stands on a plane facing
the camera that fills that rectangle.
"""

from __future__ import annotations

import math
import textwrap

import numpy as np

from .. import geometry as geo
from ..model.plot import Samples
from . import framing

# px a character and a line of a label take per unit of scale, with room to spare (viser's
# own are 5.35 and 14.2): the labels of the chart never run into each other
CHAR_PX = 6.5
LINE_PX = 16.0
PAD_PX = 6  # px between the panel's edge, the labels and the plot area
MAX_TICKS = 4  # value labels on the y axis at most
VALUE_CHARS = 4  # characters a value's label takes at most ("-0.5")
INK = (40, 40, 48)  # axes: dark on the light panel, whatever the page's theme
GRID = (200, 200, 205)
PANEL = (250, 250, 250)
NEAR = 0.6  # of the distance to the point looked at: where the panel stands (in front of the
# exhibit's middle, so the floor, seen from above, does not cut its lower edge)


def min_width(title: str, scale: float) -> float:
    """CSS px a chart must be wide for ``title`` on one line right of its values' column, at
    label ``scale``."""
    return scale * (CHAR_PX * (VALUE_CHARS + len(title)) + 12 + 3 * PAD_PX)


def nice_step(span: float) -> float:
    """A step of 1, 2 or 5 times a power of ten, about ``span`` / 3 (ticks on a range; no 2.5:
    its values take a digit more)."""
    raw = max(span, 1e-12) / 3.0
    p = 10.0 ** math.floor(math.log10(raw))
    return next(m * p for m in (1.0, 2.0, 5.0, 10.0) if m * p >= raw)


def nice_range(lo: float, hi: float) -> tuple[float, float, float]:
    """``(low, high, step)``: whole steps around ``lo``..``hi`` (a flat series gets a range
    of a tenth of its size, at least 1e-9, about it)."""
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return -1.0, 1.0, 1.0
    if hi - lo < 1e-9 * max(1.0, abs(hi)):
        half = max(0.1 * abs(hi), 1e-9) if hi else 1.0
        lo, hi = lo - half, hi + half
    step = nice_step(hi - lo)
    return math.floor(lo / step) * step, math.ceil(hi / step) * step, step


def tick_text(v: float, step: float) -> str:
    """A tick's value with as many decimals as the step needs (no "-0.0")."""
    decimals = max(0, -math.floor(math.log10(step) + 1e-9)) if step < 1 else 0
    if step * 10**decimals % 1 > 1e-6:  # a step of 2.5 x 10^k needs one more
        decimals += 1
    text = f"{v:.{decimals}f}"
    return text.lstrip("-") if float(text) == 0.0 else text


class StageChart:
    """The exhibit's main series against time [s], on a panel in the scene under the exhibit's
    root (so it hides with the exhibit), shown only while the exhibit is on stage."""

    def __init__(self, exhibit, text_scale: float) -> None:
        self.exhibit = exhibit
        self.text_scale = text_scale  # the labels' font_screen_scale (the stage's)
        s = exhibit.scene
        self.root = f"{exhibit.root}/stage_chart"
        self.frame = s.add_frame(self.root, show_axes=False, visible=False)
        self.panel = None
        self.axes = geo.lines(s, f"{self.root}/axes", np.zeros((1, 2, 3), np.float32), INK, 2.0)
        self.grid = geo.lines(s, f"{self.root}/grid", np.zeros((1, 2, 3), np.float32), GRID, 1.0)
        self.data = None  # the series' line segments, made for their number and colours
        self._capacity = 0
        add = lambda name, anchor: s.add_label(  # noqa: E731
            f"{self.root}/{name}", "", anchor=anchor, font_screen_scale=text_scale
        )
        self.y_title = add("y_title", "bottom-left")
        self.x_title = add("x_title", "top-center")
        self.x_ticks = [add("x_tick_0", "top-left"), add("x_tick_1", "top-right")]
        self.y_ticks = [add(f"y_tick_{k}", "center-right") for k in range(MAX_TICKS + 1)]
        # the plot area in the panel's own coordinates [m] (x right, y up), set by place()
        self.area = (0.0, 0.0, 1.0, 1.0)
        self.size = (1.0, 1.0)  # the panel's width and height [m]
        self.m_per_px = 0.001
        self._label_m = 0.003  # m per unit of a label's size, as placed
        self.y_range: tuple[float, float, float] | None = None
        self.t_range = (0.0, 10.0)
        self.drawn = None  # what the data's points show (skip a frame that changes nothing)
        self._series = None  # (config, variables, label, names, colours) of the running motion
        self.last_time = math.nan  # [s] the time of the chart's last point

    # ------------------------------------------------------------------ where it stands
    @property
    def visible(self) -> bool:
        return bool(self.frame.visible)

    @visible.setter
    def visible(self, on: bool) -> None:
        self.frame.visible = on

    def place(self, position, look_at, rect, size, px: float = 1.0) -> None:
        """Stand the panel so the camera at ``position`` looking at ``look_at`` sees it fill the
        page rectangle ``rect`` = ``(x0, y0, x1, y1)`` [page px] of a page of ``size`` = (width,
        height) px; ``px``: page pixels per CSS pixel of the labels."""
        w, h = size
        x0, y0, x1, y1 = rect
        f, r, u = framing.basis(position, look_at)
        depth = NEAR * float(np.dot(np.subtract(look_at, position), f))
        t = math.tan(framing.FOV / 2)
        cam = np.asarray(position, float)
        # a camera above the floor looking down: the lower edge's ray must meet the panel's
        # plane before it meets the floor
        ray_low = f + u * (1 - 2 * y1 / h) * t
        if ray_low[2] < 0 and cam[2] > 0.05:
            depth = min(depth, 0.95 * (cam[2] - 0.05) / -ray_low[2] / float(ray_low @ f))

        def world(x, y):
            ray = f + r * (2 * x / w - 1) * t * w / h + u * (1 - 2 * y / h) * t
            return cam + depth * ray

        self.m_per_px = 2 * depth * t / h
        centre = world((x0 + x1) / 2, (y0 + y1) / 2)
        self.frame.position = tuple(centre - self.exhibit.origin)
        self.frame.wxyz = tuple(geo.quat_from_matrix(np.column_stack([r, u, -f])))
        width, height = (x1 - x0) * self.m_per_px, (y1 - y0) * self.m_per_px
        self.size = (width, height)
        self._panel(width, height)
        self._layout(px)
        self.drawn = None

    def _panel(self, width: float, height: float) -> None:
        hw, hh = width / 2, height / 2
        z = -0.002 * max(width, height)  # just behind the lines
        verts = np.array([(-hw, -hh, z), (hw, -hh, z), (hw, hh, z), (-hw, hh, z)], np.float32)
        faces = np.array([(0, 1, 2), (0, 2, 3)], np.uint32)
        self.panel = self.exhibit.scene.add_mesh_simple(
            f"{self.root}/panel",
            verts,
            faces,
            color=PANEL,
            material="toon3",  # flat: a sheet of paper, not a lit surface
            side="double",
            cast_shadow=False,
            receive_shadow=False,
        )

    def _layout(self, px: float) -> None:
        """The plot area inside the panel: room for the y title above it, the time's labels
        below and the values' labels left of it, in label pixels turned into metres."""
        k = self.m_per_px * px * self.text_scale  # m per unit of label size
        self._label_m = k
        width, height = self.size
        label, _, _ = self.series()
        left = (CHAR_PX * VALUE_CHARS + 6) * k + PAD_PX * k  # the values' labels
        right = 0.5 * CHAR_PX * 3 * k + PAD_PX * k  # the last time's label, centred-ish
        # the title right of the values' column, on the row the top value stands in
        chars = max(int(((width - left) / k - 6 - PAD_PX) / CHAR_PX), 8)
        self.y_title.text = "\n".join(textwrap.wrap(label, chars))
        lines = len(self.y_title.text.splitlines())
        top = LINE_PX * k * lines + PAD_PX * k
        bottom = LINE_PX * k + PAD_PX * k
        self.area = (-width / 2 + left, -height / 2 + bottom, width / 2 - right, height / 2 - top)
        ax0, ay0, ax1, ay1 = self.area
        self.y_title.position = (ax0 + PAD_PX * k, ay1 + PAD_PX * k / 2, 0.0)
        self.x_title.position = ((ax0 + ax1) / 2, ay0 - PAD_PX * k / 2, 0.0)
        self.x_ticks[0].position = (ax0, ay0 - PAD_PX * k / 2, 0.0)
        self.x_ticks[1].position = (ax1 + right - PAD_PX * k, ay0 - PAD_PX * k / 2, 0.0)
        self.x_title.text = "t [s]"
        # a narrow plot: the window's start is left out (it is the end less the window) and
        # the title takes its place, so the labels under the axis never run into each other
        wide = (ax1 - ax0) >= (CHAR_PX * 14 + 18) * k
        self.x_ticks[0].visible = wide
        self.x_title.anchor = "top-center" if wide else "top-left"
        if not wide:
            self.x_title.position = (ax0, ay0 - PAD_PX * k / 2, 0.0)
        self.axes.points = np.array(
            [[(ax0, ay0, 0), (ax1, ay0, 0)], [(ax0, ay0, 0), (ax0, ay1, 0)]], np.float32
        )
        self.y_range = None  # the values' labels and grid anew

    # ------------------------------------------------------------------ the data
    def series(self):
        """``(label, names, colours)`` of the exhibit's stage plot and its variables, kept
        while the config is the same object (a new setting is a new config)."""
        ex = self.exhibit
        if self._series is None or self._series[0] is not ex.model.config:
            label, series = ex.stage_plot()
            variables = ex.model.plot_variables(ex.model.config)
            self._series = (ex.model.config, variables, label, tuple(n for n, _ in series),
                            tuple(c for _, c in series))  # fmt: skip
        _, variables, label, names, colours = self._series
        return label, names, colours

    def update(self, window: float, playing: bool = True) -> None:
        """The series over the last ``window`` seconds [s], ending at the exhibit's time (the
        moment shown); nothing is sent when nothing new is to be shown."""
        ex = self.exhibit
        scrubbed = getattr(ex, "scrubbed", None)
        key = (ex.model.trace.version, scrubbed, None if playing and scrubbed is None else ex.model.t,
               window, ex.model.config)  # fmt: skip
        if key == self.drawn:
            return
        self.drawn = key
        _, names, colours = self.series()
        variables = self._series[1]
        d = ex.model.sim.state.shape[1]
        rows = ex.model.trace.array()
        smp = Samples.from_rows(rows, d)
        keep = (
            smp.t < ex.model.t - 1e-9
        )  # scrubbed back: what came after the moment shown is not shown
        nan = np.array([math.nan])
        now = Samples(
            np.array([ex.model.t]), np.asarray(ex.model.state, float)[None, :d], nan, nan, nan
        )
        t = np.append(smp.t[keep], ex.model.t)
        with np.errstate(all="ignore"):
            ys = [
                np.append(variables[n].values(smp)[keep], variables[n].values(now)) for n in names
            ]
        t1 = max(ex.model.t, window)
        t0 = t1 - window
        inside = t >= t0 - 1e-9
        t, ys = t[inside], [y[inside] for y in ys]
        self.last_time = float(t[-1])
        self._axes_for(t0, t1, ys)
        ax0, ay0, ax1, ay1 = self.area
        lo, hi, _ = self.y_range
        x = ax0 + (t - t0) / (t1 - t0) * (ax1 - ax0)
        n = max(ex.model.trace.maxlen + 1, len(t))
        if self.data is None or self._capacity != n or self._colours != colours:
            self._make_data(n, colours)
        pts = np.empty((len(names), n - 1, 2, 3), np.float32)
        pts[..., 2] = 0.001 * max(self.size)  # just in front of the grid
        for j, y in enumerate(ys):
            yy = ay0 + (np.clip(np.nan_to_num(y, nan=lo), lo, hi) - lo) / (hi - lo) * (ay1 - ay0)
            # a fixed number of segments (the colours stay): the unused ones sit on the last point
            xs = np.concatenate([x, np.full(n - len(x), x[-1])])
            yy = np.concatenate([yy, np.full(n - len(yy), yy[-1])])
            pts[j, :, 0, 0], pts[j, :, 1, 0] = xs[:-1], xs[1:]
            pts[j, :, 0, 1], pts[j, :, 1, 1] = yy[:-1], yy[1:]
        self.data.points = pts.reshape(-1, 2, 3)

    def _make_data(self, n: int, colours) -> None:
        k = len(colours)
        cols = np.repeat(np.asarray(colours, np.uint8)[:, None, None, :], n - 1, axis=1)
        cols = np.broadcast_to(cols, (k, n - 1, 2, 3)).reshape(-1, 2, 3)
        self.data = geo.lines(
            self.exhibit.scene,
            f"{self.root}/data",
            np.zeros((k * (n - 1), 2, 3), np.float32),
            np.ascontiguousarray(cols),
            4.0,
        )
        self._capacity, self._colours = n, colours

    def _axes_for(self, t0: float, t1: float, ys) -> None:
        """The time's labels, and the values' range (kept while the series stays inside it
        and fills at least a third of it: the labels do not flicker)."""
        self.t_range = (t0, t1)
        for h, v in zip(self.x_ticks, (t0, t1), strict=True):
            h.text = f"{v:.0f}"
        finite = np.concatenate([y[np.isfinite(y)] for y in ys]) if ys else np.array([])
        lo, hi = (float(finite.min()), float(finite.max())) if finite.size else (-1.0, 1.0)
        if self.y_range is not None:
            c0, c1, _ = self.y_range
            if c0 <= lo and hi <= c1 and (hi - lo) >= (c1 - c0) / 3:
                return
        self.y_range = nice_range(lo, hi)
        r0, r1, step = self.y_range
        ticks = np.arange(r0, r1 + step / 2, step)
        ax0, ay0, ax1, ay1 = self.area
        ty = ay0 + (ticks - r0) / (r1 - r0) * (ay1 - ay0)
        line, pad = LINE_PX * self._label_m, PAD_PX * self._label_m
        # the least value on the time's row and the largest on the title's (a low plot shows
        # both); those between, centred on their ticks, where they clear both rows and each other
        keep = [0]
        for j in range(1, len(ticks) - 1):
            clear = ty[j] - line / 2 >= ay0 and ty[j] + line / 2 <= ay1
            if clear and ty[j] - ty[keep[-1]] >= 1.1 * line and ay1 - ty[j] >= 0.6 * line:
                keep.append(j)
        keep.append(len(ticks) - 1)
        places = {0: (ay0 - pad / 2, "top-right"), len(ticks) - 1: (ay1 + pad / 2, "bottom-right")}
        for k, h in enumerate(self.y_ticks):
            shown = k < len(keep)
            h.visible = shown
            if shown:
                j = keep[k]
                y, anchor = places.get(j, (float(ty[j]), "center-right"))
                h.text = tick_text(float(ticks[j]), step)
                h.anchor = anchor
                h.position = (ax0 - pad, y, 0.0)
        grid = [[(ax0, y, 0), (ax1, y, 0)] for y in ty]
        self.grid.points = np.array(grid, np.float32)

    # ------------------------------------------------------------------ measuring
    def time_of(self, x_local: float) -> float:
        """The time [s] at the panel's own ``x_local`` [m] (what a test reads off the points)."""
        ax0, _, ax1, _ = self.area
        t0, t1 = self.t_range
        return t0 + (x_local - ax0) / (ax1 - ax0) * (t1 - t0)

    def world_corners(self) -> np.ndarray:
        """The panel's four corners in the world [m] (for framing checks)."""
        rot = geo.matrix_from_quat(self.frame.wxyz)
        w, h = self.size
        local = np.array([(-w / 2, -h / 2, 0), (w / 2, -h / 2, 0), (w / 2, h / 2, 0),
                          (-w / 2, h / 2, 0)])  # fmt: skip
        return self.exhibit.origin + np.asarray(self.frame.position, float) + local @ rot.T
