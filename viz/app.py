"""The live viewer: three exhibits in one viser world, a GUI, and one 60 Hz simulation loop.

Layout: the cyclotron at x = -5.5 m, the spinning disk at the origin, the hoop at x = +5.5 m (+z up).
GUI callbacks (viser pool threads) only enqueue commands; the loop thread applies them between
frames, advances every exhibit by ``speed x frame time`` in one compiled ``dynamics`` call each,
and pushes all poses inside ``server.atomic()``. Nothing else touches an exhibit while the loop runs.

API for other tools (the recorder, the bench)
---------------------------------------------
Exhibits work without the GUI (:mod:`viz.exhibit` describes the common interface)::

    from viz.scene_cyclotron import CyclotronExhibit, CyclotronConfig
    from viz.scene_disk import DiskExhibit, DiskConfig
    from viz.scene_hoop import HoopExhibit, HoopConfig

    ex = CyclotronExhibit(server, CyclotronConfig.from_defaults(method="euler", dt=0.05,
                          compare_method="boris"), origin=(0.0, 0.0, 0.0))
    ex.advance(1 / 30)                 # simulated seconds; a blow-up pauses it (ex.paused, ex.failure)
    with server.atomic():
        ex.draw()                      # handle assignments only
    ex.apply({"op": "kick", "dv": 0.5})          # cyclotron: radial kick [m/s]
    ex.apply({"op": "set", "method": "rk4", "dt": 0.02})   # any config field; restarts the run
    ex.apply({"op": "set", "params": {"field": 2.0}})      # ValueError naming the field if invalid
    ex.apply({"op": "set", "mode": "released"})  # disk: "driven" / "released"
    ex.apply({"op": "set", "mode": "mode 2", "amplitude": 1.2})   # hoop: "mode 1"/"mode 2"/"mix"/"custom"
    ex.apply("reset")
    ex.sample        # dynamics.Sample of the main run (t, state (N, d), energy_error, error, ...)
    ex.compare_sample, ex.t, ex.readout(), ex.chart_data(), ex.camera  # ((position), (look_at))

Config fields: ``CyclotronConfig`` (method, dt, rtol, params{charge, mass, field}, speed, vz, beam,
beam_size, beam_speeds, kick, compare_method, trail_cap, height), ``DiskConfig`` (mode, method,
dt, rtol, params{disk_mass, radius, bead_mass, omega}, extra_spin, follow_cm), ``HoopConfig``
(method, dt, rtol, params{hoop_mass, bead_mass, radius, gravity}, mode, amplitude, angles,
compare_method, trail_cap). Defaults come from :data:`viz.defaults.DEFAULTS`.

The whole app, headless and without its loop thread::

    app = MechvizApp(port=0, start_loop=False)   # or MechvizApp(server=my_server, ...)
    app.step_frame()                 # apply queued commands, advance, draw (one frame)
    app.enqueue("hoop", {"op": "set", "method": "rk4"})   # as the GUI does
    app.enqueue("app", {"op": "pause"})                   # play / pause / toggle / step / speed / reset
    app.exhibits["hoop"]; app.common_folder  # GUI folder where extra controls (Record) can go
    app.frame_hooks.append(fn)       # fn(app) runs in the loop thread after each frame's draw
    app.frame_log.since(0)           # (first, start [s], cost [ms], loop CPU [ms]) per frame
    app.stop()

``measure_frame_cost(n_frames=300)`` returns the server-side milliseconds per frame (all three
exhibits with trails, no browser) for ``mechviz bench``.
"""

from __future__ import annotations

import contextlib
import io
import math
import queue
import threading
import time
from collections import deque
from collections.abc import Callable, Mapping
from typing import Any, ClassVar

import numpy as np

import dynamics

from .defaults import DEFAULTS
from .exhibit import LOG_FLOOR, Exhibit
from .scene_cyclotron import CyclotronConfig, CyclotronExhibit
from .scene_disk import DiskConfig, DiskExhibit
from .scene_hoop import MODES as HOOP_MODES
from .scene_hoop import HoopConfig, HoopExhibit

