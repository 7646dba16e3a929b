"""The dynamics from Python (a notebook, a script): simulate a system, get its time series as
arrays or a pandas DataFrame, the seed's analytic results as a dict, and the estimators that
measure a figure from samples, as the viewer and the recordings do.

This is the stable surface over :class:`mechviz.dynamics.Simulation`, :data:`mechviz.dynamics.SYSTEMS`, the
system modules' analytic functions, :mod:`mechviz.dynamics.measure` and :mod:`mechviz.dynamics.stability`; it
adds no physics of its own. Units are SI and the conventions are those of each system's module
(:mod:`mechviz.dynamics.cyclotron`, :mod:`mechviz.dynamics.disk`, :mod:`mechviz.dynamics.hoop`).

>>> from mechviz.dynamics import api
>>> run = api.simulate("hoop", method="rk4", dt=0.01, t_end=10.0, modes=(0.1, 0.0))
>>> run.states.shape                    # (samples, state dimension)
(501, 4)
>>> run.columns
('theta1', 'theta2', 'omega1', 'omega2')
>>> list(run.quantities)                # the system's own quantities beyond the state
['q1', 'q2']
>>> api.analyze("hoop")["mode_frequencies"]            # doctest: +ELLIPSIS
[2.21..., 3.83...]
>>> api.crossing_frequency(run.t, run.column("q1")).value   # doctest: +ELLIPSIS
2.21...
>>> df = run.to_dataframe()             # needs pandas: t, the state, energy, errors, quantities

Systems: :data:`SYSTEM_NAMES` (the disk with ``motion="driven"``, the exact uniform rotation
about the axle, or ``"released"``, the free body after the axle is removed). Every default
(parameters, start, method, step) is the one the command line, the viewer and the demo files
use. Methods: :func:`methods` (``mechviz simulate --list-methods``); the largest stable step of
one: :func:`stability_limit`. Estimators (each returns an :class:`Estimate`, a value or the
reason there is none): :func:`gyrofrequency`, :func:`fit_circle`, :func:`crossing_frequency`,
:func:`wobble_growth_rate`. Bad input raises :class:`mechviz.dynamics.params.SettingError` (a
``ValueError``) whose ``field`` names the argument; a run that blows up raises
:class:`mechviz.dynamics.IntegrationError`.

A recording ``mechviz record`` wrote is read back, checked file by file against its manifest,
with :func:`read_recording`; its traces, with their units, come from
:meth:`Recording.columns`.
"""

from __future__ import annotations

import csv
import dataclasses
import io
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np

from . import analysis
from . import params as _v
from . import stability as _stability
from .measure import Estimate, crossing_frequency, fit_circle, gyrofrequency, wobble_growth_rate
from .params import SettingError
from .registry import SPECS
from .simulation import EXACT_FLOW, RESOLVED_FACTOR, Simulation, reference_description
from .steps import Fixed

#: The shipped systems by the names the API, the command line and the demo files use (the API's
#: functions also take a system registered since, :func:`mechviz.dynamics.register`).
SYSTEM_NAMES = tuple(SPECS)

__all__ = [
    "SYSTEM_NAMES",
    "Estimate",
    "Recording",
    "Run",
    "analyze",
    "crossing_frequency",
    "fit_circle",
    "gyrofrequency",
    "methods",
    "parameters",
    "read_recording",
    "simulate",
    "stability_limit",
    "wobble_growth_rate",
]


