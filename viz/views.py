"""What the viewer shows each browser: camera presets framed for its page, presentation mode
with its key figures, and the error chart's fitted axis (:class:`Views`, a part of
:class:`mechviz.viz.app.MechvizApp`)."""

from __future__ import annotations

import math
import time

import numpy as np

from .model.base import LOG_FLOOR
from .scene import EXHIBITS, CyclotronExhibit, framing

PRESENT_TEXT = 1.6  # label size in presentation mode, times the usual
FIGURE_SCALE = 2.8  # presentation mode's key figures: 2.8 x 12 px text on an 800 px page
FIGURES_SHARE = 0.38  # of the page's width kept for them, right of the presented exhibit
PANEL_PX = framing.PANEL_PX  # px of the page's right edge the GUI panel covers
FILL = 0.72  # of the page's height an exhibit's box takes in its own view
PRESENT_FILL = 0.8  # the same in presentation mode (the panel collapsed)
# the direction the first view looks in: from the front left, 36 degrees above the floor (any
# steeper and the driven disk's L label passes over its ω label)
OVERVIEW = ((-2.42, -6.0, 4.7), (0.0, 0.0, 0.0))
OVERVIEW_FILL = 0.9  # of the page's height the three exhibits' pictures span in the first view
VIEWS = {cls.name: key for key, cls in EXHIBITS.items()}  # camera preset -> exhibit


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


class Views:
    """The app's camera presets and presentation mode (mixed into :class:`mechviz.viz.app.MechvizApp`,
    whose ``exhibits``, ``server``, ``figures``, ``presenting`` and ``theme`` they use)."""

    def _frame_new_client(self, client) -> None:
        """Frame the first view for the page of a client that has just connected, once it has
        reported its size (the initial camera is framed for 1280 x 800)."""
        deadline = time.monotonic() + 10.0
        while time.monotonic() < deadline and not camera_reported(client):
            if self._stop.wait(0.1):
                return
        view = "All" if self.presenting is None else self.exhibits[self.presenting].name
        self.enqueue(
            "app",
            {
                "op": "camera" if self.presenting is None else "present",
                "view": view,
                "value": view,
                "client": client,
            },
        )

    def camera_preset(
        self, view: str, width: int = 1280, height: int = 800, panel_px: int = PANEL_PX
    ):
        """``(position, look_at)`` of a preset for a page of ``width`` x ``height`` pixels whose
        right ``panel_px`` the GUI panel covers (:func:`mechviz.viz.scene.framing.frame`): an exhibit's
        own view frames its box to ``FILL`` of the height, in the middle of the page left of
        the panel; *All* frames the three together (as large as the free width allows); *Top*
        looks straight down on the cyclotron's orbit."""
        if view == "All":  # the three boxes' own corners: their pictures, not a box around all
            corners = np.concatenate([framing.corners(*ex.bounds) for ex in self.exhibits.values()])
            direction = np.subtract(OVERVIEW[1], OVERVIEW[0])
            return framing.frame_points(
                corners, direction, width, height, fill=OVERVIEW_FILL, panel_px=panel_px
            )
        if view == "Top":
            lo, hi = self.exhibits[CyclotronExhibit.key].bounds
            return framing.frame(
                lo, hi, (0.0, 0.01, -1.0), width, height, fill=FILL, panel_px=panel_px
            )
        ex = self.exhibits[VIEWS[view]]
        position, target = ex.camera
        lo, hi = ex.bounds
        return framing.frame(
            lo, hi, np.subtract(target, position), width, height, fill=FILL, panel_px=panel_px
        )

    def _present(self, view, client=None) -> None:
        """Presentation mode: ``view`` (an exhibit's preset name) alone on the page, framed to
        ``PRESENT_FILL`` of its height with its key figures drawn large beside it
        (``FIGURE_SCALE``), labels ``PRESENT_TEXT`` times larger and the panel minimized (its
        button opens it again); ``"Off"`` brings the three and the panel back."""
        if view not in ("Off", *VIEWS):
            raise ValueError(f"Present must be Off or one of {', '.join(VIEWS)}, got {view!r}")
        self.presenting = None if view == "Off" else VIEWS[view]
        scale = 1.0 if self.presenting is None else PRESENT_TEXT
        for key, ex in self.exhibits.items():
            ex.scene.get_handle_by_name(ex.root).visible = self.presenting in (None, key)
            for h in ex.labels():
                h.font_screen_scale = scale
            if key in self.figures:
                self.figures[key].visible = self.presenting == key
        self._show_figures()
        self._configure_page()
        if self.presenting is None:
            self._move_camera(client, "All")
        else:
            self._move_camera(client, view, present=True)

    def _build_figures(self) -> None:
        """Presentation mode's key figures: for each exhibit a label of large text at the top
        right corner of its box (``FIGURE_SCALE`` times viser's 12 px screen labels), hidden
        until the exhibit is presented."""
        for key, ex in self.exhibits.items():
            lo, hi = ex.bounds
            self.figures[key] = self.server.scene.add_label(
                f"/key_figures/{key}",
                "",
                font_size_mode="screen",
                font_screen_scale=FIGURE_SCALE,
                anchor="top-left",
                position=(float(hi[0]), float(lo[1]), float(hi[2])),
                visible=False,
            )

    def _show_figures(self) -> None:
        key = self.presenting
        if key is not None and key in self.figures:
            lines = []
            for name, value in self.exhibits[key].key_figures():
                # the theory on a line of its own: drawn large, a whole line runs off the page
                shown, _, theory = value.partition(" (theory ")
                lines.append(f"{name} = {shown}")
                if theory:
                    lines.append(f"   (theory {theory}")
            self.figures[key].text = "\n".join(lines)

    def _move_camera(self, client, view: str, *, present: bool = False) -> None:
        """Move the camera of ``client`` (all clients if None) to the preset ``view``, framed
        for its page; ``present``: the panel collapsed and room on the right for the figures."""
        clients = [client] if client is not None else list(self.server.get_clients().values())
        for c in clients:
            size = page_size(c)
            if present:
                ex = self.exhibits[VIEWS[view]]
                position, target = ex.camera
                lo, hi = ex.bounds
                position, target = framing.frame(
                    lo,
                    hi,
                    np.subtract(target, position),
                    *size,
                    fill=PRESENT_FILL,
                    panel_px=round(FIGURES_SHARE * size[0]),
                )
            else:
                position, target = self.camera_preset(view, *size)
            with c.atomic():
                c.camera.position = position
                c.camera.look_at = target
