"""viser's own player in headless Chromium, driven one frame at a time: the pictures of videos
and stills.

A recording's self-contained page is opened with the page's clock faked (no timer or animation
frame runs unless told). A picture of playback time ``t`` is made by *seeking* the player to
``t`` (its time box: every recorded message up to ``t`` is applied, exactly, whatever the
machine's speed), running one animation frame of the fake clock (one WebGL render), and copying
the canvas into an image inside the page (JPEG for video frames, PNG for stills), which is the
only thing that crosses to Python. The page is told it is hidden: viser then applies a seek's
messages at once, as the seek is made (a visible page applies them inside the next animation
frame, where the updates that go through React reach the picture one frame after the poses,
so that frame would mix two moments). One call to the page per frame takes the picture and
makes the next seek (started by one call and collected by another when pages work side by
side).

A video's frames can be drawn by several copies of the page, each in a browser of its own,
working side by side (:meth:`Player.jpegs`): software WebGL draws a frame on every core, but a
page's own work (its scripts, copying the canvas, encoding the JPEG) runs on one, and meanwhile
another page's frame can be drawn.

The page is laid out at 360 CSS pixels high whatever the picture's size and drawn at
``height / 360`` device pixels per CSS pixel, so the scene's labels (a fixed size in CSS pixels)
keep their share of the picture: 15 px at 960x540, 60 px at 3840x2160. The camera comes from
URL parameters of viser's client (:meth:`mechviz.viz.framing.Camera.query`), which override the
recording's initial camera.
"""

from __future__ import annotations

import base64
import contextlib
import io
import shutil
import tempfile
import time
import urllib.parse
from collections.abc import Iterator, Sequence
from pathlib import Path

import numpy as np

from .chromium import find_chromium, first_page, launch
from .framing import Camera

LAYOUT_HEIGHT = 360  # CSS pixels: the page's height at every picture size
LOAD_TIMEOUT_S = 180.0  # first frame of a lit scene in software WebGL, on a loaded machine
JPEG_QUALITY = 0.92
# One step of the fake clock: one animation frame (the player's rAF loop)
TICK_MS = 16

# Installed before the page's own scripts: the page reports itself hidden (see the module
# docstring), the WebGL canvas keeps its picture after it is shown (so it can be copied between
# animation frames), a seek goes through the time box's React handler, and a picture is the
# canvas painted over the page's background.
_INIT = """
(() => {
  Object.defineProperty(Document.prototype, "hidden", { get: () => true });
  Object.defineProperty(Document.prototype, "visibilityState", { get: () => "hidden" });
  const getContext = HTMLCanvasElement.prototype.getContext;
  HTMLCanvasElement.prototype.getContext = function (type, attrs) {
    if (type === "webgl2" || type === "webgl") {
      attrs = { ...(attrs || {}), preserveDrawingBuffer: true, antialias: ANTIALIAS };
    }
    return getContext.call(this, type, attrs);
  };
  const setValue = Object.getOwnPropertyDescriptor(HTMLInputElement.prototype, "value").set;
  window.__mechvizSeek = (t) => {
    const box = document.querySelector("input[data-mechviz-time]");
    // fixed-point text: the box ignores a value equal to the one it shows ("0" after "0.0")
    setValue.call(box, t.toFixed(9));
    box.dispatchEvent(new Event("input", { bubbles: true }));
  };
  // The player starts playing as soon as it has the recording: its time box is marked and the
  // player held at 0 the moment the box appears, before any timer can run.
  const hold = new MutationObserver(() => {
    const box = document.querySelector("input.mantine-NumberInput-input");
    if (box === null) return;
    hold.disconnect();
    box.setAttribute("data-mechviz-time", "");
    window.__mechvizSeek(1e-9);
  });
  hold.observe(document, { childList: true, subtree: true });
  let out = null;
  window.__mechvizPicture = (type, quality, width, height) => {
    const src = document.querySelector('canvas[data-engine^="three.js"]');
    if (out === null || out.width !== width || out.height !== height) {
      out = document.createElement("canvas");
      out.width = width;
      out.height = height;
    }
    const ctx = out.getContext("2d");
    ctx.fillStyle = getComputedStyle(document.body).backgroundColor || "#ffffff";
    if (ctx.fillStyle === "rgba(0, 0, 0, 0)") ctx.fillStyle = "#ffffff";
    ctx.fillRect(0, 0, width, height);
    ctx.drawImage(src, 0, 0, width, height);
    return out.toDataURL(type, quality);
  };
  // one call per frame: the picture the last animation frame drew, then the next seek and
  // (tickMs > 0) the animation frame that draws it, run by this page's own fake clock
  window.__mechvizPictureThenSeek = async (type, quality, width, height, t, tickMs) => {
    const picture = window.__mechvizPicture(type, quality, width, height);
    if (t !== null) {
      window.__mechvizSeek(t);
      if (tickMs > 0) await globalThis.__pwClock.controller.runFor(tickMs);
    }
    return picture;
  };
  window.__mechvizTick = (tickMs) => globalThis.__pwClock.controller.runFor(tickMs);
  // the same call started in the page's next task, so that the caller can go on to another
  // page while this one works; its result is collected by awaiting window.__mechvizJob. (A
  // message channel, because the fake clock runs no timer unless stepped.)
  window.__mechvizStart = (type, quality, width, height, t, tickMs) => {
    const channel = new MessageChannel();
    window.__mechvizJob = new Promise((resolve, reject) => {
      channel.port1.onmessage = () => {
        window.__mechvizPictureThenSeek(type, quality, width, height, t, tickMs)
          .then(resolve, reject);
      };
    });
    channel.port2.postMessage(null);
  };
})();
"""