@dataclass(frozen=True)
class Run:
    """A finished run sampled at ``len(t)`` times, under the names of ``mechviz simulate
    --json`` (:meth:`summary` gives that dict).

    ``states`` is ``(K, d)`` for one initial state and ``(K, N, d)`` for an ensemble of ``N``;
    ``energy`` [J], ``energy_error`` (signed, relative to the energy that moves,
    ``(E - E0) / (E0 - E_floor)``, as in :class:`mechviz.dynamics.Simulation`), ``error`` (relative,
    against what ``error_vs`` names: ``"exact"``, the exact solution, or ``"reference"``, a
    DOP853 run at ``rtol = 3e-15``, ``atol = 1e-17`` where there is none; ``None`` if not
    measured), ``reference_error`` (the reference's own relative error as measured in the run:
    the DOP853 reference's difference from a run ten times looser advanced beside it; zero for
    the exact solution) and each of ``quantities`` (the system's own quantities beyond the state,
    as the recordings' CSV has them: the cyclotron's ``r``, ``p_r``, ``p_phi``, ``V_eff``; the
    hoop's ``q1``, ``q2``; the disk's ``Lx``, ``Ly``, ``Lz``; labels with units in
    ``quantity_labels``) drop the last axis likewise."""

    system: str
    method: str
    step: str
    parameters: dict[str, float]
    columns: tuple[str, ...]
    t: np.ndarray
    states: np.ndarray
    energy: np.ndarray
    energy_error: np.ndarray
    error: np.ndarray | None
    error_vs: Literal["exact", "reference"] | None
    steps: int
    rhs_evaluations: int
    rhs_evaluations_count: str  # what ``rhs_evaluations`` counts for this method
    invariants: dict[str, np.ndarray] = field(default_factory=dict)
    start: dict[str, Any] = field(default_factory=dict)  # the start settings, defaults filled in
    quantities: dict[str, np.ndarray] = field(default_factory=dict)
    quantity_labels: dict[str, str] = field(default_factory=dict)
    report: dict[str, Any] = field(default_factory=dict)  # the system's figures at the end
    reference_error: np.ndarray | None = None  # like ``error``: the reference's own, measured
    #: The step control as numbers (``step`` in words): ``dt`` [s] of a fixed step, ``rtol`` and
    #: ``atol`` of an adaptive one; None where the method takes none.
    dt: float | None = None
    rtol: float | None = None
    atol: float | None = None

    def column(self, name: str) -> np.ndarray:
        """One state variable or quantity over time, e.g. ``run.column("theta1")``."""
        if name in self.quantities:
            return self.quantities[name]
        if name not in self.columns:
            names = ", ".join((*self.columns, *self.quantities))
            raise SettingError("name", f"name must be one of {names}; got {name!r}")
        return self.states[..., self.columns.index(name)]

    def to_dataframe(self):
        """A pandas DataFrame, one row per sample (and ensemble member, column ``member``):
        ``t``, the state variables, ``energy``, ``energy_error``, ``error`` and the
        quantities."""
        try:
            import pandas as pd
        except ImportError:
            raise ImportError(
                "to_dataframe needs pandas: pip install pandas (or pip install 'mechviz-lab[notebook]')"
            ) from None
        S = self.states if self.states.ndim == 3 else self.states[:, None, :]
        K, N, _ = S.shape

        def flat(a):
            return np.broadcast_to(np.asarray(a).reshape(K, -1), (K, N)).reshape(-1)

        data: dict[str, Any] = {"t": np.repeat(self.t, N)}
        if N > 1:
            data["member"] = np.tile(np.arange(N), K)
        for j, name in enumerate(self.columns):
            data[name] = S[:, :, j].reshape(-1)
        data["energy"] = flat(self.energy)
        data["energy_error"] = flat(self.energy_error)
        data["error"] = flat(self.error) if self.error is not None else np.nan
        for name, values in self.quantities.items():
            data[name] = flat(values)
        return pd.DataFrame(data)

    def summary(self) -> dict[str, Any]:
        """What ``mechviz simulate --json`` prints for this run, JSON-ready, under its names and
        signs: ``energy_drift`` the signed relative energy error at the end (of the member that
        drifted most, for an ensemble, whose ``initial_state`` and ``final_state`` are lists),
        ``max_energy_error`` the largest magnitude, ``error_vs_exact`` or
        ``error_vs_reference`` at the end (the largest of the members), ``reference`` what
        it is measured against, and against the DOP853 reference its own measured error at the
        end, ``reference_error`` (the largest of the members), and ``error_resolved``: whether
        the error is at least :data:`~mechviz.dynamics.simulation.RESOLVED_FACTOR` times that,
        a figure about the method rather than about the reference."""
        end = np.atleast_1d(self.energy_error[-1])

        def states(row):
            rows = [dict(zip(self.columns, map(float, x), strict=True)) for x in np.atleast_2d(row)]
            return rows[0] if np.ndim(row) == 1 else rows

        out: dict[str, Any] = {
            "system": self.system,
            **({"motion": self.start["motion"]} if "motion" in self.start else {}),
            "method": self.method,
            "step": self.step,
            "dt": self.dt,
            "rtol": self.rtol,
            "atol": self.atol,
            "parameters": dict(self.parameters),
            "t_end": float(self.t[-1]),
            "initial_state": states(self.states[0]),
            "final_state": states(self.states[-1]),
            "energy_drift": float(end[np.argmax(np.abs(end))]),
            "max_energy_error": float(np.max(np.abs(self.energy_error))),
            "rhs_evaluations": self.rhs_evaluations,
            "rhs_evaluations_count": self.rhs_evaluations_count,
            "steps": self.steps,
            "samples": len(self.t),
            "members": 1 if np.ndim(self.states) == 2 else int(self.states.shape[1]),
        }
        if self.error is not None:
            err = float(np.max(self.error[-1]))
            out[f"error_vs_{self.error_vs}"] = err
            out["reference"] = reference_description(self.error_vs)
            if self.error_vs == "reference" and self.reference_error is not None:
                bar = float(np.max(self.reference_error[-1]))
                out["reference_error"] = bar
                out["error_resolved"] = err >= RESOLVED_FACTOR * bar
        out.update(self.report)
        return out


