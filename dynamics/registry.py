"""The one registry of systems: each system's description, by the name a person uses.

A system is one module in :mod:`mechviz.dynamics` (its physics: parameters, equations, exact and
analytic results), its adapter in :mod:`.systems` (how the driver treats it) and one exhibit in
:mod:`mechviz.viz.model` and :mod:`mechviz.viz.scene` (its model and its view), and it is found
through here. :data:`SPECS` holds each :class:`~mechviz.dynamics.spec.SystemSpec`: its settings,
default method and step, analysis and the benchmark's problems of it (the tuned ones and a
random draw). Everything else asks these entries (:func:`spec_named`, :func:`system_named`,
:func:`lookup`) and never branches on a system's name: a name no entry has raises
:class:`KeyError` naming it and the names there are.

Adding a system to the product: its physics module, its adapter in :mod:`.systems`
(:data:`~.systems.SYSTEMS`; its compiled id in :mod:`.ids` if it has compiled kernels), its
description here (:data:`SPECS`), and its model and exhibit classes (the model answering the
hooks of :mod:`mechviz.viz.model.hooks`) listed in :data:`mechviz.viz.model.MODELS` and
:data:`mechviz.viz.scene.EXHIBITS`, which are keyed by this registry and refuse to load without
one for each system.

Adding a system at run time, without editing the product (a user's own, a test's):
:func:`register` its description and its adapters. An adapter subclasses
:data:`~.systems.Adapter` and carries as ``sys_id`` its own compiled forms
(:class:`~mechviz.dynamics.forms.SystemForms`, generated from its equations by
:meth:`~mechviz.dynamics.forms.SystemForms.from_equations`), which the integrators are handed
instead of looking them up by id; every front door that asks this registry then knows it
(:func:`mechviz.dynamics.api.simulate`, ``mechviz simulate``, the driver). The returned
:class:`Registration` undoes it (:meth:`Registration.unregister`, or as a context manager), and
also carries the entries of other tables keyed by this registry (:meth:`Registration.add`: the
viewer's model of it, say), undone with it.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, MutableMapping
from typing import Any, TypeVar

import numpy as np

from . import cyclotron, disk, hoop
from . import params as _v
from .forms import is_given
from .ids import DISK_NAME
from .spec import BenchCase, Setting, SystemSpec, param
from .systems import (
    CYCLOTRON_START,
    DISK_EXTRA_SPIN,
    HOOP_MODES,
    SYSTEMS,
    Adapter,
    Cyclotron,
    DrivenDisk,
    Hoop,
    ReleasedDisk,
)

V = TypeVar("V")


def lookup(table: Mapping[str, V], name: str, what: str = "system") -> V:
    """``table[name]``, or :class:`KeyError` naming ``name`` and the names ``table`` has: a part
    of the product that meets a system it does not know says so instead of falling through to
    another system's behaviour."""
    try:
        return table[name]
    except KeyError:
        raise KeyError(f"unknown {what} {name!r}; known: {', '.join(table) or 'none'}") from None


def system_named(name: str) -> type:
    """The driver's adapter class called ``name`` (:data:`mechviz.dynamics.systems.SYSTEMS`)."""
    return lookup(SYSTEMS, name)


def spec_named(name: str) -> SystemSpec:
    """The description of the system a person calls ``name`` (:data:`SPECS`)."""
    return lookup(SPECS, name)


def reference_runs(method: str) -> list[tuple[str, str]]:
    """``(system, method)`` for each compiled system without an exact flow from every state:
    the runs whose error is measured against a tight ``method`` run (the viewer's warm-up)."""
    return [(n, method) for n, s in SYSTEMS.items() if s.sys_id is not None and not s.closed_form]


def _angle_pair(name: str, value) -> tuple[float, float]:
    a = _v.numbers(name, value, 2)
    if any(abs(x) >= 3.0 for x in a):
        raise _v.SettingError(name, f"{name} must be angles below 3 rad, got {value!r}")
    return a


def _choice(*options: str):
    def rule(name: str, value) -> str:
        if value not in options:
            raise _v.SettingError(
                name, f"{name} must be one of {', '.join(options)}; got {value!r}"
            )
        return value

    return rule


def _build_cyclotron(p: cyclotron.CyclotronParams, start: dict) -> tuple[Cyclotron, np.ndarray]:
    state = cyclotron.circular_orbit_state(p, start["speed"], start["centre"], start["vz"])
    return Cyclotron(p), state


def _build_hoop(p: hoop.HoopParams, start: dict) -> tuple[Hoop, np.ndarray]:
    return Hoop(p), hoop.mode_state(p, start["modes"])


def _build_disk(p: disk.DiskParams, start: dict) -> tuple[DrivenDisk | ReleasedDisk, np.ndarray]:
    system = DrivenDisk(p) if start["motion"] == "driven" else ReleasedDisk(p, start["extra_spin"])
    return system, system.default_state()


