"""A demo's derived scales, checked before anything runs: every one a double can hold.

The schema and the exhibit's settings check each value on its own; these checks look at what
the values make together, with the rule ``mechviz analyze`` applies to its flags
(:func:`mechviz.dynamics.analysis.unrepresentable`), so the command line and demo files refuse the same
parameters:

- every number in the file is 0 or a normal double (a subnormal such as ``5e-324`` keeps a few
  bits at most);
- every analytic result of the parameters (frequencies, periods, inertia, forces, energy) is
  finite, and non-zero where it must be; the keys blamed are those whose default alone mends it;
- the recording's simulated time (``speed`` x ``duration``) covers at least
  :data:`MIN_PERIOD_FRACTION` of the motion's shortest period (else every frame is the same
  picture), and a double near it still resolves a millionth of that period.

Each refusal is a ``ValueError`` naming the key as the file writes it
(``parameters.disk_mass = 1e-300: ...``).
"""

from __future__ import annotations

import math
import sys
from typing import TYPE_CHECKING, Any

import numpy as np

from mechviz import dynamics
from mechviz.dynamics import analysis
from mechviz.dynamics.params import blamed

from ..model import MODELS

if TYPE_CHECKING:
    from .demo import Demo

TINY = sys.float_info.min  # the smallest normal double
MAX_STEPS = 1e8  # integration steps a recording may take, all runs and members together
MIN_PERIOD_FRACTION = 1e-9


def _numbers(value: Any, key: str):
    """``(key, number)`` for every float inside ``value`` (structs, tuples, lists, dicts)."""
    if isinstance(value, bool) or value is None or isinstance(value, str):
        return
    if isinstance(value, float | int):
        yield key, float(value)
    elif isinstance(value, dict):
        for k, v in value.items():
            yield from _numbers(v, f"{key}.{k}" if key else str(k))
    elif isinstance(value, tuple | list):
        for i, v in enumerate(value):
            yield from _numbers(v, f"{key}[{i}]")
    elif hasattr(value, "__struct_fields__"):
        for f in value.__struct_fields__:
            yield from _numbers(getattr(value, f), f"{key}.{f}" if key else f)


def check_normal_numbers(d: Demo) -> None:
    """``ValueError`` naming the first key whose number is subnormal (0 < |x| < 2.2e-308)."""
    for key, x in _numbers({f: getattr(d, f) for f in d.__struct_fields__}, ""):
        if 0.0 < abs(x) < TINY:
            raise ValueError(
                f"{key} = {x:g} is below the smallest normal double ({TINY:.3g}); use 0 or a "
                "larger value"
            )


def _analysis(system: str, params: dict[str, float], speed: float | None) -> dict:
    """``mechviz analyze``'s results for these parameters."""
    values = {**params, **({} if speed is None else {"speed": speed})}
    with np.errstate(all="ignore"):
        return dynamics.SPECS[system].analyze(values)


def _problem(system: str, params: dict[str, float], speed: float | None) -> str | None:
    try:
        return analysis.unrepresentable(_analysis(system, params, speed))
    except (ValueError, ArithmeticError) as exc:
        return str(exc)


def _blamed(d: Demo, params: dict, defaults: dict, bad) -> list[str]:
    """The demo's parameter keys whose default alone makes ``bad(params)`` false."""
    changed = [k for k in d.parameters if k in defaults and params.get(k) != defaults[k]]
    alone = blamed(changed, lambda k: not bad({**params, k: defaults[k]}))
    return [f"parameters.{k} = {d.parameters[k]:g}" for k in alone]


def _shortest_period(d: Demo, result: dict, extra_spin: bool = True) -> float | None:
    """The motion's shortest period [s] from the analytic results, None if nothing moves
    (the exhibit's model says how: :meth:`mechviz.viz.model.hooks.SystemHooks.shortest_period`)."""
    return MODELS[d.exhibit].shortest_period(d, result, extra_spin)


