"""The hoop's chaos and stability maps in the viewer: pictures in the hoop's tab, and the chaos
map standing in the scene where a click starts the hoop.

viser 1.1 reports no click position on a GUI image; a scene image node does (``on_click`` gives
the pointer's ray in world coordinates). So the chaos map stands in the scene above the
configuration-space square, in the same plane (theta1 across, theta2 up), and a click there is
turned into a start at rest: the ray meets the map's plane at a place ``(u, v)``, which
:meth:`mechviz.viz.model.atlas_map.ChaosMap.angles_at` turns into ``(theta1, theta2)``. The tab shows
the same map with its axes, colour bar, normal-mode lines and the current start, and the
stability map of the running method with the current step marked (a magenta line at ``dt`` and
a dot at the start's amplitude). The maps come from :class:`mechviz.viz.model.atlas_map.HoopMaps`.
"""

from __future__ import annotations

import atexit

import numpy as np

from .. import geometry as geo
from ..app_commands import Stage
from ..model.atlas_map import (
    CHAOS_DURATION,
    CHAOS_METHOD,
    COLOURMAP,
    STABILITY_PERIODS,
    ChaosMap,
    HoopMaps,
    StabilityMap,
    start_amplitude,
)

MAP_SIZE = 1.0  # m, the side of the map in the scene
# above the configuration square (the same axes), clear of the mode lines' names at the
# square's top edge; beside it the hoop's box would grow wider and its view smaller
MAP_SHIFT = np.array([0.0, 0.0, 1.45])  # m, from the configuration square's centre
MAP_AND_SQUARE_TITLE = "θ1 → θ2 ↑ configuration"  # under the square; the map shares its axes
MAP_TITLE = "chaos map (click)"  # above the map
MARKER_RGB = (230, 30, 30)  # the current start on the chaos maps
STEP_RGB = (255, 0, 255)  # the current step on the stability map (a colour no map uses)
REFRESH_FRAMES = 6  # frames between looks at the background work (10 Hz at 60 Hz)
PICTURE_PX = (560, 500)  # the tab's pictures (width, height), shown about half as wide


class MapPicture:
    """A matplotlib figure drawn into an RGB array for a GUI image; remembers its axes so a
    place in the picture can be read back (:meth:`data_at`, :meth:`place_of`)."""

    def __init__(self) -> None:
        import matplotlib

        matplotlib.use("Agg", force=False)
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        w, h = PICTURE_PX
        self.fig = Figure(figsize=(w / 200, h / 200), dpi=200, layout="constrained")
        self.canvas = FigureCanvasAgg(self.fig)
        self.ax = None

    def start(self, dark: bool):
        self.fig.clear()
        face, ink = ("#1f2023", "#d0d0d0") if dark else ("#ffffff", "#222222")
        self.fig.set_facecolor(face)
        ax = self.ax = self.fig.add_subplot()
        ax.set_facecolor(face)
        ax.tick_params(colors=ink, labelsize=6)
        for spine in ax.spines.values():
            spine.set_color(ink)
        self.ink = ink
        return ax

    def label(self, xlabel: str, ylabel: str) -> None:
        self.ax.set_xlabel(xlabel, fontsize=7, color=self.ink)
        self.ax.set_ylabel(ylabel, fontsize=7, color=self.ink)

    def finish(self) -> np.ndarray:
        self.canvas.draw()
        return np.asarray(self.canvas.buffer_rgba())[..., :3].copy()

    def place_of(self, x: float, y: float) -> tuple[float, float]:
        """Data ``(x, y)`` as a place ``(u, v)`` of the picture (``v`` from the top)."""
        px, py = self.ax.transData.transform((x, y))
        w, h = self.canvas.get_width_height()
        return float(px / w), float(1.0 - py / h)

    def data_at(self, u: float, v: float) -> tuple[float, float]:
        """The data ``(x, y)`` at the place ``(u, v)`` of the picture."""
        w, h = self.canvas.get_width_height()
        x, y = self.ax.transData.inverted().transform((u * w, (1.0 - v) * h))
        return float(x), float(y)


