"""Running a demo frame by frame, one frame every ``1 / fps`` of playback.

:func:`trace_demo` runs the demo's model alone (:mod:`mechviz.viz.model`, no viser): it advances it
frame by frame (simulated time ``speed / fps`` per frame), fires the scripted events at their
times (a kick is a jump of the same runs, :meth:`mechviz.dynamics.Simulation.jump`: time and counters go
on) and keeps every run's samples and the measured figures as :class:`Traces`; the CSV, the
figures and the charts of a recording come from these. :func:`run_demo` does the same with the
viewer's own exhibit in a headless viser server, drawing every frame into two scene serializers
for the ``.viser`` file and its HTML page: what a recording shows is what the viewer shows for
the same settings.
"""

from __future__ import annotations

import contextlib
import io
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from mechviz import dynamics

from ..model import MODELS
from ..model.base import ExhibitModel
from ..model.traces import Traces
from .demo import Demo
from .scales import MAX_STEPS

ProgressFn = Callable[[int, int], None]


@dataclass
class Recorded:
    """What one headless run produced: the ``.viser`` bytes, its HTML page, the traces, and
    where the exhibit stands (``scene``: its world ``bounds`` [m] and the camera ``view``
    (position, look_at) it opens with, for framing videos and stills)."""

    viser: bytes
    html: bytes
    traces: Traces
    scene: dict[str, Any] | None = None


def labels_for(ex: ExhibitModel) -> dict[str, str]:
    """Run role (``main``/``compare``) -> label: the method's name, made unique."""
    runs = ex.runs()
    out = {"main": runs["main"].method.name}
    if "compare" in runs:
        name = runs["compare"].method.name
        out["compare"] = name if name != out["main"] else f"{name} (compare)"
    return out


def build_exhibit(server, demo: Demo):
    """The demo's exhibit, as the viewer would build it for these settings: its model, and
    the view drawn over it (``.model``)."""
    from ..scene import EXHIBITS

    return EXHIBITS[demo.exhibit](server, MODELS[demo.exhibit](demo.config(), history_len=8))


def trace_demo(demo: Demo, progress: ProgressFn | None = None) -> Traces:
    """Run ``demo``'s model headless (no viser) and return every run's samples and the figures
    measured from them. Raises :class:`mechviz.dynamics.IntegrationError` if a run blows up."""
    model = MODELS[demo.exhibit](demo.config(), history_len=8)
    check_work(model, demo)
    return _run(model, demo, progress)


def run_demo(demo: Demo, progress: ProgressFn | None = None, *, theme: str = "light") -> Recorded:
    """Run ``demo`` headless and record it (see the module docstring); ``theme`` ("light" or
    "dark") is the page of the ``.html``. Raises :class:`mechviz.dynamics.IntegrationError` if a run
    blows up."""
    if theme not in ("light", "dark"):
        raise ValueError(f"theme must be light or dark, got {theme!r}")
    import viser

    with contextlib.redirect_stdout(io.StringIO()):  # viser prints a banner even when quiet
        server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        ex = build_exhibit(server, demo)
        check_work(ex.model, demo)
        position, look_at = ex.camera
        cam = demo.camera
        view = (tuple(cam.position or position), tuple(cam.look_at or look_at))
        server.initial_camera.position, server.initial_camera.look_at = view
        lo, hi = ex.bounds
        scene = {
            "bounds": [[float(x) for x in lo], [float(x) for x in hi]],
            "view": [[float(x) for x in v] for v in view],
        }
        serializers: list = []

        def draw(k: int) -> None:
            for ser in serializers:
                ser.insert_sleep(1.0 / demo.fps)  # frame k plays at t = k / fps
            with server.atomic():
                ex.draw()
            if not serializers:
                # Start after the first frame is drawn: the snapshot holds the whole scene at
                # t = 0 and every later frame only what changed. Two serializers, because each
                # one serializes once: one for the .viser file, one for viser's own HTML page.
                serializers.extend([server.get_scene_serializer(), server.get_scene_serializer()])

        traces = _run(ex.model, demo, progress, draw)
        for ser in serializers:
            ser.insert_sleep(1.0 / demo.fps)  # the last frame lasts one frame too
        data = serializers[0].serialize()
        html = serializers[1].as_html(dark_mode=theme == "dark").encode("utf-8")
        return Recorded(data, html, traces, scene)
    finally:
        with contextlib.redirect_stdout(io.StringIO()):
            server.stop()