ORIGINS = {"cyclotron": (-5.5, 0.0, 0.0), "disk": (0.0, 0.0, 0.0), "hoop": (5.5, 0.0, 0.0)}
OVERVIEW = ((2.4, -8.2, 3.0), (2.4, 0.0, 1.15))
CHART_RATE = 20.0  # Hz: how often each exhibit samples energy and error (a chart point)
CHART_SECONDS = 10.0  # the charts show the last 10 s of frames
SYSTEM_OF = {"cyclotron": "cyclotron", "disk": "free-body", "hoop": "hoop"}
_warm_lock = threading.Lock()
_warm: set[tuple[str, str]] = set()


# --------------------------------------------------------------------------- GUI helpers
def _rtol_label(rtol: float) -> str:
    """``1e-09`` -> ``"1e-9"``; other values with three significant digits."""
    return f"{rtol:.3g}".replace("e-0", "e-")


def _rtol_options(current: float) -> tuple[str, ...]:
    """The tolerance dropdown's choices: every decade from 1e-3 to 1e-13, and the current value
    if it is not one of them (set by a demo or the command line)."""
    decades = tuple(f"1e-{k}" for k in range(3, 14))
    label = _rtol_label(current)
    return decades if label in decades else (*decades, label)


# --------------------------------------------------------------------------- numba warm-up
def warm_method(system_name: str, method: str) -> float:
    """Compile (once per process) what ``method`` needs on ``system_name``; returns seconds spent."""
    key = (system_name, method)
    if key in _warm:
        return 0.0
    t0 = time.perf_counter()
    with _warm_lock:
        if key in _warm:
            return 0.0
        system = {
            "cyclotron": dynamics.Cyclotron(),
            "hoop": dynamics.Hoop(),
            "free-body": dynamics.ReleasedDisk(),
        }[system_name]
        m = dynamics.get_method(method)
        if m.backend != "scipy":
            kw: dict[str, Any] = {"rtol": 1e-6} if m.adaptive else {}
            if not m.adaptive and m.backend != "exact":
                kw["dt"] = 1e-3
            s0 = system.default_state()
            for state in (s0, np.tile(s0, (2, 1))):  # single and batched calls
                dynamics.Simulation(system, method, state=state, reference=None, **kw).advance(2e-3)
        _warm.add(key)
    return time.perf_counter() - t0


def warm_up(
    which: str = "defaults",
    configs: Mapping[str, Any] | None = None,
    should_stop: Callable[[], bool] | None = None,
) -> float:
    """Compile the kernels the exhibits start with (``"defaults"``) or every method (``"all"``).

    ``should_stop`` is polled between methods (Ctrl-C during start-up)."""
    t0 = time.perf_counter()
    needed: list[tuple[str, str]] = []
    if which == "all":
        for key, system_name in SYSTEM_OF.items():
            needed += [
                (system_name, m.name)
                for m in dynamics.methods_for(system_name)
                if m.backend != "scipy"
            ]
            del key
    else:
        cfg = configs or {}
        cyc = cfg.get("cyclotron") or CyclotronConfig.from_defaults()
        disk = cfg.get("disk") or DiskConfig.from_defaults()
        hoop = cfg.get("hoop") or HoopConfig.from_defaults()
        needed += [("cyclotron", cyc.method), ("free-body", disk.method), ("hoop", hoop.method)]
        needed += [("hoop", "dop853"), ("free-body", "dop853")]  # their error references
        for system_name, m in (("cyclotron", cyc.compare_method), ("hoop", hoop.compare_method)):
            if m:
                needed.append((system_name, m))
    for system_name, method in needed:
        if should_stop is not None and should_stop():
            break
        warm_method(system_name, method)
    return time.perf_counter() - t0


