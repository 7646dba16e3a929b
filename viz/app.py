"""The live viewer: three exhibits, one on stage at a time, a GUI, and one 60 Hz simulation loop.

Layout (:data:`ORIGINS`, +z up): the spinning disk near the origin, the cyclotron to its left, the
hoop to its right and nearer the home view's camera: seen from above the front left, the three
go down the page as well as across it, so together they use its height. An exhibit on stage is
shown alone, large, with its key figures beside it (:mod:`mechviz.viz.views`).
GUI callbacks (viser pool threads) only enqueue commands; the loop thread applies them between
frames, advances every exhibit by ``speed x frame time`` in one compiled ``dynamics`` call each,
and pushes all poses inside ``server.atomic()``. Nothing else touches an exhibit while the loop runs.

API for other tools (the recorder, the bench)
---------------------------------------------
Exhibits work without the app (:mod:`mechviz.viz.scene` holds them and describes the contract):
a view built over its headless model, which runs and takes the commands::

    from mechviz.viz.model import CyclotronConfig, CyclotronModel, Kick, Reset, Set
    from mechviz.viz.scene import CyclotronExhibit

    model = CyclotronModel(CyclotronConfig(method="euler", dt=0.05, compare_method="boris"))
    ex = CyclotronExhibit(server, model)   # draws ``model`` (ex.model); observes it
    model.advance(1 / 30)      # simulated seconds; a blow-up pauses it (model.paused, .failure)
    with server.atomic():
        ex.draw_if_changed()   # handle assignments only, if the model changed since drawn
    model.apply(Kick(dv=0.5))                                # cyclotron: radial kick [m/s]
    model.apply(Set(fields={"method": "rk4", "dt": 0.02}))   # any config field; restarts the run
    model.apply(Set(params={"field": 2.0}))                  # ValueError naming the field if invalid
    model.apply(Reset())                                     # commands.parse reads one from a dict
    model.sample, model.measured(), model.chart_data(), ex.readout(), ex.camera

The whole app, headless and without its loop thread::

    app = MechvizApp(port=0, start_loop=False)   # or MechvizApp(server=my_server, ...)
    app.step_frame()                 # apply queued commands, advance, draw (one frame)
    app.enqueue("hoop", Set(fields={"method": "rk4"}))    # as the GUI does
    app.w["hoop.dt"].value = "2.5e-2"; app.number_fields["hoop.dt"].submit()  # typed, Enter
    app.enqueue("app", Pause())      # viz.app_commands: Play, Step, Speed, ResetAll, Stage, ...
    app.enqueue("app", Scrub(-10))   # paused, 10 s of the show back
    app.exhibits["hoop"]; app.common_folder  # GUI folder where extra controls (Record) can go
    app.frame_hooks.append(fn)       # fn(app) runs in the loop thread after each frame's draw
    app.frame_log.since(0)           # (first, start [s], cost [ms], loop CPU [ms]) per frame
    app.stop()

:func:`mechviz.viz.frame_cost.measure_frame_cost` times frames of the whole app for ``mechviz bench``.
"""

from __future__ import annotations

import contextlib
import io
import queue
import threading
import time
from collections import deque
from collections.abc import Callable, Mapping
from typing import Any, ClassVar

import numpy as np

from . import app_commands as ac
from .frames import FrameLog, refresh_frames
from .live_record import add_record_toggle
from .model import MODELS
from .model.commands import COMMANDS, Command, refused
from .rewind_control import RewindControl
from .scene import EXHIBITS, Exhibit
from .scene.fields import NumberField, ThreadFlag, Typing
from .scene.panel import Panel, parse_number
from .views import GRIDS, HOME, OVERVIEW, VIEWS, Views, log_axis  # noqa: F401  (re-exported)
from .warm import warm_up  # noqa: F401  (compile what the exhibits start with; re-exported)

# m: where each exhibit stands, as its model says (mechviz.viz.model.hooks.SystemHooks.origin)
ORIGINS = {key: cls.origin for key, cls in MODELS.items()}

CHART_RATE = 20.0  # Hz: how often each exhibit samples energy and error (a chart point)
CHART_SECONDS = 10.0  # the charts show the last 10 s by default
# The chart window choices [s]: each chart holds at most CHART_RATE x 10 s points, spread evenly
# over the window, so a 10-minute window costs the browser no more than a 10-second one.
CHART_WINDOWS = {"10 s": 10.0, "1 min": 60.0, "10 min": 600.0}
FPS = 60.0  # display rate of the simulation loop
SPEEDS = (0.1, 10.0)  # simulated seconds per real second: the speed control's range


