"""Measured against predicted: the figure a model reports for a recording, as a JSON-ready dict.

Every measured number comes from :mod:`mechviz.dynamics.measure` applied to the recorded frames, the
same estimators the viewer's readouts apply to the samples a model keeps; every predicted number
from the system's module in :mod:`dynamics`. A figure the frames cannot support (too short a
stretch, too few crossings, aliased) has no measured value and says why (``not_resolved``)
rather than guess. Each model's ``recorded_figures`` lists its own.
"""

from __future__ import annotations

import math
from typing import Any

from mechviz.dynamics import measure


def figure(
    name: str,
    measured,
    predicted,
    unit: str,
    note: str = "",
    *,
    since: float = 0.0,
    until: float | None = None,
    theory: str = "theory",
) -> dict[str, Any]:
    """One figure. ``since``/``until``: the stretch of simulated time [s] the figure is true of
    (a kick's effects from the kick on; a final error only at the end), so that a video shows it
    only then; ``theory``: what the predicted value comes from ("linear theory", ...)."""
    reason = ""
    if isinstance(measured, measure.Estimate):
        measured, reason = measured.value, measured.reason
    rel = None
    if predicted not in (None, 0) and measured is not None and math.isfinite(measured):
        rel = abs(measured - predicted) / abs(predicted)
    return {
        "name": name,
        "measured": None if measured is None else float(measured),
        "predicted": None if predicted is None else float(predicted),
        "unit": unit,
        "relative_difference": rel,
        "since": float(since),
        **({"until": float(until)} if until is not None else {}),
        **({"theory": theory} if theory != "theory" else {}),
        **({"note": note} if note else {}),
        **({"not_resolved": reason} if reason else {}),
    }


def keep(figs: list, name: str, measured, *args, **kw) -> None:
    """Add the figure; an estimate not resolved is kept with its reason, a plain ``None`` left
    out."""
    if measured is not None:
        figs.append(figure(name, measured, *args, **kw))
