"""Demo files: the schema, its checks, and the exhibit settings a demo stands for.

A *demo* is data: one small TOML file (the built-in ones under ``assets/demos/``) naming the
exhibit, its physical parameters and start, the method and step, the playback duration, frame
rate and speed, the camera, an optional second method shown beside the first (``[compare]``)
and scripted events (``[[events]]``, a radial kick at ``t = 5 s``). Units are SI; times are
*simulated* seconds except ``duration`` (seconds of playback; simulated time runs ``speed``
times faster).

The schema is a set of :mod:`msgspec` structs: a key the schema does not know, or a value of the
wrong kind, is refused with the file name and the key's path (``helix.toml: events[0].t: ...``).
:meth:`Demo.config` maps a valid demo onto the settings of its exhibit (:mod:`mechviz.viz.model`): every
demo the schema allows is expressible there, so the recorder draws every demo with the viewer's
own exhibits.
"""

from __future__ import annotations

import dataclasses
import math
import os
import tomllib
from pathlib import Path
from typing import Any, Literal

import msgspec

from mechviz import dynamics
from mechviz.dynamics.assets import asset

from ..model import MODELS, ExhibitConfig
from ..printable import has_control_characters, printable
from .scales import check_scales, config_keys, in_demo_terms

DEMO_DIR = asset("demos")
MAX_FRAMES = 100_000


class _Struct(msgspec.Struct, forbid_unknown_fields=True, frozen=True, omit_defaults=True):
    pass


class Event(_Struct):
    """A scripted action at simulated time ``t`` [s]: ``kick`` adds ``dv`` [m/s] of radial
    velocity to the charge (every charge of a beam)."""

    t: float
    action: Literal["kick"]
    dv: float = 0.5


class Compare(_Struct):
    """A second method run beside the first from the same start; ``dt`` / ``rtol`` default to
    the demo's."""

    method: str
    dt: float | None = None
    rtol: float | None = None


class Camera(_Struct):
    position: tuple[float, float, float] | None = None
    look_at: tuple[float, float, float] | None = None


class Initial(_Struct):
    """The start. Cyclotron: ``speed`` [m/s] on a circle about ``centre`` [m] with ``vz``, or a
    ``beam`` of that many charges with ``speeds`` (low, high); hoop: ``modes`` (amplitudes of
    mode 1 and mode 2 [rad], at rest); disk: ``extra_spin`` [rad/s] at release; cyclotron and
    hoop: ``state``, the whole initial state. Keys left out take the viewer's defaults."""

    speed: float | None = None
    vz: float | None = None
    centre: tuple[float, float] | None = None
    beam: int | None = None
    speeds: tuple[float, float] | None = None
    state: list[float] | None = None
    modes: tuple[float, float] | None = None
    extra_spin: tuple[float, float, float] | None = None


class Demo(_Struct):
    """One demo file (see the module docstring); ``name`` and ``source`` come from the file."""

    exhibit: str
    duration: float
    title: str = ""
    description: str = ""
    method: str = ""
    fps: int = 30
    speed: float = 1.0
    dt: float | None = None
    rtol: float | None = None
    motion: Literal["driven", "released"] | None = None
    ghost: Literal["linear"] | None = None
    parameters: dict[str, float] = {}
    initial: Initial = Initial()
    compare: Compare | None = None
    camera: Camera = Camera()
    events: tuple[Event, ...] = ()
    name: str = "demo"
    source: str | None = None

    @property
    def frames(self) -> int:
        """Frames in the recording, the first at ``t = 0`` included."""
        return int(round(self.duration * self.fps)) + 1

    @property
    def simulated_time(self) -> float:
        return (self.frames - 1) / self.fps * self.speed

    def with_overrides(
        self,
        *,
        duration: float | None = None,
        fps: int | None = None,
        method: str | None = None,
        dt: float | None = None,
    ) -> Demo:
        """This demo with command-line overrides applied and checked (``ValueError`` naming the
        option otherwise). A new method drops the demo's step setting it does not take."""
        changes: dict[str, Any] = {}
        if duration is not None:
            changes["duration"] = duration
        if fps is not None:
            changes["fps"] = fps
        if method is not None and method != self.method:
            changes["method"] = method
            try:
                m = dynamics.get_method(method)
            except ValueError as exc:
                raise dynamics.SettingError("method", str(exc)) from None
            if m.adaptive:
                changes["dt"] = None
            else:
                changes["rtol"] = None
        if dt is not None:
            changes["dt"] = dt
        demo = msgspec.structs.replace(self, **changes)
        check(demo)
        return demo

    def as_dict(self) -> dict[str, Any]:
        """The demo as the TOML table it was read from (defaults left out)."""
        d = msgspec.to_builtins(self)
        d.pop("name", None)
        d.pop("source", None)
        return d

    def config(self) -> ExhibitConfig:
        """The settings of this demo's exhibit (:mod:`mechviz.viz.model`); ``ValueError`` naming the
        setting if the demo's values are out of range for it."""
        cls = MODELS[self.exhibit].Config
        base = cls()
        kw: dict[str, Any] = {"params": {**base.params, **self.parameters}}
        if self.motion != "driven":
            kw["method"] = self.method
        kw.update({k: v for k, v in (("dt", self.dt), ("rtol", self.rtol)) if v is not None})
        if self.compare is not None:
            kw["compare_method"] = self.compare.method
            kw["compare_dt"] = self.compare.dt
            kw["compare_rtol"] = self.compare.rtol
        ini = {f: getattr(self.initial, f) for f in self.initial.__struct_fields__}
        ini = {k: v for k, v in ini.items() if v is not None}
        # the system's own settings from the rest of the file: its model says which (.model.hooks)
        kw.update(MODELS[self.exhibit].demo_settings(ini, self, kw["params"]))
        return dataclasses.replace(base, **kw)


