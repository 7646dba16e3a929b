"""Any variable against any other: the quantities an exhibit can plot, and one drawn against
another with the exact curves of the system's theory beside the motion.

One path for the live viewer and the recordings. An exhibit's model names its quantities
(:meth:`mechviz.viz.model.base.ExhibitModel.plot_variables`: state, energy, errors and the quantities its
theory is told in, such as the charge's ``r`` and ``V_eff`` or the hoop's modal coordinates),
each computed from :class:`Samples` of a run; and the exact curves that go with a pair
(:meth:`~mechviz.viz.model.base.ExhibitModel.plot_curves`: the well ``V_eff(r)``, the mode-1 pendulum's
separatrix, the mode lines of configuration space). The live panel draws the main run's samples
over the chart window into an image (:class:`PlotImage`); a recording writes the same quantities
as CSV columns and draws the exhibit's pictures (``ExhibitModel.pictures``) in its PNG, both with
:func:`draw_xy`.

uPlot, viser's chart, needs an x that only grows (time); a path in a plane does not, hence
matplotlib here.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

# Colours that read on a light and on a dark page alike (the panel follows the theme).
PATH_COLOUR = "#2f6fde"
POINT_COLOUR = "#e8432a"
CURVE_COLOURS = ("#8e44c9", "#7f7f7f", "#d08a00", "#1a9e77")


@dataclass(frozen=True)
class Samples:
    """Samples of one run (one member of an ensemble), oldest first: times ``t`` [s] (K,),
    ``states`` (K, d), ``energy`` [J], ``energy_error`` (relative, see :mod:`mechviz.dynamics.simulation`)
    and ``error`` (relative, NaN where nothing is measured), each (K,)."""

    t: np.ndarray
    states: np.ndarray
    energy: np.ndarray
    energy_error: np.ndarray
    error: np.ndarray

    def __len__(self) -> int:
        return len(self.t)

    @classmethod
    def from_rows(cls, rows: np.ndarray, d: int) -> Samples:
        """From rows ``[t, state (d), energy, energy_error, error]`` (the live trace)."""
        rows = np.asarray(rows, dtype=float).reshape(-1, d + 4)
        return cls(rows[:, 0], rows[:, 1 : 1 + d], rows[:, 1 + d], rows[:, 2 + d], rows[:, 3 + d])


@dataclass(frozen=True)
class Variable:
    """A quantity to plot: its axis label (with the unit) and how to compute it from samples."""

    label: str
    values: Callable[[Samples], np.ndarray]


@dataclass(frozen=True)
class Curve:
    """An exact curve drawn with the motion: points ``x``, ``y`` and what it is (the legend)."""

    x: np.ndarray
    y: np.ndarray
    label: str
    dashed: bool = False
    kw: dict = field(default_factory=dict)
    #: ``((x0, x1), (y0, y1))`` the axes must show whatever the motion does (a well, from
    #: :func:`well_axes`); the curve's points outside them are cut off.
    axes: tuple[tuple[float, float], tuple[float, float]] | None = None


def well_axes(
    r_max: float, level: float, floor: float = 0.0
) -> tuple[tuple[float, float], tuple[float, float]]:
    """The axes that show a particle's radial well ``V(r)`` whole at the level ``E`` [J]: ``r``
    from 0 to twice the outer turning point ``r_max`` [m], ``V`` from ``floor`` (the
    least the well can be, 0 for the cyclotron's square) to twice the level. The walls cross
    the level at the turning points, so they show whether ``r`` swings between them or stays
    put at the bottom (a circle centred on the axis: then the path is one point and the
    well's own shape is all there is to scale by)."""
    r1 = 2.0 * r_max if r_max > 0 else 1.0
    top = floor + 2.0 * (level - floor) if level > floor else floor + 1.0
    return (0.0, r1), (floor, top)


def common_variables(state_labels: dict[str, str]) -> dict[str, Variable]:
    """Time, the state's components (``state_labels``: name -> label, in state order), energy
    and the two errors: the quantities every exhibit can plot."""
    out = {"t": Variable("t [s]", lambda s: s.t)}
    for j, (name, label) in enumerate(state_labels.items()):
        out[name] = Variable(label, lambda s, j=j: s.states[:, j])
    out["energy"] = Variable("energy E [J]", lambda s: s.energy)
    out["energy_error"] = Variable("relative energy error", lambda s: s.energy_error)
    out["error"] = Variable("relative error", lambda s: s.error)
    return out


def draw_xy(
    ax,
    variables: dict[str, Variable],
    x: str,
    y: str,
    samples: Samples,
    curves: Sequence[Curve] = (),
    *,
    path_label: str = "motion",
    legend: bool = True,
) -> list:
    """Draw ``y`` against ``x`` of ``samples`` on the matplotlib axes ``ax``: the path, its
    newest point, and ``curves``; the axes' limits from :func:`limits`. Returns the data's
    artists: one line per curve, then the path and the point."""
    xs, ys = _finite(variables, x, y, samples)
    artists = []
    for k, c in enumerate(curves):
        # solid curves under the path (it runs on them), dashed ones over it (both show)
        style = {
            "color": CURVE_COLOURS[k % len(CURVE_COLOURS)],
            "lw": 1.3,
            "ls": "--" if c.dashed else "-",
            "zorder": 3 if c.dashed else 1,
            **c.kw,
        }
        artists += ax.plot(c.x, c.y, label=c.label, **style)
    artists += ax.plot(xs, ys, color=PATH_COLOUR, lw=1.2, label=path_label, zorder=2)
    artists += ax.plot(xs[-1:], ys[-1:], "o", color=POINT_COLOUR, ms=5, zorder=4)
    ax.set_xlabel(variables[x].label)
    ax.set_ylabel(variables[y].label)
    lims = limits(xs, ys, curves)
    if lims is not None:
        ax.set_xlim(*lims[0])
        ax.set_ylim(*lims[1])
    ax.grid(True, lw=0.4, alpha=0.5)
    if legend and (curves or path_label):
        # below the axes, not over the path: the figure's constrained layout makes room
        ax.legend(
            handles=artists[:-1],
            fontsize=7,
            loc="upper center",
            bbox_to_anchor=(0.5, -0.2),
            ncols=2 if len(artists) > 3 else 1,
            frameon=False,
            handlelength=1.4,
            columnspacing=0.8,
        )
    return artists


def _finite(variables, x: str, y: str, samples: Samples) -> tuple[np.ndarray, np.ndarray]:
    with np.errstate(all="ignore"):
        xs, ys = variables[x].values(samples), variables[y].values(samples)
    keep = np.isfinite(xs) & np.isfinite(ys)
    return xs[keep], ys[keep]


def limits(xs: np.ndarray, ys: np.ndarray, curves: Sequence[Curve]):
    """``((x0, x1), (y0, y1))``: the path with a margin, widened to the curves' points within
    twice its span (so the separatrix shows around a small swing, but a well's walls at infinity
    do not) and to the axes a curve asks for (:attr:`Curve.axes`: the whole well, also when the
    path is a point); ``None`` without a path."""
    if len(xs) == 0:
        return None
    lo, hi = np.array([xs.min(), ys.min()]), np.array([xs.max(), ys.max()])
    span = np.maximum(hi - lo, 1e-9 * np.maximum(1.0, np.abs(hi)))
    near_lo, near_hi = lo - 2 * span, hi + 2 * span
    for c in curves:
        pts = np.column_stack([c.x, c.y])
        pts = pts[np.all(np.isfinite(pts), axis=1)]
        pts = pts[np.all((pts >= near_lo) & (pts <= near_hi), axis=1)]
        if len(pts):
            lo, hi = np.minimum(lo, pts.min(axis=0)), np.maximum(hi, pts.max(axis=0))
    pad = 0.06 * np.maximum(hi - lo, span)
    lo, hi = lo - pad, hi + pad
    for c in curves:  # the axes a curve must be seen in, around the path
        if c.axes is not None:
            (x0, x1), (y0, y1) = c.axes
            lo, hi = np.minimum(lo, (x0, y0)), np.maximum(hi, (x1, y1))
    return (lo[0], hi[0]), (lo[1], hi[1])


def _holds(current, wanted) -> bool:
    """Whether the axes' ``current`` limits still frame ``wanted`` well: they contain it and
    are at most twice as wide on each axis (so a steady motion keeps its axes)."""
    for (c0, c1), (w0, w1) in zip(current, wanted, strict=True):
        if w0 < c0 or w1 > c1 or (c1 - c0) > 2.0 * (w1 - w0):
            return False
    return True


class PlotImage:
    """One matplotlib figure drawn into an RGB array for a viser GUI image.

    Drawing the axes (ticks, labels, legend) costs 20-40 ms; the data alone about 1 ms. So the
    axes are drawn once per pair and whenever the motion outgrows them (with room to spare,
    :func:`_holds`), kept as a background, and each update restores it and draws the data's
    artists over it (matplotlib's blitting)."""

    # The panel shows the image about 280 px wide: drawn at twice that, it stays sharp on a
    # high-density screen and its 8-point text reads at 11 px.
    def __init__(self, width_px: int = 560, height_px: int = 500, dpi: int = 200) -> None:
        import matplotlib

        matplotlib.use("Agg", force=False)
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        self.fig = Figure(figsize=(width_px / dpi, height_px / dpi), dpi=dpi, layout="constrained")
        self.canvas = FigureCanvasAgg(self.fig)
        self.ax = self.fig.add_subplot()
        self._key = None  # what the background shows: the pair, the curves, the theme
        self._artists: list = []
        self._background = None
        self.full_draws = 0  # how often the axes were drawn (for tests)

    def render(self, dark: bool = False, **draw) -> np.ndarray:
        """:func:`draw_xy` with ``draw``'s arguments, as an (H, W, 3) uint8 image."""
        curves = draw.get("curves", ())
        key = (draw["x"], draw["y"], tuple(c.label for c in curves), draw.get("path_label"), dark)
        xs, ys = _finite(draw["variables"], draw["x"], draw["y"], draw["samples"])
        if key != self._key:
            self._redraw(dark, draw)
            self._key = key
        else:
            for artist, c in zip(self._artists, curves, strict=False):
                artist.set_data(c.x, c.y)
            self._artists[-2].set_data(xs, ys)
            self._artists[-1].set_data(xs[-1:], ys[-1:])
            wanted = limits(xs, ys, curves)
            current = (self.ax.get_xlim(), self.ax.get_ylim())
            if wanted is not None and not _holds(current, wanted):
                # outgrown (or far too wide): new axes, with room for the motion to grow
                (x0, x1), (y0, y1) = wanted
                mx, my = 0.15 * (x1 - x0), 0.15 * (y1 - y0)
                self.ax.set_xlim(x0 - mx, x1 + mx)
                self.ax.set_ylim(y0 - my, y1 + my)
                self._draw_background()
            else:
                self.canvas.restore_region(self._background)
        for artist in sorted(self._artists, key=lambda a: a.get_zorder()):
            self.ax.draw_artist(artist)
        return np.asarray(self.canvas.buffer_rgba())[..., :3].copy()

    def _redraw(self, dark: bool, draw: dict) -> None:
        self.ax.clear()
        face, ink = ("#1f2023", "#d0d0d0") if dark else ("#ffffff", "#222222")
        self.fig.set_facecolor(face)
        self.ax.set_facecolor(face)
        for spine in self.ax.spines.values():
            spine.set_color(ink)
        self.ax.tick_params(colors=ink, labelsize=7)
        self._artists = draw_xy(self.ax, **draw)
        legend = self.ax.get_legend()
        if legend is not None:
            for text in legend.get_texts():
                text.set_color(ink)
        self.ax.xaxis.label.set_color(ink)
        self.ax.yaxis.label.set_color(ink)
        self.ax.xaxis.label.set_fontsize(8)
        self.ax.yaxis.label.set_fontsize(8)
        for artist in self._artists:  # after the legend, which copies its handles' properties
            artist.set_animated(True)
        self._draw_background()

    def _draw_background(self) -> None:
        self.canvas.draw()  # everything but the animated data
        self._background = self.canvas.copy_from_bbox(self.fig.bbox)
        self.full_draws += 1
