"""mechviz in a Jupyter notebook: a recorded demo or the live viewer, inline.

>>> from mechviz.viz import notebook
>>> notebook.show("radial-kick", dv=0.8)      # the demo recorded headless, played inline
>>> notebook.live()                           # the viewer with its GUI, inline
>>> notebook.recorded("out/helix")            # a recording mechviz record wrote, inline

:func:`show` runs a demo headless (the recorder's own run, :func:`mechviz.viz.record.run_demo`: the
viewer's exhibit for the demo's settings) and returns an :class:`Embed`, which a notebook shows
as two outputs: a still of the scene (a PNG of viser's player paused at the last frame,
:mod:`mechviz.viz.page_still`), and viser's self-contained player in an ``<iframe srcdoc>`` (play/pause,
time, scrubber, speed; the view turns with the mouse) with the measured-against-predicted
figures below it. Each is stored once, with a one-line text form. Jupyter drops the player from
a notebook that is not trusted (one opened from someone else, until its cells are run), and
GitHub shows no live page: the still shows there. The player carries viser's browser client
(about 0.8 MB) plus the recording; ``save="demos/kick.html"`` writes the page, and the still
beside it (``kick.png``), to files instead: the notebook then holds only a linked picture and an
``<iframe src>`` (under 1 kB). The files must sit under the folder Jupyter serves.

:func:`recorded` shows a recording read back from its folder, every file checked against its
manifest first (:func:`mechviz.dynamics.api.read_recording`): a folder holding a mix of two
recordings raises ``ValueError`` naming the file that does not belong.

:func:`live` starts the viewer (:class:`mechviz.viz.app.MechvizApp`) inside the kernel, once, and
embeds an ``<iframe>`` to its address, 127.0.0.1 and a port of its own: the browser showing the
notebook must run on the machine of the kernel. It does not reach a browser through JupyterHub,
Colab, Binder or a remote VS Code session (which forward only Jupyter's own port); there, use
:func:`show`, or run ``mechviz view`` where the browser is. :func:`stop` stops it.
"""

from __future__ import annotations

import base64
import contextlib
import html as html_module
import io
import json
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import msgspec

__all__ = ["Embed", "demos", "live", "load", "recorded", "show", "stop"]

DEFAULT_HEIGHT = 480
_app = None  # the live viewer started by live()


