"""Demo files: the schema, its checks, and the exhibit settings a demo stands for.

A *demo* is data: one small TOML file (the built-in ones under ``assets/demos/``) naming the
exhibit, its physical parameters and start, the method and step, the playback duration, frame
rate and speed, the camera, an optional second method shown beside the first (``[compare]``)
and scripted events (``[[events]]``, a radial kick at ``t = 5 s``). Units are SI; times are
*simulated* seconds except ``duration`` (seconds of playback; simulated time runs ``speed``
times faster).

The schema is a set of :mod:`msgspec` structs: a key the schema does not know, or a value of the
wrong kind, is refused with the file name and the key's path (``helix.toml: events[0].t: ...``).
:meth:`Demo.config` maps a valid demo onto the settings of its exhibit (:mod:`viz.scene`): every
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

import dynamics
from dynamics import hoop

from ..scene import EXHIBITS, CyclotronConfig, DiskConfig, ExhibitConfig, HoopConfig

DEMO_DIR = Path(__file__).resolve().parents[2] / "assets" / "demos"
MAX_FRAMES = 100_000
_INITIAL_KEYS = {
    "cyclotron": {"speed", "vz", "centre", "beam", "speeds", "state"},
    "disk": {"extra_spin"},
    "hoop": {"modes", "state"},
}


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

    title: str
    description: str
    exhibit: Literal["cyclotron", "disk", "hoop"]
    method: str
    duration: float
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
        self, *, duration: float | None = None, fps: int | None = None,
        method: str | None = None, dt: float | None = None,
    ) -> Demo:  # fmt: skip
        """This demo with command-line overrides applied and checked (``ValueError`` naming the
        option otherwise). A new method drops the demo's step setting it does not take."""
        changes: dict[str, Any] = {}
        if duration is not None:
            changes["duration"] = duration
        if fps is not None:
            changes["fps"] = fps
        if method is not None and method != self.method:
            changes["method"] = method
            m = dynamics.get_method(method)
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
        """The settings of this demo's exhibit (:mod:`viz.scene`); ``ValueError`` naming the
        setting if the demo's values are out of range for it."""
        cls = EXHIBITS[self.exhibit].Config
        base = cls()
        kw: dict[str, Any] = {"params": {**base.params, **self.parameters}}
        if self.exhibit != "disk" or self.motion == "released":
            kw["method"] = self.method
        kw.update({k: v for k, v in (("dt", self.dt), ("rtol", self.rtol)) if v is not None})
        if self.compare is not None:
            kw["compare_method"] = self.compare.method
            kw["compare_dt"] = self.compare.dt
            kw["compare_rtol"] = self.compare.rtol
        ini = {f: getattr(self.initial, f) for f in self.initial.__struct_fields__}
        ini = {k: v for k, v in ini.items() if v is not None}
        if cls is CyclotronConfig:
            kw.update({k: ini[k] for k in ("speed", "vz", "centre") if k in ini})
            if "state" in ini:
                kw["state"] = tuple(ini["state"])
            if "beam" in ini:
                kw["beam"], kw["beam_size"] = True, ini["beam"]
            if "speeds" in ini:
                kw["beam_speeds"] = ini["speeds"]
        elif cls is DiskConfig:
            kw["mode"] = self.motion
            if "extra_spin" in ini:
                kw["extra_spin"] = ini["extra_spin"]
        elif cls is HoopConfig:
            kw["ghost"] = self.ghost == "linear"
            if "state" in ini:
                kw.update(mode="custom", state=tuple(ini["state"]))
            elif "modes" in ini:
                a1, a2 = ini["modes"]
                if a2 == 0.0:
                    kw.update(mode="mode 1", amplitude=a1)
                elif a1 == 0.0:
                    kw.update(mode="mode 2", amplitude=a2)
                elif a1 == a2:
                    kw.update(mode="mix", amplitude=2 * a1)
                else:
                    p = hoop.HoopParams(**kw["params"])
                    kw.update(mode="custom", state=tuple(hoop.mode_state(p, (a1, a2)).tolist()))
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
    if path.suffix != ".toml" or not path.exists():
        path = DEMO_DIR / f"{text}.toml"
        if not path.exists():
            raise ValueError(
                f"unknown demo {text!r}; choose one of {', '.join(demo_names())} "
                "(or give the path of a .toml demo file)"
            )
    if not path.is_file():
        raise ValueError(f"{path.name}: not a file")
    try:
        raw = tomllib.loads(path.read_bytes().decode("utf-8"))
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
    try:
        demo = msgspec.convert({**raw, "name": name, "source": source}, Demo, strict=True)
    except msgspec.ValidationError as exc:
        raise ValueError(f"{where}: {_schema_message(str(exc))}") from None
    try:
        check(demo)
    except ValueError as exc:
        raise ValueError(f"{where}: {exc}") from None
    return msgspec.structs.replace(demo, events=tuple(sorted(demo.events, key=lambda e: e.t)))


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
def _finite_positive(key: str, value: float) -> None:
    if not math.isfinite(value) or value <= 0:
        raise ValueError(f"{key} must be a positive, finite number, got {value!r}")