def check_scales(d: Demo) -> None:
    """Raise ``ValueError`` naming the key(s) if a derived scale of ``d`` is not representable
    (see the module docstring). ``d`` has passed the other checks of :func:`.demo.check`."""
    check_normal_numbers(d)
    if d.frames < 2:
        raise dynamics.SettingError(
            "duration",
            f"duration = {d.duration:g} s at fps = {d.fps} gives one frame; a recording needs "
            f"two at least (duration >= {1 / d.fps:.3g} s)",
        )
    cfg = d.config()
    defaults = MODELS[d.exhibit].Config().params
    params = dict(cfg.params)
    # the start settings the system's analysis takes (its description names them), as given
    speed = _analysis_speed(d)
    problem = _problem(d.exhibit, params, speed)
    if problem is not None:
        names = _blamed(d, params, defaults, lambda p: _problem(d.exhibit, p, speed) is not None)
        if not names and speed is not None and _problem(d.exhibit, params, None) is None:
            names = [f"initial.speed = {speed:g}"]
        shown = (
            ", ".join(names)
            or ", ".join(f"parameters.{k} = {v:g}" for k, v in d.parameters.items())
            or "the parameters"
        )
        raise ValueError(f"{shown}: {problem}")
    span = d.simulated_time
    _check_steps(d, span)
    _check_start(d, cfg, span)
    period = _shortest_period(d, _analysis(d.exhibit, params, speed))
    if period is None:
        return
    when = f"speed = {d.speed:g} x duration = {d.duration:g} s gives {span:.3g} s of simulated time"

    def period_of(p: dict, extra_spin: bool = True) -> float:
        return _shortest_period(d, _analysis(d.exhibit, p, speed), extra_spin) or math.inf

    def set_by(bad) -> str:
        names = _blamed(d, params, defaults, lambda p: bad(period_of(p)))
        if d.initial.extra_spin is not None and not bad(period_of(params, extra_spin=False)):
            names.append(f"initial.extra_spin = {list(d.initial.extra_spin)}")
        return f", set by {', '.join(names)}" if names else ""

    if span < MIN_PERIOD_FRACTION * period:
        by = set_by(lambda T: span < MIN_PERIOD_FRACTION * T)
        raise ValueError(
            f"{when}, under {MIN_PERIOD_FRACTION:g} of the motion's shortest period "
            f"({period:.3g} s{by}): every frame would show the same picture"
        )
    if math.ulp(span) > 1e-6 * period:
        by = set_by(lambda T: math.ulp(span) > 1e-6 * T)
        raise ValueError(
            f"{when}; a double near it resolves time only to {math.ulp(span):.2g} s, too coarse "
            f"for the motion's shortest period ({period:.3g} s{by})"
        )


def _check_steps(d: Demo, span: float) -> None:
    """A fixed step no longer than the recording (one step at least, else nothing moves), and
    not so short that the recording's steps pass :data:`MAX_STEPS` (the exact count,
    adaptive runs included, is checked again before the run)."""
    for key, dt in (("dt", d.dt), ("compare.dt", d.compare.dt if d.compare else None)):
        if dt is None:
            continue
        if dt > span:
            raise dynamics.SettingError(
                key,
                f"{key} = {dt:g} s is longer than the recording's {span:.3g} s of simulated time "
                f"(speed = {d.speed:g} x duration = {d.duration:g} s): no step would be taken",
            )
        if span / dt > MAX_STEPS:
            raise dynamics.SettingError(
                key,
                f"{key} = {dt:g} s gives {span / dt:.3g} steps over the recording's {span:.3g} s "
                f"of simulated time (speed x duration); the limit is {MAX_STEPS:.0e}",
            )


def _analysis_speed(d: Demo) -> float | None:
    """The demo's start speed where the system's analysis takes one
    (:attr:`mechviz.dynamics.SystemSpec.analysis_start`), else None."""
    takes = "speed" in dynamics.spec_named(d.exhibit).analysis_start
    return getattr(d.initial, "speed", None) if takes else None


def _check_start(d: Demo, cfg, span: float) -> None:
    """The start and what the scripted kicks add, checked by the exhibit's model
    (:meth:`mechviz.viz.model.hooks.SystemHooks.check_recording_start`)."""
    MODELS[d.exhibit].check_recording_start(d, cfg, span)


# The exhibit settings every demo's keys become (:meth:`.demo.Demo.config`), by the settings'
# names; each exhibit's own are its model's (:func:`config_keys`).
CONFIG_KEYS = {
    "compare_method": "compare.method",
    "compare_dt": "compare.dt",
    "compare_rtol": "compare.rtol",
}


def config_keys(d: Demo) -> dict[str, str]:
    """The demo key each exhibit setting of ``d`` comes from, by the setting's name: the common
    ones and its model's own (:attr:`mechviz.viz.model.hooks.SystemHooks.demo_keys`)."""
    return {**CONFIG_KEYS, **MODELS[d.exhibit].demo_keys}


def in_demo_terms(message: str, d: Demo) -> str:
    """A refusal of the exhibit's settings (``beam_speeds must be ...``, ``charge must be
    ...``) with the setting named by the demo key it came from (``initial.speeds``,
    ``parameters.charge``)."""
    word, sep, rest = message.partition(" ")
    name = word.rstrip(":")
    if name in MODELS[d.exhibit].Config().params:
        key = f"parameters.{name}"
    elif name in config_keys(d):
        key = config_keys(d)[name]
    else:
        return message
    return f"{key}{word[len(name) :]}{sep}{rest}"
