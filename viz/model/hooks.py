"""What the rest of the product asks an exhibit about its system: one hook each, answered in the
system's own model module (:mod:`.cyclotron`, :mod:`.disk`, :mod:`.hoop`), so that no other module
branches on a system's name.

A model class (:class:`mechviz.viz.model.base.ExhibitModel`) inherits these; one that leaves a
required hook out raises :class:`NotImplementedError` naming itself when the hook is asked, never
another system's answer. The viewer's home layout (:attr:`SystemHooks.origin`), a demo's settings
(:meth:`SystemHooks.demo_settings`), the recording's checks (:meth:`SystemHooks.shortest_period`,
:meth:`SystemHooks.check_recording_start`), the recording's chart of the motion
(:meth:`SystemHooks.draw_motion_chart`) and the benchmark's exhibit-defaults sweep
(:meth:`SystemHooks.screen_case`) come from here.
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

import numpy as np

#: Period marks drawn at most on a chart: a recording that spans more periods marks every k-th,
#: so the chart's work stays bounded whatever the demo's speed.
MAX_PERIOD_MARKS = 200
#: The runs' colours on a recording's chart, main run first.
CHART_COLOURS = ("tab:blue", "tab:red", "tab:green")


class SystemHooks:
    """The hooks (see the module docstring); the defaults say "nothing to add"."""

    #: Where the exhibit stands in the viewer [m] (+z up), as the first view sees the exhibits
    #: (:mod:`mechviz.viz.views`): staggered in depth, so that view shows them one below another
    #: as well as side by side.
    origin: ClassVar[tuple[float, float, float]] = (0.0, 0.0, 0.0)
    #: The comparison method the viewer's frame-cost benchmark adds (:mod:`mechviz.bench.frame_cost`);
    #: None: none.
    frame_cost_compare: ClassVar[str | None] = None
    #: The demo key each of its own settings comes from when the demo calls it otherwise
    #: (``{"beam_speeds": "initial.speeds"}``), so a refusal names the key the file wrote.
    demo_keys: ClassVar[dict[str, str]] = {}

    @classmethod
    def _missing(cls, hook: str) -> NotImplementedError:
        return NotImplementedError(f"{cls.__name__} does not say its {hook}")

    @classmethod
    def demo_settings(cls, initial: dict[str, Any], demo: Any, params: dict[str, Any]) -> dict:
        """The exhibit settings a demo's ``[initial]`` values (``initial``, those given) and its
        other keys become, beyond the method, steps, parameters and comparison; ``params``: the
        exhibit's parameters as the demo sets them."""
        return {}

    @classmethod
    def shortest_period(cls, demo: Any, result: dict, extra_spin: bool = True) -> float | None:
        """The motion's shortest period [s] from the analytic ``result``; None if nothing moves.
        ``extra_spin``: count a start's extra spin (else leave it out, to blame the key)."""
        raise cls._missing("shortest period")

    @classmethod
    def check_recording_start(cls, demo: Any, config: Any, span: float) -> None:
        """``ValueError`` naming the key if the start (and what scripted events add) would make
        a number no double holds over ``span`` [s] of simulated time."""

    @classmethod
    def draw_motion_chart(cls, ax: Any, demo: Any, tr: Any, params: Any) -> None:
        """The recording chart's first panel: the motion with the predictions marked."""
        raise cls._missing("motion chart")

    @classmethod
    def screen_case(cls) -> tuple[str, dict[str, Any]] | None:
        """The benchmark's exhibit-defaults sweep of this exhibit (:mod:`mechviz.bench.exhibits`):
        its name and ``{"system", "state", "state_note", "size", "error", "methods"}`` (the
        default run, the on-screen error [m] of a state against the reference, the exhibit's
        size [m] and the candidate methods); None to leave it out."""
        return None


def demo_value(demo: Any, key: str) -> str:
    """The value a demo gives ``key`` (``initial.speed``, ``events[0].dv``) as the file writes it."""
    if key.startswith("events["):
        return f"{demo.events[int(key[7 : key.index(']')])].dv:g}"
    value = getattr(demo.initial, key.split(".")[1])
    return f"{value:g}" if isinstance(value, float) else str(list(value))


def mark_periods(ax, T: float, t_end: float, label: str, color: str = "k") -> None:
    """Dashed lines at each whole period ``T`` [s] up to ``t_end`` (every nth past
    :data:`MAX_PERIOD_MARKS`)."""
    ratio = t_end / T if T > 0 else math.nan
    n = math.floor(ratio + 1e-9) if math.isfinite(ratio) else 0
    if n < 1:
        return
    every = max(1, math.ceil(n / MAX_PERIOD_MARKS))
    if every > 1:
        label = f"{label}, every {every}th"
    marks = T * np.arange(every, n + 1, every, dtype=float)
    ax.vlines(
        marks,
        0,
        1,
        transform=ax.get_xaxis_transform(),
        colors=color,
        linestyles="--",
        lw=0.8,
        alpha=0.6,
        label=label,
    )


def by_system(classes: tuple[type, ...], what: str) -> dict[str, type]:
    """``classes`` (models or exhibits, each with its system's ``key``) by key, in the order of
    the one registry of systems (:data:`mechviz.dynamics.registry.SPECS`); ``KeyError`` naming a
    system with no class here, or a class whose system the registry does not know."""
    from mechviz.dynamics.registry import SPECS, lookup

    keyed = {cls.key: cls for cls in classes}
    for key in keyed:
        lookup(SPECS, key)  # a class of a system the registry does not know
    missing = [name for name in SPECS if name not in keyed]
    if missing:
        raise KeyError(f"no {what} for the system(s) {', '.join(missing)}")
    return {name: keyed[name] for name in SPECS}
