"""The exhibit layer shared by the three scenes: usable with or without the GUI.

An exhibit owns the :class:`dynamics.Simulation` (s) of one system, the scene nodes that show it,
and the short history its charts and readouts need. It knows nothing of integration details: it
asks :mod:`dynamics` for states and draws them. Every exhibit has

- ``config``: a frozen dataclass (``dataclasses.replace`` it, or pass ``apply({"op": "set", ...})``),
- ``advance(sim_seconds, measure=True)``: one compiled ``dynamics`` call per simulation (a
  blow-up pauses the exhibit and queues a message in ``events`` instead of raising); ``measure``
  also samples the energy and error (a chart point) and checks them for divergence,
- ``draw()``: handle assignments only; the caller wraps ``server.atomic()``,
- ``apply(command)``: ``{"op": "reset"}``, ``{"op": "set", field: value, ...}`` and the exhibit's
  own operations; an invalid value raises ``ValueError`` naming the field and changes nothing,
- ``state`` (the current state, cheap: what ``draw()`` uses), ``sample`` (the current
  :class:`dynamics.Sample` with energies and errors, computed on demand), ``t``, ``paused``,
  ``failure``, ``readout()`` (markdown), ``chart_data()`` (for the energy/error chart) and
  ``camera``,
- ``revision``: a counter bumped by every ``advance``, ``apply``, ``set`` and ``reset``; while it
  is unchanged, ``draw()`` and ``readout()`` would show the same thing (the app skips them).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from typing import Any, ClassVar

import numpy as np

import dynamics

# |E - E0| / |E0| beyond this counts as a blow-up even while the state is still finite.
DIVERGED = 24.0
LOG_FLOOR = -17.0  # log10 of an error that is exactly zero


def log10_abs(x) -> float:
    v = float(np.abs(x).max()) if x is not None else 0.0
    return math.log10(v) if v > 10.0**LOG_FLOOR else LOG_FLOOR


def make_simulation(system, method: str, dt: float, rtol: float, state, *, reference="auto"):
    """A :class:`dynamics.Simulation` with ``dt`` or ``rtol`` as the method needs."""
    m = dynamics.get_method(method)
    kwargs: dict[str, Any] = {}
    if m.adaptive:
        kwargs["rtol"] = rtol
    elif m.backend != "exact":
        kwargs["dt"] = dt
    return dynamics.Simulation(system, m.name, state=state, reference=reference, **kwargs)


def check_method(system_name: str, method: str | None, field: str = "method") -> None:
    if method is None:
        return
    names = [m.name for m in dynamics.methods_for(system_name)]
    if method not in names:
        raise ValueError(
            f"{field} must be one of {', '.join(names)} for {system_name}; got {method!r}"
        )


def positive(field: str, value) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{field} must be a number, got {value!r}") from None
    if not math.isfinite(x) or x <= 0.0:
        raise ValueError(f"{field} must be positive and finite, got {value!r}")
    return x


def fmt(x: float, digits: int = 4) -> str:
    return f"{x:.{digits}g}"


class History:
    """Bounded per-frame samples for the charts: ``t`` and named series (the last ``maxlen``).

    Stored in one preallocated ring buffer written twice (at ``i`` and ``i + maxlen``), so the
    newest ``maxlen`` samples are always one contiguous slice: adding a sample allocates
    nothing and :meth:`arrays` copies one block. ``count`` grows with every sample added and
    is reset by :meth:`clear` (with ``version``, it tells a reader whether anything changed).
    """

    def __init__(self, names: tuple[str, ...], maxlen: int = 600) -> None:
        self.names = tuple(names)
        self.maxlen = int(maxlen)
        self._buf = np.full((1 + len(self.names), 2 * self.maxlen), math.nan)
        self._i = 0  # where the next sample goes (mod maxlen)
        self._n = 0  # samples held (<= maxlen)
        self.count = 0
        self.version = 0  # changes on every add and clear

    def __len__(self) -> int:
        return self._n

    def clear(self) -> None:
        self._i = self._n = self.count = 0
        self.version += 1

    def add(self, t: float, **values: float) -> None:
        col = [t]
        col += [values.get(n, math.nan) for n in self.names]
        i, m = self._i, self.maxlen
        self._buf[:, i] = col
        self._buf[:, i + m] = col
        self._i = (i + 1) % m
        self._n = min(self._n + 1, m)
        self.count += 1
        self.version += 1

    @property
    def t(self) -> np.ndarray:
        return self.arrays()[0]

    def arrays(self) -> tuple[np.ndarray, ...]:
        """``(t, *series)`` oldest first, as fresh arrays."""
        end = self._i + self.maxlen
        block = self._buf[:, end - self._n : end].copy()
        return tuple(block)


class Exhibit:
    """Base class: subclasses define ``Config``, ``key``, ``title``, ``system_name`` and the
    hooks ``_build`` (scene nodes, once), ``_start`` (simulations from the config),
    ``_after_advance`` (measurements), ``draw``, ``readout``, ``_apply_op`` (own operations)."""

    key: ClassVar[str] = ""
    title: ClassVar[str] = ""
    Config: ClassVar[type]
    chart_series: ClassVar[tuple[str, ...]] = ("energy", "error")

    def __init__(
        self, server, config=None, *, origin=(0.0, 0.0, 0.0), history_len: int = 600
    ) -> None:
        self.server = server
        self.scene = server.scene
        self.origin = np.asarray(origin, dtype=float)
        self.config = config if config is not None else self.Config.from_defaults()
        self.config.validate()
        self.root = f"/{self.key}"
        self.paused = False
        self.failure: str | None = None
        self.events: list[tuple[str, str]] = []  # (title, body) for notifications
        self.revision = 0  # bumped by anything that may change what draw() or readout() show
        self.history = History(self.chart_series, maxlen=max(2, int(history_len)))
        self.t_offset = 0.0
        self.sim: dynamics.Simulation | None = None
        self.compare: dynamics.Simulation | None = None
        self._sample: dynamics.Sample | None = None
        self._compare_sample: dynamics.Sample | None = None
        self._build()
        self._start()

    # ------------------------------------------------------------------ state
    @property
    def t(self) -> float:
        return self.t_offset + (self.sim.t if self.sim is not None else 0.0)

    @property
    def state(self) -> np.ndarray:
        """The main run's current state (d,): what drawing needs, without the energies and
        errors of :attr:`sample` (a view, valid until the next advance)."""
        return self.sim.state[0]

    @property
    def compare_state(self) -> np.ndarray | None:
        return None if self.compare is None else self.compare.state[0]

    @property
    def sample(self) -> dynamics.Sample:
        if self._sample is None:
            self._sample = self.sim.sample()
        return self._sample

    @property
    def compare_sample(self) -> dynamics.Sample | None:
        if self.compare is None:
            return None
        if self._compare_sample is None:
            self._compare_sample = self.compare.sample()
        return self._compare_sample

    def simulations(self) -> list[dynamics.Simulation]:
        return [s for s in (self.sim, self.compare) if s is not None]

    # ------------------------------------------------------------------ stepping
    def advance(self, sim_seconds: float, *, measure: bool = True) -> None:
        """Advance every simulation of the exhibit by ``sim_seconds`` (no-op while paused).

        ``measure``: also sample the energy and error (a chart point, and the divergence check).
        The live app measures each exhibit on every third frame only, staggered: a
        :class:`dynamics.Sample` costs more than the step itself and the chart needs no more.
        A run that fails is always measured."""
        if self.paused or sim_seconds <= 0.0:
            return
        self.revision += 1
        for sim in self.simulations() + self._extra_simulations():
            try:
                sim.advance(sim_seconds)
            except dynamics.IntegrationError as exc:
                self._fail(f"{exc}. Paused; press Reset (or pick another method or step).")
                break
        self._sample = None
        self._compare_sample = None
        if measure or self.paused:
            if not self.paused:
                self._check_divergence()
            self._record()
        self._after_advance()

    def _extra_simulations(self) -> list[dynamics.Simulation]:
        return []

    def _check_divergence(self) -> None:
        for label, smp, sim in (
            ("", self.sample, self.sim),
            ("comparison ", self.compare_sample, self.compare),
        ):
            if smp is None:
                continue
            grown = float(np.max(np.abs(smp.energy_error)))
            if not math.isfinite(grown) or grown > DIVERGED:
                self._fail(
                    f"{label}method {sim.method.name} with {sim.step_label()} diverged: the energy "
                    f"changed by a factor {1 + grown:.3g} by t = {self.t:.4g} s. Paused; press Reset "
                    "(or pick another method or a smaller step)."
                )
                return

    def stability_text(self) -> str:
        """Where the running method's step stops being stable, for the step-size control
        (markdown): the largest stable dt from :func:`dynamics.stability.stability_limit` for
        the current parameters (the free body's at its current state), and whether the chosen
        dt is inside it. Called when the method, step or parameters change, not per frame."""
        from dynamics import stability

        sim = self.sim
        m = sim.method
        if m.adaptive:
            return f"<small>{m.name}: adaptive, the step follows rtol; no fixed limit</small>"
        if m.backend == "exact":
            return "<small>exact flow: any step</small>"
        limit = stability.stability_limit(m.name, sim.system, self.state)
        reason = stability.REASONS.get(m.name, "")
        if limit is None:
            return f"<small>Stable at any dt ({reason}).</small>"
        if limit == 0.0:
            return f"<small>⚠ Unstable at every dt: {reason}.</small>"
        omega = stability.fastest_frequency(sim.system, self.state)
        where = (
            f"dt = {fmt(sim.dt)} s is {sim.dt / limit:.1%} of it"
            if sim.dt <= limit
            else f"⚠ dt = {fmt(sim.dt)} s is beyond it: expect the run to blow up"
        )
        return (
            f"<small>**Stability limit dt < {fmt(limit)} s** (ω_max = {fmt(omega)} rad/s; "
            f"{reason}); {where}.</small>"
        )

    def _fail(self, message: str) -> None:
        self.paused = True
        self.failure = message
        self.events.append((f"{self.title}: integration stopped", message))

    def _record(self) -> None:
        smp = self.sample
        values = {"energy": log10_abs(smp.energy_error), "error": log10_abs(smp.error)}
        c = self.compare_sample
        if c is not None:
            values["energy_compare"] = log10_abs(c.energy_error)
            values["error_compare"] = log10_abs(c.error)
        self.history.add(self.t, **values)

    def chart_data(self) -> tuple[np.ndarray, ...]:
        """``(t, log10|dE/E0|, log10 error, ...)`` of the last samples (see ``chart_series``)."""
        return self.history.arrays()

    # ------------------------------------------------------------------ commands
    def apply(self, command: Mapping[str, Any] | str) -> str:
        """Apply one command; returns a short description. ``ValueError`` leaves all untouched."""
        self.revision += 1
        if isinstance(command, str):
            command = {"op": command}
        command = dict(command)
        op = command.pop("op", None)
        if op == "reset":
            self.reset()
            return f"{self.title}: reset"
        if op == "set":
            return self.set(**command)
        return self._apply_op(op, command)

    def _apply_op(self, op, args: dict) -> str:
        raise ValueError(f"op must be one of reset, set{self._ops_hint()}; got {op!r}")

    def _ops_hint(self) -> str:
        return ""

    def set(self, **changes) -> str:
        """Change config fields (validated first; the running simulation is kept on error)."""
        self.revision += 1
        fields = {f.name for f in dataclasses.fields(self.config)}
        for name in changes:
            if name not in fields:
                raise ValueError(
                    f"{name} is not a setting of {self.key}; choose from {', '.join(sorted(fields))}"
                )
        if "params" in changes:
            params = dict(self.config.params)
            for k, v in dict(changes["params"]).items():
                if k not in params:
                    raise ValueError(
                        f"{k} is not a parameter of {self.key}; choose from {', '.join(params)}"
                    )
                params[k] = v
            changes["params"] = params
        new = dataclasses.replace(self.config, **changes)
        if new == self.config:
            return f"{self.title}: unchanged"
        new.validate()
        # _start() builds every simulation before it touches the scene or the state, and
        # replaces (never mutates) the old ones, so restoring the attributes undoes it.
        snapshot = dict(self.__dict__)
        self.config = new
        try:
            self._start()
        except (ValueError, TypeError, ZeroDivisionError):
            self.__dict__.clear()
            self.__dict__.update(snapshot)
            raise
        return f"{self.title}: " + ", ".join(f"{k} = {v}" for k, v in changes.items())

    def reset(self) -> None:
        self.revision += 1
        self._start()

    def _reset_common(self) -> None:
        self.paused = False
        self.failure = None
        self.t_offset = 0.0
        self._sample = None
        self._compare_sample = None
        self.history.clear()

    # ------------------------------------------------------------------ subclass hooks
    def _build(self) -> None:  # pragma: no cover - abstract
        raise NotImplementedError

    def _start(self) -> None:  # pragma: no cover - abstract
        raise NotImplementedError

    def _after_advance(self) -> None:
        pass

    def draw(self) -> None:  # pragma: no cover - abstract
        raise NotImplementedError

    def readout(self) -> str:  # pragma: no cover - abstract
        raise NotImplementedError

    @property
    def camera(self) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
        raise NotImplementedError

    def world(self, local) -> np.ndarray:
        return self.origin + np.asarray(local, dtype=float)

    def method_line(self, sim: dynamics.Simulation) -> str:
        return f"`{sim.method.name}` ({sim.step_label()})"
