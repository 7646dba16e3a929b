"""What the three scenes share: the exhibit, the viser view of an exhibit's model.

An *exhibit* is a view built over a model (:class:`mechviz.viz.model.base.ExhibitModel`: the
runs, events, samples and measured figures, headless), kept as its ``model``: it draws the
model in a viser scene and builds its GUI panel. The view observes the model
(:meth:`mechviz.viz.model.observed.Observed.observe`) and so knows when to draw again, whoever
changed it; everything about the run (advance, apply a command, scrub, the figures, the charts'
data) is asked of ``exhibit.model``. The live viewer (:mod:`mechviz.viz.app`) and the recorder's
``.viser`` files (:mod:`mechviz.viz.record`) draw the same exhibits, so a demo reaches the screen
by one path. Every exhibit has

- ``model``, and ``model_type``: the model class it draws (the registries pair them by system),
- ``draw()``: handle assignments only; the caller wraps ``server.atomic()``; ``to_draw`` says
  whether the model changed since (``draw_if_changed()`` draws only then),
- ``readout()`` (markdown), ``camera``, ``bounds``, ``labels()``,
- ``build_panel(panel)``: its controls, in the tab the app gives it (:mod:`mechviz.viz.scene.panel`),
- ``close()``: it stops observing its model (the model runs on, undrawn),

and the hooks ``_build`` (scene nodes, once) and ``_started`` (the model's ``"started"``: reset
what is drawn for a new start); a subclass answers the model's other announcements
(:data:`mechviz.viz.model.observed.Event`) in ``listens``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, ClassVar

import numpy as np

from mechviz.dynamics.simulation import error_verdict

from ..model.base import (  # noqa: F401  (re-exported for the scenes)
    DIVERGED,
    LOG_FLOOR,
    PAUSED_HINT,
    ExhibitConfig,
    ExhibitModel,
    History,
    Motion,
    Ring,
    finite_numbers,
    fmt,
    log10_abs,
    positive,
)
from ..model.observed import Event


def brief(x, digits: int = 4) -> str:
    """A measured figure short enough to show large: its value, or "not resolved"."""
    if hasattr(x, "value"):
        return "not resolved" if x.value is None else fmt(x.value, digits)
    return fmt(x, digits)


def against_theory(x, unit: str, theory: float) -> str:
    """A measured figure beside its theory, short enough to show large: ``2.208 rad/s (theory
    2.215)``, or ``not resolved (theory 3.836 rad/s)``, the unit never after "not resolved"."""
    shown = brief(x)
    if shown == "not resolved":
        return f"not resolved (theory {fmt(theory, 4)} {unit})"
    return f"{shown} {unit} (theory {fmt(theory, 4)})"


def error_text(smp) -> str:
    """A sample's error against its reference with the reference's own measured error
    (:func:`mechviz.dynamics.simulation.error_verdict`); "0.00e+00" where not measured."""
    if smp.error is None:
        return f"{0.0:.2e}"
    bar = None if smp.reference_accuracy is None else float(np.max(smp.reference_accuracy))
    return error_verdict(float(np.max(smp.error)), bar)


class NodeBook:
    """An exhibit's view of viser's scene API that keeps every handle it creates, by name.

    viser 1.1 has no public way to list the nodes under a name, and the stage needs them: it
    hides the other exhibits and sizes every label. Every ``add_*`` call goes through this book
    (the scenes, their helpers in :mod:`mechviz.viz.geometry` and the maps take it as their
    ``scene``); anything else is viser's own API, passed through. Line segments are made and
    removed by the thousand as trails grow (:class:`mechviz.viz.geometry.ChunkedTrail`), so they
    are not kept: they hide with their exhibit's root frame. ``label_scale`` is the size new
    labels get (the stage sets it, and the size of the ones already made, for the page).
    """

    def __init__(self, scene) -> None:
        self._scene = scene
        self.handles: dict[str, Any] = {}  # node name -> the handle of its latest add_* call
        self.label_scale = 1.0  # times viser's screen label size, for labels made from now on

    def __getattr__(self, attr: str):
        value = getattr(self._scene, attr)
        if not attr.startswith("add_") or not callable(value):
            return value

        def add(name: str, *args, **kwargs):
            if attr == "add_label":
                kwargs.setdefault("font_screen_scale", self.label_scale)
            handle = value(name, *args, **kwargs)
            if attr != "add_line_segments":
                self.handles[name] = handle
            return handle

        return add

    def under(self, root: str) -> dict[str, Any]:
        """Name -> handle of the kept nodes at or below ``root`` (a name made again is its
        newest handle)."""
        prefix = root.rstrip("/") + "/"
        return {
            name: h
            for name, h in list(self.handles.items())  # a snapshot: the loop may add nodes
            if name == root or name.startswith(prefix)
        }


class Exhibit:
    """A model drawn: subclasses name their ``model_type`` and add ``icon``, ``_build``,
    ``_started``, ``draw``, ``readout``, ``camera``, ``_extent`` and ``build_panel``.

    Built over ``model`` (a model of ``model_type``; a config, or ``None`` for the defaults,
    builds one with ``history_len``). ``bounded``: beside other exhibits (the live viewer), a
    runaway is drawn only inside the exhibit's box, and the model is told that box (a run that
    leaves it has diverged, :meth:`mechviz.viz.model.base.ExhibitModel.confine`); alone (a
    recording) it is drawn all."""

    model_type: ClassVar[type[ExhibitModel]]
    key: ClassVar[str] = ""  # its system's name, the model type's
    icon: ClassVar[str] = "CIRCLE"  # a viser.Icon name for the exhibit's tab
    caption: ClassVar[str] = ""  # "what you see", shown on the exhibit's stage
    # what the view does when the model announces it, beyond drawing again: a method's name
    listens: ClassVar[dict[Event, str]] = {"started": "_started"}

    def __init_subclass__(cls, **kwargs) -> None:
        super().__init_subclass__(**kwargs)
        if "model_type" in cls.__dict__:
            cls.key = cls.model_type.key

    def __init__(
        self,
        server,
        model: ExhibitModel | ExhibitConfig | None = None,
        *,
        origin=(0.0, 0.0, 0.0),
        history_len: int = 600,
        bounded: bool = False,
    ) -> None:
        if isinstance(model, ExhibitModel) and not isinstance(model, self.model_type):
            raise TypeError(
                f"{type(self).__name__} draws a {self.model_type.__name__}, not {model!r}"
            )
        if not isinstance(model, self.model_type):
            model = self.model_type(model, history_len=history_len)
        self.model = model
        self.bounded = bounded
        self.server = server
        self.scene = NodeBook(server.scene)  # every node this exhibit makes, by name
        self.origin = np.asarray(origin, dtype=float)
        self.root = f"/{self.key}"
        self.to_draw = True  # the model changed since last drawn (drawn once at least)
        self._build()
        self._started()
        self._stops: list[Callable[[], None]] = [model.observe(self._model_changed)]
        for event, method in self.listens.items():
            self._stops.append(model.on(event, getattr(self, method)))
        if bounded:  # the box is the config's: told again at every start
            self._confine()
            self._stops.append(model.on("started", self._confine))

    def _confine(self) -> None:
        lo, hi = self._extent()
        self.model.confine((np.asarray(lo, float), np.asarray(hi, float)))

    def _model_changed(self, _model: ExhibitModel) -> None:
        """The model changed (an advance, a command, a scrub): draw it again next frame."""
        self.to_draw = True

    def draw_if_changed(self) -> bool:
        """Draw if the model changed since last drawn (or the view asked to be); whether it did."""
        if not self.to_draw:
            return False
        self.to_draw = False  # before: a change while drawing is drawn next time
        self.draw()
        return True

    def close(self) -> None:
        """Stop observing the model: its changes are no longer drawn (its nodes stay)."""
        for stop in self._stops:
            stop()
        self._stops.clear()

    # ------------------------------------------------------------------ subclass hooks
    def _build(self) -> None:  # pragma: no cover - abstract
        raise NotImplementedError

    def draw(self) -> None:  # pragma: no cover - abstract
        raise NotImplementedError

    def readout(self) -> str:  # pragma: no cover - abstract
        raise NotImplementedError

    def build_panel(self, panel) -> None:  # pragma: no cover - abstract
        raise NotImplementedError

    def refresh_panel(self, panel) -> None:
        """Pictures of the exhibit's own in its panel, refreshed with the readout (5 Hz)."""

    def sync_panel(self, panel) -> None:
        """Widgets of the exhibit's own that :meth:`mechviz.viz.scene.panel.Panel.sync` does not know."""

    @property
    def camera(self) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
        raise NotImplementedError

    @property
    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """World box (low corner, high corner) [m] that holds what the exhibit draws, for
        framing: subclasses give it relative to their origin in ``_extent``."""
        lo, hi = self._extent()
        return self.origin + np.asarray(lo, float), self.origin + np.asarray(hi, float)

    def _extent(self):  # pragma: no cover - abstract
        raise NotImplementedError

    @property
    def home_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """World box [m] of what the exhibit shows at home, beside the others (what it draws
        only on stage left out, :meth:`on_stage`): by default :attr:`bounds`."""
        return self.bounds

    def key_figures(self) -> list[tuple[str, str]]:
        """``(name, value)`` of the figures presentation mode shows large beside the exhibit:
        the time and the relative energy error, and each exhibit's own measured figures."""
        smp = self.model.sample
        return [
            ("t", f"{self.model.t:.1f} s"),
            ("ΔE/E", f"{float(np.max(np.abs(smp.energy_error))):.1e}"),
        ]

    @property
    def nodes(self) -> dict[str, Any]:
        """Name -> handle of every scene node of the exhibit (its root frame included)."""
        return self.scene.under(self.root)

    def labels(self) -> list:
        """The exhibit's text labels in the scene (the stage sizes them for the page)."""
        return [h for h in self.nodes.values() if type(h).__name__ == "LabelHandle"]

    def on_stage(self, shown: bool) -> None:
        """The exhibit goes on stage (``shown``) or leaves it: what it draws only there (the
        model is the same either way)."""

    def stage_plot(self) -> tuple[str, tuple[tuple[str, tuple[int, int, int]], ...]]:
        """The chart the stage shows against time (:mod:`mechviz.viz.scene.stage_chart`): its
        y axis's label with the unit, and ``(name, colour)`` of each series, names of the
        model's ``plot_variables``. By default the relative energy error."""
        return "relative energy error ΔE/E", (("energy_error", (60, 110, 240)),)

    def stage_labels(self) -> list:
        """Labels shown only while the exhibit is on stage (at home, beside the other
        exhibits, they would run into them)."""
        return []

    def world(self, local) -> np.ndarray:
        return self.origin + np.asarray(local, dtype=float)