class PlayerError(RuntimeError):
    """The page could not be loaded or drawn; the message says what happened."""


def drawn(img: np.ndarray) -> bool:
    """More than a blank background."""
    return len(np.unique(img[::4, ::4].reshape(-1, 3), axis=0)) > 40


def decode(data: bytes) -> np.ndarray:
    """A JPEG or PNG as ``(H, W, 3)`` uint8."""
    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(data)).convert("RGB"))


class Player:
    """The recording's page open in headless Chromium, at ``size = (W, H)`` device pixels, seen
    from ``camera``. A context manager: Chromium, its profile and the page's copy live in a
    temporary folder removed on exit, whatever ends the block (Ctrl-C and SIGTERM included).

    ``antialias``: the WebGL canvas's multisampling (smoother lines; in software WebGL it costs
    about as much as the rest of a frame). ``pages``: copies of the page that draw a video's
    frames side by side (see :meth:`jpegs`)."""

    def __init__(
        self,
        page_html: bytes,
        size: tuple[int, int],
        *,
        camera: Camera | None = None,
        antialias: bool = True,
        pages: int = 1,
        executable: str | None = None,
    ) -> None:
        if pages < 1:
            raise ValueError(f"pages: at least 1, got {pages}")
        self.page_html = page_html
        self.pages = int(pages)
        self.size = (int(size[0]), int(size[1]))
        self.camera = camera or Camera()
        self.antialias = antialias
        self.executable = executable or find_chromium()
        self.load_seconds = 0.0
        self._stack = contextlib.ExitStack()
        self._page = None
        self._all: list = []  # every page; ``_page`` is the first
        self._own_clock = False  # see _load

    # ------------------------------------------------------------------ set-up
    def __enter__(self) -> Player:
        from playwright.sync_api import Error as PlaywrightError
        from playwright.sync_api import sync_playwright

        if self.executable is None:
            raise PlayerError("no Chromium found")
        t0 = time.perf_counter()
        try:
            tmp = tempfile.mkdtemp(prefix="mechviz-video-")
            self._stack.callback(shutil.rmtree, tmp, ignore_errors=True)
            html = Path(tmp) / "recording.html"
            html.write_bytes(self.page_html)
            pw = self._stack.enter_context(sync_playwright())
            W, H = self.size
            scale = H / LAYOUT_HEIGHT
            init = _INIT.replace("ANTIALIAS", "true" if self.antialias else "false")
            # one browser per page: each has a GPU process (software WebGL) of its own, so the
            # pages' first frames (shaders compiled, the environment map prepared) are made
            # side by side, and a page's fake clock steps that page alone
            for i in range(self.pages):
                profile = str(Path(tmp) / f"profile{i}")
                context = launch(pw, profile, self.executable, W / scale, H / scale, scale)
                self._stack.callback(_close_quietly, context)
                page = first_page(context)
                page.add_init_script(init)
                self._all.append(page)
            self._page = self._all[0]
            self._load(html, scale)
            # playwright's clock keeps a log of every step it makes (and replays it into every
            # page); where the page's own end of it can be reached, the page is stepped by it,
            # in the same call that takes its picture
            self._own_clock = all(
                p.evaluate("typeof globalThis.__pwClock?.controller?.runFor === 'function'")
                for p in self._all
            )
        except PlaywrightError as exc:
            self._stack.close()
            raise PlayerError(f"Chromium failed while loading the recording: {exc}") from None
        except BaseException:
            self._stack.close()
            raise
        self.load_seconds = time.perf_counter() - t0
        return self

    def __exit__(self, *exc) -> None:
        self._stack.close()

    def _load(self, html: Path, scale: float) -> None:
        """Every page loaded side by side, each on its own fake clock."""
        pages = self._all
        query = {"fixedDpr": f"{scale:.6g}", **self.camera.query()}
        for page in pages:
            page.clock.install(time=0)
            page.clock.pause_at(1)  # from the start: no timer runs unless stepped
            page.goto(html.as_uri() + "?" + urllib.parse.urlencode(query, safe=","))
        deadline = time.monotonic() + LOAD_TIMEOUT_S

        def wait(ready, step_ms: int, what: str) -> None:
            waiting = list(pages)
            while True:
                waiting = [page for page in waiting if not ready(page)]
                if not waiting:
                    return
                if time.monotonic() > deadline:
                    raise PlayerError(what)
                for page in waiting:
                    page.clock.run_for(step_ms)

        wait(self._hold, TICK_MS, "the recording's page did not load in Chromium (no player)")
        canvas = 'canvas[data-engine^="three.js"]'
        wait(
            lambda page: page.locator(canvas).count(),
            100,
            "the recording's page did not load in Chromium (no canvas)",
        )
        wait(
            lambda page: drawn(decode(self._picture("image/jpeg", page))),
            100,
            "the recording's scene was never drawn in Chromium",
        )

    def _hold(self, page) -> bool:
        """Once the player is there: its time box marked and the player held at 0 (the page's
        own script does both as the box appears; here, if it did not know the box, as soon as
        it is seen), and the page made invisible. False while the player is not there yet."""
        if not page.locator("input[data-mechviz-time]").count():
            time_box = page.get_by_role("textbox")
            if not time_box.count():
                return False
            time_box.first.evaluate("el => el.setAttribute('data-mechviz-time', '')")
        # Nothing on the page is ever shown (pictures are copied from the canvas's own buffer):
        # hidden, the playback bar costs no layout or paint when a seek re-renders it, and the
        # page's compositor has nothing to draw.
        page.add_style_tag(content=".mantine-Paper-root, canvas { visibility: hidden !important; }")
        self._seek(1e-9, page)  # seeking pauses the player: from now on only our seeks move it
        return True

    # ------------------------------------------------------------------ pictures
    def _seek(self, t: float, page=None) -> None:
        (page or self._page).evaluate(f"window.__mechvizSeek({float(t)!r})")

    def _tick(self, page=None) -> None:
        page = page or self._page
        if self._own_clock:
            page.evaluate(f"window.__mechvizTick({TICK_MS})")
        else:
            page.clock.run_for(TICK_MS)

    def _picture(self, mime: str, page=None) -> bytes:
        W, H = self.size
        url = (page or self._page).evaluate(
            f"window.__mechvizPicture({mime!r}, {JPEG_QUALITY}, {W}, {H})"
        )
        return base64.b64decode(url.split(",", 1)[1])

    def jpegs(self, times: Sequence[float]) -> Iterator[bytes]:
        """JPEG pictures of the recording at each playback time in ``times`` (ascending), one
        WebGL render each (see the module docstring), in the order of ``times``.

        With ``n`` pages, page ``i`` draws frames ``i, i + n, i + 2n, ...``. Each page is given
        a job (the picture of its frame, then the seek to its next frame and the animation
        frame that draws it) that it starts on its own and that is collected later, so the
        pages work side by side while Python collects, decodes and encodes: the picture of
        frame ``k`` is collected from page ``k % n``, which is then given its next job. Without
        the page's own clock (each step through playwright's), the pages are called in turn."""
        from playwright.sync_api import Error as PlaywrightError

        W, H = self.size
        count = len(times)
        n = min(len(self._all), count)
        pages = self._all[:n]
        tick = TICK_MS if self._own_clock else 0

        def job(k: int) -> str:
            """The page's call that takes the picture of frame ``k`` and draws frame ``k + n``."""
            t = repr(float(times[k + n])) if k + n < count else "null"
            return f"('image/jpeg', {JPEG_QUALITY}, {W}, {H}, {t}, {tick})"

        try:
            for i, page in enumerate(pages):
                self._seek(times[i], page)
                self._tick(page)  # draws frame i
            side_by_side = n > 1 and self._own_clock
            if side_by_side:
                for i, page in enumerate(pages):
                    page.evaluate(f"window.__mechvizStart{job(i)}")
            for k in range(count):
                page = pages[k % n]
                if side_by_side:
                    url = page.evaluate("window.__mechvizJob")
                    if k + n < count:
                        page.evaluate(f"window.__mechvizStart{job(k + n)}")
                else:
                    # with the page's own clock, its animation frame drew frame k + n too
                    url = page.evaluate(f"window.__mechvizPictureThenSeek{job(k)}")
                    if k + n < count and not tick:
                        self._tick(page)  # draws frame k + n
                yield base64.b64decode(url.split(",", 1)[1])
        except PlaywrightError as exc:
            raise PlayerError(f"Chromium failed while drawing the frames: {exc}") from None

    def png(self, t: float) -> bytes:
        """A lossless picture of the recording at playback time ``t``."""
        from playwright.sync_api import Error as PlaywrightError

        try:
            self._seek(t)
            self._tick()
            self._tick()
            return self._picture("image/png")
        except PlaywrightError as exc:
            raise PlayerError(f"Chromium failed while drawing the picture: {exc}") from None


def _close_quietly(context) -> None:
    with contextlib.suppress(Exception):
        context.close()