# What a live exhibit takes (Setting.span): masses within six decades of 1 kg keep every motion
# moving on screen; radii up to 2 m keep each exhibit clear of its neighbours (4.4 m apart).
MASSES = (1e-3, 1e3)
RADII = (0.1, 2.0)


def _signed(rng: np.random.Generator, lo: float, hi: float) -> float:
    return float(rng.uniform(lo, hi) * rng.choice((-1.0, 1.0)))


# The benchmark's cases nobody tuned for (:mod:`mechviz.bench.untuned`): one system's case drawn
# at random (its ranges in that module's docstring).
def _draw_charge(rng: np.random.Generator, key: str) -> BenchCase:
    q, m, b = _signed(rng, 0.3, 3.0), float(rng.uniform(0.3, 3.0)), _signed(rng, 0.3, 3.0)
    system = Cyclotron(cyclotron.CyclotronParams(charge=q, mass=m, field=b))
    state = tuple(float(v) for v in np.concatenate([rng.uniform(-2, 2, 3), rng.uniform(-2, 2, 3)]))
    periods = int(rng.integers(10, 301))
    period = 2.0 * math.pi * m / abs(q * b)
    title = f"charge q={q:.3g} m={m:.3g} B={b:.3g}, {periods} gyro-periods"
    return BenchCase(key, title, system, state, periods * period, (), 0, 1e-13, period, True)


def _draw_hoop(rng: np.random.Generator, key: str) -> BenchCase:
    M, m, a = float(rng.uniform(0.2, 3.0)), float(rng.uniform(0.1, 3.0)), float(rng.uniform(0.3, 2))
    system = Hoop(hoop.HoopParams(hoop_mass=M, bead_mass=m, radius=a))
    rate = math.sqrt(9.81 / a)
    state = tuple(
        float(v)
        for v in np.concatenate([rng.uniform(-1.5, 1.5, 2), rate * rng.uniform(-0.5, 0.5, 2)])
    )
    span = float(rng.uniform(5.0, 30.0))
    title = f"hoop M={M:.3g} m={m:.3g} a={a:.3g}, {span:.1f} s"
    return BenchCase(key, title, system, state, span, (), 0, 1e-13, 2 * math.pi / rate, False)


def _draw_disk(rng: np.random.Generator, key: str) -> BenchCase:
    M, R, m = (
        float(rng.uniform(0.3, 3.0)),
        float(rng.uniform(0.3, 2.0)),
        float(rng.uniform(0.05, 3)),
    )
    w = _signed(rng, 0.3, 5.0)
    extra = tuple(float(v) for v in abs(w) * rng.uniform(-0.5, 0.5, 3))
    system = ReleasedDisk(
        disk.DiskParams(disk_mass=M, radius=R, bead_mass=m, omega=w), extra_spin=extra
    )
    span = float(rng.uniform(10.0, 100.0))
    title = f"disk M={M:.3g} R={R:.3g} bead={m:.3g} spin={w:.3g}, {span:.1f} s"
    state = tuple(float(v) for v in system.default_state())
    return BenchCase(key, title, system, state, span, (), 0, 1e-13, 2 * math.pi / abs(w), False)


# The benchmark's problems (:class:`BenchCase`): on each system the one the methods were tuned on,
# then one they were not (other parameters, larger amplitudes, longer spans).
_BENCH_DISK = ReleasedDisk(disk.DiskParams(omega=1.0), extra_spin=(0.01, 0.0, 0.01))
_UNTUNED_DISK = ReleasedDisk(
    disk.DiskParams(radius=0.8, bead_mass=0.4, omega=1.5), extra_spin=(0.3, 0.0, 0.2)
)
CYCLOTRON_BENCH = (
    BenchCase(
        "charge",
        "Charge in a uniform field (100 gyro-periods)",
        Cyclotron(),
        (1.0, 0.0, 0.0, 0.0, 1.0, 0.1),
        200.0 * math.pi,
        ("rk4", "boris", "yoshida4", "midpoint", "euler"),
        256,
        1e-13,
        2.0 * math.pi,
        True,
        # the long run's step is loose on purpose: a frame-budget step
        long_run=(0.1, ("rk4", "boris", "yoshida4", "midpoint")),
    ),
    BenchCase(
        "charge-untuned",
        "Charge, q = -2, m = 1.5, B = 0.7, faster and off axis (1000 gyro-periods)",
        Cyclotron(cyclotron.CyclotronParams(charge=-2.0, mass=1.5, field=0.7)),
        (0.4, -1.1, 0.3, 0.9, 1.7, 0.02),
        1000 * 2.0 * math.pi * 1.5 / 1.4,
        ("rk4",),
        1024,
        1e-13,
        2.0 * math.pi * 1.5 / 1.4,
        True,
    ),
)
HOOP_BENCH = (
    BenchCase(
        Hoop.name,
        "Bead on a hoop (20 s)",
        Hoop(),
        (0.5, -0.3, 0.0, 0.0),
        20.0,
        ("rk4", "verlet", "yoshida4", "midpoint", "euler"),
        64,
        1e-13,
        2.0 * math.pi / math.sqrt(9.81 / 2.0),  # the slower normal mode
        False,
        long_run=(0.05, ("rk4", "verlet", "yoshida4")),
    ),
    BenchCase(
        f"{Hoop.name}-untuned",
        "Hoop, M = 0.7, m = 1.3, a = 0.6, larger swing (1.2, -0.8) (60 s)",
        Hoop(hoop.HoopParams(hoop_mass=0.7, bead_mass=1.3, radius=0.6)),
        (1.2, -0.8, 0.5, 0.0),
        60.0,
        ("rk4",),
        256,
        1e-13,
        1.0,
        False,
    ),
)