# --------------------------------------------------------------------------- frame log
class FrameLog:
    """Start time (``time.perf_counter``, s), server-side cost (wall ms) and the loop thread's CPU
    time in it (ms) of the last ``capacity`` frames, in preallocated arrays: written by the loop
    thread once per frame, read by anyone. A cost well above its CPU time is time the thread
    waited (for the interpreter lock, or for a core).

    ``count`` is the number of frames ever logged; :meth:`since` returns the frames from a given
    index on (those still held), so a reader polling more often than ``capacity`` frames (136 s
    at 60 Hz by default) sees every frame exactly once.
    """

    def __init__(self, capacity: int = 8192) -> None:
        self.capacity = int(capacity)
        self.start = np.zeros(self.capacity)
        self.cost_ms = np.zeros(self.capacity)
        self.cpu_ms = np.zeros(self.capacity)
        self.count = 0

    def add(self, start: float, cost_ms: float, cpu_ms: float = math.nan) -> None:
        i = self.count % self.capacity
        self.start[i] = start
        self.cost_ms[i] = cost_ms
        self.cpu_ms[i] = cpu_ms
        self.count += 1

    def since(self, first: int) -> tuple[int, np.ndarray, np.ndarray, np.ndarray]:
        """``(index of the first frame returned, starts, costs, cpu times)`` for frames
        ``first ..``; the index is larger than ``first`` when older frames were overwritten."""
        n = self.count
        lo = max(int(first), n - self.capacity + 1, 0)  # slot n may be being rewritten
        idx = np.arange(lo, n) % self.capacity
        return lo, self.start[idx], self.cost_ms[idx], self.cpu_ms[idx]


