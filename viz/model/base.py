"""What the three exhibits' models share: the settings base class and the headless model of an
exhibit (its sample buffers are in :mod:`mechviz.viz.model.history`).

An exhibit's *model* owns the :class:`mechviz.dynamics.Simulation` (s) of one system, its events, the
samples its readouts and charts need, and the figures measured from them; it imports no viser and
draws nothing. A view (:mod:`mechviz.viz.scene`) is built over a model, observes it and draws
what it reads there; the recorder, the notebook and the tests run the model alone. Every model has

- ``config``: a frozen, validated settings dataclass (:class:`ExhibitConfig`); change it with
  ``apply(Set(fields={field: value, ...}))``,
- ``advance(sim_seconds)`` / ``advance_to(t)``: one compiled ``dynamics`` call per simulation (a
  blow-up pauses the exhibit and queues a message in ``events`` instead of raising);
  ``measure=True`` also samples the energy and error (a chart point) and checks for divergence,
- ``apply(command)``: ``Reset()``, ``Set(...)``, the exhibit's own (``Kick(dv)``), typed values of
  :mod:`mechviz.viz.model.commands`; an invalid one raises ``ValueError`` naming it, changing nothing,
- ``state``, ``sample``, ``t``, ``paused``, ``failure``, ``measured()`` (the figures measured
  from the motion, by name, from :mod:`mechviz.dynamics.measure`), ``chart_data()``, ``runs()`` (the
  simulations a recording traces, by role),
- ``observe(callback)``: ``callback(model)`` after every change (:mod:`.observed`); ``revision``
  counts them; ``on(event, callback)`` for what a view must act on (a new start, a rewind),
- ``plot_variables(config)``, ``plot_curves(config, x, y, samples)``, ``pictures(config)``
  and ``default_plot(config)``: what a plot of any variable against any other and a recording's
  pictures draw (:mod:`mechviz.viz.model.plot`); ``plot_samples()`` the main run's samples over the
  chart window.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from mechviz import dynamics
from mechviz.dynamics import params as _v

from .commands import Command, Reset, Set, refused
from .history import History, LongHistory, Motion, Ring  # noqa: F401  (re-exported)
from .hooks import SystemHooks
from .plot import Curve, Samples, Variable, common_variables
from .rewind import Rewinding

# |E - E0| / |E0| beyond this counts as a blow-up even while the state is still finite.
DIVERGED = 24.0
# Beyond this |dE/E0|, a run whose drawing leaves its exhibit (``_outside``) has diverged: it left
# because the method is wrong, not because of the physics (a kick moves E0 with it).
ESCAPED = 0.1
LOG_FLOOR = -17.0  # log10 of an error that is exactly zero
PAUSED_HINT = "Paused; press Reset (or pick another method or a smaller step)."


def log10_abs(x) -> float:
    v = float(np.abs(x).max()) if x is not None else 0.0
    return math.log10(v) if v > 10.0**LOG_FLOOR else LOG_FLOOR


def fmt(x, digits: int = 4) -> str:
    """A number to ``digits`` significant digits, "—" for ``None``; a
    :class:`mechviz.dynamics.measure.Estimate` shows its value or "not resolved (reason)"."""
    if hasattr(x, "text"):
        return x.text(digits)
    return "—" if x is None else f"{x:.{digits}g}"


positive = _v.positive
finite_numbers = _v.numbers


# =========================================================================== settings
@dataclass(frozen=True)
class ExhibitConfig:
    """Settings every exhibit has; subclasses add their own and ``_validate`` them.

    ``method`` is integrated with ``dt`` [s] if it takes fixed steps, ``rtol`` if adaptive (the
    method picks, :meth:`mechviz.dynamics.Method.step_options`). ``params`` are the system's physical
    parameters by name (its ``Params`` dataclass checks them). Validated on construction, so an
    instance always holds settings a run can start from."""

    system_name: ClassVar[str]  # the driver's name of the system (:data:`mechviz.dynamics.SYSTEMS`)
    spec: ClassVar[dynamics.SystemSpec]  # the system's description: parameters, start, step
    demo_initial_keys: ClassVar[frozenset[str]] = frozenset()  # a demo's [initial] keys

    method: str = "rk4"
    dt: float = 1 / 60
    rtol: float = 1e-9
    params: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.physics()  # SettingError naming the parameter
        names = [m.name for m in dynamics.methods_for(dynamics.SYSTEMS[self.system_name])]
        for fld in ("method", *(["compare_method"] if hasattr(self, "compare_method") else [])):
            m = getattr(self, fld)
            if m is not None and m not in names:
                raise dynamics.SettingError(
                    fld, f"{fld} must be one of {', '.join(names)}; got {m!r}"
                )
        # the step settings every run takes, and those of a comparison run where there is one,
        # by the rules of dynamics.steps
        for name in ("dt", "compare_dt"):
            if getattr(self, name, None) is not None:
                _v.positive(name, getattr(self, name))
        for name in ("rtol", "compare_rtol"):
            if getattr(self, name, None) is not None:
                _v.below_one(name, getattr(self, name))
        cap = getattr(self, "trail_cap", 2)
        if not (isinstance(cap, int) and cap >= 2):
            raise dynamics.SettingError(
                "trail_cap", f"trail_cap must be a whole number of at least 2, got {cap!r}"
            )
        self._validate()

    def _validate(self) -> None:
        pass

    def physics(self):
        """The validated parameter dataclass of :mod:`dynamics` for ``params``
        (:meth:`mechviz.dynamics.SystemSpec.parameters`)."""
        return self.spec.parameters(self.params)


# =========================================================================== the exhibit
class ExhibitModel(Rewinding, SystemHooks):
    """Base class: subclasses define ``Config`` (``key`` and ``chart_series`` follow from it),
    ``title``, ``name`` and the hooks
    ``_start`` (simulations from the config), ``_observe`` (record the motion samples after each
    advance), ``measured`` and ``_apply_command`` (its own ``commands``). ``_start`` ends with
    ``_started()``, which announces ``"started"`` (:mod:`.observed`): a view builds its picture
    of the new runs then."""

    key: ClassVar[str] = ""
    title: ClassVar[str] = ""
    name: ClassVar[str] = ""  # one word: its tab and camera preset
    Config: ClassVar[type[ExhibitConfig]]
    chart_series: ClassVar[tuple[str, ...]] = ("energy", "error")
    # settings that change only how the exhibit is drawn: applied without touching the runs
    view_fields: ClassVar[frozenset[str]] = frozenset()
    # settings that only choose the start: applied as a jump of the running simulations to the
    # new start, so the clock and the work counters go on (``_jump_to_start``)
    start_fields: ClassVar[frozenset[str]] = frozenset()
    # settings applied to the running exhibit by ``_apply_live`` (a beam added to the run):
    # the clock, the runs and what was given them (a kick) go on
    live_fields: ClassVar[frozenset[str]] = frozenset()
    # the command classes ``apply`` takes; an exhibit's own are handled by its _apply_command
    commands: ClassVar[tuple[type, ...]] = (Reset, Set)

    def __init_subclass__(cls, **kwargs) -> None:
        super().__init_subclass__(**kwargs)
        if "Config" in cls.__dict__:
            # an exhibit is known by its system's name; one with a comparison run charts it too
            cls.key = cls.Config.spec.name
            if any(f.name == "compare_method" for f in dataclasses.fields(cls.Config)):
                cls.chart_series = ("energy", "error", "energy_compare", "error_compare")

    def __init__(self, config=None, *, history_len: int = 600, start: bool = True) -> None:
        self.config = config if config is not None else self.Config()
        self.paused = False
        self.failure: str | None = None  # why the run stopped, in words (no viewer advice)
        self.failure_error: dynamics.IntegrationError | None = None  # the same, as an error
        self.events: list[tuple[str, str]] = []  # (title, body) for notifications
        self.revision = 0
        self.steps_last_advance = 0  # steps the main run took in the last advance
        self.history = History(self.chart_series, maxlen=history_len)
        self.trace = Ring((1,), history_len)  # sized for the run's state in _reset_common
        self.chart_spacing = 0.0  # simulated seconds between chart points (0: every sample)
        self.long_history = LongHistory(self.chart_series)  # what every window draws on
        self.chart_window: float | None = None  # s shown by chart_data (None: the last points)
        self._chart_t = 0.0  # time of the newest chart point
        self.sim: dynamics.Simulation | None = None
        self.compare: dynamics.Simulation | None = None
        self._sample: dynamics.Sample | None = None
        self._compare_sample: dynamics.Sample | None = None
        self._kept: dict[str, Any] = {}  # the last resolved figure of each name (measured())
        # the box [m] the runs are drawn in, about the exhibit's origin (None: anywhere): a run
        # whose drawing leaves it has diverged (``_outside``); a view drawn beside others sets it
        self.box: tuple[np.ndarray, np.ndarray] | None = None
        if start:
            self._start()

    # ------------------------------------------------------------------ state
    @property
    def t(self) -> float:
        return self.sim.t if self.sim is not None else 0.0

    @property
    def state(self) -> np.ndarray:
        """The main run's current state (d,): what drawing needs (a view until the next advance)."""
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
        return [s for s in (self.sim, self.compare, *self._extra_simulations()) if s is not None]

    def runs(self) -> dict[str, dynamics.Simulation]:
        """The runs a recording traces: ``"main"`` and, if there is one, ``"compare"``."""
        out = {"main": self.sim}
        if self.compare is not None:
            out["compare"] = self.compare
        return out

    def _make_simulation(self, system, method: str, state, *, dt=None, rtol=None, reference="auto"):
        """A :class:`mechviz.dynamics.Simulation` of ``method`` with the step setting it takes (``dt``
        and ``rtol`` default to the config's)."""
        c = self.config
        m = dynamics.get_method(method)
        opts = m.step_options(c.dt if dt is None else dt, c.rtol if rtol is None else rtol)
        return dynamics.Simulation(system, m, state=state, reference=reference, **opts)

    def _make_runs(self) -> tuple[dynamics.Simulation, dynamics.Simulation | None]:
        """The main run of ``config.method`` and, if the config names one, the comparison run
        of ``compare_method`` with its own ``compare_dt`` / ``compare_rtol`` (else the main
        run's), both of the config's system from its ``initial_state()``."""
        c = self.config
        system = dynamics.SYSTEMS[self.system_for(c)](c.physics())
        s0 = c.initial_state()
        sim = self._make_simulation(system, c.method, s0)
        cmp_ = None
        if getattr(c, "compare_method", None):
            cmp_ = self._make_simulation(
                system, c.compare_method, s0, dt=c.compare_dt, rtol=c.compare_rtol
            )
        return sim, cmp_

    # ------------------------------------------------------------------ stepping
    def advance(
        self, sim_seconds: float, *, measure: bool = True, shown: float | None = None
    ) -> None:
        """Advance every simulation by ``sim_seconds`` (no-op while paused; scrubbed back, the
        run goes on from the moment shown, :mod:`mechviz.viz.model.rewind`). ``measure``: also sample
        the energy and error (a chart point, and the divergence check); the live app measures
        each exhibit on every third frame, as a sample costs more than the step. ``shown``: the
        seconds of the show this advance stands for (default ``sim_seconds``, as at 1x)."""
        if self.scrubbed is not None and sim_seconds > 0.0:
            self.resume_here()
        if self.paused or sim_seconds <= 0.0:
            return
        shown = sim_seconds if shown is None else shown
        self._advance(lambda sim: sim.advance(sim_seconds), measure, shown)

    def advance_to(self, t: float, *, measure: bool = True) -> None:
        """Advance every simulation to time ``t`` [s] (fixed steps: the last step at or before)."""
        if self.scrubbed is not None and t > self.t:
            self.resume_here()
        if self.paused or t <= self.t:
            return
        self._advance(lambda sim: sim.advance_to(max(t, sim.t)), measure, t - self.t)

    def _advance(self, move, measure: bool, shown: float) -> None:
        self.changed()
        steps_before = self.sim.steps
        for sim in self.simulations():
            try:
                move(sim)
            except dynamics.IntegrationError as exc:
                self._fail(exc)
                break
        self.steps_last_advance = self.sim.steps - steps_before
        self._sample = None
        self._compare_sample = None
        if measure or self.paused:
            if not self.paused:
                self._check_divergence()
            self._record()
        self._observe()
        self._rewind_keep(shown)

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
            where = self._outside(sim) if grown > ESCAPED else None
            if not math.isfinite(grown) or grown > DIVERGED or where:
                reason = f"{label}run diverged: the energy changed by a factor {1 + grown:.3g}"
                if where:
                    reason = f"{label}run diverged: {where}, its energy changed by a factor {1 + grown:.3g}"
                self._fail(
                    dynamics.IntegrationError(sim.method.name, sim.step_label(), sim.t, reason)
                )
                return

    def confine(self, box: tuple[np.ndarray, np.ndarray] | None) -> None:
        """Count a run whose drawing leaves ``box`` (low, high corners [m] about the exhibit's
        origin; ``None``: no box) as diverged: a view that draws the exhibit beside others
        gives its box, as a run's leaving it means the method is wrong, not the physics."""
        self.box = None if box is None else tuple(np.asarray(c, float) for c in box)

    def _outside(self, sim: dynamics.Simulation) -> str | None:
        """What of ``sim``'s drawing lies outside :attr:`box`, in words (``None``: nothing, no
        box, or a model that does not say)."""
        return None

    def _fail(self, error: dynamics.IntegrationError) -> None:
        self.paused = True
        self.failure = str(error)
        self.failure_error = error
        self.events.append((f"{self.title}: integration stopped", f"{error}. {PAUSED_HINT}"))

    def set_chart_window(self, seconds: float) -> None:
        """Spread the chart's points evenly over the last ``seconds`` of simulated time (the
        number of points stays the same), taken from the long history (ten minutes,
        :mod:`mechviz.viz.model.history`): the chart keeps what it showed; the trace starts afresh."""
        self.chart_spacing = float(seconds) / self.history.maxlen
        self.chart_window = float(seconds)
        self.history.clear()
        self.trace.clear()
        self.changed()

    def _record(self) -> None:
        self.long_history.keep(self.t, self._chart_values(), force=self.paused)
        self._record_window()

    def _chart_values(self) -> dict[str, float]:
        smp = self.sample
        values = {"energy": log10_abs(smp.energy_error), "error": log10_abs(smp.error)}
        c = self.compare_sample
        if c is not None:
            values["energy_compare"] = log10_abs(c.energy_error)
            values["error_compare"] = log10_abs(c.error)
        return values

    def _record_window(self) -> None:
        if len(self.history) and self.t - self._chart_t < self.chart_spacing and not self.paused:
            return  # not yet time for the next point of a long window
        self._chart_t = self.t
        smp = self.sample
        self.history.add(self.t, **self._chart_values())
        err = smp.error[0] if smp.error is not None else math.nan
        self.trace.add([self.t, *smp.state[0], smp.energy[0], smp.energy_error[0], err])

    def chart_data(self) -> tuple[np.ndarray, ...]:
        """``(t, log10|dE/E0|, log10 error, ...)`` of the last samples (see ``chart_series``);
        with a ``chart_window`` set, at most ``history.maxlen`` points evenly spread over that
        much of the long history."""
        if self.chart_window is None or not len(self.long_history):
            data = self.history.arrays()
        else:
            data = self.long_history.window(self.chart_window, self.history.maxlen)
        if self.scrubbed is not None:  # scrubbed back: the charts end at the moment shown
            keep = data[0] <= self.t + 1e-12
            data = tuple(a[keep] for a in data)
            if not data[0].size or data[0][-1] < self.t - 1e-12:
                # the kept points are spaced (a long window's even more): the last one at the
                # moment shown is that moment's own sample
                values = self._chart_values()
                now = (self.t, *(values.get(n, math.nan) for n in self.history.names))
                data = tuple(np.append(a, v) for a, v in zip(data, now, strict=True))
        return data

    def stability_text(self) -> str:
        """Where the running method's step stops being stable (markdown, for the step control):
        :func:`mechviz.viz.model.stability_note.stability_note` of the main run now."""
        from .stability_note import stability_note

        return stability_note(self.sim, self.state)

    # ------------------------------------------------------------------ commands
    def apply(self, command: Command) -> str:
        """Apply one command (:mod:`mechviz.viz.model.commands`), returning a short description; one
        it does not take or an invalid value raises ``ValueError`` naming it, changing nothing."""
        if not isinstance(command, self.commands):
            raise refused(self.key, self.commands, command)
        if self.scrubbed is not None:  # a change goes on from the moment shown
            self.resume_here()
        done = self._apply_command(command)
        self.changed()  # after: a refused command changed nothing, so nothing to draw anew
        return done

    def _apply_command(self, command: Command) -> str:
        """Reset and Set; an exhibit's override handles its own commands and passes on the rest."""
        match command:
            case Reset():
                self.reset()
                return f"{self.title}: reset"
            case Set(fields=fields, params=params):
                return self.set(**fields, **({"params": params} if params else {}))
        raise refused(self.key, self.commands, command)  # in ``commands`` but handled nowhere

    def set(self, **changes) -> str:
        """Change config fields (validated first; the run is kept on error); ``apply`` notifies."""
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
        try:
            new = dataclasses.replace(self.config, **changes)
        except TypeError as exc:  # a value of the wrong kind for a comparison inside validation
            raise ValueError(str(exc)) from None
        if new == self.config:
            return f"{self.title}: unchanged"
        old = self.config
        changed = {
            f.name for f in dataclasses.fields(new) if getattr(new, f.name) != getattr(old, f.name)
        }
        described = f"{self.title}: " + ", ".join(f"{k} = {v}" for k, v in changes.items())
        if changed <= self.view_fields:  # how it is drawn, not what moves: the run goes on
            self.config = new
            return described
        if changed <= self.view_fields | self.live_fields:  # applied to the run as it goes
            self.config = new
            try:
                self._apply_live(changed & self.live_fields)
            except (ValueError, TypeError):
                self.config = old
                raise
            return described
        if changed <= self.start_fields:  # a new start, applied now: time and counts go on
            self.config = new
            try:
                self._jump_to_start()
            except (ValueError, TypeError):
                self.config = old
                raise
            return described
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
        return described

    def _apply_live(self, changed: set[str]) -> None:
        """Apply the ``live_fields`` in ``changed`` (already in the config) to the run."""
        raise NotImplementedError

    def _jump_to_start(self) -> None:
        """Put every run at the configured start without restarting it
        (:meth:`mechviz.dynamics.Simulation.jump`), for exhibits that list ``start_fields``."""
        raise NotImplementedError

    def reset(self) -> None:
        self.changed()
        self._start()

    def _reset_common(self) -> None:
        self.paused = False
        self.failure = None
        self.failure_error = None
        self._sample = None
        self._compare_sample = None
        self.history.clear()
        self.long_history.clear()
        self.forget_figures()
        d = self.sim.state.shape[1]
        if self.trace.shape != (d + 4,):  # t, the state, energy, energy error, error
            self.trace = Ring((d + 4,), self.history.maxlen)
        self.trace.clear()
        self._rewind_start()

    # ------------------------------------------------------------------ any variable against any other
    @classmethod
    def plot_variables(cls, config) -> dict[str, Variable]:
        """The quantities the exhibit can plot for ``config``, by name (:mod:`mechviz.viz.model.plot`):
        at least time, the state, energy and the errors."""
        system = dynamics.SYSTEMS[cls.system_for(config)]
        return {**common_variables(system.state_labels), **cls.quantities(config)}

    @classmethod
    def quantities(cls, config) -> dict[str, Variable]:
        """The system's own quantities beyond the state, as its description names them
        (:attr:`mechviz.dynamics.systems.Cyclotron.quantity_labels` and the like)."""
        system = dynamics.SYSTEMS[cls.system_for(config)](config.physics())
        return {
            name: Variable(label, lambda s, name=name: system.quantities(s.states)[name])
            for name, label in system.quantity_labels.items()
        }

    @classmethod
    def system_for(cls, config) -> str:
        """The name of the :data:`mechviz.dynamics.SYSTEMS` entry a run of ``config`` integrates."""
        return config.system_name

    @classmethod
    def plot_curves(cls, config, x: str, y: str, samples: Samples) -> list[Curve]:
        """The exact curves that go with ``y`` against ``x`` (none by default)."""
        return []

    @classmethod
    def pictures(cls, config) -> tuple[tuple[str, str], ...]:
        """The pairs a recording draws in its PNG: the seed's own pictures of the system."""
        return ()

    @classmethod
    def default_plot(cls, config) -> tuple[str, str]:
        """The pair the panel's plot shows first: the first picture (else energy against t)."""
        return (cls.pictures(config) or (("t", "energy"),))[0]

    def plot_samples(self) -> Samples:
        """The main run's samples over the chart window (member 0 of an ensemble)."""
        d = self.sim.state.shape[1]
        return Samples.from_rows(self.trace.array(), d)

    # ------------------------------------------------------------------ subclass hooks
    def _start(self) -> None:  # pragma: no cover - abstract
        raise NotImplementedError

    def _started(self) -> None:
        """Called at the end of every ``_start``: announces it (a view resets what it draws)."""
        self.announce("started")

    def _observe(self) -> None:
        pass

    def measured(self) -> dict[str, Any]:
        """The figures measured from the motion, by name (``None``: not yet): ``_measure()``'s,
        where a figure no longer resolved (its samples slid on to a stretch that cannot tell,
        a growth that saturated) shows the last value it was measured at, until the motion
        changes (:meth:`forget_figures`: a new start, a jump, a kick)."""
        out = self._measure()
        for name, value in out.items():
            if isinstance(value, dynamics.measure.Estimate):
                if value:
                    self._kept[name] = value
                elif name in self._kept:
                    out[name] = self._kept[name]
        return out

    def forget_figures(self, *names: str) -> None:
        """The motion changed: the figures ``names`` (all if none given) are measured afresh."""
        for name in names or list(self._kept):
            self._kept.pop(name, None)

    def _measure(self) -> dict[str, Any]:  # the figures from the samples now, by name
        return {}

    @classmethod
    def recorded_figures(cls, config, tr) -> list[dict[str, Any]]:
        """The figures a recording of ``config`` reports, measured from its traces
        (:class:`mechviz.viz.model.traces.Traces`) against theory (:mod:`mechviz.viz.model.figures`)."""
        return []

    def method_line(self, sim: dynamics.Simulation) -> str:
        """The method and its step setting; for an adaptive main run also the steps it took over
        the last advance (a frame, live) and the length of the step it is in: the tolerance
        shows there."""
        line = f"`{sim.method.name}` ({sim.step_label()})"
        if sim is self.sim and sim.method.adaptive:
            # averaged over the run: a frame often ends inside one long step (0 steps then)
            rate = self.sample.steps / self.t if self.t > 0 else 0.0
            line += f", {rate:.3g} steps per simulated second"
            if sim.last_step is not None:
                line += f", h = {fmt(sim.last_step, 2)} s"
        return line

    def work_line(self) -> str:
        smp = self.sample
        lines = [f"\nSteps {smp.steps}; evaluations {smp.nfev}: {self.sim.method.counts}."]
        if self.failure:
            lines.append(f"\n**Paused:** {self.failure}. {PAUSED_HINT}")
        return "\n".join(lines)
