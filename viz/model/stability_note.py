"""The step control's note on stability: where a run's fixed step stops being stable, in words.

Kept apart from :mod:`mechviz.viz.model.base` (which calls it from
:meth:`~mechviz.viz.model.base.ExhibitModel.stability_text`) so that module stays readable.
"""

from __future__ import annotations

import numpy as np

from mechviz import dynamics


def fmt(x: float) -> str:
    """A step or a frequency to four significant digits (as the readouts show numbers)."""
    return f"{x:.4g}"


def stability_note(sim: dynamics.Simulation, state: np.ndarray) -> str:
    """Markdown: the largest stable dt from :func:`mechviz.dynamics.stability.stability_limit`
    for ``sim``'s method and parameters at ``state``, and whether its dt is inside it."""
    from mechviz.dynamics import stability

    m = sim.method
    if m.adaptive:
        return f"<small>{m.name}: adaptive, the step follows rtol; no fixed limit</small>"
    if m.closed_form:
        return "<small>exact flow: any step</small>"
    limit = stability.stability_limit(m.name, sim.system, state)
    reason = m.limit_reason
    if limit is None:
        return f"<small>Stable at any dt ({reason}).</small>"
    if limit == 0.0:
        return f"<small>⚠ Unstable at every dt: {reason}.</small>"
    omega = stability.fastest_frequency(sim.system, state)
    where = (
        f"dt = {fmt(sim.dt)} s is {sim.dt / limit:.1%} of it"
        if sim.dt <= limit
        else f"⚠ dt = {fmt(sim.dt)} s is beyond it: expect the run to blow up"
    )
    return (
        f"<small>**Stability limit dt < {fmt(limit)} s** (ω_max = {fmt(omega)} rad/s; "
        f"{reason}); {where}.</small>"
    )
