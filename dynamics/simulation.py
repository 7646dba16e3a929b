"""The simulation driver: advances any system with any method and reports what happened.

The driver owns time, the step size or tolerance, the evaluation and step counters and the
reference against which the error is measured: the exact solution where the system has one for this
initial state, otherwise a DOP853 run at ``rtol = 3e-15``, ``atol = 1e-17`` advanced in lock-step.
That reference's own error is measured, not assumed: a second DOP853 run at ten times its
tolerances (:data:`CHECK_TOL`) is advanced beside it, and their relative difference is the
reference's error bar (:meth:`Simulation.reference_error`; the looser run's error is the larger, so
the difference bounds the tight run's error from above). On the exact motions it stays below 5e-13
over 100 s; on a chaotic start it grows with the motion's Lyapunov exponent (a hoop at rest from
(1.3, -0.8) rad: 1e-11 at 30 s, 8e-9 at 60 s against a 30-digit integration), and an error against
the reference is a figure about the method only where it is well above that bar
(:data:`RESOLVED_FACTOR`). A user's adaptive run must be at least 100 times looser
(:data:`MIN_COMPARED_TOL`, ``1e-12``) to be compared with it; a tighter one reports no error rather
than a meaningless one. The viewer and the recorder stream exactly what :meth:`Simulation.sample`
returns.

The relative energy error is ``(E - E0) / (E0 - E_floor)``, where ``E_floor`` is the lowest
energy the system can have (``System.energy_floor()``): it measures the energy that moves, not
the arbitrary zero of a potential. Both ``E - E_floor`` and ``E0 - E_floor`` are the system's
own ``energy_above_floor`` (evaluated without cancellation), so the error resolves round-off
relative to the moving energy at any amplitude.

Compiled code runs in chunks of about :data:`CHUNK_SECONDS` each, so Ctrl-C (``KeyboardInterrupt``)
ends any run within a fraction of a second, leaving the simulation at the end of the last whole
chunk; :meth:`Simulation.estimated_steps` says beforehand how much work a run is.

Fixed-step methods always take steps of exactly ``dt``: :meth:`Simulation.advance_to` takes
the whole number of steps that fits and carries the remainder, so ``t`` is ``steps * dt``.
Adaptive methods land exactly on the requested time; the compiled ones (DOP853, Taylor's method)
by their dense output: their steps are not cut at the times asked for (nor at the chunks'
ends), the step that passes one is kept and evaluated there, and the next call goes on from its
end, so sampling a run does not change the steps it takes (:attr:`Simulation.last_step`). A
final time (``advance_to(t, final=True)``, the end of :meth:`Simulation.run`) is different:
DOP853 cuts its last step to end there and answers with the stepped end point, as scipy does.
"""

from __future__ import annotations

import math
import time

import numpy as np

from . import params as _v
from .aot import taylor_runner
from .integrators.base import IntegrationError, Method, integration_error, step_functions
from .integrators.codes import OK
from .integrators.taylor_carry import TaylorCarry
from .run_plan import compiled as _compiled
from .run_plan import plan as _plan
from .spec import all_finite, checked_state
from .steps import DEFAULT_RTOL, Step
from .systems import System

__all__ = [
    "DEFAULT_RTOL",
    "Sample",
    "Simulation",
    "Trajectory",
    "error_verdict",
    "reference_run",
]
from .results import (  # noqa: F401  (re-exported: the driver's results)
    CHECK_ATOL,
    CHECK_TOL,
    CHUNK_SECONDS,
    EXACT_FLOW,
    MIN_COMPARED_TOL,
    REFERENCE_ACCURACY,
    REFERENCE_ATOL,
    REFERENCE_METHOD,
    REFERENCE_RUN,
    REFERENCE_TOL,
    RESOLVED_FACTOR,
    Sample,
    Trajectory,
    error_verdict,
    reference_description,
)


