"""What the viewer shows each browser: a home view of the three exhibits and one stage per
exhibit, framed for the page, with the exhibit's key figures on the stage itself
(:class:`Views`, a part of :class:`mechviz.viz.app.MechvizApp`).

*Home* shows the three exhibits together, their titles large, to choose one. An exhibit *on
stage* is alone: the others' scene nodes are hidden (their root frames ``visible = False``), its
title, key figures (measured against theory, time, energy error) and a "what you see" caption
stand in one label beside it, every label of the scene is :data:`STAGE_TEXT` times viser's
screen size, and the camera frames the exhibit as large as the page leaves room for: the
figures go in a column right of the exhibit or in a band above it, whichever lets the exhibit
be larger on that page (:meth:`Views.stage_view`). *Present* is a stage with the panel
minimized; a button and the Escape key leave it.

viser 1.1 draws a screen label at a size in CSS pixels that does not depend on the page: "Hg"
is :data:`LABEL_INK_PX` from the top of the H to the bottom of the g per unit of
``font_screen_scale`` (measured at 1280x800, 1920x1080 and 800x1000 in headless Chromium).
The page's CSS height is not reported (the camera's image size follows the browser's drawing
scale), so the stage's text is sized for a 1080-pixel page and is larger than 3 % on smaller ones.
"""

from __future__ import annotations

import math
import textwrap
import time

import numpy as np

from .app_commands import Present, Reframe
from .model.base import LOG_FLOOR
from .scene import EXHIBITS, framing
from .scene.stage_chart import StageChart, min_width

LABEL_INK_PX = 11.0  # px of "Hg" ink per unit of font_screen_scale (viser 1.1.1, any page)
TEXT_SHARE = 0.03  # of a page's height: the least any text of a stage is, on a 1080-px page
STAGE_TEXT = 3.0  # font_screen_scale on a stage: 33 px of ink, 3.06 % of 1080 px
HOME_TEXT = 1.0  # the labels other than the titles at home (the titles: TITLE_TEXT)
TITLE_TEXT = 1.6  # 18 px of ink: a name to choose by from across a room
LINE_PX = 14.5  # px a line of a label takes (text and box) per unit of scale (measured 14.2)
CHAR_PX = 5.6  # px a character of the figures takes, on average, per unit of scale (5.35)
COLUMN_CHARS = 20  # characters a line of the figures' column holds
GAP_PX = 16  # px between the exhibit and its figures
STAGE_FILL = 0.98  # of the height the figures leave, the exhibit's box at most
STAGE_SHARE = 0.76  # of the page's height an exhibit on stage should fill (75 % and a margin),
STAGE_WIDTH = 0.91  # or of the width the panel leaves, when its shape is wide
# the places of the stage's words and chart, in the order of preference ("words-chart"): a
# band above the exhibit and the chart right of it, a column right of the exhibit with the
# chart under the words, a band above and the chart below, the words and the chart side by
# side above the exhibit; with the caption, then without it (the panel's readout explains more)
LAYOUTS = ("band-right", "column-under", "band-below", "split-top")
LAYOUTS = (*LAYOUTS, *(f"{layout}-short" for layout in LAYOUTS))
CHART_MIN = (300, 170)  # CSS px: the least the chart takes (its labels are the stage's size)
BAR_PX = 60  # CSS px: the height of a minimized panel's title bar, at the page's top right
CHART_ASPECT = (0.3, 1.8)  # height / width of the chart's rectangle, least and most
NARROW = 0.6  # a page whose panel would leave less than this share of its width free has the
# panel minimized on stage (the panel's button opens it over the scene)
PANEL_PX = framing.PANEL_PX  # px of the page's right edge the GUI panel covers
FILL = STAGE_FILL  # the exhibits' presets are their stages
# the direction the home view looks in: from the front left, 36 degrees above the floor
OVERVIEW = ((-2.42, -6.0, 4.7), (0.0, 0.0, 0.0))
OVERVIEW_FILL = 0.9  # of the page's height the three exhibits' pictures span at home
VIEWS = {cls.model_type.name: key for key, cls in EXHIBITS.items()}  # stage name -> exhibit
HOME = "Home"