# --------------------------------------------------------------------------- the app
class MechvizApp(Views):
    """Server, exhibits, GUI and the simulation loop."""

    # the app is setting widgets itself, in this thread: a person's change runs its callback on
    # a pool thread, and must not be taken for the app's own (a flag shared by all threads was)
    _syncing = ThreadFlag()

    def __init__(
        self,
        server=None,
        *,
        host: str = "127.0.0.1",
        port: int = 8080,
        configs: Mapping[str, Any] | None = None,
        gui: bool = True,
        start_loop: bool = True,
        environment_map: bool = True,
        fps: float | None = None,
        quiet: bool = True,
        theme: str = "light",
        dev: bool = False,
    ) -> None:
        import viser

        self._viser = viser
        if server is None:
            out = io.StringIO() if quiet else None
            with contextlib.redirect_stdout(out) if out is not None else contextlib.nullcontext():
                server = viser.ViserServer(host=host, port=port, verbose=False)
        self.server = server
        self.host = host
        self.fps = float(fps or FPS)
        self.frame_dt = 1.0 / self.fps
        self.speed = 1.0  # simulated seconds per real second
        self.playing = True
        self.sim_time = 0.0  # simulated seconds the app has advanced (all exhibits together)
        self.frame = 0
        self.commands: queue.SimpleQueue = queue.SimpleQueue()
        self.messages: list[tuple[str, str]] = []  # every notification sent (title, body)
        self.frame_hooks: list[Callable[[MechvizApp], None]] = []
        self.frame_log = FrameLog()  # start time and cost of the last frames (status line, bench)
        self._rtf_window: deque = deque(maxlen=240)
        self._to_show: set[str] = set()  # exhibits changed since their readout was shown
        self._charted: dict[str, int] = {}  # exhibit key -> history version its chart shows
        self._cost_text = ""
        self.stage: str | None = None  # the exhibit on stage; None: home, the three together
        self.presenting: str | None = None  # the exhibit on stage with the panel minimized
        self.figures: dict[str, Any] = {}  # key -> the label of its key figures
        self.dev = dev  # viser's share button shown (developers only)
        self._page_shapes: dict[int, tuple[int, int]] = {}  # client id -> page shape framed for
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.common_folder = None
        # number fields typed in; leaving them is carried out between frames
        self.typing = Typing(run=lambda fn: self.enqueue("call", lambda app: fn()))
        self.number_fields: dict[str, NumberField] = {}  # keyed as the widget table ``w``
        self.rewind_control = RewindControl(
            self
        )  # pause and scrub back (mechviz.viz.rewind_control)

        scene = server.scene
        scene.set_up_direction("+z")
        if not environment_map:
            scene.configure_environment_map(None)
            # the map is also the scene's ambient light: without it, faces turned away from the
            # default directional lights render black (the disk, seen edge-on to them)
            scene.add_light_hemisphere(
                "/lights/sky",
                sky_color=(255, 255, 255),
                ground_color=(110, 110, 120),
                intensity=1.2,
            )
        if theme not in GRIDS:
            raise ValueError(f"theme must be one of {', '.join(GRIDS)}; got {theme!r}")
        self.theme = theme
        self.grid = scene.add_grid(
            "/floor",
            width=20.0,
            height=16.0,  # 4 m and more in front of the nearest exhibit (the hoop)
            cell_size=0.5,
            section_size=1.0,
            position=(0.0, 0.0, 0.0),
        )
        self.grid.plane_color, self.grid.cell_color, self.grid.section_color = GRIDS[theme]
        cfg = dict(configs or {})
        # energies and errors (chart points, divergence checks) at CHART_RATE; poses every frame
        self._measure_every = max(1, round(self.fps / CHART_RATE))
        history_len = round(CHART_SECONDS * CHART_RATE)
        self.chart_window = CHART_SECONDS
        # each system's model, then the view drawn over it: the view observes its model and
        # marks itself to draw (``to_draw``); the app runs and commands the models
        self.exhibits: dict[str, Exhibit] = {}
        for key, cls in EXHIBITS.items():
            model = cls.model_type(cfg.get(key), history_len=history_len)
            model.chart_window = self.chart_window  # the charts draw on the long history
            model.observe(lambda _model, key=key: self._to_show.add(key))
            self.exhibits[key] = cls(server, model, origin=ORIGINS[key], bounded=True)
        self.panels: dict[str, Panel] = {}
        self._build_stage()
        with server.atomic():
            self._draw()
        server.on_client_connect(self._frame_new_client)
        self.gui = None
        self.recorder = None  # the Record toggle's live_record.LiveRecorder (with the GUI)
        if gui:
            self._build_gui()
            self._show_stage()  # the labels the GUI's parts made (the hoop's maps), for home
            self._update_gui(force=True)
            self.recorder = add_record_toggle(self)
        # after the GUI, which builds the hoop's maps: every node is in place to be framed
        server.initial_camera.position, server.initial_camera.look_at = self.camera_preset("Home")
        if start_loop:
            self.start()

    # ------------------------------------------------------------------ properties
    @contextlib.contextmanager
    def quiet(self):
        """A context in which the app's own widget changes are not taken for the person's."""
        syncing, self._syncing = self._syncing, True
        try:
            yield
        finally:
            self._syncing = syncing

    def field_hooks(self) -> dict[str, Any]:
        """What every :class:`mechviz.viz.scene.fields.NumberField` of the app is given."""
        later = lambda fn: self.enqueue("call", lambda app: fn())  # noqa: E731
        notify = lambda title, body: self.notify(title, body, color="orange")  # noqa: E731
        return {"on": self._on, "typing": self.typing, "quiet": self.quiet, "defer": later,
                "notify": notify}  # fmt: skip

    @property
    def port(self) -> int:
        return self.server.get_port()

    @property
    def url(self) -> str:
        host = "127.0.0.1" if self.host in ("0.0.0.0", "") else self.host
        return f"http://{host}:{self.port}/"

    @property
    def real_time_factor(self) -> float | None:
        """Simulated seconds per wall second over the last frames; ``None`` while paused or
        until two frames have played since the last reset or speed change."""
        if not self.playing:
            return None
        w = self._rtf_window
        if len(w) < 2 or w[-1][0] - w[0][0] <= 0:
            return None
        return (w[-1][1] - w[0][1]) / (w[-1][0] - w[0][0])

    # ------------------------------------------------------------------ commands
    def enqueue(self, target: str, command: Command | ac.AppCommand | Callable) -> None:
        """Queue a command for the loop: to an exhibit ``target`` one of its typed commands
        (:mod:`mechviz.viz.model.commands`), to ``"app"`` one of :mod:`mechviz.viz.app_commands`;
        a callable (target ``"call"``) runs in the loop thread with the app. Anything else is
        refused here, in the caller's thread."""
        if target in self.exhibits and not isinstance(command, COMMANDS):
            raise refused(target, COMMANDS, command)
        if target == "app" and not isinstance(command, ac.APP_COMMANDS):
            raise ac.refused(command)
        self.commands.put((target, command))

    def _apply_commands(self) -> None:
        while True:
            try:
                target, command = self.commands.get_nowait()
            except queue.Empty:
                return
            try:
                if target == "call":
                    command(self)
                    for ex in self.exhibits.values():  # it may have changed anything
                        ex.to_draw = True
                elif target == "app":
                    self._apply_app(command)
                else:
                    ex = self.exhibits[target]
                    ex.model.apply(command)
                    self._sync_widgets(target)
            except ValueError as exc:
                if target in self.exhibits:
                    panel = self.panels.get(target)
                    title = self.exhibits[target].model.title
                    self.notify(
                        f"Invalid value ({title})", panel.explain(exc) if panel else str(exc)
                    )
                    self._sync_widgets(target)
                else:
                    self.notify("Invalid value", str(exc), color="red")

    def _apply_app(self, cmd: ac.AppCommand) -> None:
        match cmd:
            case ac.Play() | ac.Pause() | ac.Toggle():
                playing = {ac.Play: True, ac.Pause: False, ac.Toggle: not self.playing}[type(cmd)]
                if playing != self.playing:
                    self._rtf_window.clear()  # a pause is not a slow-down
                if playing:
                    self.rewind_control.resume()  # scrubbed back: on from the moment shown
                self.playing = playing
            case ac.Step():
                self.rewind_control.resume()
                self.playing = False
                self._advance(self.speed * self.frame_dt, measure_all=True)
            case ac.Speed(value):
                try:
                    v = parse_number("Speed [×]", value, *SPEEDS)
                finally:
                    self._show_speed()  # the box shows the speed in force (springs back if refused)
                self.speed = v
                self._show_speed()
                self._rtf_window.clear()
            case ac.ResetAll():
                for ex in self.exhibits.values():
                    ex.model.reset()
                self.sim_time = 0.0
                self._rtf_window.clear()  # the clock went back: the old samples say nothing now
                self.rewind_control.forget()
            case ac.Scrub(value):
                self.rewind_control.scrub(value)
            case ac.Camera(view, client):
                self._move_camera(client, view)
            case ac.Stage(value, client):
                self._set_stage(value, client)
            case ac.Reframe(client):  # a page changed shape (or has just connected)
                view = "Home" if self.stage is None else self.exhibits[self.stage].model.name
                self._move_camera(client, view)
            case ac.ChartWindow(value):
                if value not in CHART_WINDOWS.values():
                    raise ValueError(
                        f"Chart window must be one of {', '.join(CHART_WINDOWS)}, got {value!r}"
                    )
                self.chart_window = float(value)
                for ex in self.exhibits.values():
                    ex.model.set_chart_window(self.chart_window)
                self._charted.clear()
            case ac.Present(value, client):
                self._present(value, client)
            case ac.Theme(value):
                if value not in GRIDS:
                    raise ValueError(f"Theme must be one of {', '.join(GRIDS)}, got {value!r}")
                self._apply_theme(value)
        if self.gui is not None:
            self._sync_play_button()

    def _show_speed(self) -> None:
        if self.gui is not None:
            with self.quiet():
                self.speed_field.show(self.speed)

    def notify(self, title: str, body: str, color: str = "red") -> None:
        self.messages.append((title, body))
        for client in self.server.get_clients().values():
            with contextlib.suppress(Exception):
                client.add_notification(title, body, auto_close_seconds=8.0, color=color)

    # ------------------------------------------------------------------ the frame
    def _advance(self, sim_seconds: float, *, measure_all: bool = False) -> None:
        for key, ex in self.exhibits.items():
            ex.model.advance(
                sim_seconds,
                measure=measure_all or self._measures_now(key),
                shown=sim_seconds / self.speed,  # seconds of the show, for the Rewind control
            )
        self.sim_time += sim_seconds

    def _measures_now(self, key: str) -> bool:
        """Whether this frame samples ``key``'s energy and error: one exhibit per frame in turn
        (at 60 Hz each one every third frame), and the frame that refreshes its readout."""
        n = self._measure_every
        return n == 1 or self.frame % n == self.MEASURE_PHASE[key] % n

    def step_frame(self, frame_dt: float | None = None) -> None:
        """One frame: apply queued commands, advance (if playing), draw, refresh the GUI."""
        t0 = time.perf_counter()
        c0 = time.thread_time()
        self._apply_commands()
        if self.playing:
            self._advance(self.speed * (self.frame_dt if frame_dt is None else frame_dt))
        with self.server.atomic():
            self._draw()
            if self.gui is not None:
                self._update_gui()
        for ex in self.exhibits.values():
            while ex.model.events:
                title, body = ex.model.events.pop(0)
                self.notify(title, body, color="orange")
        for hook in list(self.frame_hooks):
            hook(self)
        self.frame += 1
        now = time.perf_counter()
        self._rtf_window.append((now, self.sim_time))
        cost_ms = 1e3 * (now - t0)
        self.frame_log.add(t0, cost_ms, 1e3 * (time.thread_time() - c0))

    def _draw(self) -> None:
        """Draw the exhibits whose state changed since they were last drawn (while paused a
        frame pushes nothing)."""
        for ex in self.exhibits.values():
            ex.draw_if_changed()
        self._draw_stage_chart()

    def _loop(self) -> None:
        next_t = time.perf_counter()
        while not self._stop.is_set():
            try:
                self.step_frame()
            except Exception as exc:  # keep serving; report once per kind
                self.notify("Viewer error", f"{type(exc).__name__}: {exc}")
            next_t += self.frame_dt
            delay = next_t - time.perf_counter()
            if delay > 0:
                self._stop.wait(delay)
            elif delay < -0.25:  # fell far behind (a slow frame): do not try to catch up
                next_t = time.perf_counter()

    def start(self) -> None:
        if self._thread is None:
            self._thread = threading.Thread(target=self._loop, name="mechviz-loop", daemon=True)
            self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5.0)
            self._thread = None
        with contextlib.redirect_stdout(io.StringIO()):
            self.server.stop()

    # ------------------------------------------------------------------ GUI
    def _build_gui(self) -> None:
        viser = self._viser
        gui = self.server.gui
        self.gui = gui
        self.w: dict[str, Any] = {}
        w = self.w
        self._apply_theme(self.theme)
        gui.add_markdown("**mechviz**: three systems of classical mechanics, integrated live.")
        # the main actions at the top: an exhibit on stage (Home: the three), presenting
        w["stage"] = gui.add_button_group("Stage", options=(HOME, *VIEWS))
        w["present"] = gui.add_dropdown(
            "Present",
            options=("Off", *VIEWS),
            initial_value="Off",
            hint="An exhibit on stage with the panel minimized, for a projector (Escape leaves)",
        )
        with gui.add_folder("Simulation", expand_by_default=True) as folder:
            self.common_folder = folder
            w["play"] = gui.add_button(
                "Pause", icon=viser.Icon.PLAYER_PAUSE, hint="Play / pause every exhibit"
            )
            w["step"] = gui.add_button(
                "Step", icon=viser.Icon.PLAYER_TRACK_NEXT, hint="Advance one frame"
            )
            w["reset"] = gui.add_button("Reset all", icon=viser.Icon.REFRESH)
            self.speed_field = NumberField(
                gui,
                "Speed [×]",
                self.speed,
                read=lambda text: self.enqueue("app", ac.Speed(text)),
                current=lambda: self.speed,
                hint="Simulated seconds per real second",
                **self.field_hooks(),
                track=(SPEEDS[0], SPEEDS[1], 0.1),
                track_apply=lambda x: self.enqueue("app", ac.Speed(x)),
            )
            w["speed"], w["speed_track"] = self.speed_field.box, self.speed_field.track
            self.number_fields["speed"] = self.speed_field
            self.rewind_control.build(gui)
            w["status"] = gui.add_markdown("t = 0 s")
            w["view"] = gui.add_button_group("Camera", options=("Frame", "Top"))
            w["chart_window"] = gui.add_dropdown(
                "Chart window",
                options=tuple(CHART_WINDOWS),
                initial_value="10 s",
                hint="How much of the past the energy and error charts show",
            )
            w["theme"] = gui.add_dropdown(
                "Theme",
                options=tuple(GRIDS),
                initial_value=self.theme,
                hint="Light or dark page; the scene's colours read on both (also on a projector)",
            )
        self._on(w["theme"], lambda v: self.enqueue("app", ac.Theme(v)))

        @w["present"].on_update
        def _(event) -> None:
            if not self._syncing:
                self.enqueue("app", ac.Present(w["present"].value, event.client))

        self._on(
            w["chart_window"],
            lambda v: self.enqueue("app", ac.ChartWindow(CHART_WINDOWS.get(v, v))),
        )
        w["play"].on_click(lambda _: self._click(ac.Toggle()))
        w["step"].on_click(lambda _: self._click(ac.Step()))
        w["reset"].on_click(lambda _: self._click(ac.ResetAll()))

        @w["view"].on_click
        def _(event) -> None:
            view = w["view"].value
            if view == "Frame":  # the view in force, framed again
                view = HOME if self.stage is None else self.exhibits[self.stage].model.name
            self.enqueue("app", ac.Camera(view, event.client))

        @w["stage"].on_click
        def _(event) -> None:
            if self._syncing:  # viser calls this for the loop's own setting of the value too
                return
            self.typing.left()  # the person moved on: a box typed in shows the value in force
            self.enqueue("app", ac.Stage(w["stage"].value, event.client))

        self._build_leave()

        tabs = gui.add_tab_group()
        for key, ex in self.exhibits.items():
            with tabs.add_tab(ex.model.name, icon=getattr(viser.Icon, ex.icon)):
                panel = self.panels[key] = Panel(self, ex)
                ex.build_panel(panel)

    def _on(self, widget, fn: Callable[[Any], None]) -> None:
        """on_update that ignores the loop's own widget syncs and passes the new value. A
        person touching a control has left any number box typed into: that text is read first
        (the number fields' own boxes are not such a move)."""

        @widget.on_update
        def _(_event) -> None:
            if not self._syncing:
                if type(widget).__name__ != "GuiTextHandle":
                    self.typing.left()
                fn(widget.value)

    def _click(self, command) -> None:
        """A button of the app: pending typed numbers are read first, then ``command``."""
        self.typing.left()
        self.enqueue("app", command)

    def _sync_play_button(self) -> None:
        b = self.w["play"]
        b.label = "Pause" if self.playing else "Play"
        b.icon = self._viser.Icon.PLAYER_PAUSE if self.playing else self._viser.Icon.PLAYER_PLAY

    def _sync_widgets(self, key: str) -> None:
        """Make the widgets show the exhibit's actual config (after a change or a refusal)."""
        if self.gui is None:
            return
        with self.quiet():
            self.panels[key].sync()

    # GUI refresh schedule, a 12-frame cycle at 60 Hz: the status line at 10 Hz (frames 0 and 6),
    # each exhibit's readout and chart at 5 Hz (one frame each); the other frames push nothing.
    # An exhibit's refresh frame is one where it was just measured (MEASURE_PHASE: frame % 3),
    # so its readout reuses that sample.
    GUI_CYCLE: ClassVar[int] = 12
    STATUS_FRAMES: ClassVar[tuple[int, ...]] = (0, 6)
    MEASURE_PHASE: ClassVar[dict[str, int]] = {
        key: (len(EXHIBITS) - 1 - i) % 3 for i, key in enumerate(EXHIBITS)
    }
    EXHIBIT_FRAMES: ClassVar[dict[str, int]] = refresh_frames(
        MEASURE_PHASE, GUI_CYCLE, STATUS_FRAMES
    )

    def _update_gui(self, force: bool = False) -> None:
        """Refresh the status line and the readouts and charts on their staggered frames (see
        ``GUI_CYCLE``); a paused exhibit's readout and chart are not pushed again."""
        k = self.frame % self.GUI_CYCLE
        if force or k in self.STATUS_FRAMES:
            if force or not self._cost_text or self.frame % 60 == 0:  # median: once a second
                _, _, ms, _ = self.frame_log.since(self.frame_log.count - 600)  # the last 10 s
                self._cost_text = f"frame {np.median(ms) if len(ms) else 0:.2f} ms median"
            rtf = self.real_time_factor
            # no time here: each exhibit's readout has its own clock (each restarts on its own),
            # and a second time beside it, counted since the viewer started, read as a contradiction
            self.w["status"].content = (
                f"Real-time factor {'—' if rtf is None else f'{rtf:.2f}'} · speed {self.speed:g}× · "
                f"{'playing' if self.playing else 'paused'}{self.rewind_control.status()}  \n"
                f"<small>{self._cost_text} (server side)</small>"
            )
        for key, slot in self.EXHIBIT_FRAMES.items():
            if not (force or k == slot):
                continue
            ex = self.exhibits[key]
            charted = self._charted.get(key)
            if not force and key not in self._to_show and charted == ex.model.chart_version():
                continue  # nothing new to show (e.g. paused)
            self._to_show.discard(key)
            self.w[f"{key}.readout"].content = ex.readout()
            if key == self.stage:
                self._show_figures()
            if key in self.panels:
                ex.refresh_panel(self.panels[key])
                self.panels[key].refresh_plot()
            if force or charted != ex.model.chart_version():
                chart = self.w[f"{key}.chart"]
                data = ex.model.chart_data()[: len(chart.series)]
                if len(data[0]) >= 2:
                    chart.data = data
                    self.panels[key].keep_time_axis(
                        "chart", float(data[0][-1]), self.chart_window, log_axis(data[1:])
                    )
            self._charted[key] = ex.model.chart_version()

    # ------------------------------------------------------------------ running
    def run_forever(self, until: threading.Event | None = None) -> None:
        """Block until Ctrl-C, ``until`` is set, or :meth:`stop` is called from another thread."""
        try:
            while not self._stop.is_set() and not (until is not None and until.is_set()):
                self._stop.wait(0.2)
        except KeyboardInterrupt:
            pass
        finally:
            self.stop()