# --------------------------------------------------------------------------- the app
class MechvizApp:
    """Server, exhibits, GUI and the simulation loop."""

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
    ) -> None:
        import viser

        self._viser = viser
        if server is None:
            out = io.StringIO() if quiet else None
            with contextlib.redirect_stdout(out) if out is not None else contextlib.nullcontext():
                server = viser.ViserServer(host=host, port=port, verbose=False)
        self.server = server
        self.host = host
        self.fps = float(fps or DEFAULTS["app"]["fps"])
        self.frame_dt = 1.0 / self.fps
        self.speed = float(DEFAULTS["app"]["speed"])
        self.playing = True
        self.sim_time = 0.0  # simulated seconds the app has advanced (all exhibits together)
        self.frame = 0
        self.commands: queue.SimpleQueue = queue.SimpleQueue()
        self.messages: list[tuple[str, str]] = []  # every notification sent (title, body)
        self.frame_hooks: list[Callable[[MechvizApp], None]] = []
        self.frame_log = FrameLog()  # start time and cost of the last frames (status line, bench)
        self._rtf_window: deque = deque(maxlen=240)
        self._drawn: dict[str, int] = {}  # exhibit key -> revision last drawn
        self._shown: dict[str, tuple[int, int]] = {}  # key -> (revision, history version) shown
        self._cost_text = ""
        self._syncing = False
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.common_folder = None

        scene = server.scene
        scene.set_up_direction("+z")
        if not environment_map:
            scene.configure_environment_map(None)
            # the map is also the scene's ambient light: without it, faces turned away from the
            # default directional lights render black (the disk, seen edge-on to them)
            scene.add_light_hemisphere(
                "/lights/sky", sky_color=(255, 255, 255), ground_color=(110, 110, 120),
                intensity=1.2,
            )  # fmt: skip
        scene.add_grid(
            "/floor",
            width=20.0,
            height=8.0,
            cell_size=0.5,
            section_size=1.0,
            position=(0.0, 0.0, 0.0),
        )
        cfg = dict(configs or {})
        # energies and errors (chart points, divergence checks) at CHART_RATE; poses every frame
        self._measure_every = max(1, round(self.fps / CHART_RATE))
        history_len = round(CHART_SECONDS * self.fps / self._measure_every)
        self.exhibits: dict[str, Exhibit] = {
            key: cls(server, cfg.get(key), origin=ORIGINS[key], history_len=history_len)
            for key, cls in (
                ("cyclotron", CyclotronExhibit),
                ("disk", DiskExhibit),
                ("hoop", HoopExhibit),
            )
        }
        server.initial_camera.position = OVERVIEW[0]
        server.initial_camera.look_at = OVERVIEW[1]
        with server.atomic():
            self._draw()
        self.gui = None
        self.recorder = None  # the Record toggle's viz.recording.LiveRecorder (with the GUI)
        if gui:
            self._build_gui()
            self._update_gui(force=True)
            from .recording import add_record_toggle

            self.recorder = add_record_toggle(self)
        if start_loop:
            self.start()

    # ------------------------------------------------------------------ properties
    @property
    def port(self) -> int:
        return self.server.get_port()

    @property
    def url(self) -> str:
        host = "127.0.0.1" if self.host in ("0.0.0.0", "") else self.host
        return f"http://{host}:{self.port}/"

    @property
    def real_time_factor(self) -> float | None:
        w = self._rtf_window
        if len(w) < 2 or w[-1][0] - w[0][0] <= 0:
            return None
        return (w[-1][1] - w[0][1]) / (w[-1][0] - w[0][0])

    # ------------------------------------------------------------------ commands
    def enqueue(self, target: str, command: Mapping[str, Any] | str | Callable) -> None:
        """Queue a command for the loop: ``target`` is an exhibit key or ``"app"``; a callable
        (with target ``"call"``) is run in the loop thread with the app as argument."""
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
                    self._drawn.clear()  # it may have changed anything: draw all again
                elif target == "app":
                    self._apply_app(
                        dict(command) if not isinstance(command, str) else {"op": command}
                    )
                else:
                    ex = self.exhibits[target]
                    ex.apply(command)
                    self._sync_widgets(target)
            except ValueError as exc:
                self.notify(f"Invalid value ({target})", str(exc), color="red")
                if target in self.exhibits:
                    self._sync_widgets(target)

    def _apply_app(self, cmd: dict) -> None:
        op = cmd.get("op")
        if op == "play":
            self.playing = True
        elif op == "pause":
            self.playing = False
        elif op == "toggle":
            self.playing = not self.playing
        elif op == "step":
            self.playing = False
            self._advance(self.speed * self.frame_dt, measure_all=True)
        elif op == "speed":
            v = float(cmd["value"])
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"speed must be positive, got {cmd['value']!r}")
            self.speed = v
        elif op == "reset":
            for ex in self.exhibits.values():
                ex.reset()
            self.sim_time = 0.0
        elif op == "camera":
            self._move_camera(cmd.get("client"), cmd["view"])
        else:
            raise ValueError(
                f"app op must be play, pause, toggle, step, speed, reset or camera; got {op!r}"
            )
        if self.gui is not None:
            self._sync_play_button()

    def notify(self, title: str, body: str, color: str = "red") -> None:
        self.messages.append((title, body))
        for client in self.server.get_clients().values():
            with contextlib.suppress(Exception):
                client.add_notification(title, body, auto_close_seconds=8.0, color=color)

    def camera_preset(self, view: str):
        if view == "All":
            return OVERVIEW
        key = {"Cyclotron": "cyclotron", "Disk": "disk", "Hoop": "hoop"}[view]
        return self.exhibits[key].camera

    def _move_camera(self, client, view: str) -> None:
        position, target = self.camera_preset(view)
        clients = [client] if client is not None else list(self.server.get_clients().values())
        for c in clients:
            with c.atomic():
                c.camera.position = position
                c.camera.look_at = target

    # ------------------------------------------------------------------ the frame
    def _advance(self, sim_seconds: float, *, measure_all: bool = False) -> None:
        for key, ex in self.exhibits.items():
            ex.advance(sim_seconds, measure=measure_all or self._measures_now(key))
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
            while ex.events:
                title, body = ex.events.pop(0)
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
        for key, ex in self.exhibits.items():
            if self._drawn.get(key) != ex.revision:
                ex.draw()
                self._drawn[key] = ex.revision

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
        gui.configure_theme(control_width="medium", show_logo=False, brand_color=(40, 110, 200))
        self.w: dict[str, Any] = {}
        w = self.w
        gui.add_markdown("**mechviz**: three systems of classical mechanics, integrated live.")
        with gui.add_folder("Simulation", expand_by_default=True) as folder:
            self.common_folder = folder
            w["play"] = gui.add_button(
                "Pause", icon=viser.Icon.PLAYER_PAUSE, hint="Play / pause every exhibit"
            )
            w["step"] = gui.add_button(
                "Step", icon=viser.Icon.PLAYER_TRACK_NEXT, hint="Advance one frame"
            )
            w["reset"] = gui.add_button("Reset all", icon=viser.Icon.REFRESH)
            w["speed"] = gui.add_slider(
                "Speed",
                min=0.1,
                max=10.0,
                step=0.1,
                initial_value=self.speed,
                hint="Simulated seconds per real second",
            )
            w["status"] = gui.add_markdown("t = 0 s")
            w["view"] = gui.add_button_group("View", options=("All", "Cyclotron", "Disk", "Hoop"))
        w["play"].on_click(lambda _: self.enqueue("app", {"op": "toggle"}))
        w["step"].on_click(lambda _: self.enqueue("app", {"op": "step"}))
        w["reset"].on_click(lambda _: self.enqueue("app", {"op": "reset"}))
        self._on(w["speed"], lambda v: self.enqueue("app", {"op": "speed", "value": v}))

        @w["view"].on_click
        def _(event) -> None:
            self.enqueue("app", {"op": "camera", "view": w["view"].value, "client": event.client})

        tabs = gui.add_tab_group()
        with tabs.add_tab("Cyclotron", icon=viser.Icon.ATOM):
            self._gui_cyclotron()
        with tabs.add_tab("Disk", icon=viser.Icon.DISC):
            self._gui_disk()
        with tabs.add_tab("Hoop", icon=viser.Icon.CIRCLE):
            self._gui_hoop()

    def _on(self, widget, fn: Callable[[Any], None]) -> None:
        """on_update that ignores the loop's own widget syncs and passes the new value."""

        @widget.on_update
        def _(_event) -> None:
            if not self._syncing:
                fn(widget.value)

    def _param_inputs(self, key: str, labels: dict[str, str], step: float = 0.01) -> None:
        ex = self.exhibits[key]
        with self.gui.add_folder("Physical parameters"):
            for name, label in labels.items():
                value = ex.config.params[name]
                h = self.gui.add_number(label, initial_value=float(value), step=step)
                self.w[f"{key}.params.{name}"] = h
                self._on(h, lambda v, n=name: self.enqueue(key, {"op": "set", "params": {n: v}}))

    def _integrator_inputs(self, key: str, system_name: str, *, compare: bool) -> None:
        gui, ex = self.gui, self.exhibits[key]
        names = [m.name for m in dynamics.methods_for(system_name)]
        with gui.add_folder("Integrator"):
            method = gui.add_dropdown("Method", options=names, initial_value=ex.config.method)
            about = gui.add_markdown(self._method_text(ex.config.method))
            dt = gui.add_number("Step dt [s]", initial_value=float(ex.config.dt), step=0.0001)
            limit = gui.add_markdown(ex.stability_text())
            # a dropdown of decades: a number input shows 1e-9 as 0.0000000
            rtol = gui.add_dropdown(
                "Tolerance rtol",
                options=_rtol_options(ex.config.rtol),
                initial_value=_rtol_label(ex.config.rtol),
                hint="Relative (and absolute) tolerance of the adaptive methods",
            )
            self.w[f"{key}.method"], self.w[f"{key}.about"] = method, about
            self.w[f"{key}.limit"] = limit
            self.w[f"{key}.dt"], self.w[f"{key}.rtol"] = dt, rtol

            def choose(v, field="method"):
                # compile the method's kernels here, in the callback's thread, not in a frame
                if v in names:
                    warm_method(system_name, v)
                self.enqueue(key, {"op": "set", field: v})

            self._on(method, choose)
            self._on(dt, lambda v: self.enqueue(key, {"op": "set", "dt": v}))
            self._on(rtol, lambda v: self.enqueue(key, {"op": "set", "rtol": float(v)}))
            if compare:
                cmp_ = gui.add_dropdown(
                    "Compare with",
                    options=["none", *names],
                    initial_value=ex.config.compare_method or "none",
                )
                self.w[f"{key}.compare_method"] = cmp_

                def choose_cmp(v):
                    if v != "none":
                        warm_method(system_name, v)
                    self.enqueue(key, {"op": "set", "compare_method": None if v == "none" else v})

                self._on(cmp_, choose_cmp)
            reset = gui.add_button(f"Reset {ex.title.lower()}", icon=self._viser.Icon.REFRESH)
            reset.on_click(lambda _: self.enqueue(key, "reset"))

    @staticmethod
    def _method_text(name: str) -> str:
        m = dynamics.get_method(name)
        text = m.describe()
        if m.stability:
            text += f". Stability: {m.stability}"
        return f"<small>{text}</small>"

    def _chart(self, key: str, compare: bool) -> None:
        viser = self._viser
        series = [
            viser.uplot.Series(label="t [s]"),
            viser.uplot.Series(label="log10 |ΔE/E₀|", stroke="#d03030", width=1.5),
            viser.uplot.Series(label="log10 error", stroke="#3060d0", width=1.5),
        ]
        if compare:
            series += [
                viser.uplot.Series(
                    label="compare log10 |ΔE/E₀|", stroke="#e08080", width=1.0, dash=[4, 3]
                ),
                viser.uplot.Series(
                    label="compare log10 error", stroke="#80a0e0", width=1.0, dash=[4, 3]
                ),
            ]
        n = len(series)
        self.w[f"{key}.chart"] = self.gui.add_uplot(
            data=tuple(np.zeros(2) for _ in range(n)),
            series=tuple(series),
            scales={
                "x": viser.uplot.Scale(time=False),
                "y": viser.uplot.Scale(auto=False, range=(LOG_FLOOR, 2.0)),
            },
            aspect=1.6,
        )

    def _gui_cyclotron(self) -> None:
        gui, key = self.gui, "cyclotron"
        self.w[f"{key}.readout"] = gui.add_markdown("")
        self._chart(key, compare=True)
        self._param_inputs(
            key, {"charge": "Charge q [C]", "mass": "Mass m [kg]", "field": "Field B [T]"}
        )
        self._integrator_inputs(key, "cyclotron", compare=True)
        ex = self.exhibits[key]
        with gui.add_folder("Kick and beam"):
            strength = gui.add_slider(
                "Kick dv [m/s]", min=-1.0, max=1.0, step=0.05, initial_value=ex.config.kick
            )
            kick = gui.add_button(
                "Kick", hint="Radial velocity kick: the predicted circle moves at once"
            )
            beam = gui.add_checkbox(
                "Beam", initial_value=ex.config.beam, hint="Many charges, a spread of speeds"
            )
            size = gui.add_slider(
                "Beam size", min=2, max=200, step=1, initial_value=ex.config.beam_size
            )
        self.w.update({f"{key}.kick": strength, f"{key}.beam": beam, f"{key}.beam_size": size})
        kick.on_click(lambda _: self.enqueue(key, {"op": "kick", "dv": float(strength.value)}))
        self._on(beam, lambda v: self.enqueue(key, {"op": "set", "beam": bool(v)}))
        self._on(size, lambda v: self.enqueue(key, {"op": "set", "beam_size": int(v)}))

    def _gui_disk(self) -> None:
        gui, key = self.gui, "disk"
        ex = self.exhibits[key]
        self.w[f"{key}.readout"] = gui.add_markdown("")
        self._chart(key, compare=False)
        with gui.add_folder("Motion"):
            mode = gui.add_dropdown(
                "Motion", options=("driven", "released"), initial_value=ex.config.mode
            )
            spin = gui.add_slider(
                "Extra spin at release [rad/s]",
                min=0.0,
                max=0.5,
                step=0.01,
                initial_value=float(ex.config.extra_spin[2]),
                hint="Spin about the disk normal added at release: seeds the tumble",
            )
            follow = gui.add_checkbox("Follow centre of mass", initial_value=ex.config.follow_cm)
        self.w.update({f"{key}.mode": mode, f"{key}.spin": spin, f"{key}.follow_cm": follow})
        self._on(mode, lambda v: self.enqueue(key, {"op": "set", "mode": v}))
        self._on(
            spin, lambda v: self.enqueue(key, {"op": "set", "extra_spin": (0.0, 0.0, float(v))})
        )
        self._on(follow, lambda v: self.enqueue(key, {"op": "set", "follow_cm": bool(v)}))
        self._param_inputs(
            key,
            {
                "disk_mass": "Disk mass M [kg]",
                "radius": "Radius R [m]",
                "bead_mass": "Bead mass m [kg]",
                "omega": "Spin ω [rad/s]",
            },
        )
        self._integrator_inputs(key, "free-body", compare=False)

    def _gui_hoop(self) -> None:
        gui, key = self.gui, "hoop"
        ex = self.exhibits[key]
        self.w[f"{key}.readout"] = gui.add_markdown("")
        self._chart(key, compare=True)
        with gui.add_folder("Initial condition"):
            mode = gui.add_dropdown("Mode", options=HOOP_MODES, initial_value=ex.config.mode)
            amp = gui.add_slider(
                "Amplitude [rad]",
                min=0.05,
                max=2.5,
                step=0.05,
                initial_value=float(ex.config.amplitude),
            )
            th1 = gui.add_number(
                "θ1 (custom) [rad]", initial_value=float(ex.config.angles[0]), step=0.01
            )
            th2 = gui.add_number(
                "θ2 (custom) [rad]", initial_value=float(ex.config.angles[1]), step=0.01
            )
        self.w.update(
            {f"{key}.mode": mode, f"{key}.amplitude": amp, f"{key}.th1": th1, f"{key}.th2": th2}
        )
        self._on(mode, lambda v: self.enqueue(key, {"op": "set", "mode": v}))
        self._on(amp, lambda v: self.enqueue(key, {"op": "set", "amplitude": float(v)}))
        self._on(
            th1,
            lambda v: self.enqueue(
                key, {"op": "set", "mode": "custom", "angles": (float(v), float(th2.value))}
            ),
        )
        self._on(
            th2,
            lambda v: self.enqueue(
                key, {"op": "set", "mode": "custom", "angles": (float(th1.value), float(v))}
            ),
        )
        self._param_inputs(
            key,
            {
                "hoop_mass": "Hoop mass M [kg]",
                "bead_mass": "Bead mass m [kg]",
                "radius": "Radius a [m]",
                "gravity": "Gravity g [m/s²]",
            },
        )
        self._integrator_inputs(key, "hoop", compare=True)

    def _sync_play_button(self) -> None:
        b = self.w["play"]
        b.label = "Pause" if self.playing else "Play"
        b.icon = self._viser.Icon.PLAYER_PAUSE if self.playing else self._viser.Icon.PLAYER_PLAY

    def _sync_widgets(self, key: str) -> None:
        """Make the widgets show the exhibit's actual config (after a change or a rejection)."""
        if self.gui is None:
            return
        c = self.exhibits[key].config
        self._syncing = True
        try:
            for name, value in c.params.items():
                h = self.w.get(f"{key}.params.{name}")
                if h is not None and value is not None:
                    h.value = float(value)
            h = self.w.get(f"{key}.rtol")
            if h is not None:
                h.options = _rtol_options(c.rtol)
                h.value = _rtol_label(c.rtol)
            for field in (
                "method",
                "dt",
                "beam",
                "beam_size",
                "mode",
                "follow_cm",
                "amplitude",
            ):
                h = self.w.get(f"{key}.{field}")
                if h is not None and hasattr(c, field):
                    h.value = getattr(c, field)
            h = self.w.get(f"{key}.compare_method")
            if h is not None:
                h.value = c.compare_method or "none"
            self.w[f"{key}.about"].content = self._method_text(c.method)
            self.w[f"{key}.limit"].content = self.exhibits[key].stability_text()
            if key == "hoop":
                self.w["hoop.th1"].value, self.w["hoop.th2"].value = (float(x) for x in c.angles)
        finally:
            self._syncing = False

    # GUI refresh schedule, a 12-frame cycle at 60 Hz: the status line at 10 Hz (frames 0 and 6),
    # each exhibit's readout and chart at 5 Hz (one frame each); the other frames push nothing.
    # An exhibit's refresh frame is one where it was just measured (MEASURE_PHASE: frame % 3),
    # so its readout reuses that sample.
    GUI_CYCLE: ClassVar[int] = 12
    STATUS_FRAMES: ClassVar[tuple[int, ...]] = (0, 6)
    EXHIBIT_FRAMES: ClassVar[dict[str, int]] = {"cyclotron": 2, "disk": 4, "hoop": 9}
    MEASURE_PHASE: ClassVar[dict[str, int]] = {"cyclotron": 2, "disk": 1, "hoop": 0}

    def _update_gui(self, force: bool = False) -> None:
        """Refresh the status line and the readouts and charts on their staggered frames (see
        ``GUI_CYCLE``); a paused exhibit's readout and chart are not pushed again."""
        k = self.frame % self.GUI_CYCLE
        if force or k in self.STATUS_FRAMES:
            if force or not self._cost_text or self.frame % 60 == 0:  # median: once a second
                _, _, ms, _ = self.frame_log.since(self.frame_log.count - 600)  # the last 10 s
                self._cost_text = f"frame {np.median(ms) if len(ms) else 0:.2f} ms median"
            rtf = self.real_time_factor
            self.w["status"].content = (
                f"**t = {self.sim_time:.2f} s** simulated · real-time factor "
                f"{'—' if rtf is None else f'{rtf:.2f}'} · speed {self.speed:g}× · "
                f"{'playing' if self.playing else 'paused'}  \n"
                f"<small>{self._cost_text} (server side)</small>"
            )
        for key, slot in self.EXHIBIT_FRAMES.items():
            if not (force or k == slot):
                continue
            ex = self.exhibits[key]
            shown = self._shown.get(key)
            if not force and shown == (ex.revision, ex.history.version):
                continue  # nothing new to show (e.g. paused)
            self.w[f"{key}.readout"].content = ex.readout()
            if force or shown is None or shown[1] != ex.history.version:
                chart = self.w[f"{key}.chart"]
                data = ex.chart_data()
                if len(data[0]) >= 2:
                    chart.data = data[: len(chart.series)]
            self._shown[key] = (ex.revision, ex.history.version)

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