def draw_chaos(pic: MapPicture, m: ChaosMap, start, dark: bool) -> np.ndarray:
    """The chaos map with its colour bar, the two normal-mode lines and the current start."""
    from mechviz.dynamics.atlas.theory import normal_mode_slopes

    ax = pic.start(dark)
    spec = m.spec
    top = m.colour_scale()
    xs, ys = spec.x.values(), spec.y.values()
    mesh = ax.pcolormesh(xs, ys, m.lyapunov, shading="nearest", cmap=COLOURMAP, vmin=0, vmax=top)
    bar = pic.fig.colorbar(mesh, ax=ax, shrink=0.85)
    bar.set_label("largest Lyapunov exponent [1/s]", fontsize=6, color=pic.ink)
    bar.ax.tick_params(labelsize=6, colors=pic.ink)
    t = np.linspace(xs[0], xs[-1], 100)
    for k, slope in enumerate(normal_mode_slopes(spec.make_system().params)):
        ax.plot(t, slope * t, color="white", lw=0.8, ls="-" if k == 0 else ":")
    ax.plot([start[0]], [start[1]], "+", color=np.array(MARKER_RGB) / 255, ms=9, mew=2)
    ax.set_xlim(xs[0], xs[-1])
    ax.set_ylim(ys[0], ys[-1])
    ax.set_aspect("equal")
    pic.label("hoop angle θ1 at rest [rad]", "bead angle θ2 at rest [rad]")
    return pic.finish()


def draw_stability(pic: MapPicture, m: StabilityMap, amplitude: float, dt: float, dark: bool):
    """Bounded (pale) or not (dark) over (amplitude, dt), the measured boundary, the linear
    limit dashed, and the current step: a magenta line at ``dt``, a dot at ``amplitude``."""
    from matplotlib.colors import ListedColormap

    ax = pic.start(dark)
    spec = m.spec
    xs, ys = spec.x.values(), spec.y.values()
    shades = ListedColormap(["#5b2a2a", "#dfe9f3"] if not dark else ["#7a3030", "#3a4a5a"])
    ax.pcolormesh(xs, ys, m.bounded.astype(float), shading="nearest", cmap=shades, vmin=0, vmax=1)
    limit = m.linear_limit()
    if np.all(np.isfinite(limit)) and np.all(limit > 0):
        ax.plot(xs, limit, color=pic.ink, ls="--", lw=1.0, label="linear theory")
        ax.legend(fontsize=6, loc="lower right", frameon=False, labelcolor=pic.ink)
    ax.set_yscale("log")
    ax.set_xlim(xs[0], xs[-1])
    ax.set_ylim(ys[0], ys[-1])
    step = np.array(STEP_RGB) / 255
    if ys[0] <= dt <= ys[-1]:
        ax.axhline(dt, color=step, lw=1.4)
        ax.plot([min(max(amplitude, xs[0]), xs[-1])], [dt], "o", color=step, ms=6)
    pic.label("amplitude A of each normal mode [rad]", "step dt [s]")
    ax.set_title(
        f"{spec.methods[0]}: bounded after {spec.periods:g} periods", fontsize=7, color=pic.ink
    )
    return pic.finish()