class Simulation:
    """Advance ``system`` from ``state`` (d,) or (N, d) with ``method``.

    Parameters
    ----------
    system : a :mod:`mechviz.dynamics.systems` adapter.
    method : a name from :data:`mechviz.dynamics.integrators.METHODS` (``mechviz simulate --list-methods``).
    dt : step size [s] for fixed-step methods (must be > 0 and finite).
    rtol, atol : tolerances for adaptive methods (default ``1e-9`` and ``rtol``). ``atol`` is in
        the state's units: where a component is much smaller than 1 (a swing of 0.01 rad) it
        is held to ``atol``, not to ``rtol`` of itself, so its relative error exceeds ``rtol``
        by about the ratio of the two; give a smaller ``atol`` for such motions.
    step : the step control as one value (:mod:`mechviz.dynamics.steps`), instead of dt/rtol/atol.
    state : initial state(s); default the system's ``default_state()``.
    reference : measure the error against the exact solution, or a tight DOP853 run when there
        is none (``"auto"``; not for an adaptive run tighter than :data:`MIN_COMPARED_TOL`, see
        ``reference_note``); ``"exact"`` only where exact; ``None`` never.

    ``on_chunk``, if set to a callable, is called with the simulation after each chunk of
    compiled work (for progress displays).
    """

    on_chunk = None
    _chunk_steps = 4096  # per member; adapted to CHUNK_SECONDS as the run goes
    # What every run starts with, as class attributes: a run that never changes them (a solve
    # to one time) does not pay for setting them. Each is replaced on the instance when it
    # changes; all are immutable.
    t0 = 0.0  # time at which state0 holds (moves with a jump)
    t = 0.0  # time reached (fixed step: steps * dt)
    clock = 0.0  # time asked for; fixed-step runs carry clock - t to the next call
    steps = nfev = rejected = 0
    _start_energy: tuple[np.ndarray, np.ndarray] | None = None  # see _energies
    _exact_known: bool | None = None  # see _has_exact
    # the compiled adaptive method's kept steps (a TaylorCarry or an RKCarry, made on its
    # first call)
    _carry = None
    _taylor_h: float | None = None  # mean Taylor step of the last chunk [s]
    _runner = None  # what takes the Taylor steps (chosen on the first call)
    _reference: Simulation | None = None
    #: Why the error is not measured although a reference was asked for ("" otherwise).
    reference_note = ""

    def __init__(
        self,
        system: System,
        method: str | Method = "rk4",
        *,
        dt: float | None = None,
        rtol: float | None = None,
        atol: float | None = None,
        state: np.ndarray | None = None,
        reference: str | None = "auto",
        step: Step | None = None,
    ) -> None:
        plan = _plan(system, method, dt, rtol, atol, step)
        self.system, self.method, _, step, self.dt, self.rtol, self.atol, self.p = plan
        #: The step control in force (:mod:`mechviz.dynamics.steps`).
        self.step = step
        s0 = checked_state(system, system.default_state() if state is None else state, copy=True)
        self._single = s0.ndim == 1
        self.state0 = s0 if s0.ndim == 2 else s0[None]  # our own copy: the caller keeps theirs
        self.state = self.state0.copy()
        if (
            reference == "auto"
            and not self._has_exact
            and self.method.adaptive
            and min(self.rtol, self.atol) < MIN_COMPARED_TOL
        ):
            self.reference_note = (
                f"no error: rtol/atol below {MIN_COMPARED_TOL:g} is not clearly looser than the "
                f"reference run (DOP853 at rtol {REFERENCE_TOL:g})"
            )
            reference = None
        if reference == "auto" and not self._has_exact:
            self._reference = reference_run(system, self.state0)
        self._track_error = reference is not None and (self._has_exact or reference == "auto")
        self._reference_mode = reference

    def __getattr__(self, name: str):
        # The work arrays of the compiled loops, made when first used: a run that is built and
        # dropped, or a Taylor run, needs only some of them.
        if name not in ("_H", "_F", "_stats", "_status"):
            raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")
        n = len(self.state)
        if name == "_H":
            self._H = np.zeros(n)
        elif name == "_F":
            self._F = np.zeros(self.state.shape)
        elif name == "_stats":
            self._stats = np.zeros((n, 3), dtype=np.int64)
        else:
            self._status = np.zeros(3, dtype=np.int64)
        return vars(self)[name]

    def _checked_state(self, state) -> np.ndarray:
        return checked_state(self.system, state)

    @property
    def E0(self) -> np.ndarray:
        """The start's energy [J] (N,), against which the energy error is measured."""
        return self._energies()[0]

    @property
    def _moving0(self) -> np.ndarray:
        """The start's energy above the system's floor [J] (N,) (module docstring)."""
        return self._energies()[1]

    @property
    def _has_exact(self) -> bool:
        """Whether the system has a closed form from the start (asked when first needed: a run
        without a reference may never need it)."""
        if self._exact_known is None:
            self._exact_known = bool(self.system.has_exact(self.state0))
        return self._exact_known

    def _energies(self) -> tuple[np.ndarray, np.ndarray]:
        # Worked out when first asked for, not when built: a solve that never samples the
        # energy (a parameter scan) does not pay for it.
        if self._start_energy is None:
            self._start_energy = (
                np.asarray(self.system.energy(self.state0), dtype=float),
                np.asarray(self.system.energy_above_floor(self.state0), dtype=float),
            )
        return self._start_energy

    def jump(self, state: np.ndarray) -> None:
        """Replace the state at the current time ``t`` without restarting the run: an impulse
        (a kick) or a new configuration that keeps the clock.

        Time, the step and evaluation counters and the step size carry on; a kept step (dense
        output) is dropped, so the next step starts at ``t`` from the new state. What the run is
        measured against moves with the jump, because a jump is not an integration error: the
        energy reference becomes the new state's energy, and the error is measured against the
        exact solution from the new state (or a fresh tight reference run started at ``t``).
        ``state`` has the shape of :attr:`state` (ValueError otherwise, and nothing changes)."""
        s = np.atleast_2d(self._checked_state(state)).astype(np.float64)
        if s.shape != self.state.shape:
            raise ValueError(f"state must have shape {self.state.shape}; got {s.shape}")
        self.state0 = s.copy()
        self.state = s.copy()
        self.t0 = self.t
        self._start_energy = None
        self._exact_known = None
        if self._carry is not None:
            self._carry.forget()  # a kept step and its series or interpolant belong to the old state
        self._taylor_h = None
        self._reference = None
        if self._reference_mode == "auto" and not self._has_exact:
            ref = reference_run(self.system, self.state0)
            for run in (ref, ref._reference):  # the systems are autonomous: start them now
                run.t = run.clock = run.t0 = self.t
            self._reference = ref
        self._track_error = self._reference_mode is not None and (
            self._has_exact or self._reference_mode == "auto"
        )

    # ------------------------------------------------------------------ stepping
    def restart(self, state: np.ndarray | None = None) -> None:
        """Go back to ``t = 0`` with the same system, method and settings, from the initial state
        or from ``state`` (same shape): counters, kept steps and the reference start afresh.
        Costs under a microsecond (without a reference run), a fraction of building a new
        Simulation (which checks its start and makes its arrays anew; its step control and
        the system's kernel parameters it takes from the first run of the same settings)."""
        if state is not None:
            s0 = np.array(state, dtype=np.float64).reshape(self.state0.shape)  # a copy
            if not all_finite(s0.ravel()):
                raise ValueError("state must be finite")
            self.state0 = s0
            self._start_energy = None
            self._taylor_h = None
        self.state = self.state0.copy()
        self.t = self.clock = self.t0 = 0.0
        self.steps = self.nfev = self.rejected = 0
        # fill() rather than slice assignment: a third of the cost on these small arrays, and
        # restart() is the whole per-solve overhead of a kept Simulation (not made: nothing to do)
        made = vars(self)
        if "_H" in made:
            self._H.fill(0.0)
        if "_stats" in made:
            self._stats.fill(0)
        if self._carry is not None:
            self._carry.forget()
        if self._reference is not None:
            self._reference.restart(state)

    def step_label(self) -> str:
        return self.step.label()

    def advance_to(self, t_target: float, *, final: bool = False) -> None:
        """Advance to ``t_target`` (fixed step: the last whole step at or before it). ``final``:
        it is the run's end; DOP853 cuts its last step to end there (module docstring)."""
        t_target = _v.finite("t", t_target)
        if t_target < self.t:
            raise ValueError(f"t must not go backwards: {t_target} < {self.t}")
        self.clock = t_target
        m = self.method
        if m.closed_form and (self.system.sys_id is None or self.dt is None):
            # Closed form evaluated at the time asked for (no compiled flow, or no step given).
            self.state = np.atleast_2d(self.system.exact(self.state0, t_target - self.t0))
            self.t = t_target
        elif not m.adaptive:
            n = int(math.floor((t_target - self.t) / self.dt + 1e-9))
            if n > 0:
                self._run_fixed(n)
        elif t_target > self.t:
            if m.backend == "scipy":
                nfev, steps, failure = _compiled.advance_scipy(
                    m.scipy_name,
                    self.system.sys_id,
                    self.p,
                    self.state,
                    self.t,
                    t_target,
                    self.rtol,
                    self.atol,
                )
                self.nfev += nfev
                self.steps += steps
                if failure:
                    raise IntegrationError(m.name, self.step_label(), t_target, failure)
            elif m.pair is not None:
                self._run_rk(t_target, final)
            elif m.series:
                self._run_taylor(t_target)
            else:
                raise ValueError(f"no compiled adaptive runner for method {m.name!r}")
            self.t = t_target
        if self._reference is not None:
            self._reference.advance_to(self.t, final=final)

    def advance(self, duration: float) -> None:
        """Advance the clock by ``duration`` [s]; a fixed-step method takes the whole steps that
        fit and carries the remainder, so many short calls add up to the same run as one long."""
        self.advance_to(self.clock + _v.finite("duration", duration))

    def _timed_chunk(self, run_chunk, steps: int) -> None:
        """Run ``run_chunk(steps)``, then adapt the chunk size (:meth:`_chunk_done`)."""
        t0 = time.perf_counter()
        run_chunk(steps)
        self._chunk_done(time.perf_counter() - t0, full=steps >= self._chunk_steps)

    def _chunk_done(self, elapsed: float, full: bool) -> None:
        """After a chunk that took ``elapsed`` seconds: double the chunk if it was ``full`` (as
        long as asked) and took under a quarter of :data:`CHUNK_SECONDS`, halve it if it took
        longer than that; then report to ``on_chunk``."""
        if elapsed < CHUNK_SECONDS / 4 and full:
            self._chunk_steps = min(self._chunk_steps * 2, 1 << 40)
        elif elapsed > CHUNK_SECONDS:
            self._chunk_steps = max(1, self._chunk_steps // 2)
        if self.on_chunk is not None:
            self.on_chunk(self)

    def _run_fixed(self, n: int) -> None:
        """``n`` steps of ``dt`` in chunks (Ctrl-C is seen between them). If the method fails,
        the run is left where this call found it."""
        start = self.state.copy(), self.steps, self.t
        try:
            while n > 0:
                k = min(n, self._chunk_steps)
                self._timed_chunk(self._run_fixed_chunk, k)
                n -= k
        except IntegrationError:
            self.state[:], self.steps, self.t = start
            raise

    def _run_rk(self, t_target: float, final: bool = False) -> None:
        """The method's compiled Runge-Kutta pair to ``t_target`` in chunks of about
        ``_chunk_steps`` steps (the length of a chunk from the last step size; Ctrl-C is seen
        between chunks). A chunk's end is one more time asked for: the step across it is kept,
        not cut, so the chunks take the steps of one call (the dense output's extra evaluations
        per chunk, for the state at its end)."""
        while self.t < t_target:
            h = float(np.mean(self._H)) if np.all(self._H > 0) else 0.0
            if h <= 0.0:  # no step yet: guess one from the system's time scale
                h = self.system.time_scale(self.state) / self.method.steps_per_period(self.rtol)
            span = self._chunk_steps * h
            t_next = t_target if not span < t_target - self.t else self.t + span
            land = final and t_next == t_target
            self._timed_chunk(lambda _k, t1=t_next, c=land: self._rk_to(t1, c), self._chunk_steps)
            self.t = t_next

    def _leg(self, t1: float) -> tuple:
        """What every compiled adaptive loop is told first: the system, the members, the
        kernel parameters, from ``t`` to ``t1`` [s], at ``rtol`` and ``atol``."""
        return self.system.sys_id, self.state, self.p, self.t, t1, self.rtol, self.atol

    def _rk_to(self, t1: float, land: bool = False) -> None:
        """One chunk of the compiled pair, with its kept step, from ``t`` to ``t1`` (``land``:
        the last step cut to end at ``t1``)."""
        if self._carry is None:
            self._carry = _compiled.RKCarry(
                *self.state.shape, _compiled.load_pair(self.method.pair)
            )
        pair = self._carry.pair
        args = (self._H, self._F, self._stats, self._status, self._carry, land)
        _compiled.run_rk(pair, *self._leg(t1), *args)
        self.nfev, self.steps, self.rejected = (int(x) for x in self._stats.sum(axis=0))
        if self._status[0] != OK:
            raise integration_error(self.method.name, self.step_label(), self.t, self._status[0])

    def _run_taylor(self, t_target: float) -> None:
        """Taylor's method to ``t_target`` in chunks of about ``_chunk_steps`` steps per member
        (Ctrl-C is seen between chunks). A chunk's span is that many steps of the mean step of
        the last chunk (at first a guess from the system's time scale); where the chunks end does
        not change the steps taken (each call keeps its last step, :mod:`.integrators.taylor`).
        Kept lean: a benchmark run is ``restart()`` and one call of a few microseconds."""
        members = len(self.state)
        if self._carry is None:
            self._carry = TaylorCarry(*self.state.shape)
            self._runner = taylor_runner(self.system.sys_id, members)
        while self.t < t_target:
            h = self._taylor_h
            if h is None:
                h = self.system.time_scale(self.state) / self.method.steps_per_period(self.rtol)
            span = self._chunk_steps * h
            t1 = t_target if not span < t_target - self.t else self.t + span
            start = time.perf_counter()
            steps = self._runner(*self._leg(t1), self._stats, self._status, self._carry)
            elapsed = time.perf_counter() - start
            self.steps += steps
            self.nfev += steps
            if self._status[0] != OK:
                raise integration_error(
                    self.method.name, self.step_label(), self.t, self._status[0]
                )
            if steps:
                self._taylor_h = (t1 - self.t) * members / steps
            self.t = t1
            self._chunk_done(elapsed, full=steps >= self._chunk_steps * members)

    def estimated_steps(self, t_end: float) -> float:
        """The steps a run from the current time to ``t_end`` [s] would take, summed over the
        ensemble and including the reference run's (a float: it may be huge or infinite).

        Exact for fixed-step methods (``(t_end - t) / dt`` per member); 0 for a closed-form flow;
        for adaptive methods an estimate from the system's shortest period
        (``System.time_scale``) and the method's order, ``2 rtol^(-1/order)`` steps per period.
        Measured on the three systems at rtol 1e-4 to 1e-12: DOP853 (ours and scipy's) and RK45
        take 1.5 to 4.3 times fewer steps than estimated, Radau from 1.1 times fewer to 2.9 times
        more, LSODA and odeint 2.5 to 7 times more (their order varies; 12 is their highest).
        Callers that must bound their work (the CLI's ``--max-steps``, the recorder) compare this
        with their limit before running.
        """
        t_end = _v.finite("t_end", t_end)
        m = self.method
        members = len(self.state)
        with np.errstate(over="ignore", divide="ignore"):
            span = max(0.0, t_end - self.t)
            if m.closed_form and (self.system.sys_id is None or self.dt is None):
                own = 0.0
            elif not m.adaptive:
                own = math.floor(span / self.dt + 1e-9) if span / self.dt < 1e300 else math.inf
            elif span == 0.0:
                own = 0.0
            else:
                periods = span / self.system.time_scale(self.state)
                own = max(1.0, periods * m.steps_per_period(self.rtol))
        ref = 0.0 if self._reference is None else self._reference.estimated_steps(t_end)
        return float(own) * members + ref

    def _run_fixed_chunk(self, n: int) -> None:
        step, inner = step_functions(self.method, self.system.sys_id)
        before = self.state.copy()
        loops = _compiled.kernels
        if inner is None:
            nfev = loops.run_direct(step, self.state, self.p, self.dt, n, self._status)
        else:
            nfev = loops.run_composed(step, inner, self.state, self.p, self.dt, n, self._status)
        self.nfev += int(nfev)
        code, k = int(self._status[0]), int(self._status[1])
        if code != OK:
            # Leave the run at the last state it reached before this call, not at garbage.
            self.state[:] = before
            t_fail = (self.steps + k + 1) * self.dt
            raise integration_error(self.method.name, self.step_label(), t_fail, code)
        self.steps += n
        self.t = self.steps * self.dt

    @property
    def last_step(self) -> float | None:
        """The length [s] of the step the compiled adaptive method kept at ``t`` (the step that
        passed the last time asked for), averaged over the ensemble; ``None`` before the first
        step, after a jump or a restart, and for the other methods (fixed steps: ``dt``)."""
        carry = self._carry
        if carry is None or not np.all(carry.span > 0.0):
            return None
        return float(np.mean(carry.span))

    # ------------------------------------------------------------------ measuring
    @property
    def reference_kind(self) -> str | None:
        """``"exact"``, ``"reference"`` (tight DOP853) or ``None``: what ``Sample.error`` is against."""
        if not self._track_error:
            return None
        return EXACT_FLOW if self._has_exact else REFERENCE_RUN

    def reference_state(self) -> np.ndarray | None:
        """The exact state at ``t`` if known, else the tight reference run's, else ``None``."""
        if self._has_exact:
            return np.atleast_2d(self.system.exact(self.state0, self.t - self.t0))
        if self._reference is not None:
            return self._reference.state
        return None

    def reference_error(self) -> np.ndarray | None:
        """The measured relative error (N,) of what ``Sample.error`` is against, now: zeros for
        the exact solution, the tight reference's relative difference from its check run (ten
        times looser, :data:`CHECK_TOL`) for the DOP853 reference, ``None`` if not measured."""
        kind = self.reference_kind
        if kind is None:
            return None
        if kind == EXACT_FLOW:
            return np.zeros(len(self.state))
        ref = self._reference
        check = None if ref is None else ref._reference
        if check is None:
            return None
        return np.asarray(self.system.error(check.state, ref.state), dtype=float)

    def energy_scale(self) -> np.ndarray:
        """``E0 - E_floor`` (N,): the energy that moves, by which the energy error is divided
        (1 where nothing moves: there the error is absolute, in J)."""
        moving = self._moving0
        return np.where(moving > 0.0, moving, 1.0)

    def sample(self) -> Sample:
        # A state about to blow up is huge but finite: its energy may overflow, and that is the
        # information we want to show, not a warning.
        with np.errstate(over="ignore", invalid="ignore"):
            energy = np.asarray(self.system.energy(self.state), dtype=float)
            moving = np.asarray(self.system.energy_above_floor(self.state), dtype=float)
            scale = self.energy_scale()
            ref = self.reference_state() if self._track_error else None
            err = None if ref is None else self.system.error(self.state, ref)
            invariants = self.system.invariants(self.state)
        return Sample(
            self.t,
            self.state.copy(),
            energy,
            (moving - self._moving0) / scale,
            err,
            None if ref is None else ref.copy(),
            self.nfev,
            self.steps,
            invariants,
            self.reference_kind,
            self.reference_error() if self._track_error else None,
        )

    def run(self, t_end: float, n_samples: int = 2) -> Trajectory:
        """Run to ``t_end`` [s], sampling ``n_samples`` equally spaced times (first and last
        included; fixed-step samples fall on the last step at or before each time; ``t_end`` is
        a final time, see :meth:`advance_to`)."""
        t_end = _v.positive("t_end", t_end)
        if n_samples < 2:
            raise ValueError(f"n_samples must be at least 2, got {n_samples}")
        samples = []
        times = np.linspace(0.0, t_end, n_samples)
        for t in times:
            if t > 0:
                self.advance_to(float(t), final=t == times[-1])
            samples.append(self.sample())
        err = None if samples[0].error is None else np.stack([s.error for s in samples])
        bars = [s.reference_accuracy for s in samples]
        bar = None if any(b is None for b in bars) else np.stack(bars)
        names = samples[0].invariants or {}
        return Trajectory(
            np.array([s.t for s in samples]),
            np.stack([s.state for s in samples]),
            np.stack([s.energy_error for s in samples]),
            err,
            self.nfev,
            self.steps,
            np.stack([s.energy for s in samples]),
            {n: np.stack([s.invariants[n] for s in samples]) for n in names},
            bar,
        )


def reference_run(system: System, state: np.ndarray) -> Simulation:
    """The tight DOP853 run the error is measured against where there is no exact solution, with
    its check run (:data:`CHECK_TOL`) as its own ``_reference``: advanced, restarted and
    snapshot with it."""
    ref = Simulation(
        system,
        REFERENCE_METHOD,
        rtol=REFERENCE_TOL,
        atol=REFERENCE_ATOL,
        state=state,
        reference=None,
    )
    ref._reference = Simulation(
        system, REFERENCE_METHOD, rtol=CHECK_TOL, atol=CHECK_ATOL, state=state, reference=None
    )
    return ref
