"""mechviz in a Jupyter notebook: a recorded demo or the live viewer, inline.

>>> from viz import notebook
>>> notebook.show("radial-kick", dv=0.8)      # the demo recorded headless, played inline
>>> notebook.live()                           # the viewer with its GUI, inline

:func:`show` runs a demo headless (the recorder's own run, :func:`viz.record.run_demo`: the
viewer's exhibit for the demo's settings), and returns an :class:`Embed` that a notebook
displays as viser's self-contained player in an ``<iframe srcdoc>`` (play/pause, time, scrubber,
speed; the view turns with the mouse), with the measured-against-predicted figures below it.
Each embed carries viser's browser client (about 0.8 MB) plus the recording, so a notebook
with three embeds saved with its outputs weighs about 2.5 MB. To keep notebooks small, clear
the outputs before saving or committing (Jupyter: *Edit -> Clear Outputs of All Cells*; or
``jupyter nbconvert --clear-output --inplace NB.ipynb``), or pass ``save="demos/kick.html"``:
the page is written to that file and the notebook holds only an ``<iframe src>`` to it (a few
hundred bytes; the file must sit beside the notebook, under the folder Jupyter serves).

:func:`live` starts the viewer (:class:`viz.app.MechvizApp`) inside the kernel, once, and
embeds an ``<iframe>`` to its local address; :func:`stop` stops it. The browser showing the
notebook must run on the same machine as the kernel (the viewer binds 127.0.0.1).
"""

from __future__ import annotations

import html as html_module
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import msgspec

__all__ = ["Embed", "demos", "live", "load", "show", "stop"]

DEFAULT_HEIGHT = 480
_app = None  # the live viewer started by live()


@dataclass
class Embed:
    """A recorded demo, displayed inline by Jupyter (``_repr_html_``).

    ``page`` is the self-contained player page; ``figures`` the measured-against-predicted
    figures (as in the recording's manifest); ``src`` the file the page was saved to, if any."""

    name: str
    title: str
    page: bytes
    figures: list[dict[str, Any]] = field(default_factory=list)
    height: int = DEFAULT_HEIGHT
    src: str | None = None

    @property
    def size_bytes(self) -> int:
        """Bytes this embed adds to a saved notebook."""
        return len(self._repr_html_().encode("utf-8"))

    def _repr_html_(self) -> str:
        if self.src is not None:
            frame = (
                f'<iframe src="{html_module.escape(self.src, quote=True)}" width="100%" '
                f'height="{self.height}" style="border:none;display:block"></iframe>'
            )
        else:
            doc = html_module.escape(self.page.decode("utf-8"), quote=True)
            frame = (
                f'<iframe srcdoc="{doc}" width="100%" height="{self.height}" '
                'style="border:none;display:block"></iframe>'
            )
        rows = "".join(
            f"<tr><td>{html_module.escape(f['name'])}</td><td>{f['measured']:.6g}</td>"
            f"<td>{'' if f['predicted'] is None else format(f['predicted'], '.6g')}</td>"
            f"<td>{html_module.escape(f.get('unit') or '')}</td></tr>"
            for f in self.figures
            if f.get("measured") is not None
        )
        table = (
            "<table><tr><th>measured</th><th></th><th>theory</th><th></th></tr>" + rows + "</table>"
            if rows
            else ""
        )
        return (
            f'<div class="mechviz-embed" data-demo="{html_module.escape(self.name)}">'
            f"<b>{html_module.escape(self.title)}</b>"
            f'<div style="border:1px solid #ddd">{frame}</div>{table}</div>'
        )


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
    **changes: Any,
) -> Embed:
    """Record ``demo`` headless (with :func:`load`'s ``changes``) and return it for inline
    display; ``save`` writes the page to that file instead of into the notebook."""
    from dynamics.files import write_files_atomically

    from . import record as rec

    d = load(demo, **changes)
    recorded = rec.run_demo(d)
    figs = rec.figures(d, recorded.traces)
    src = None
    if save is not None:
        path = Path(save)
        write_files_atomically(
            path.parent if str(path.parent) else Path("."), {path.name: recorded.html}
        )
        src = str(save)
    return Embed(d.name, d.title, recorded.html, figs, height, src)


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
        return f"mechviz viewer at {self.url}"


def live(*, port: int = 8080, height: int = 650, environment_map: bool = True) -> _Live:
    """Start the viewer in this kernel (once; later calls reuse it) and embed it with its GUI.
    A busy ``port`` moves to the next free one."""
    global _app
    if _app is None:
        from .app import MechvizApp

        _app = MechvizApp(host="127.0.0.1", port=port, environment_map=environment_map)
    return _Live(_app.url, height)


def stop() -> None:
    """Stop the viewer :func:`live` started (nothing if none runs)."""
    global _app
    if _app is not None:
        _app.stop()
        _app = None
