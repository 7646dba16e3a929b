"""Recording through the live viewer's exhibits, so a recording looks like the viewer.

:func:`driver_for` maps a demo (:class:`viz.recording.Demo`) onto the configuration of the
viewer's exhibit for that system (:mod:`viz.scene_cyclotron`, :mod:`viz.scene_disk`,
:mod:`viz.scene_hoop`; the exhibit interface is documented in :mod:`viz.exhibit`) and wraps it in
the driver interface the recorder uses (see :mod:`viz.recording_scene`). It returns ``None``
when the demo asks for something the exhibit cannot show (then the recorder draws its own
scene): a comparison method with a step size of its own, for instance.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import dynamics
from dynamics import cyclotron, hoop


def _exhibit_classes():
    try:
        from .scene_cyclotron import CyclotronExhibit
        from .scene_disk import DiskExhibit
        from .scene_hoop import HoopExhibit
    except ImportError:
        return None
    return {"cyclotron": CyclotronExhibit, "disk": DiskExhibit, "hoop": HoopExhibit}


def exhibit_config(demo, cls) -> Any | None:
    """The exhibit ``Config`` for ``demo``, or ``None`` if the exhibit cannot show it."""
    d = demo
    kw: dict[str, Any] = {"method": d.method, "params": dict(d.parameters)}
    if d.dt is not None:
        kw["dt"] = d.dt
    if d.rtol is not None:
        kw["rtol"] = d.rtol
    if d.compare is not None:
        c = d.compare
        if c.get("dt", d.dt) != d.dt or c.get("rtol", d.rtol) != d.rtol:
            return None  # the exhibit compares at the same step size only
        if c["method"] == d.method:
            return None
        kw["compare_method"] = c["method"]
    ini = d.initial
    if "state" in ini:
        return None
    if d.exhibit == "cyclotron":
        if "centre" in ini:
            return None
        kw["speed"] = float(ini.get("speed", 1.0))
        kw["vz"] = float(ini.get("vz", 0.0))
        if "beam" in ini:
            kw["beam"] = True
            kw["beam_size"] = int(ini["beam"])
            kw["beam_speeds"] = tuple(float(x) for x in ini.get("speeds", (0.5, 1.5)))
            kw["compare_method"] = None
    elif d.exhibit == "disk":
        kw["mode"] = d.motion
        kw["extra_spin"] = tuple(float(x) for x in ini.get("extra_spin", (0.0, 0.0, 0.0)))
        if d.motion == "driven":
            kw["method"] = "splitting"  # unused when driven; keeps the config valid
    else:
        a1, a2 = (float(x) for x in ini.get("modes", (0.3, 0.0)))
        if a2 == 0.0:
            kw.update(mode="mode 1", amplitude=a1)
        elif a1 == 0.0:
            kw.update(mode="mode 2", amplitude=a2)
        elif a1 == a2:
            kw.update(mode="mix", amplitude=2 * a1)
        else:
            th = hoop.mode_state(hoop.HoopParams(**d.parameters), (a1, a2))
            kw.update(mode="custom", angles=(float(th[0]), float(th[1])))
    names = {f.name for f in dataclasses.fields(cls.Config)}
    kw = {k: v for k, v in kw.items() if k in names}
    try:
        config = cls.Config.from_defaults(**kw)
        config.validate()
    except (TypeError, ValueError):
        return None
    return config


class ExhibitDriver:
    """Drives one viewer exhibit headless: ``advance_to``, ``apply`` (events), ``samples``,
    ``draw``. The main run is the exhibit's own simulation (its beam when the demo is a beam),
    the comparison its ``compare`` simulation."""

    kind = "viewer-exhibit"

    def __init__(self, server, demo, cls, config):
        self.demo = demo
        self.exhibit = cls(server, config)
        ex = self.exhibit
        self.beam = bool(getattr(config, "beam", False))
        self.labels = [demo.method]
        if ex.compare is not None:
            self.labels.append(demo.compare["method"])
        self.camera = ex.camera
        self._steps_before = dict.fromkeys(self.labels, 0)
        self._nfev_before = dict.fromkeys(self.labels, 0)

    def _sims(self) -> dict[str, dynamics.Simulation]:
        ex = self.exhibit
        main = ex.beam if self.beam and getattr(ex, "beam", None) is not None else ex.sim
        out = {self.labels[0]: main}
        if len(self.labels) > 1:
            out[self.labels[1]] = ex.compare
        return out

    def _check(self) -> None:
        ex = self.exhibit
        if ex.failure:
            sim = ex.sim
            raise dynamics.IntegrationError(sim.method.name, sim.step_label(), ex.t, ex.failure)

    def advance_to(self, t: float) -> None:
        dt = t - self.exhibit.t
        if dt > 0:
            self.exhibit.advance(dt)
        self._check()

    def apply(self, ev) -> dict[str, Any]:
        ex = self.exhibit
        if ev.action != "kick":
            raise ValueError(f"unknown event action {ev.action!r}")
        dv = float(ev.args.get("dv", 0.5))
        before = {lbl: sim.state.copy() for lbl, sim in self._sims().items()}
        work = {lbl: (sim.steps, sim.nfev) for lbl, sim in self._sims().items()}
        ex.apply({"op": "kick", "dv": dv})
        for lbl, sims in self._sims().items():
            if sims is not None and sims.steps < work[lbl][0]:  # restarted: keep the count
                self._steps_before[lbl] += work[lbl][0]
                self._nfev_before[lbl] += work[lbl][1]
        p = ex.params
        out = {}
        for lbl, st in before.items():
            res = [cyclotron.radial_kick(p, s, dv) for s in st]
            out[lbl] = {
                "state_before": st.tolist(),
                "predicted_centre": [r[1][:2].tolist() for r in res],
                "predicted_radius": [r[2] for r in res],
                "predicted_shift": abs(dv) / abs(cyclotron.signed_gyrofrequency(p)),
            }
        return out

    def samples(self) -> dict[str, dynamics.Sample]:
        t = self.exhibit.t
        return {lbl: dataclasses.replace(sim.sample(), t=t) for lbl, sim in self._sims().items()}

    def steps(self) -> dict[str, tuple[int, int, str | None]]:
        return {
            lbl: (self._steps_before[lbl] + sim.steps, self._nfev_before[lbl] + sim.nfev,
                  sim.reference_kind)
            for lbl, sim in self._sims().items()
        }  # fmt: skip

    def draw(self, frame) -> None:
        self.exhibit.draw()


def driver_for(server, demo) -> ExhibitDriver | None:
    classes = _exhibit_classes()
    if classes is None:
        return None
    cls = classes[demo.exhibit]
    config = exhibit_config(demo, cls)
    if config is None:
        return None
    if demo.exhibit == "cyclotron" and demo.events and "beam" in demo.initial:
        return None  # a kicked beam: the exhibit kicks only the single charge
    return ExhibitDriver(server, demo, cls, config)