def parameters(system: str, **params: float) -> dict[str, float]:
    """The physical parameters of ``system`` with the defaults filled in (``ValueError`` naming
    an unknown name or a bad value)."""
    return dataclasses.asdict(_spec(system).parameters(params))


def methods(system: str, motion: Literal["driven", "released"] | None = None) -> list[str]:
    """Names of the methods that apply to ``system`` (the disk's: for its ``motion``)."""
    spec = _spec(system)
    start = {} if motion is None else {"motion": motion}
    return [m.name for m in spec.methods(start)]


def analyze(system: str, **settings: float) -> dict[str, Any]:
    """The seed's analytic results for ``system`` (what ``mechviz analyze SYSTEM --json``
    prints): cyclotron gyrofrequency, period, radius for ``speed`` [m/s] (default 1), canonical
    momentum and effective potential; disk inertia tensor, principal moments and axes, bearing
    forces; hoop normal-mode frequencies, periods and shapes. ``settings`` are the system's
    parameters (:func:`parameters`) and the cyclotron's ``speed``."""
    _spec(system)
    return analysis.analyze(system, settings)


#: The samples of a run when none are asked for (about that many with a fixed step).
SAMPLES = 501


def simulate(
    system: str,
    *,
    t_end: float,
    method: str | None = None,
    dt: float | None = None,
    rtol: float | None = None,
    atol: float | None = None,
    samples: int | None = None,
    state: Any = None,
    reference: Literal["auto", "exact"] | None = "auto",
    **settings: Any,
) -> Run:
    """Run ``system`` with ``method`` to ``t_end`` [s] and sample it ``samples`` times, equally
    spaced, first and last included, each at exactly its time. By default about
    :data:`SAMPLES` samples; with a fixed step they are a whole number of steps apart and the step
    is shortened only to land on ``t_end`` (the fewest steps that do, as the command line lands on
    ``--t-end``, rounded up to a whole number per sample: under 1/:data:`SAMPLES` more).
    Given ``samples``, a fixed step that does not divide the interval between them is shortened
    to the largest step that does (:attr:`Run.step` says which step ran).

    ``settings`` are the system's physical parameters (:func:`parameters`) and the settings of
    its start, each defaulting as everywhere else in mechviz (``mechviz simulate SYSTEM --help``
    lists them): the cyclotron's transverse ``speed`` [m/s], ``centre`` (x, y) [m] and ``vz``
    [m/s]; the hoop's ``modes`` (amplitudes of mode 1 and mode 2 [rad], at rest); the disk's
    ``motion`` (``"driven"`` or ``"released"``) and ``extra_spin`` [rad/s] (disk-frame
    components, added at release). ``state`` (``(d,)`` or an ensemble ``(N, d)``, layout
    :attr:`Run.columns`) replaces the start (the disk's ``motion`` still says which
    system it is a state of: ``motion="released"`` with the free body's state). ``method``
    defaults to the system's, ``dt`` to its step for fixed-step methods; ``rtol`` (default
    1e-9) and ``atol`` (default ``rtol``, in the
    state's units: a motion much smaller than 1 is then held to ``atol``, not to ``rtol`` of
    itself) are for adaptive ones.
    ``reference`` as in :class:`mechviz.dynamics.Simulation` (``None`` skips the error measurement, which
    for systems without an exact solution runs a tight DOP853 beside the method)."""
    spec = _spec(system)
    start_names = {s.name for s in spec.start}
    start = {k: v for k, v in settings.items() if k in start_names}
    params = {k: v for k, v in settings.items() if k not in start_names}
    if reference not in ("auto", EXACT_FLOW, None):
        raise SettingError(
            "reference", f"reference must be 'auto', 'exact' or None; got {reference!r}"
        )
    # A word setting (the disk's motion) picks the system the state is of; the others shape the
    # initial state, which ``state`` gives whole.
    shaping = [k for k in start if not spec.setting(k).choices]
    if state is not None and shaping:
        raise SettingError(
            shaping[0], "state gives the whole start; leave out " + ", ".join(shaping)
        )
    try:
        setup = spec.setup(params, start, method=method, dt=dt, rtol=rtol, atol=atol, state=state)
    except SettingError as exc:  # a start setting is an argument of its own name here
        field = exc.field.removeprefix("initial.")
        raise SettingError(field, str(exc), fields=(field,)) from None
    t_end = _v.positive("t_end", t_end)
    step = setup.step
    if samples is None and isinstance(step, Fixed):
        # the step kept: the fewest steps that land on t_end, rounded up to a multiple of k,
        # k steps between samples and at most SAMPLES - 1 intervals
        n = max(1, math.ceil(t_end / step.dt - 1e-9))
        k = math.ceil(n / (SAMPLES - 1))
        n = k * math.ceil(n / k)
        samples, step = n // k + 1, Fixed(t_end / n)
    elif samples is None:
        samples = SAMPLES
    if isinstance(samples, bool) or not isinstance(samples, int) or samples < 2:
        raise SettingError(
            "samples", f"samples must be a whole number of at least 2, got {samples!r}"
        )
    if isinstance(step, Fixed) and step is setup.step:
        # Samples at exactly the times asked: the largest step <= dt that divides the interval
        # between samples (as the command line lands on --t-end).
        interval = t_end / (samples - 1)
        step = Fixed(interval / max(1, math.ceil(interval / step.dt - 1e-9)))
    sim = Simulation(setup.system, setup.method, step=step, state=setup.state, reference=reference)
    single = np.ndim(setup.state) == 1
    traj = sim.run(t_end, n_samples=samples)

    def member(a):
        return a[:, 0] if single else a

    states = member(traj.states)
    return Run(
        system=spec.name,
        method=sim.method.name,
        step=sim.step_label(),
        parameters=dataclasses.asdict(setup.params),
        columns=tuple(setup.system.state_names),
        t=traj.t,
        states=states,
        energy=member(traj.energy),
        energy_error=member(traj.energy_error),
        error=None if traj.error is None else member(traj.error),
        error_vs=sim.reference_kind,
        steps=sim.steps,
        rhs_evaluations=sim.nfev,
        rhs_evaluations_count=sim.method.counts,
        invariants={n: member(v) for n, v in traj.invariants.items()},
        start=dict(setup.start),
        quantities=setup.system.quantities(states),
        quantity_labels=dict(setup.system.quantity_labels),
        report=setup.system.report(float(traj.t[-1])),
        reference_error=None if traj.reference_error is None else member(traj.reference_error),
        dt=sim.dt,
        rtol=sim.rtol,
        atol=sim.atol,
    )