def log_axis(series) -> tuple[float, float]:
    """The error chart's y range [decades] for ``series`` of log10 values: whole decades from
    below the least to above the largest finite value (at least two decades; the floor where
    an error is exactly 0), so the lines fill the chart whatever their size."""
    values = np.concatenate([np.asarray(y, float) for y in series]) if len(series) else []
    values = values[np.isfinite(values)] if len(values) else values
    if not len(values):
        return (LOG_FLOOR, 2.0)
    lo, hi = math.floor(values.min()) - 0.5, math.ceil(values.max()) + 0.5
    if hi - lo < 2.0:
        lo, hi = (lo + hi) / 2 - 1.0, (lo + hi) / 2 + 1.0
    return (max(lo, LOG_FLOOR - 0.5), hi)


def camera_reported(client) -> bool:
    try:
        return client.camera.update_timestamp > 0
    except AssertionError:  # viser: not yet
        return False


def page_size(client) -> tuple[int, int]:
    """The client's page as the framing takes it: its shape, scaled to 800 pixels high (1280 x
    800 until the client has reported its camera). viser reports the size the page is drawn at,
    which the browser lowers when frames are slow and raises on a dense screen, while the GUI
    panel keeps its width in CSS pixels; a page is rarely less than 800 CSS pixels high, so the
    panel's share of the width is taken no smaller than it is."""
    try:
        w, h = client.camera.image_width, client.camera.image_height
    except AssertionError:  # viser: the client has not reported its camera yet
        return (1280, 800)
    return (round(800 * w / h), 800) if w and h else (1280, 800)


def css_scale(client) -> float:
    """Page pixels (as :func:`page_size` takes the page, 800 high) per CSS pixel, for what
    keeps its size in CSS pixels (the panel, the labels): 800 over the height the client
    reports, taken between 800 and 1080 (a dense screen reports more pixels than it has CSS
    pixels, and a browser drawing slowly fewer: both err towards more room for the words)."""
    try:
        h = client.camera.image_height
    except AssertionError:  # not reported yet
        return 1.0
    return 800.0 / min(max(float(h or 800), 800.0), 1080.0)


def _tidy(rect, middle: float) -> tuple[float, float, float, float]:
    """``rect`` ``(x0, y0, x1, y1)`` [px] no taller than :data:`CHART_ASPECT` allows (centred
    on ``middle``, the exhibit's, as far as it can be) and no wider (kept at its left)."""
    x0, y0, x1, y1 = rect
    w, h = x1 - x0, y1 - y0
    if h > CHART_ASPECT[1] * w:
        c = min(max(middle, y0 + CHART_ASPECT[1] * w / 2), y1 - CHART_ASPECT[1] * w / 2)
        y0, y1 = c - CHART_ASPECT[1] * w / 2, c + CHART_ASPECT[1] * w / 2
    if h < CHART_ASPECT[0] * w:
        x1 = x0 + h / CHART_ASPECT[0]
    return (float(x0), float(y0), float(x1), float(y1))


def wrap(parts: list[str], chars: int) -> list[str]:
    """``parts`` joined with wide spaces into lines of at most ``chars`` characters (a part
    longer than that is a line of its own)."""
    lines: list[str] = []
    for part in parts:
        if lines and len(lines[-1]) + 3 + len(part) <= chars:
            lines[-1] += "   " + part
        else:
            lines.append(part)
    return lines


def label_px(text: str, scale: float) -> tuple[float, float]:
    """Width and height [px] a label of ``text`` takes at ``scale``."""
    lines = text.split("\n")
    return scale * (CHAR_PX * max(len(t) for t in lines) + 6), scale * LINE_PX * len(lines)