@dataclass(frozen=True)
class Embed:
    """A recorded demo, for inline display by Jupyter (two outputs: the still, the player).

    ``page``: the self-contained player page; ``figures``: the measured-against-predicted
    figures (as in the recording's manifest); ``still``: a PNG of the scene at ``at`` [s of
    playback] (``None``, and ``still_note`` says why, where none could be taken); ``src`` and
    ``still_src``: the files the page and the still were saved to, if any (the notebook then
    links to them instead of holding them)."""

    name: str
    title: str
    page: bytes = field(repr=False)
    figures: list[dict[str, Any]] = field(default_factory=list, repr=False)
    height: int = DEFAULT_HEIGHT
    src: str | None = None
    still: bytes | None = field(default=None, repr=False)
    still_src: str | None = None
    at: float = 0.0
    still_note: str = ""

    def __post_init__(self) -> None:
        if self.still_src is not None and self.src is None:
            raise ValueError("still_src needs src: a saved still goes with a saved page")

    @property
    def size_bytes(self) -> int:
        """Bytes this embed adds to a saved notebook (its outputs as JSON)."""
        return len(json.dumps([data for data, _meta in self.outputs()]))

    def outputs(self) -> list[tuple[dict[str, str], dict[str, Any]]]:
        """The notebook outputs, as ``(data, metadata)`` mime bundles: the still (when it is
        held inline), then the player with the figures."""
        text = repr(self)
        out = []
        if self.still is not None and self.still_src is None:
            out.append(
                (
                    {
                        "image/png": base64.b64encode(self.still).decode("ascii"),
                        "text/plain": f"still of {self.name} at t = {self.at:.4g} s",
                    },
                    {"image/png": _png_size(self.still)},
                )
            )
        out.append(({"text/html": self._repr_html_(), "text/plain": text}, {}))
        return out

    def _ipython_display_(self) -> None:
        from IPython.display import display

        for data, metadata in self.outputs():
            display(data, metadata=metadata, raw=True)

    def _repr_html_(self) -> str:
        esc = html_module.escape
        if self.src is not None:
            frame = (
                f'<iframe src="{esc(self.src, quote=True)}" width="100%" '
                f'height="{self.height}" style="border:none;display:block"></iframe>'
            )
            picture = ""
            if self.still_src is not None:
                picture = (
                    f'<a href="{esc(self.src, quote=True)}" target="_blank">'
                    f'<img src="{esc(self.still_src, quote=True)}" '
                    f'alt="still of {esc(self.name)} at t = {self.at:.4g} s" '
                    'style="max-width:100%"></a>'
                )
            note = (
                f'The player: <a href="{esc(self.src, quote=True)}" target="_blank">'
                f"{esc(self.src)}</a>"
            )
        else:
            # an attribute value needs only & and the quote escaped
            doc = self.page.decode("utf-8").replace("&", "&amp;").replace('"', "&quot;")
            frame = (
                f'<iframe srcdoc="{doc}" width="100%" height="{self.height}" '
                'style="border:none;display:block"></iframe>'
            )
            picture = ""
            note = (
                "The player shows where the notebook is trusted (run the cell, or trust the "
                "notebook); elsewhere the still above shows the scene"
            )
        if self.still is None and self.still_note:
            note += f"; no still: {esc(self.still_note)}"
        rows = "".join(
            f"<tr><td>{esc(f['name'])}</td><td>{f['measured']:.6g}</td>"
            f"<td>{'' if f['predicted'] is None else format(f['predicted'], '.6g')}</td>"
            f"<td>{esc(f.get('unit') or '')}</td></tr>"
            for f in self.figures
            if f.get("measured") is not None
        )
        table = (
            "<table><tr><th>measured</th><th></th><th>theory</th><th></th></tr>" + rows + "</table>"
            if rows
            else ""
        )
        return (
            f'<div class="mechviz-embed" data-demo="{esc(self.name)}">'
            f"<b>{esc(self.title)}</b><br><small>{note}.</small>{picture}"
            f'<div style="border:1px solid #ddd">{frame}</div>{table}</div>'
        )


def _png_size(png: bytes) -> dict[str, int]:
    """A PNG's width and height [px], from its header (Jupyter sizes the picture by them)."""
    from PIL import Image

    with Image.open(io.BytesIO(png)) as img:
        return {"width": img.width, "height": img.height}


def demos() -> dict[str, str]:
    """The built-in demos: name -> one-line description."""
    from . import record as rec

    return {d.name: d.description for d in rec.list_demos()}


def load(
    demo: str,
    *,
    duration: float | None = None,
    fps: int | None = None,
    method: str | None = None,
    dt: float | None = None,
    dv: float | None = None,
    **parameters: float,
):
    """A demo (built-in name or ``.toml`` path) with changes, checked: ``duration`` [s of
    playback], ``fps``, ``method``, ``dt``, ``dv`` (every scripted kick's strength, m/s) and the
    exhibit's physical parameters by name (``field=2.0``). ``ValueError`` names what is wrong."""
    from . import record as rec
    from .record.demo import check

    d = rec.load_demo(demo)
    d = d.with_overrides(duration=duration, fps=fps, method=method, dt=dt)
    changes: dict[str, Any] = {}
    if dv is not None:
        if not d.events:
            raise ValueError(f"dv: the demo {d.name} has no kick")
        changes["events"] = tuple(msgspec.structs.replace(e, dv=float(dv)) for e in d.events)
    if parameters:
        changes["parameters"] = {**d.parameters, **{k: float(v) for k, v in parameters.items()}}
    if changes:
        d = msgspec.structs.replace(d, **changes)
        try:
            check(d)
        except TypeError as exc:
            raise ValueError(str(exc)) from None
    return d