def stability_limit(system: str, method: str, **settings: Any) -> float | None:
    """The largest stable fixed step [s] of ``method`` on ``system`` for ``settings`` (its
    parameters and start, as :func:`simulate` takes them; the disk's methods other than
    ``exact`` need ``motion="released"``), from the method's stability region and the motion's
    fastest frequency (:mod:`mechviz.dynamics.stability`). ``None``: stable at any step (or adaptive,
    or exact); ``0.0``: stable at none (explicit Euler on an oscillation)."""
    spec = _spec(system)
    start_names = {s.name for s in spec.start}
    start = {k: v for k, v in settings.items() if k in start_names}
    params = {k: v for k, v in settings.items() if k not in start_names}
    try:
        setup = spec.setup(params, start, method=method)
    except SettingError as exc:
        field = exc.field.removeprefix("initial.")
        raise SettingError(field, str(exc), fields=(field,)) from None
    return _stability.stability_limit(setup.method.name, setup.system, setup.state)


def _spec(system: str):
    if system not in SPECS:
        raise SettingError("system", f"system must be one of {', '.join(SPECS)}; got {system!r}")
    return SPECS[system]


# --------------------------------------------------------------------------- recordings
#: The files of a recording besides its manifest (``DEMO.json``).
RECORDING_SUFFIXES = (".viser", ".html", ".csv", ".png", ".svg", ".pdf", ".json")