CYCLOTRON = SystemSpec(
    name=Cyclotron.name,
    title="Charge in a uniform magnetic field",
    Params=cyclotron.CyclotronParams,
    params=(
        param("charge", "Charge q", "C", "charge q [C] (signed, nonzero)", span=(-1e3, 1e3)),
        param("mass", "Mass m", "kg", span=MASSES),
        param("field", "Field B", "T", "field B [T] along +z (nonzero)", span=(-1e3, 1e3)),
    ),
    start=(
        Setting(
            "speed",
            "Speed v⊥",
            "m/s",
            CYCLOTRON_START[0],
            _v.positive,
            "speed in the plane normal to B [m/s]",
        ),
        Setting(
            "centre",
            "Centre (x, y)",
            "m",
            CYCLOTRON_START[1],
            lambda n, v: _v.numbers(n, v, 2),
            "centre of the circle (x, y) [m]",
        ),
        Setting("vz", "Speed along B", "m/s", CYCLOTRON_START[2], _v.finite, "speed along B [m/s]"),
    ),
    build=_build_cyclotron,
    default_method=lambda start: "exact",
    dt=0.01,
    analysis=cyclotron.analysis,
    analysis_start=("speed",),
    state_overrides=cyclotron.STATE_NAMES,
    bench=CYCLOTRON_BENCH,
    bench_draw=_draw_charge,
)

HOOP = SystemSpec(
    name=Hoop.name,
    title="Bead on a hanging hoop",
    Params=hoop.HoopParams,
    params=(
        param("hoop_mass", "Hoop mass M", "kg", span=MASSES),
        param("bead_mass", "Bead mass m", "kg", span=MASSES),
        param("radius", "Radius a", "m", "hoop radius a [m]", span=RADII),
        param("gravity", "Gravity g", "m/s²", span=(1e-2, 1e3)),
    ),
    start=(
        Setting(
            "modes",
            "Mode amplitudes (1, 2)",
            "rad",
            HOOP_MODES,
            _angle_pair,
            "amplitudes of mode 1 and mode 2 [rad], at rest",
        ),
    ),
    build=_build_hoop,
    default_method=lambda start: "rk4",
    dt=1 / 60,
    analysis=hoop.analysis,
    state_overrides=hoop.STATE_NAMES,
    bench=HOOP_BENCH,
    bench_draw=_draw_hoop,
)

DISK = SystemSpec(
    name=DISK_NAME,
    title="Spinning disk with a bead",
    Params=disk.DiskParams,
    params=(
        param("disk_mass", "Disk mass M", "kg", span=MASSES),
        param("radius", "Radius R", "m", "disk radius R [m]", span=RADII),
        param("bead_mass", "Bead mass m", "kg", span=MASSES),
        param("omega", "Spin ω", "rad/s", "spin rate about the axle [rad/s]", span=(-50.0, 50.0)),
    ),
    start=(
        Setting(
            "motion",
            "Motion",
            "",
            "driven",
            _choice("driven", "released"),
            "driven: uniform rotation about the axle (exact); released: the axle removed "
            "at t = 0 (a free rigid body)",
            choices=("driven", "released"),
        ),
        Setting(
            "extra_spin",
            "Extra spin at release",
            "rad/s",
            DISK_EXTRA_SPIN,
            lambda n, v: _v.numbers(n, v, 3),
            "spin added at release (disk-frame components) [rad/s]",
            components=("wx", "wy", "wz"),
            needs=("motion", "released"),
        ),
    ),
    build=_build_disk,
    default_method=lambda start: "exact" if start["motion"] == "driven" else "rk4",
    dt=1 / 60,
    analysis=disk.analysis,
    bench=(
        BenchCase(
            DISK_NAME,
            "Released disk with bead (50 s)",
            _BENCH_DISK,
            tuple(_BENCH_DISK.default_state()),
            50.0,
            ("rk4", "splitting", "yoshida4", "midpoint", "euler"),
            32,
            1e-13,
            2.0 * math.pi,  # one turn at the spin rate of 1 rad/s
            False,
            long_run=(0.1, ("rk4", "splitting", "yoshida4")),
        ),
        BenchCase(
            f"{DISK_NAME}-untuned",
            "Released disk, R = 0.8, bead 0.4 kg, tumbling (extra spin 0.3, 0, 0.2) (250 s)",
            _UNTUNED_DISK,
            tuple(_UNTUNED_DISK.default_state()),
            250.0,
            ("rk4",),
            128,
            1e-13,
            2.0 * math.pi / 1.5,
            False,
        ),
    ),
    bench_draw=_draw_disk,
)