# =========================================================================== reading
def demo_names() -> list[str]:
    """Names of the built-in demos (the TOML files under ``assets/demos``), sorted."""
    return sorted(p.stem for p in DEMO_DIR.glob("*.toml"))


def list_demos() -> list[Demo]:
    return [load_demo(n) for n in demo_names()]


def load_demo(name_or_path: str | os.PathLike) -> Demo:
    """A built-in demo by name, or any demo file by path; ``ValueError`` for a bad file, with
    the file name and the key at fault."""
    text = str(name_or_path)
    path = Path(text)
    try:
        if path.suffix != ".toml" or not path.exists():
            path = DEMO_DIR / f"{text}.toml"
            if not path.exists():
                raise ValueError(
                    f"unknown demo {printable(repr(text))}; choose one of {', '.join(demo_names())} "
                    "(or give the path of a .toml demo file)"
                )
        if not path.is_file():
            raise ValueError(f"{printable(path.name)}: not a file")
    except OSError as exc:  # a name too long for the file system, a folder we may not read
        raise ValueError(f"{printable(text)}: {exc.strerror or exc}") from None
    try:
        raw = tomllib.loads(path.read_bytes().decode("utf-8"))
    except RecursionError:
        raise ValueError(f"{path.name}: tables or arrays nested too deeply") from None
    except UnicodeDecodeError:
        raise ValueError(f"{path.name}: not UTF-8 text") from None
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{path.name}: {exc}") from None
    except OSError as exc:
        raise ValueError(f"{path.name}: {exc.strerror or exc}") from None
    return parse_demo(raw, name=path.stem, source=str(path))


def parse_demo(raw: dict[str, Any], *, name: str, source: str | None = None) -> Demo:
    """Build and check a :class:`Demo` from the TOML table ``raw``."""
    where = f"{name}.toml" if source is None else Path(source).name
    if "name" in raw or "source" in raw:
        raise ValueError(f"{where}: unknown key {'name' if 'name' in raw else 'source'!r}")
    _check_texts(raw, where)
    params = raw.get("parameters")
    for key, value in params.items() if isinstance(params, dict) else ():
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise dynamics.SettingError(
                f"parameters.{key}", f"{where}: parameters.{key} must be a number, got {value!r}"
            )
    try:
        demo = msgspec.convert({**raw, "name": name, "source": source}, Demo, strict=True)
    except msgspec.ValidationError as exc:
        raise ValueError(f"{where}: {_schema_message(str(exc))}") from None
    except RecursionError:
        raise ValueError(f"{where}: tables or arrays nested too deeply") from None
    try:
        demo = with_defaults(demo)
        check(demo)
    except dynamics.SettingError as exc:
        raise dynamics.SettingError(exc.field, f"{where}: {exc}", fields=exc.fields) from None
    except ValueError as exc:
        raise ValueError(f"{where}: {exc}") from None
    return msgspec.structs.replace(demo, events=tuple(sorted(demo.events, key=lambda e: e.t)))