def check(d: Demo) -> None:
    """Raise ``ValueError`` naming the key of the first thing wrong with ``d`` beyond the schema."""
    _finite_positive("duration", d.duration)
    _finite_positive("speed", d.speed)
    if not 1 <= d.fps <= 240:
        raise ValueError(f"fps must be a whole number from 1 to 240, got {d.fps!r}")
    if not d.duration * d.fps < MAX_FRAMES:  # before counting frames: 1e308 x 30 overflows
        raise ValueError(
            f"duration x fps gives {d.duration * d.fps:.3g} frames; the limit is {MAX_FRAMES}"
        )
    if d.exhibit == "disk" and d.motion is None:
        raise ValueError("motion must be driven or released for the disk")
    if d.exhibit != "disk" and d.motion is not None:
        raise ValueError(f"motion is for the disk only, not the {d.exhibit}")
    if d.ghost is not None and d.exhibit != "hoop":
        raise ValueError(f"ghost is for the hoop only, not the {d.exhibit}")
    ini = {f for f in d.initial.__struct_fields__ if getattr(d.initial, f) is not None}
    unknown = ini - _INITIAL_KEYS[d.exhibit]
    if unknown:
        keys = ", ".join(sorted(_INITIAL_KEYS[d.exhibit]))
        raise ValueError(f"initial.{sorted(unknown)[0]} is not a key for the {d.exhibit} ({keys})")
    if d.initial.beam is not None and not 1 <= d.initial.beam <= 1000:
        raise ValueError(f"initial.beam must be a whole number from 1 to 1000, got {d.initial.beam}")
    if d.initial.state is not None and {"speed", "vz", "centre", "beam", "modes"} & ini:
        raise ValueError("initial.state gives the whole start; leave out the other initial keys")
    if d.compare is not None and d.exhibit == "disk":
        raise ValueError("compare: the disk shows one run; a comparison is for the cyclotron and the hoop")
    if d.compare is not None and d.initial.beam is not None:
        raise ValueError("compare: a beam runs one method; leave out [compare] or initial.beam")
    for key, value in (("position", d.camera.position), ("look_at", d.camera.look_at)):
        if value is not None and not all(math.isfinite(v) for v in value):
            raise ValueError(f"camera.{key} must be three finite numbers, got {list(value)}")
    for i, e in enumerate(d.events):
        if d.exhibit != "cyclotron":
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
    from .scales import check_scales, in_demo_terms

    try:
        d.config()
    except (ValueError, TypeError) as exc:
        raise ValueError(in_demo_terms(str(exc), d)) from None

    check_scales(d)  # what the values make together: every derived scale a double can hold


def _check_run(d: Demo, where: str, method: str, dt, rtol, eff_dt, eff_rtol) -> None:
    """``dt`` / ``rtol``: what the run's own table gives; ``eff_*``: what it runs with."""
    system = "driven-disk" if d.motion == "driven" else EXHIBITS[d.exhibit].Config.system_name
    names = [m.name for m in dynamics.methods_for(system)]
    if method not in names:
        if method in dynamics.METHODS:
            raise ValueError(
                f"{where}method {method!r} does not apply to the {system}; choose one of "
                f"{', '.join(names)}"
            )
        raise ValueError(f"{where}method must be one of {', '.join(names)}; got {method!r}")
    m = dynamics.get_method(method)
    if m.adaptive and dt is not None:
        raise ValueError(f"{where}dt: {method} is adaptive; give rtol instead")
    if not m.adaptive and rtol is not None:
        raise ValueError(f"{where}rtol: {method} takes a fixed step; give dt instead")
    if not m.adaptive and m.backend != "exact" and eff_dt is None:
        raise ValueError(f"{where}dt: required for the fixed-step method {method}")
    if eff_dt is not None:
        _finite_positive(f"{where}dt", eff_dt)
    if eff_rtol is not None and not (math.isfinite(eff_rtol) and 0 < eff_rtol < 1):
        raise ValueError(f"{where}rtol must lie in (0, 1), got {eff_rtol!r}")