def _run(
    ex: ExhibitModel,
    demo: Demo,
    progress: ProgressFn | None,
    draw: Callable[[int], None] | None = None,
) -> Traces:
    """Advance ``ex`` through the demo's frames, firing its events, and sample every run at
    every frame; ``draw(k)`` (a view's) is called after frame ``k`` is reached."""
    labels = labels_for(ex)
    runs = {labels[role]: sim for role, sim in ex.runs().items()}
    K = demo.frames
    t_frames = np.arange(K) / demo.fps * demo.speed
    d = next(iter(runs.values())).state.shape[1]
    times = {lbl: np.empty(K) for lbl in runs}
    states = {lbl: np.empty((K, len(s.state), d)) for lbl, s in runs.items()}
    energy = {lbl: np.empty((K, len(s.state))) for lbl, s in runs.items()}
    eerr = {lbl: np.empty((K, len(s.state))) for lbl, s in runs.items()}
    err: dict[str, np.ndarray | None] = {
        lbl: np.full((K, len(s.state)), np.nan) for lbl, s in runs.items()
    }
    bar = {lbl: np.full((K, len(s.state)), np.nan) for lbl, s in runs.items()}
    ghost = np.empty((K, 1, d)) if getattr(ex.config, "ghost", False) else None
    pending = list(demo.events)
    log: list[dict[str, Any]] = []
    for k, t in enumerate(t_frames):
        while pending and pending[0].t <= t + 1e-12:
            ev = pending.pop(0)
            ex.advance_to(ev.t)
            _raise_if_failed(ex)
            effects = ex.kick_effects(ev.dv)  # the only scripted action (the schema says so)
            log.append(
                {
                    "t": ev.t,
                    "action": ev.action,
                    "dv": ev.dv,
                    "effects": {labels[role]: e for role, e in effects.items()},
                }
            )
        ex.advance_to(float(t))
        _raise_if_failed(ex)
        for lbl, sim in runs.items():
            s = sim.sample()
            times[lbl][k], states[lbl][k] = s.t, s.state
            energy[lbl][k], eerr[lbl][k] = s.energy, s.energy_error
            if s.error is not None:
                err[lbl][k] = s.error
            if s.reference_accuracy is not None:
                bar[lbl][k] = s.reference_accuracy
        if ghost is not None:
            ghost[k, 0] = ex.ghost_state()
        if draw is not None:
            draw(k)
        if progress is not None:
            progress(k + 1, K)
    for lbl in runs:
        if np.all(np.isnan(err[lbl])):
            err[lbl] = None
        if np.all(np.isnan(bar[lbl])):
            bar[lbl] = None
    return Traces(
        t_frames,
        times,
        states,
        energy,
        eerr,
        err,
        {lbl: s.reference_kind for lbl, s in runs.items()},
        {lbl: s.steps for lbl, s in runs.items()},
        {lbl: s.nfev for lbl, s in runs.items()},
        {lbl: _describe(s) for lbl, s in runs.items()},
        ghost,
        log,
        ex.measured(),
        bar,
    )


def check_work(ex: ExhibitModel, demo: Demo) -> None:
    """Refuse, before anything runs, a demo whose runs would take more than :data:`MAX_STEPS`
    steps (:meth:`mechviz.dynamics.Simulation.estimated_steps`), naming what sets the count."""
    steps = sum(sim.estimated_steps(demo.simulated_time) for sim in ex.simulations())
    if not steps <= MAX_STEPS:
        raise ValueError(
            f"the runs would take about {steps:.3g} steps ({demo.simulated_time:.4g} s of simulated "
            f"time = speed x duration, dt = {demo.dt}); the limit is {MAX_STEPS:.0e}: give a larger "
            "dt or rtol, or a smaller speed or duration"
        )


def _describe(sim: dynamics.Simulation) -> dict[str, Any]:
    m = sim.method
    return {
        "method": m.name,
        "title": m.title,
        "order": _order(sim),
        "evaluations": m.counts,
        "structure": list(m.structure_on(sim.system)),
        "step": sim.step_label(),
        "dt": sim.dt,
        "rtol": sim.rtol,
    }


def _order(sim: dynamics.Simulation) -> int | None:
    """The order the run used: Taylor's from its tolerance, ``None`` for LSODA's variable one."""
    return sim.method.order_at(sim.rtol, sim.atol, sim.system.sys_id)


def _raise_if_failed(ex: ExhibitModel) -> None:
    if ex.failure_error is not None:
        raise ex.failure_error