def _check_texts(value: Any, where: str, at: str = "") -> None:
    """Refuse (``ValueError`` naming the key) any text of the demo, keys included, that holds a
    control character (line breaks and tabs aside): titles, captions and event texts reach the
    terminal, the page and the video's frames, where an escape sequence or a NUL does harm."""
    if isinstance(value, str):
        if has_control_characters(value):
            raise ValueError(f"{where}: {at or 'a text'} holds a control character")
    elif isinstance(value, dict):
        for key, item in value.items():
            name = f"{at}.{key}" if at else str(key)
            if has_control_characters(str(key)):
                raise ValueError(f"{where}: a key holds a control character ({key!r})")
            _check_texts(item, where, name)
    elif isinstance(value, list | tuple):
        for i, item in enumerate(value):
            _check_texts(item, where, f"{at}[{i}]")


def _schema_message(text: str) -> str:
    """msgspec's ``Expected `float`, got `str` - at `$.events[0].t``` as ``events[0].t:
    expected `float`, got `str```; ``Object contains unknown field `x``` keeps its words."""
    message, _, at = text.partition(" - at `$")
    at = at.rstrip("`").lstrip(".")
    message = message.replace("Object contains", "contains")
    if message.startswith("Expected"):
        message = "e" + message[1:]
    if at:
        return f"{at}: {message}"
    return message


# =========================================================================== checks
def with_defaults(d: Demo) -> Demo:
    """``d`` with what it leaves out taken from its system's description
    (:data:`mechviz.dynamics.SPECS`): the title, the disk's motion and the method."""
    if d.exhibit not in dynamics.SPECS:
        raise dynamics.SettingError(
            "exhibit",
            f"exhibit must be one of {', '.join(dynamics.SPECS)}; got {d.exhibit!r}",
        )
    spec = dynamics.SPECS[d.exhibit]
    changes: dict[str, Any] = {}
    if not d.title:
        changes["title"] = spec.title
    if d.motion is None and any(s.name == "motion" for s in spec.start):
        changes["motion"] = spec.setting("motion").default
    if not d.method:
        start = (
            {"motion": changes.get("motion", d.motion)} if "motion" in changes or d.motion else {}
        )
        changes["method"] = spec.default_method(spec.start_values(start))
    return msgspec.structs.replace(d, **changes) if changes else d


def demo_key(d: Demo, field: str) -> str:
    """The demo key of a setting (:class:`mechviz.dynamics.SettingError` ``field``): a physical
    parameter under ``parameters.``, a start setting under ``initial.``, the rest as named."""
    spec = dynamics.SPECS[d.exhibit]
    if field in {s.name for s in spec.params}:
        return f"parameters.{field}"
    if field == "initial.motion":
        return "motion"
    return config_keys(d).get(field, field)


def _finite_positive(key: str, value: float) -> None:
    if not math.isfinite(value) or value <= 0:
        raise dynamics.SettingError(key, f"{key} must be a positive, finite number, got {value!r}")