class HoopMapsView:
    """The maps of one hoop exhibit, in its tab and its scene (module docstring)."""

    def __init__(self, panel, exhibit) -> None:
        self.panel, self.exhibit = panel, exhibit
        self.app = panel.app
        self.maps = HoopMaps()
        self.shown = True  # in the scene (the hoop's stage), as :meth:`show` sets it
        self._inside = False  # the start's marker falls on the map
        atexit.register(self.maps.close)
        self.chaos_picture, self.stability_picture = MapPicture(), MapPicture()
        self._shown: tuple | None = None  # what the pictures show
        # the step the stability picture marks: (amplitude [rad], dt [s], its place (u, v))
        self.step_drawn: tuple[float, float, tuple[float, float]] | None = None
        gui = panel.gui
        with gui.add_folder("Chaos map", expand_by_default=False):
            panel.put(
                "chaos_note",
                gui.add_markdown(
                    "<small>Each start at rest (θ1, θ2) coloured by its largest Lyapunov "
                    f"exponent (renormalised twin runs 1e-9 apart, {CHAOS_METHOD}, "
                    f"{CHAOS_DURATION:g} s): dark, regular; bright, chaotic. White: the two "
                    "normal-mode lines; red +: the current start. **Click the map standing "
                    "above the configuration square in the scene to start the hoop "
                    "there.**</small>"
                ),
            )
            self.chaos_image = panel.put("chaos_map", gui.add_image(self._blank(), format="png"))
            self.status = panel.put("maps_status", gui.add_markdown(""))
        with gui.add_folder("Stability map", expand_by_default=False):
            gui.add_markdown(
                "<small>Where the chosen method stays bounded on this hoop: pale, bounded after "
                f"{STABILITY_PERIODS:g} periods of the fastest mode; dark, not. Dashed: linear "
                "theory's limit. Magenta: the current step (line) at the start's amplitude (dot).</small>"
            )
            self.stability_image = panel.put(
                "stability_map", gui.add_image(self._blank(), format="png")
            )
            self.stability_note = panel.put("stability_note", gui.add_markdown(""))
        self._build_scene()
        self._frames = 0
        self.app.frame_hooks.append(self._on_frame)
        self.refresh()

    # ------------------------------------------------------------------ the scene's map
    def _build_scene(self) -> None:
        ex = self.exhibit
        s, r = ex.scene, ex.root
        self.centre_local = ex.config_space.centre + MAP_SHIFT
        # the image's own plane is its x-y with the picture's top along -y; a quarter turn
        # about x stands it in the x-z plane facing -y (the cameras' side), its top down, so
        # the picture is given upside down
        self.wxyz = np.array([np.cos(np.pi / 4), np.sin(np.pi / 4), 0.0, 0.0])
        self.node = s.add_image(
            f"{r}/chaos_map",
            np.full((8, 8, 3), 128, np.uint8),
            MAP_SIZE,
            MAP_SIZE,
            format="png",
            position=self.centre_local,
            wxyz=self.wxyz,
            cast_shadow=False,
            receive_shadow=False,
        )
        self.node.on_click(self._clicked)
        # named with the square below it, whose axes it shares (a title of its own, over or
        # under it, runs into the disk's or the mode lines' names in the first view)
        ex.config_space.title.text = MAP_AND_SQUARE_TITLE
        self.title = s.add_label(
            f"{r}/chaos_map_title",
            MAP_TITLE,
            position=self.centre_local + (-0.5 * MAP_SIZE, 0.0, 0.5 * MAP_SIZE + 0.1),
            anchor="bottom-left",
        )
        self.marker = geo.lines(
            s, f"{r}/chaos_map_start", np.zeros((2, 2, 3), np.float32), MARKER_RGB, 3.0
        )

    def world_of(self, u: float, v: float) -> np.ndarray:
        """The world point [m] at the place ``(u, v)`` of the scene's map."""
        local = self.centre_local + MAP_SIZE * np.array([u - 0.5, 0.0, 0.5 - v])
        return self.exhibit.world(local)

    def place_at(self, origin, direction) -> tuple[float, float] | None:
        """Where the ray from ``origin`` along ``direction`` (world) meets the map's plane, as
        a place ``(u, v)``; None if it runs parallel to it."""
        o, d = np.asarray(origin, float), np.asarray(direction, float)
        centre = self.exhibit.world(self.centre_local)
        if abs(d[1]) < 1e-12:
            return None
        hit = o + d * ((centre[1] - o[1]) / d[1])
        return (
            float((hit[0] - centre[0]) / MAP_SIZE + 0.5),
            float(0.5 - (hit[2] - centre[2]) / MAP_SIZE),
        )

    def _clicked(self, event) -> None:
        m = self.maps.chaos
        place = self.place_at(event.ray_origin, event.ray_direction)
        if m is None or place is None:
            return
        angles = m.angles_at(*place)
        if angles is not None:
            self.panel.change(mode="custom", angles=angles)

    def look_clicked(self, event) -> None:
        """The panel's "Look at the map": the hoop on stage, the camera in front of its map."""
        # the map stands on the hoop's stage only: the stage first, then the camera on the map
        # (the app applies the two in this order, in its own thread)
        self.app.enqueue("app", Stage(self.exhibit.model.name, event.client))
        self.app.enqueue("call", lambda _app: self.look_at_map(event.client))

    def look_at_map(self, client) -> None:
        """Put ``client``'s camera straight in front of the scene's map."""
        if client is None:
            return
        centre = self.exhibit.world(self.centre_local)
        with client.atomic():
            client.camera.position = tuple(centre + (0.0, -2.2 * MAP_SIZE, 0.0))
            client.camera.look_at = tuple(centre)
            client.camera.up_direction = (0.0, 0.0, 1.0)

    # ------------------------------------------------------------------ refreshing
    def _on_frame(self, _app) -> None:
        self._frames += 1
        if self._frames % REFRESH_FRAMES == 0:
            self.refresh()

    def refresh(self) -> None:
        """Take finished maps, ask for missing ones, and draw what changed."""
        ex = self.exhibit
        changed = self.maps.update(ex.model.params, ex.model.config.method)
        status = f"<small>{self.maps.status}</small>" if self.maps.status else ""
        if self.status.content != status:  # an assignment is sent to every client, even unchanged
            self.status.content = status
        start = tuple(float(x) for x in ex.model.sim.state0[0, :2])
        dark = getattr(self.app, "theme", "light") == "dark"
        key = (
            start,
            ex.model.config.dt,
            ex.model.config.method,
            dark,
            id(self.maps.chaos),
            id(self.maps.stability),
        )
        if not changed and key == self._shown:
            return
        self._shown = key
        chaos = self.maps.chaos
        if chaos is not None:
            self.chaos_image.image = draw_chaos(self.chaos_picture, chaos, start, dark)
            self.node.image = np.ascontiguousarray(chaos.rgb()[::-1])
            self._mark(chaos, start)
        stab = self.maps.stability
        if stab is not None:
            amp = start_amplitude(ex.model.params, start)
            dt = float(ex.model.config.dt)
            self.stability_image.image = draw_stability(self.stability_picture, stab, amp, dt, dark)
            self.step_drawn = (amp, dt, self.stability_picture.place_of(amp, dt))
        elif not self.maps.worker.busy("stability"):
            self.stability_image.image = self._blank()
        fixed = not ex.model.sim.method.adaptive
        self.stability_note.content = (
            ""
            if fixed
            else f"<small>{ex.model.config.method} is adaptive: its step follows the tolerance, "
            "so there is no fixed step to mark.</small>"
        )

    def _mark(self, chaos: ChaosMap, start) -> None:
        u, v = chaos.place_of(*start)
        c = self.world_of(u, v) - self.exhibit.origin
        c[1] -= 0.01  # in front of the picture
        half = 0.04 * MAP_SIZE
        cross = [[c - (half, 0, 0), c + (half, 0, 0)], [c - (0, 0, half), c + (0, 0, half)]]
        self.marker.points = np.asarray(cross, np.float32)
        self._inside = 0.0 <= u <= 1.0 and 0.0 <= v <= 1.0
        self.marker.visible = self.shown and self._inside

    def show(self, shown: bool) -> None:
        """The map in the scene (``shown``, on the hoop's stage) or not (at home)."""
        self.shown = shown
        self.node.visible = shown
        self.marker.visible = shown and self._inside

    @staticmethod
    def _blank() -> np.ndarray:
        w, h = PICTURE_PX
        return np.full((h // 4, w // 4, 3), 255, np.uint8)


def add_maps(panel, exhibit) -> HoopMapsView:
    """The hoop's maps in its tab and scene (call from its ``build_panel``)."""
    return HoopMapsView(panel, exhibit)