#: Every system by the name a person uses (the CLI's, the API's and the demo files').
SPECS: dict[str, SystemSpec] = {s.name: s for s in (CYCLOTRON, DISK, HOOP)}


class Registration:
    """A system registered by :func:`register`: its description and adapters, and the entries
    added with it to other tables (:meth:`add`). :meth:`unregister` (or leaving a ``with``
    block) takes every one of them out again, the last added first, so that a test that
    registers a system leaves the product as it found it."""

    def __init__(self, spec: SystemSpec, adapters: tuple[type, ...]) -> None:
        self.spec = spec
        self.adapters = adapters
        self._entries: list[tuple[MutableMapping, str, Any]] = []
        self.active = False

    def add(self, table: MutableMapping[str, Any], key: str, value: Any) -> Registration:
        """Put ``value`` in ``table`` under ``key`` until this registration is undone (a table
        keyed by the registry: the viewer's models, its exhibits). ``key`` must be new there:
        a registration never replaces what the product or another registration put."""
        if not self.active:
            raise RuntimeError(f"the registration of {self.spec.name!r} was undone")
        if key in table:
            raise KeyError(f"{key!r} is taken; a registration adds, it never replaces")
        table[key] = value
        self._entries.append((table, key, value))
        return self

    def unregister(self) -> None:
        """Take out everything this registration put in (again: nothing more)."""
        while self._entries:
            table, key, value = self._entries.pop()
            if table.get(key) is value:
                del table[key]
        self.active = False

    def __enter__(self) -> Registration:
        return self

    def __exit__(self, *exc: object) -> None:
        self.unregister()


def register(spec: SystemSpec, adapters: Iterable[type]) -> Registration:
    """Make the system ``spec`` describes known to every part of the product that asks this
    registry, with ``adapters``, the driver's classes its ``build`` returns (one or more: the
    disk has two motions). Returns the :class:`Registration` that undoes it.

    Checked before anything changes (``ValueError`` or ``TypeError`` naming what is wrong): the
    names are new (neither a description's nor an adapter's), each adapter subclasses
    :data:`~.systems.Adapter` and has its compiled forms of its own (a
    :class:`~mechviz.dynamics.forms.SystemForms` as ``sys_id``, its dimension the state's) or
    none (``sys_id`` None: the closed form only); the shipped tables' ids belong to the shipped
    systems. And the description builds, from its defaults, one of ``adapters`` and a start of
    its state's size."""
    adapters = tuple(adapters)
    if spec.name in SPECS:
        raise ValueError(f"a system {spec.name!r} is registered already")
    if not adapters:
        raise ValueError(f"{spec.name}: at least one adapter (the driver's class of it)")
    for cls in adapters:
        if not (isinstance(cls, type) and issubclass(cls, Adapter)):
            raise TypeError(f"{spec.name}: {cls!r} is not an adapter (subclass systems.Adapter)")
        if cls.name in SYSTEMS:
            raise ValueError(f"{spec.name}: an adapter {cls.name!r} is registered already")
        sys_id = cls.sys_id
        if sys_id is not None and not is_given(sys_id):
            raise TypeError(
                f"{cls.name}: sys_id must be its own SystemForms (or None), not {sys_id!r}: "
                "the compiled ids index the shipped systems' tables"
            )
        if sys_id is not None and sys_id.dim != len(cls.state_names):
            raise ValueError(
                f"{cls.name}: forms of {sys_id.dim} components, state of {len(cls.state_names)}"
            )
    system, state = spec.build(spec.parameters(), spec.start_values())
    if type(system) not in adapters or np.shape(state) != (len(system.state_names),):
        raise ValueError(
            f"{spec.name}: build must return one of the adapters given and a start of its state"
        )
    reg = Registration(spec, adapters)
    reg.active = True
    reg.add(SPECS, spec.name, spec)
    for cls in adapters:
        reg.add(SYSTEMS, cls.name, cls)
    return reg
