"""What an atlas computes: its kind, system, methods, two axes, settings, and the chunks it is cut into.

An atlas is a map over a grid of ``(method, y, x)`` cells. Each kind names its axes:

============ ================================ ================================
kind         y (rows)                         x (columns)
============ ================================ ================================
stability    ``dt`` [s], the step              ``amplitude`` (see :mod:`.theory`)
accuracy     ``dt`` [s] or ``rtol``            ``amplitude``
chaos        a section of the hoop's starts (:data:`CHAOS_SECTIONS`; hoop only)
============ ================================ ================================

A chaos map is a section of the hoop's start space ``(theta1, theta2, omega1, omega2)`` (angles
[rad], rates [rad/s]): its two axes name the coordinates that vary, the other two are zero.

The grid is cut into rectangular chunks of ``chunk = (rows, columns)`` cells of one method, each
one task. The chunk shape is part of the run (it is hashed into :meth:`AtlasSpec.run_key`), so a
resumed run cuts the grid exactly as the first one did; :func:`chunk_shape_for` picks one worth
about :data:`CHUNK_SECONDS` of work from a rough cost per step.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Literal

import numpy as np

from .. import params as _v
from ..integrators import get_method, methods_for
from ..systems import SYSTEMS

Kind = Literal["stability", "chaos", "accuracy"]
#: The chaos map's sections by name: (y, x) axes. ``rest``: both angles, at rest; ``theta1``:
#: the hoop's angle and rate with ``theta2 = omega2 = 0`` (the bead straight below the hoop's
#: centre, not turning); ``theta2``: the bead's angle and rate on the hoop hanging at rest.
CHAOS_SECTIONS = {
    "rest": ("theta2", "theta1"),
    "theta1": ("omega1", "theta1"),
    "theta2": ("omega2", "theta2"),
}
#: Where each coordinate sits in the hoop's state.
HOOP_COORDINATES = {"theta1": 0, "theta2": 1, "omega1": 2, "omega2": 3}
KINDS: tuple[str, ...] = ("stability", "chaos", "accuracy")


def system_names() -> tuple[str, ...]:
    """The systems an atlas can map, as the registry has them now (a system registered at run
    time too, :func:`mechviz.dynamics.registry.register`): those with a compiled right-hand side
    and a family of starts by amplitude (the adapter's ``amplitude``), those with a chaos map
    (the adapter's ``chaos_map``) first."""
    return tuple(
        sorted(
            (n for n, s in SYSTEMS.items() if s.sys_id is not None and s.amplitude is not None),
            key=lambda n: not SYSTEMS[n].chaos_map,
        )
    )


def chaos_systems() -> tuple[str, ...]:
    """The systems whose start plane the chaos map covers (:attr:`_Adapter.chaos_map`)."""
    return tuple(n for n in system_names() if SYSTEMS[n].chaos_map)


#: The tightest tolerance an accuracy map takes (``simulate``'s ``MIN_COMPARED_TOL``).
MIN_RTOL = 1e-12
#: The chaos map's twin offsets allowed (``separation``).
MIN_SEPARATION, MAX_SEPARATION = 1e-12, 1e-3
#: Target wall time [s] of one chunk (one task) on one core.
CHUNK_SECONDS = 1.0


@dataclass(frozen=True)
class Axis:
    """``n`` values from ``start`` to ``stop`` (both included), evenly spaced (``"linear"``) or
    in geometric progression (``"log"``, both ends positive)."""

    name: str
    start: float
    stop: float
    n: int
    scale: Literal["linear", "log"] = "linear"

    def __post_init__(self) -> None:
        object.__setattr__(self, "start", _v.finite(f"{self.name} start", self.start))
        object.__setattr__(self, "stop", _v.finite(f"{self.name} stop", self.stop))
        if not isinstance(self.n, int | np.integer) or self.n < 1:
            raise ValueError(f"{self.name}: the number of points must be a positive integer")
        object.__setattr__(self, "n", int(self.n))
        if self.scale not in ("linear", "log"):
            raise ValueError(f"{self.name}: scale must be 'linear' or 'log', got {self.scale!r}")
        if self.scale == "log" and not (self.start > 0 and self.stop > 0):
            raise ValueError(f"{self.name}: a log axis needs positive ends")
        if self.n > 1 and self.start == self.stop:
            raise ValueError(f"{self.name}: start and stop are equal")

    def values(self) -> np.ndarray:
        if self.scale == "log":
            return np.geomspace(self.start, self.stop, self.n)
        return np.linspace(self.start, self.stop, self.n)


@dataclass(frozen=True)
class AtlasSpec:
    """One atlas: everything that decides its numbers (and nothing that does not, such as the
    cluster it runs on).

    kind : ``"stability"``, ``"chaos"`` or ``"accuracy"`` (module docstring).
    system : a name in :func:`system_names` (chaos: :func:`chaos_systems`).
    params : the system's parameters by field name (its dataclass validates them).
    methods : method names; stability: fixed-step methods; chaos: one fixed-step method.
    y, x : the axes (names as in the module docstring).
    periods : stability: run length in periods of the fastest linear mode.
    threshold : stability: a cell is unbounded once its relative energy error exceeds this.
    duration : chaos and accuracy: run length [s].
    step : chaos: the fixed step [s] of the method the exponent is computed with.
    renormalise : chaos: time [s] between renormalisations of the twin's offset.
    separation : chaos: the twin's offset (Euclidean, in state space) after each renormalisation.
    chunk : (rows, columns) of one chunk.
    """

    kind: Kind
    system: str
    methods: tuple[str, ...]
    y: Axis
    x: Axis
    params: tuple[tuple[str, float], ...] = ()
    periods: float = 50.0
    threshold: float = 1.0
    duration: float = 60.0
    step: float = 0.01
    renormalise: float = 1.0
    separation: float = 1e-9
    chunk: tuple[int, int] = field(default=(0, 0))

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"kind must be one of {', '.join(KINDS)}, got {self.kind!r}")
        names = system_names()
        if self.system not in names:
            raise ValueError(f"system must be one of {', '.join(names)}, got {self.system!r}")
        chaos = chaos_systems()
        if self.kind == "chaos" and self.system not in chaos:
            raise ValueError(
                f"system: the chaos map is of the start plane of {', '.join(chaos)} only"
            )
        object.__setattr__(
            self, "params", tuple(sorted((str(k), float(v)) for k, v in self.params))
        )
        self.make_system()  # the parameters' own dataclass validates them
        object.__setattr__(self, "methods", tuple(self.methods))
        if not self.methods:
            raise ValueError("methods: give at least one")
        if len(set(self.methods)) != len(self.methods):
            raise ValueError("methods: a method is named twice")
        allowed = {m.name for m in methods_for(SYSTEMS[self.system]) if m.backend == "numba"}
        for name in self.methods:
            try:
                m = get_method(name)
            except (KeyError, ValueError):
                raise ValueError(f"methods: unknown method {name!r}") from None
            if name not in allowed:
                raise ValueError(f"methods: {name} is not a compiled method of the {self.system}")
            if self.kind != "accuracy" and m.adaptive:
                raise ValueError(
                    f"methods: {name} is adaptive; the {self.kind} map takes fixed steps"
                )
        if self.kind == "chaos" and len(self.methods) != 1:
            raise ValueError("methods: the chaos map is computed with one method")
        if self.kind == "accuracy":
            adaptive = {get_method(m).adaptive for m in self.methods}
            if len(adaptive) > 1:
                raise ValueError("methods: mix no fixed-step and adaptive methods in one map")
            want = "rtol" if adaptive.pop() else "dt"
            if self.y.name != want:
                raise ValueError(f"y axis: {self.methods[0]} takes {want}, not {self.y.name}")
            ends = (self.y.start, self.y.stop)
            if want == "rtol" and not (MIN_RTOL <= min(ends) and max(ends) < 1):
                # tighter, the error would be measured against a reference run (DOP853 at
                # 3e-15) no tighter than the run itself, and an adaptive step cannot meet the
                # tolerance at all below the doubles' resolution
                raise ValueError(f"rtol: must lie from {MIN_RTOL:g} to below 1, got {min(ends):g}")
        expected = {
            "stability": ("dt", "amplitude"),
            "chaos": CHAOS_SECTIONS.get(self.section, ("theta2", "theta1")),
            "accuracy": (self.y.name, "amplitude"),
        }[self.kind]
        if (self.y.name, self.x.name) != expected:
            raise ValueError(f"axes: the {self.kind} map has y = {expected[0]}, x = {expected[1]}")
        if self.y.name == "dt" and min(self.y.start, self.y.stop) <= 0:
            raise ValueError("dt: the steps must be positive")
        for name in ("periods", "threshold", "duration", "step", "renormalise", "separation"):
            _v.positive(name, getattr(self, name))
        if self.kind == "chaos" and self.renormalise < self.step:
            raise ValueError(
                f"renormalise: must be at least one --step ({self.step:g} s), got {self.renormalise:g}"
            )
        if not MIN_SEPARATION <= self.separation <= MAX_SEPARATION:
            # a twin offset by more is no neighbour, and by less it is lost in the rounding of
            # the state (angles of a few radians, resolved to about 1e-15)
            raise ValueError(
                f"separation: must lie from {MIN_SEPARATION:g} to {MAX_SEPARATION:g}, "
                f"got {self.separation:g}"
            )
        if self.chunk == (0, 0):
            object.__setattr__(self, "chunk", chunk_shape_for(self))
        rows, cols = (int(c) for c in self.chunk)
        if rows < 1 or cols < 1:
            raise ValueError(f"chunk: rows and columns must be at least 1, got {self.chunk}")
        object.__setattr__(self, "chunk", (min(rows, self.y.n), min(cols, self.x.n)))

    # ---------------------------------------------------------------- the system
    def make_system(self):
        """The :mod:`mechviz.dynamics.systems` adapter with :attr:`params`."""
        from .theory import make_system

        return make_system(self.system, dict(self.params))

    # ---------------------------------------------------------------- the grid
    @property
    def section(self) -> str | None:
        """The chaos map's section (:data:`CHAOS_SECTIONS`) its axes name, else None."""
        pair = (self.y.name, self.x.name)
        return next((k for k, v in CHAOS_SECTIONS.items() if v == pair), None)

    @property
    def shape(self) -> tuple[int, int, int]:
        return (len(self.methods), self.y.n, self.x.n)

    @property
    def chunk_grid(self) -> tuple[int, int, int]:
        """Chunks along (method, y, x)."""
        return (len(self.methods), -(-self.y.n // self.chunk[0]), -(-self.x.n // self.chunk[1]))

    def chunks(self) -> list[tuple[int, int, int]]:
        """Every chunk's index ``(method, row block, column block)``, in row-major order."""
        return [tuple(int(v) for v in i) for i in np.ndindex(*self.chunk_grid)]

    def cells(self, index: tuple[int, int, int]) -> tuple[int, slice, slice]:
        """The method index and the row and column slices of chunk ``index``."""
        k, by, bx = index
        cy, cx = self.chunk
        rows = slice(by * cy, min((by + 1) * cy, self.y.n))
        return k, rows, slice(bx * cx, min((bx + 1) * cx, self.x.n))

    # ---------------------------------------------------------------- identity
    def as_dict(self) -> dict:
        d = asdict(self)
        d["params"] = dict(self.params)
        d["methods"] = list(self.methods)
        d["chunk"] = list(self.chunk)
        return d

    def run_key(self) -> str:
        """A hash of everything that decides the numbers, the source of the physics and of the
        atlas's kernels included: two runs with the same key compute the same chunks bit for
        bit."""
        from .._jit import _source_hash

        here = Path(__file__).parent
        # the physics (hashed for numba's cache, which leaves this package out) and what here
        # decides a cell's numbers
        code = [_source_hash()] + [
            (here / f).read_text() for f in ("grid.py", "theory.py", "kernels.py")
        ]
        digest = hashlib.sha256("\n".join(code).encode()).hexdigest()
        text = json.dumps({"spec": self.as_dict(), "code": digest}, sort_keys=True)
        return hashlib.sha256(text.encode()).hexdigest()[:20]

    @classmethod
    def from_dict(cls, d: dict) -> AtlasSpec:
        d = dict(d)
        d["y"], d["x"] = Axis(**d["y"]), Axis(**d["x"])
        d["params"] = tuple(d["params"].items())
        d["methods"], d["chunk"] = tuple(d["methods"]), tuple(d["chunk"])
        return cls(**d)


def steps_per_cell(spec: AtlasSpec, method: str) -> float:
    """Compiled member-steps one cell costs at the finest step of the grid (an upper bound)."""
    from .theory import fastest_period

    if spec.kind == "chaos":
        return 2.0 * spec.duration / spec.step
    if spec.y.name == "dt":
        finest = min(spec.y.start, spec.y.stop)
        span = spec.periods * fastest_period(spec) if spec.kind == "stability" else spec.duration
        return span / finest
    # adaptive: about 2 rtol^(-1/p) steps per fastest period (p the method's order, at most 8:
    # Taylor's rule picks higher orders only where they pay), and a reference run beside it
    rtol = min(spec.y.start, spec.y.stop)
    order = min(get_method(method).order, 8)
    return 2.0 * spec.duration / fastest_period(spec) * 2.0 * rtol ** (-1.0 / order)


def estimated_steps(spec: AtlasSpec) -> float:
    """The compiled member-steps the whole atlas takes (a float: it may be huge or infinite),
    reckoned as ``mechviz simulate`` reckons a run (``Simulation.estimated_steps``): a fixed step
    takes ``span / dt`` steps per cell and row (stability: ``periods`` of the motion's shortest
    period at the largest amplitude; chaos: ``duration`` for the start and its twin); an adaptive
    method ``2 rtol^(-1/order)`` steps per shortest period; a map measured against a tight DOP853
    run (accuracy, where the system has no exact solution) adds that run, once per chunk."""
    from ..integrators import get_method
    from ..simulation import REFERENCE_TOL

    cells = spec.y.n * spec.x.n
    if spec.kind == "chaos":
        return float(len(spec.methods) * cells * 2.0 * (spec.duration / spec.step))
    with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
        period = fastest_period_of(spec)
        ys = spec.y.values()
        total = 0.0
        for name in spec.methods:
            m = get_method(name)
            if spec.kind == "stability":
                total += float(np.sum(spec.periods * period / ys)) * spec.x.n
            elif m.adaptive:
                per = sum(m.steps_per_period(float(r)) for r in ys)
                total += spec.duration / period * per * spec.x.n
            else:
                total += float(np.sum(spec.duration / ys)) * spec.x.n
        if spec.kind == "accuracy":
            system = spec.make_system()
            from .theory import start_states

            amps = np.array([max(abs(spec.x.start), abs(spec.x.stop))])
            if not system.has_exact(start_states(system, amps)):
                ref = spec.duration / period * get_method("dop853").steps_per_period(REFERENCE_TOL)
                # each chunk runs it for its own columns: every column once per row of chunks
                total += ref * spec.x.n * spec.chunk_grid[0] * spec.chunk_grid[1]
    return float(total) if math.isfinite(total) else math.inf


def fastest_period_of(spec: AtlasSpec) -> float:
    """:func:`.theory.fastest_period`, or NaN where the parameters leave it unrepresentable."""
    from .theory import fastest_period

    try:
        with np.errstate(all="ignore"):
            return float(fastest_period(spec))
    except (ArithmeticError, ValueError):
        return math.nan


def chunk_shape_for(spec: AtlasSpec) -> tuple[int, int]:
    """(rows, columns) worth about :data:`CHUNK_SECONDS` on one core: whole rows of the grid when
    they fit (a chunk of a stability or accuracy map shares one step size per row), else part of
    one row."""
    worst = max(get_method(m).step_cost_ns * steps_per_cell(spec, m) for m in spec.methods)
    cells = max(1, int(CHUNK_SECONDS * 1e9 / max(worst, 1.0)))
    if cells >= spec.x.n:
        return (max(1, min(spec.y.n, cells // spec.x.n)), spec.x.n)
    return (1, cells)


def grid_values(spec: AtlasSpec) -> dict[str, np.ndarray]:
    return {spec.y.name: spec.y.values(), spec.x.name: spec.x.values()}


def ceil_div(a: float, b: float) -> int:
    return int(math.ceil(a / b - 1e-9))