# The floor grid of each theme (plane, cells, sections): quiet against the theme's background.
GRIDS = {
    "light": ((255, 255, 255), (200, 200, 200), (140, 140, 140)),
    "dark": ((33, 34, 38), (62, 64, 70), (100, 102, 110)),
}


class Views:
    """The app's home view, stages and presentation mode (mixed into
    :class:`mechviz.viz.app.MechvizApp`, whose ``exhibits``, ``server``, ``stage``,
    ``presenting`` and ``theme`` they use)."""

    def scene_nodes(self) -> dict:
        """Name -> handle of every node the viewer keeps: each exhibit's (its
        :class:`mechviz.viz.scene.base.NodeBook`; trail pieces are not kept) and the stage's
        words. Public viser API only: the handles as they were made."""
        nodes = {"/stage/words": self.stage_label}
        for ex in self.exhibits.values():
            nodes.update(ex.scene.handles)
        return nodes

    # ------------------------------------------------------------------ clients
    def _frame_new_client(self, client) -> None:
        """Frame the view in force for the page of a client that has just connected, once it
        has reported its size, and again whenever the page changes shape (a resize)."""
        deadline = time.monotonic() + 10.0
        while time.monotonic() < deadline and not camera_reported(client):
            if self._stop.wait(0.1):
                return
        shapes = self._page_shapes
        shapes[client.client_id] = page_size(client)

        @client.camera.on_update
        def _(_camera) -> None:
            size = page_size(client)
            if shapes.get(client.client_id) != size:
                shapes[client.client_id] = size
                self.enqueue("app", Reframe(client))

        self.enqueue("app", Reframe(client))

    # ------------------------------------------------------------------ cameras
    def camera_preset(
        self, view: str, width: int = 1280, height: int = 800, panel_px: int = PANEL_PX
    ):
        """``(position, look_at)`` of a view for a page of ``width`` x ``height`` pixels whose
        right ``panel_px`` the GUI panel covers (:func:`mechviz.viz.scene.framing.frame`):
        *Home* (or *All*) frames the three together as large as the page allows; an exhibit's
        name, its stage (:meth:`stage_view`); *Top* looks straight down on the exhibit on
        stage (at home, on the cyclotron's orbit)."""
        if view in (HOME, "All"):  # the three boxes' own corners: their pictures
            corners = np.concatenate(
                [framing.corners(*ex.home_bounds) for ex in self.exhibits.values()]
            )
            direction = np.subtract(OVERVIEW[1], OVERVIEW[0])
            return framing.frame_points(
                corners, direction, width, height, fill=OVERVIEW_FILL, panel_px=panel_px
            )
        if view == "Top":  # on the exhibit on stage (at home: the cyclotron's orbit)
            # at home: the first exhibit's (in the registry's order)
            lo, hi = self.exhibits[self.stage or next(iter(self.exhibits))].bounds
            return framing.frame(
                lo, hi, (0.0, 0.01, -1.0), width, height, fill=FILL, panel_px=panel_px
            )
        position, target, *_ = self.stage_view(VIEWS[view], width, height, panel_px)
        return position, target

    def stage_view(
        self,
        key: str,
        width: int = 1280,
        height: int = 800,
        panel_px: float = PANEL_PX,
        px: float = 1.0,
        bar_px: float | None = None,
    ):
        """``(position, look_at, words, chart)`` of ``key``'s stage on a page of ``width`` x
        ``height`` px whose right ``panel_px`` the panel covers. ``words`` places the label of
        the title, figures and caption: ``(text, page point (x, y) [px], anchor, layout,
        width [CSS px] its lines may take)``; ``chart`` is the page rectangle ``(x0, y0, x1,
        y1)`` [px] of the exhibit's chart (:mod:`mechviz.viz.scene.stage_chart`). The words go
        in a band above the exhibit, a column right of it, or the left of a band whose right
        holds the chart; the chart right of the exhibit, below it, or below the words'
        column (:data:`LAYOUTS`). The first layout in which the exhibit fills
        :data:`STAGE_SHARE` of the height or :data:`STAGE_WIDTH` of the free width, the chart
        at least :data:`CHART_MIN` CSS px, is taken; failing that, one where the exhibit
        fits (its chart then smaller), else one whose chart has its least size, the exhibit
        largest. ``px``: page pixels per CSS pixel of the labels (:func:`css_scale`);
        ``bar_px``: page pixels on the right the words keep clear of (the panel's width by
        default: a minimized panel keeps its title bar at the top right, where the band of
        words runs)."""
        ex = self.exhibits[key]
        lo, hi = ex.bounds
        position, target = ex.camera
        direction = np.subtract(target, position)
        free = float(max(width - panel_px, 1))
        across = float(max(width - (panel_px if bar_px is None else bar_px), 1))  # the words' width
        # a low chart (above or below the exhibit) at least as wide as its y axis's title on
        # one line: two lines would leave its plot no height
        title = min_width(ex.stage_plot()[0], STAGE_TEXT)
        ch = CHART_MIN[1] * px
        gap, H = GAP_PX * px, float(height)
        best = None
        for layout in LAYOUTS:
            words_at, chart_at = layout.split("-")[:2]
            short = layout.endswith("-short")
            low = chart_at in ("top", "below")
            # under words and chart side by side the region's top has its margin: all of it
            fill = 1.0 if words_at == "split" else STAGE_FILL
            cw = max(CHART_MIN[0], title if low else 0.0) * px
            m = 4.0 * px  # the page's edge kept clear
            if words_at == "split":  # the words left, the chart right, above the exhibit
                words_w = min(across - m, free - cw - gap)
                free_css = words_w / px
            else:
                free_css = across / px
            text = self._stage_text(key, words_at + ("-short" if short else ""), free_css)
            w, h = (px * v for v in label_px(text, STAGE_TEXT))
            top = min(h + gap, 0.5 * H)
            if words_at == "column":
                col = max(w, cw)
                region = (0.0, 0.0, max(free - col - gap, 0.3 * free), H)
            elif words_at == "split":  # the chart from the page's top edge down (below a
                # minimized panel's title bar, if it reaches under it)
                chart_top = 2.0 if free - m <= across + 1 else BAR_PX * px
                # the words' height as the layout checks take it (a line 16 px a unit)
                top = min(max(h * 16.0 / LINE_PX, chart_top + ch) + gap / 2, 0.5 * H)
                region = (0.0, top, free, H)
            elif chart_at == "right":
                region = (0.0, top, max(free - cw - gap, 0.3 * free), H)
            else:  # the chart below the exhibit
                region = (0.0, top, free, max(H - max(ch, 0.25 * H) - gap, top + 0.3 * H))
            pos, look = framing.frame(lo, hi, direction, width, height, fill=fill, region=region)
            share, x0, x1, y0, y1 = framing.share(lo, hi, pos, look, width, height)
            if words_at == "column":
                wx = min(x1 + gap, region[2] + gap)
                words = (text, (wx, max(y0, 4.0)), "top-left")
                chart = (wx, max(y0, 4.0) + h + gap, free - m, H - m)
            elif words_at == "split":
                # down to the exhibit's picture (a wide one leaves room under the words)
                bottom = max(top, y0) - gap / 2
                if chart_top < BAR_PX * px:  # the panel open: the chart left, the words right
                    # (text runs on to the right, where the panel's edge is, never into the chart)
                    words = (text, (free - m - w, 4.0), "top-left")
                    chart = (m, chart_top, free - m - w - gap / 2, bottom)
                else:  # the words left, the chart right, under the minimized panel's bar
                    words = (text, (m, 4.0), "top-left")
                    chart = (m + w + gap / 2, chart_top, free - m, bottom)
            elif chart_at == "right":
                words = (text, (across / 2, 4.0), "top-center")
                chart = (x1 + gap, top, free - m, H - m)
            else:
                words = (text, (across / 2, 4.0), "top-center")
                chart = (m, y1 + gap, free - m, H - m)
            chart = _tidy(chart, (y0 + y1) / 2)
            fits = share >= STAGE_SHARE or (x1 - x0) >= STAGE_WIDTH * free
            roomy = chart[2] - chart[0] >= cw - 1 and chart[3] - chart[1] >= ch - 1
            size = max(share / STAGE_SHARE, (x1 - x0) / (STAGE_WIDTH * free))
            result = (pos, look, (*words, layout, free_css), chart)
            if fits and roomy:  # the first layout (in the order of preference) that fits
                return result
            # none both: the exhibit keeping its figure comes first (it is what the stage is
            # for; a slow page reports fewer pixels and its words then take more room), then
            # a chart of its full size, then the larger exhibit
            rank = (fits, roomy, size)
            if best is None or rank > best[0]:
                best = (rank, result)
        return best[1]

    def _stage_text(self, key: str, layout: str, free_px: float) -> str:
        """The words of ``key``'s stage: title, key figures and (``layout`` not ending in
        ``-short``) the caption, wrapped for ``layout``: a narrow column, or a band across the
        ``free_px`` the panel leaves."""
        ex = self.exhibits[key]
        figures = []
        for name, value in ex.key_figures():
            shown, _, theory = value.partition(" (theory ")
            # a figure not measured yet: short, so the words keep their lines (the panel's
            # readout says "not resolved")
            shown = "…" if shown == "not resolved" else shown
            figures.append((f"{name} {shown}", f"  theory {theory[:-1]}" if theory else ""))
        headline = (
            ex.model.title if layout.endswith("-short") else f"{ex.model.title}: {ex.caption}"
        )
        if layout.startswith("column"):
            lines = textwrap.wrap(headline, COLUMN_CHARS)
            for figure, theory in figures:
                lines += [figure] + ([theory] if theory else [])
            return "\n".join(lines)
        chars = max(int(free_px / (CHAR_PX * STAGE_TEXT)) - 1, COLUMN_CHARS)
        parts = []
        for f, t in figures:  # a figure too long for a line: its theory on the next
            whole = f"{f} ({t.strip()})" if t else f
            parts += [whole] if len(whole) <= chars else [f, f"({t.strip()})"]
        if layout.endswith("-short"):  # the title shares its line with the figures
            return "\n".join(wrap([headline, *parts], chars))
        return "\n".join([*textwrap.wrap(headline, chars), *wrap(parts, chars)])

    def _move_camera(self, client, view: str) -> None:
        """Move the camera of ``client`` (all clients if None) to ``view`` framed for its page
        (the panel's width left free unless it is minimized for presenting)."""
        clients = [client] if client is not None else list(self.server.get_clients().values())
        if not clients and view in VIEWS:  # no page yet: the words where a 1280 x 800 one has them
            position, target, words, chart = self.stage_view(VIEWS[view])
            self._place_words(words, position, target, (1280, 800))
            self._place_chart(VIEWS[view], chart, position, target, (1280, 800), 1.0)
        for c in clients:
            size, px = page_size(c), css_scale(c)
            panel = 0 if self.presenting else PANEL_PX * px
            if view in VIEWS and size[0] - panel < NARROW * size[0]:
                panel = 0  # a narrow page: the exhibit takes it all, the panel minimized
                c.gui.main_panel.minimize()
            if view in VIEWS:
                bar = PANEL_PX * px  # minimized, the panel keeps its bar at the top right
                position, target, words, chart = self.stage_view(
                    VIEWS[view], *size, panel_px=panel, px=px, bar_px=bar
                )
                self._place_words(words, position, target, size)
                self._place_chart(VIEWS[view], chart, position, target, size, px)
            else:
                position, target = self.camera_preset(view, *size, panel_px=panel)
            self.framed[c.client_id] = (position, target)
            with c.atomic():
                c.camera.position = position
                c.camera.look_at = target
                c.camera.up_direction = (0.0, 0.0, 1.0)

    def _place_words(self, words, position, target, size) -> None:
        """Put the stage's label where ``words`` says, for the camera ``position`` looking at
        ``target`` on a page of ``size``: on the plane through the point looked at, facing
        the camera (viser draws labels over the scene, so the depth only sets the point)."""
        text, (x, y), anchor, layout, self._words_free = words
        self._stage_layout = layout.split("-")[0] + ("-short" if layout.endswith("-short") else "")
        w, h = size
        f, r, u = framing.basis(position, target)
        depth = float(np.dot(np.subtract(target, position), f))
        t = math.tan(framing.FOV / 2)
        nx, ny = 2 * x / w - 1, 1 - 2 * y / h
        ray = f + r * nx * t * w / h + u * ny * t
        self.stage_label.position = tuple(np.asarray(position, float) + depth * ray)
        self.stage_label.anchor = anchor
        self.stage_label.text = text
        self._stage_words = words

    def _place_chart(self, key, rect, position, target, size, px: float) -> None:
        """Stand ``key``'s chart in the page rectangle ``rect`` the stage left it, drawn anew."""
        chart = self.charts[key]
        chart.place(position, target, rect, size, px)
        self.chart_rects[key] = rect
        self._framed_bounds = self.exhibits[key].bounds
        chart.update(self.chart_window, self.playing)

    def _draw_stage_chart(self) -> None:
        """A frame's part of the stage: the chart on stage follows its exhibit (one node
        update, only when there is something new); an exhibit whose box changed on stage
        (the disk released: Poinsot's construction beside it) is framed again."""
        if self.stage is None:
            return
        ex = self.exhibits[self.stage]
        bounds = ex.bounds
        framed = getattr(self, "_framed_bounds", None)
        if framed is not None and not all(
            np.allclose(a, b) for a, b in zip(bounds, framed, strict=True)
        ):
            self._framed_bounds = bounds
            self.enqueue("app", Reframe())
        self.charts[self.stage].update(self.chart_window, self.playing)

    # ------------------------------------------------------------------ the stage
    def _build_stage(self) -> None:
        """The stage's one label (title, key figures, caption), hidden at home."""
        self.stage_label = self.server.scene.add_label(
            "/stage/words",
            "",
            font_size_mode="screen",
            font_screen_scale=STAGE_TEXT,
            anchor="top-left",
            visible=False,
        )
        self._stage_words = None
        self._stage_layout = "band"
        self._words_free = 940.0  # CSS px across the page the words' lines may take
        # each exhibit's chart on its stage (under its root: it hides with the exhibit)
        self.charts = {key: StageChart(ex, STAGE_TEXT) for key, ex in self.exhibits.items()}
        self.chart_rects: dict[str, tuple] = {}  # key -> page rectangle [px] last placed in
        self.framed: dict[int, tuple] = {}  # client id -> (position, look_at) last framed for it
        self._show_stage()

    def _set_stage(self, view, client=None) -> None:
        """Put ``view`` (an exhibit's name, or *Home*) on stage for every page."""
        if view not in (HOME, "All", *VIEWS):
            raise ValueError(f"Stage must be {HOME} or one of {', '.join(VIEWS)}, got {view!r}")
        self.stage = VIEWS.get(view)
        if self.stage is None:
            self.presenting = None
        elif self.presenting is not None:
            self.presenting = self.stage
        self._show_stage()
        self._configure_page()
        self._move_camera(None, HOME if self.stage is None else view)
        self._show_figures()

    def _present(self, view, client=None) -> None:
        """Presentation mode: ``view`` (an exhibit's name) on stage with the panel minimized;
        ``"Off"`` goes back home with the panel open."""
        if view not in ("Off", *VIEWS):
            raise ValueError(f"Present must be Off or one of {', '.join(VIEWS)}, got {view!r}")
        self.presenting = None if view == "Off" else VIEWS[view]
        self._set_stage(HOME if view == "Off" else view, client)

    def _show_stage(self) -> None:
        """Nodes and label sizes for the view in force: at home every exhibit, its title
        large and its other labels small; on stage the one exhibit and every label large."""
        for key, ex in self.exhibits.items():
            on = self.stage in (None, key)
            ex.nodes[ex.root].visible = on
            scale = STAGE_TEXT if self.stage == key else HOME_TEXT
            ex.scene.label_scale = scale
            for h in ex.labels():
                h.font_screen_scale = TITLE_TEXT if h is ex.label and self.stage is None else scale
            ex.label.visible = self.stage is None  # on stage the title is in the stage's words
            for h in ex.stage_labels():
                h.visible = self.stage == key
            self.charts[key].visible = self.stage == key
            ex.on_stage(self.stage == key)
        self.stage_label.visible = self.stage is not None
        if "stage" in getattr(self, "w", {}):
            shown = HOME if self.stage is None else self.exhibits[self.stage].model.name
            if self.w["stage"].value != shown:
                self._syncing = True
                self.w["stage"].value = shown
                self._syncing = False
        if "present" in getattr(self, "w", {}):
            shown = "Off" if self.presenting is None else self.exhibits[self.presenting].model.name
            if self.w["present"].value != shown:
                self._syncing = True
                self.w["present"].value = shown
                self._syncing = False
        leave = getattr(self, "leave_panel", None)
        if leave is not None:
            leave.visible = self.presenting is not None

    def _show_figures(self) -> None:
        """The stage's words anew (the figures move on), where the framing put them."""
        if self.stage is None:
            return
        self.stage_label.text = self._stage_text(self.stage, self._stage_layout, self._words_free)

    def _build_leave(self) -> None:
        """The ways out of presentation mode: the Escape key (a command of viser's palette with
        that hotkey) and a button in a small panel floating at the page's bottom left, shown
        only while presenting (the main panel is minimized then)."""
        viser, gui = self._viser, self.gui

        def leave(_event) -> None:
            if self.presenting is not None:
                self.enqueue("app", Present("Off"))

        gui.add_command(
            "Leave presentation", description="Back home, the panel open", hotkey="escape"
        ).on_trigger(leave)
        self.leave_panel = gui.add_panel(visible=False)
        with self.leave_panel.add_tab("Presenting"):
            self.w["leave"] = gui.add_button(
                "Leave presentation (Esc)", icon=viser.Icon.X, hint="Back home, the panel open"
            )
        self.w["leave"].on_click(leave)
        self.leave_panel.float(x=15, y=-15)

    # ------------------------------------------------------------------ the page
    def _apply_theme(self, theme: str) -> None:
        """Page and floor for ``theme``; the scene's palette reads on both (mechviz.viz.geometry)."""
        self.theme = theme
        if "theme" in getattr(self, "w", {}) and self.w["theme"].value != theme:
            with self.quiet():
                self.w["theme"].value = theme
        self.grid.plane_color, self.grid.cell_color, self.grid.section_color = GRIDS[theme]
        self._show_figures()
        self._configure_page()

    def _configure_page(self) -> None:
        """The page's theme; while presenting, the panel minimized (its button brings it back).
        viser's share button only for developers (``mechviz view --dev``)."""
        if self.gui is not None:
            self.gui.configure_theme(
                control_width="medium",
                show_logo=False,
                show_share_button=self.dev,
                brand_color=(40, 110, 200),
                dark_mode=self.theme == "dark",
            )
            if self.presenting:
                self.gui.main_panel.minimize()
            else:
                self.gui.main_panel.expand()