def check(d: Demo) -> None:
    """Raise ``ValueError`` naming the key of the first thing wrong with ``d`` beyond the schema."""
    _finite_positive("duration", d.duration)
    _finite_positive("speed", d.speed)
    if not 1 <= d.fps <= 240:
        raise dynamics.SettingError(
            "fps", f"fps must be a whole number from 1 to 240, got {d.fps!r}"
        )
    if not d.duration * d.fps < MAX_FRAMES:  # before counting frames: 1e308 x 30 overflows
        raise dynamics.SettingError(
            "duration",
            f"duration x fps gives {d.duration * d.fps:.3g} frames; the limit is {MAX_FRAMES}",
        )
    has_motion = any(s.name == "motion" for s in dynamics.SPECS[d.exhibit].start)
    if not has_motion and d.motion is not None:
        raise ValueError(f"motion is for the disk only, not the {d.exhibit}")
    fields_of = {f.name for f in dataclasses.fields(MODELS[d.exhibit].Config)}
    if d.ghost is not None and "ghost" not in fields_of:
        raise ValueError(f"ghost is for the hoop only, not the {d.exhibit}")
    ini = {f for f in d.initial.__struct_fields__ if getattr(d.initial, f) is not None}
    allowed = MODELS[d.exhibit].Config.demo_initial_keys
    unknown = ini - allowed
    if unknown:
        keys = ", ".join(sorted(allowed))
        raise ValueError(f"initial.{sorted(unknown)[0]} is not a key for the {d.exhibit} ({keys})")
    if d.initial.beam is not None and not 1 <= d.initial.beam <= 1000:
        raise ValueError(
            f"initial.beam must be a whole number from 1 to 1000, got {d.initial.beam}"
        )
    if d.initial.state is not None and {"speed", "vz", "centre", "beam", "modes"} & ini:
        raise ValueError("initial.state gives the whole start; leave out the other initial keys")
    if d.compare is not None and "compare_method" not in fields_of:
        raise ValueError(
            "compare: the disk shows one run; a comparison is for the cyclotron and the hoop"
        )
    if d.compare is not None and d.initial.beam is not None:
        raise ValueError("compare: a beam runs one method; leave out [compare] or initial.beam")
    for key, value in (("position", d.camera.position), ("look_at", d.camera.look_at)):
        if value is not None and not all(math.isfinite(v) for v in value):
            raise ValueError(f"camera.{key} must be three finite numbers, got {list(value)}")
    for i, e in enumerate(d.events):
        if "kick" not in fields_of:
            raise ValueError(f"events[{i}].action: the {d.exhibit} has no scripted events")
        if not 0.0 <= e.t <= d.simulated_time:
            raise ValueError(
                f"events[{i}].t = {e.t!r} s lies outside the recording (0 to {d.simulated_time:g} s "
                f"of simulated time: speed = {d.speed:g} x duration = {d.duration:g} s)"
            )
        if not math.isfinite(e.dv):
            raise ValueError(f"events[{i}].dv must be finite, got {e.dv!r}")
    _check_run(d, "", d.method, d.dt, d.rtol, d.dt, d.rtol)
    if d.compare is not None:
        c = d.compare
        eff_dt = c.dt if c.dt is not None else d.dt
        eff_rtol = c.rtol if c.rtol is not None else d.rtol
        _check_run(d, "compare.", c.method, c.dt, c.rtol, eff_dt, eff_rtol)
    try:
        d.config()
    except dynamics.SettingError as exc:
        key = demo_key(d, exc.field)
        message = str(exc)
        shown = message if message.startswith(key) else f"{key}: {message}"
        raise dynamics.SettingError(key, shown) from None
    except (ValueError, TypeError) as exc:
        raise ValueError(in_demo_terms(str(exc), d)) from None
    check_scales(d)  # what the values make together: every derived scale a double can hold
    check_scale(d)


#: Limits that keep a recording's work in proportion to the demo; each is refused up front
#: with the key that passes it. The step count is bounded separately (mechviz.viz.record.scales.MAX_STEPS).
MAX_EVENTS = 100  # scripted events per recording: each cuts the run and is drawn in the chart
MIN_RTOL = 1e-15  # below it float64 rounding, not the tolerance, limits the step (and Taylor's
#                  method raises its order, and its cost per step, without end)


def check_scale(d: Demo) -> None:
    """Raise ``ValueError`` naming the key if ``d`` asks for more work than its scale needs."""
    if len(d.events) > MAX_EVENTS:
        raise ValueError(f"events: {len(d.events)} scripted events; the limit is {MAX_EVENTS}")
    runs = [("", d.rtol)]
    if d.compare is not None:
        runs.append(("compare.", d.compare.rtol if d.compare.rtol is not None else d.rtol))
    for where, rtol in runs:
        if rtol is not None and rtol < MIN_RTOL:
            raise ValueError(
                f"{where}rtol = {rtol:g} is below {MIN_RTOL:g}, where float64 rounding and not "
                "the tolerance sets the error"
            )


def _check_run(d: Demo, where: str, method: str, dt, rtol, eff_dt, eff_rtol) -> None:
    """``dt`` / ``rtol``: what the run's own table gives; ``eff_*``: what it runs with. The
    method and step are checked by the system's description (:meth:`mechviz.dynamics.SystemSpec.setup`),
    as everywhere else; a refusal names the key here (``compare.dt``)."""
    spec = dynamics.SPECS[d.exhibit]
    m = dynamics.METHODS.get(method)
    if m is not None and m.adaptive and dt is not None:
        raise dynamics.SettingError(
            f"{where}dt", f"{where}dt: {method} is adaptive; give rtol instead"
        )
    if m is not None and not m.adaptive and rtol is not None:
        raise dynamics.SettingError(
            f"{where}rtol", f"{where}rtol: {method} takes a fixed step; give dt instead"
        )
    start = {"motion": d.motion} if d.motion else {}
    try:
        spec.setup(start=start, method=method, dt=eff_dt, rtol=eff_rtol)
    except dynamics.SettingError as exc:
        raise dynamics.SettingError(f"{where}{exc.field}", f"{where}{exc}") from None