# --------------------------------------------------------------------------- bench hook
def measure_frame_cost(
    n_frames: int = 300, *, warmup_frames: int = 30, compare: bool = False
) -> dict:
    """Server-side milliseconds per frame with all three exhibits and their trails, no browser.

    The app runs headless on a free port without its loop thread; each frame is what the live
    loop does (commands, one ``dynamics`` call per simulation, drawing inside ``server.atomic()``,
    staggered GUI readouts), timed with ``time.perf_counter``. The exhibits start from
    :data:`viz.defaults.DEFAULTS` (trails on the charge and the bead); ``compare=True`` adds a
    comparison run (and its trail) to the charge and the hoop. Returns median, p95, mean and max
    [ms] and the number of trail segments drawn at the end.
    """
    configs = {}
    if compare:
        configs = {
            "cyclotron": CyclotronConfig.from_defaults(compare_method="boris"),
            "hoop": HoopConfig.from_defaults(compare_method="rk4"),
        }
    warm_up("defaults", configs)
    app = MechvizApp(port=0, configs=configs, start_loop=False)
    try:
        for _ in range(warmup_frames):
            app.step_frame()
        times = []
        for _ in range(n_frames):
            t0 = time.perf_counter()
            app.step_frame()
            times.append(1e3 * (time.perf_counter() - t0))
        trails = sum(
            getattr(ex, name).n_segments
            for ex in app.exhibits.values()
            for name in ("trail", "compare_trail", "cmp_trail")
            if hasattr(ex, name)
        )
    finally:
        app.stop()
    a = np.asarray(times)
    return {
        "n_frames": int(n_frames),
        "median_ms": float(np.median(a)),
        "p95_ms": float(np.percentile(a, 95)),
        "mean_ms": float(a.mean()),
        "max_ms": float(a.max()),
        "trail_segments": int(trails),
        "compare": bool(compare),
    }