@dataclass(frozen=True)
class Recording:
    """A recording read back and checked: ``manifest`` (``DEMO.json``) and ``files``, the bytes
    of every file it lists (``DEMO.viser``, ``DEMO.html``, ``DEMO.csv``, ``DEMO.png``, ...) and of
    the manifest itself, each file matching the size and SHA-256 the manifest gives."""

    name: str
    folder: Path
    manifest: dict[str, Any] = field(repr=False)
    files: dict[str, bytes] = field(repr=False)

    @property
    def units(self) -> dict[str, str]:
        """The unit of each column of ``DEMO.csv`` ("" for a count or a label; empty if the
        recording predates units in its manifest)."""
        cols = self.manifest.get("csv_columns") or {}
        return {k: v.get("units", "") for k, v in cols.items() if isinstance(v, dict)}

    def columns(self) -> dict[str, np.ndarray]:
        """``DEMO.csv`` by column: ``run`` as strings, ``member`` as int, every other column as
        float (an empty cell as NaN)."""
        rows = list(csv.reader(io.StringIO(self.files[f"{self.name}.csv"].decode())))
        header, body = rows[0], rows[1:]
        out: dict[str, np.ndarray] = {}
        for i, col in enumerate(header):
            cells = [r[i] for r in body]
            if col == "run":
                out[col] = np.array(cells, dtype=str)
            elif col == "member":
                out[col] = np.array([int(c) for c in cells], dtype=int)
            else:
                out[col] = np.array([float(c) if c else math.nan for c in cells], dtype=float)
        return out


def read_recording(path: str | os.PathLike) -> Recording:
    """The recording at ``path``: its folder and demo name (``out/helix``), or any of its files
    (``out/helix.json``, ``out/helix.viser``). ``ValueError`` if there is none there;
    :class:`mechviz.dynamics.fileset.SetMismatch` (a ``ValueError``) names the file that does not
    belong when the folder holds a mix ("helix.csv is from an older recording than
    helix.json")."""
    from . import fileset

    p = Path(path)
    if p.suffix in RECORDING_SUFFIXES:
        p = p.with_suffix("")
    folder, name = p.parent, p.name
    manifest_name = f"{name}.json"
    with fileset.reading(folder):  # a recording written meanwhile waits until this is read
        man, files = fileset.check_set(folder, manifest_name)
    if man is None:
        raise ValueError(f"{folder / manifest_name}: no recording manifest there")
    return Recording(name, folder, man, files)
