"""The viewer's Record toggle: the live scene, recorded as the user drives it, as one HTML file.

Everything the scene shows is recorded (kicks, mode changes, method switches, pauses), timed by
the wall clock; GUI panels are not part of the scene. The page is viser's own self-contained
player (``StateSerializer.as_html``): it plays from file:// with no server and no Python. It also
carries what a video of it needs (:func:`mechviz.viz.video.with_session_info`): the camera the viewer
had when recording started, the title of the exhibit it looked at, and that exhibit's bounds.
"""

from __future__ import annotations

import contextlib
import threading
import time
from typing import Any

import numpy as np


class LiveRecorder:
    """Records the live viewer's scene while the Record toggle is on, then offers it as a
    download (the self-contained HTML: it plays from file:// with no server).

    Everything the scene shows is recorded as the user drives it (kicks, mode changes, method
    switches, pauses), timed by the wall clock; GUI panels are not part of the scene. Start and
    stop run in the app's loop thread (the toggle only enqueues them); serializing and sending
    run on a worker thread so the loop keeps its rate. Sessions stop by themselves after
    ``max_seconds``.
    """

    def __init__(self, app, *, max_seconds: float = 600.0) -> None:
        self.app = app
        self.server = app.server
        self.max_seconds = max_seconds
        self.serializer = None
        self.seconds = 0.0
        self.checkbox = None
        self.last_result: tuple[str, bytes] | None = None  # (filename, html) of the last session
        self.finished = threading.Event()
        self._last = 0.0
        self._client = None
        self._info: dict[str, Any] = {}
        app.frame_hooks.append(self.on_frame)

    @property
    def recording(self) -> bool:
        return self.serializer is not None

    def start(self, client=None) -> None:
        if self.recording:
            return
        self.finished.clear()
        self.serializer = self.server.get_scene_serializer()
        self.seconds = 0.0
        self._last = time.perf_counter()
        self._client = client
        self._info = {}
        for source in (client, None):  # a client whose camera cannot be read: the initial one
            try:
                self._info = session_info(self.app, source)
                break
            except Exception:  # the recording itself must start whatever the camera says
                continue
        self.app.notify("Recording", "The scene is being recorded; untick Record to stop.", "blue")

    def on_frame(self, app) -> None:
        if self.serializer is None:
            return
        now = time.perf_counter()
        self.serializer.insert_sleep(max(now - self._last, 0.0))
        self.seconds += now - self._last
        self._last = now
        if self.seconds >= self.max_seconds:
            self.stop()
            if self.checkbox is not None:
                self.checkbox.value = False

    def stop(self, client=None, *, wait: bool = False) -> None:
        serializer, self.serializer = self.serializer, None
        if serializer is None:
            return
        serializer.insert_sleep(max(time.perf_counter() - self._last, 1e-3))
        target = client or self._client
        seconds = self.seconds
        worker = threading.Thread(
            target=self._finish, args=(serializer, target, seconds, self._info), daemon=True
        )
        worker.start()
        if wait:
            worker.join()

    def _finish(self, serializer, client, seconds: float, info: dict[str, Any]) -> None:
        try:
            from .video import with_session_info

            html = with_session_info(serializer.as_html().encode("utf-8"), info)
            name = time.strftime("mechviz-session-%Y%m%d-%H%M%S.html", time.localtime())
            self.last_result = (name, html)
            clients = self.server.get_clients()
            if client is not None and client.client_id in clients:
                client.send_file_download(name, html, save_immediately=True)
            else:
                self.server.send_file_download(name, html, save_immediately=True)
            self.app.notify(
                "Recording saved",
                f"{name}: {seconds:.1f} s, {len(html) / 1e6:.2f} MB; opens in any browser.",
                "green",
            )
        except Exception as exc:  # never take the viewer down
            self.app.notify("Recording failed", f"{type(exc).__name__}: {exc}")
        finally:
            self.finished.set()


def session_info(app, client=None) -> dict[str, Any]:
    """What a video of a session needs: the camera ``client`` has (the server's initial camera
    without one), the exhibit it looks at (the one presented, else the one nearest the point
    looked at): its title and world bounds, and when."""
    cam = client.camera if client is not None else app.server.initial_camera
    position = [float(x) for x in np.asarray(cam.position, float)]
    look_at = [float(x) for x in np.asarray(cam.look_at, float)]
    exhibits = app.exhibits
    key = app.presenting
    if key is None:
        key = min(
            exhibits,
            key=lambda k: float(np.linalg.norm(np.mean(exhibits[k].bounds, axis=0) - look_at)),
        )
    ex = exhibits[key]
    lo, hi = ex.bounds
    fov = getattr(cam, "fov", None)
    return {
        "title": ex.model.title,
        "caption": time.strftime("Recorded in the live viewer, %Y-%m-%d %H:%M", time.localtime()),
        "camera": {
            "position": position,
            "look_at": look_at,
            "fov": float(fov) if fov is not None else None,
        },
        "scene": {
            "bounds": [[float(x) for x in lo], [float(x) for x in hi]],
            "view": [[float(x) for x in v] for v in ex.camera],
        },
    }


def add_record_toggle(app) -> LiveRecorder:
    """Add the Record checkbox to the viewer's common GUI folder (:class:`mechviz.viz.app.MechvizApp`)
    and return its :class:`LiveRecorder`. Call once, after the app built its GUI."""
    recorder = LiveRecorder(app)
    folder = app.common_folder
    with folder if folder is not None else contextlib.nullcontext():
        box = app.server.gui.add_checkbox(
            "Record",
            initial_value=False,
            hint="Record the scene as you drive it; untick to download it as one HTML file",
        )
    recorder.checkbox = box

    @box.on_update
    def _(event) -> None:
        on, client = box.value, event.client
        if on:
            app.enqueue("call", lambda _app: recorder.start(client))
        else:
            app.enqueue("call", lambda _app: recorder.stop(client))

    return recorder