def show(
    demo: str,
    *,
    height: int = DEFAULT_HEIGHT,
    save: str | os.PathLike | None = None,
    still: bool = True,
    **changes: Any,
) -> Embed:
    """Record ``demo`` headless (with :func:`load`'s ``changes``) and return it for inline
    display, with a still of its last frame (``still=False`` leaves the still out; it needs
    Chromium and playwright, and takes seconds). ``save`` (a path ending in ``.html``) writes
    the page there and the still beside it (``.png``), and the notebook links to them."""
    from mechviz.dynamics.files import write_files_atomically

    from . import record as rec
    from .page_still import StillUnavailable, page_still

    path = None
    if save is not None:
        path = Path(save)
        if path.suffix != ".html":
            raise ValueError(f"save must name an .html file, got {str(save)!r}")
    d = load(demo, **changes)
    with _quiet():
        recorded = rec.run_demo(d)
    figs = rec.figures(d, recorded.traces)
    at = (d.frames - 1) / d.fps  # the last frame, in playback time
    png, note = None, ""
    if still:
        try:
            png = page_still(recorded.html, at)
        except StillUnavailable as exc:
            note = str(exc)
    src = still_src = None
    if path is not None:
        files = {path.name: recorded.html}
        if png is not None:
            files[path.with_suffix(".png").name] = png
            still_src = str(Path(save).with_suffix(".png"))
        write_files_atomically(path.parent if str(path.parent) else Path("."), files)
        src = str(save)
    return Embed(d.name, d.title, recorded.html, figs, height, src, png, still_src, at, note)


def recorded(path: str | os.PathLike, *, height: int = DEFAULT_HEIGHT) -> Embed:
    """The recording ``mechviz record`` wrote at ``path`` (``out/helix``, or one of its files),
    checked against its manifest, for inline display: its player page and figures (no still;
    its chart is ``DEMO.png`` beside it). ``ValueError`` names the file that does not belong
    when the folder holds a mix of two recordings."""
    from mechviz.dynamics.api import read_recording

    rec = read_recording(path)
    page = rec.files.get(f"{rec.name}.html")
    if page is None:
        raise ValueError(f"{rec.folder / rec.name}.json lists no {rec.name}.html")
    figures = rec.manifest.get("figures")
    return Embed(
        rec.name,
        str(rec.manifest.get("title", rec.name)),
        page,
        figures if isinstance(figures, list) else [],
        height,
        still_note="a recording read from its folder; its chart is the .png beside it",
    )


class _Live:
    """The live viewer inline (``_repr_html_``): an ``<iframe>`` to its local address."""

    def __init__(self, url: str, height: int):
        self.url, self.height = url, height

    def _repr_html_(self) -> str:
        return (
            f'<iframe src="{html_module.escape(self.url, quote=True)}" width="100%" '
            f'height="{self.height}" style="border:1px solid #ddd"></iframe>'
        )

    def __repr__(self) -> str:
        return f"mechviz viewer at {self.url} (a browser on this machine only)"


def live(*, port: int = 8080, height: int = 650, environment_map: bool = True) -> _Live:
    """Start the viewer in this kernel (once; later calls reuse it) and embed it with its GUI.
    A busy ``port`` moves to the next free one. The viewer listens on 127.0.0.1 only: the
    browser must run on the kernel's machine (not JupyterHub, Colab, Binder or a remote VS
    Code session; see the module docstring)."""
    global _app
    if _app is None:
        from .app import MechvizApp

        with _quiet():
            _app = MechvizApp(host="127.0.0.1", port=port, environment_map=environment_map)
    return _Live(_app.url, height)


def stop() -> None:
    """Stop the viewer :func:`live` started (nothing if none runs)."""
    global _app
    if _app is not None:
        with _quiet():
            _app.stop()
        _app = None


@contextlib.contextmanager
def _quiet():
    """Hold back viser's start-up banner and its "Server stopped" line. viser prints them with
    rich, which in a Jupyter kernel shows them as outputs of their own, not through stdout, and
    the second from the server's own thread: rich's console is silenced (for every thread) while
    the server starts and stops."""
    import rich

    console = rich.get_console()
    was = console.quiet
    console.quiet = True
    try:
        with contextlib.redirect_stdout(io.StringIO()):
            yield
    finally:
        console.quiet = was
