"""Measured against predicted: the figures a recording's manifest and chart report, as each
exhibit's model lists them (:meth:`mechviz.viz.model.base.ExhibitModel.recorded_figures`,
:mod:`mechviz.viz.model.figures`)."""

from __future__ import annotations

from typing import Any

from ..model import MODELS
from ..model.traces import Traces
from .demo import Demo


def figures(d: Demo, tr: Traces) -> list[dict[str, Any]]:
    """The demo's figures, in the order the chart lists them."""
    return MODELS[d.exhibit].recorded_figures(d.config(), tr)
