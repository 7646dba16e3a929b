"""Measured against predicted: the figures a recording's manifest and chart report.

Every measured number comes from :mod:`dynamics.measure` applied to the recorded frames, the
same estimators the viewer's readouts apply to the samples their exhibits keep; every predicted
number from the system's module in :mod:`dynamics`. A figure the frames cannot support (too
short a stretch, too few crossings, aliased) has no measured value and says why
(``not_resolved``) rather than guess.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from dynamics import cyclotron, disk, hoop, measure

from .demo import Demo
from .run import Traces


def figure(name: str, measured, predicted, unit: str, note: str = "") -> dict[str, Any]:
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
        **({"note": note} if note else {}),
        **({"not_resolved": reason} if reason else {}),
    }


def figures(d: Demo, tr: Traces) -> list[dict[str, Any]]:
    """The demo's figures (see the module docstring), in the order the chart lists them."""
    p = d.config().physics()
    if d.exhibit == "cyclotron":
        return _cyclotron(d, tr, p)
    if d.exhibit == "disk":
        return _driven(tr, p) if d.motion == "driven" else _released(tr, p)
    return _hoop(d, tr, p)


def _keep(figs: list, name: str, measured, *args, **kw) -> None:
    """Add the figure; an estimate not resolved is kept with its reason, a plain ``None`` left
    out."""
    if measured is not None:
        figs.append(figure(name, measured, *args, **kw))


def _cyclotron(d: Demo, tr: Traces, p) -> list[dict[str, Any]]:
    figs: list[dict[str, Any]] = []
    main = tr.main
    t, S = tr.times[main], tr.states[main]
    w = cyclotron.gyrofrequency(p)
    pre = t < (d.events[0].t if d.events else math.inf)  # before the first kick
    if S.shape[1] == 1:
        w_meas = measure.gyrofrequency(t[pre], S[pre, 0, 3:5], xy=S[pre, 0, :2])
        _keep(figs, "gyrofrequency", w_meas, w, "rad/s")
        circle = measure.fit_circle(S[pre, 0, :2])
        radius = measure.Estimate(circle.value[1]) if circle else circle
        figs.append(figure("Larmor radius", radius, cyclotron.larmor_radius(p, S[0, 0]), "m"))
        if w_meas and abs(S[0, 0, 5]) > 0:
            pitch = measure.slope(t[pre], S[pre, 0, 2]) * 2 * math.pi / w_meas.value
            figs.append(figure("helix pitch", pitch, S[0, 0, 5] * cyclotron.period(p), "m"))
    else:
        rates = measure.gyrofrequency(t, S[:, :, 3:5], xy=S[:, :, :2])
        if rates:
            periods = 2 * math.pi / np.asarray(rates.value)
            figs.append(figure("shortest period in the beam", periods.min(), 2 * math.pi / w, "s"))
            figs.append(figure("longest period in the beam", periods.max(), 2 * math.pi / w, "s"))
        v = np.hypot(S[0, :, 3], S[0, :, 4])
        figs.append(figure("speed ratio in the beam", v.max() / v.min(), None, "",
                           "the periods agree although the speeds differ by this factor"))  # fmt: skip
    for entry in tr.event_log:
        eff = entry["effects"][main]
        post = t > entry["t"] + 1e-9
        before = measure.fit_circle(S[pre, 0, :2])
        after = measure.fit_circle(S[post, 0, :2])
        if not before or not after:
            continue
        shift = float(np.linalg.norm(after.value[0] - before.value[0]))
        figs.append(figure("circle shift after the kick", shift, eff["predicted_shift"], "m"))
        figs.append(figure("radius after the kick", after.value[1], eff["predicted_radius"][0], "m"))
        _keep(figs, "gyrofrequency after the kick",
              measure.gyrofrequency(t[post], S[post, 0, 3:5], xy=S[post, 0, :2]),
              w, "rad/s", "unchanged: the period does not depend on the energy")  # fmt: skip
    if len(tr.states) > 1:
        for label, run in tr.runs.items():
            E = tr.energy_error[label][:, 0]
            pred, note = None, ""
            if run["method"] == "euler":
                pred = (1 + (w * run["dt"]) ** 2) ** tr.steps[label] - 1
                note = "explicit Euler: |v|^2 grows by 1 + (Omega dt)^2 every step"
            elif run["method"] in ("boris", "exact"):
                pred, note = 0.0, "Boris keeps |v| to round-off"
            figs.append(figure(f"final energy error, {label}", float(E[-1]), pred, "", note))
    return figs


def _driven(tr: Traces, p) -> list[dict[str, Any]]:
    t, S = tr.times[tr.main], tr.states[tr.main]
    figs = [figure("spin rate", measure.slope(t, S[:, 0, 0]), p.omega, "rad/s")]
    _keep(figs, "bearing force amplitude at B",
          measure.bearing_force_amplitude(p, t, S[:, 0, 0], S[:, 0, 1]), disk.axle_force_amplitude(p),
          "N", "from d L / dt of the simulated motion; seed: 5/8 M R omega^2")  # fmt: skip
    if len(t) >= 3:
        F = measure.bearing_force(p, t, S[:, 0, 0], S[:, 0, 1])
        _keep(figs, "bearing force frequency", measure.crossing_frequency(t, F[:, 0]), p.omega, "rad/s")
    return figs


def _released(tr: Traces, p) -> list[dict[str, Any]]:
    t, S = tr.times[tr.main], tr.states[tr.main]
    moments = disk.free_kernel_params(p)
    figs: list[dict[str, Any]] = []
    _keep(figs, "wobble growth rate", measure.wobble_growth_rate(t, S[:, 0, :3]),
          measure.wobble_growth_rate_theory(moments, S[0, 0, :3]), "1/s",
          "spin about the intermediate axis: w_perp grows as exp(rate t)")  # fmt: skip
    L = np.linalg.norm(disk.free_angular_momentum_space(moments, S[:, 0]), axis=-1)
    figs.append(figure("final |L| change", abs(L[-1] - L[0]) / L[0], 0.0, "",
                       "torque-free: |L| is conserved"))  # fmt: skip
    return figs


def _hoop(d: Demo, tr: Traces, p) -> list[dict[str, Any]]:
    figs: list[dict[str, Any]] = []
    freqs, shapes = hoop.normal_modes(p)
    t, S = tr.times[tr.main], tr.states[tr.main]
    if len(tr.states) > 1:  # two methods: the energy drift is the point
        for label in tr.states:
            E = tr.energy_error[label][:, 0]
            figs.append(figure(f"final energy error, {label}", float(E[-1]), None, ""))
            figs.append(figure(f"largest |energy error|, {label}", float(np.abs(E).max()), None, ""))
        return figs
    amps = measure.modal_coordinates(S[0, 0, :2], shapes)
    measured = measure.mode_frequencies(t, S[:, 0, :2], shapes)
    for k in (0, 1):
        _keep(figs, f"mode {k + 1} frequency (linear theory)", measured[k], freqs[k], "rad/s")
    a1 = abs(float(amps[0]))
    if measured[0] and abs(amps[1]) < 1e-12 and a1 > 0.2:
        figs.append(figure("mode 1 frequency (exact, finite amplitude)", measured[0],
                           2 * math.pi / hoop.mode1_period(p, a1), "rad/s",
                           "rigid-pendulum period 4 K(sin^2(A/2)) / omega_1"))  # fmt: skip
    return figs
