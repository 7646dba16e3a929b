"""The dynamics from Python (a notebook, a script): simulate a system, get its time series as
arrays or a pandas DataFrame, and the seed's analytic results as a dict.

This is the stable surface over :class:`dynamics.Simulation`, :data:`dynamics.SYSTEMS`, the
system modules' analytic functions and :mod:`dynamics.measure`; it adds no physics of its own.
Units are SI and the conventions are those of each system's module (:mod:`dynamics.cyclotron`,
:mod:`dynamics.disk`, :mod:`dynamics.hoop`).

>>> from dynamics import api
>>> run = api.simulate("hoop", method="rk4", dt=0.01, t_end=10.0, modes=(0.1, 0.0))
>>> run.states.shape                    # (samples, state dimension)
(501, 4)
>>> run.columns
('theta1', 'theta2', 'omega1', 'omega2')
>>> api.analyze("hoop")["mode_frequencies"]            # doctest: +ELLIPSIS
[2.21..., 3.83...]
>>> df = run.to_dataframe()             # needs pandas: t, the state, energy, errors

Systems: ``"cyclotron"``, ``"hoop"``, ``"disk"`` (``motion="driven"``, the exact uniform rotation
about the axle, or ``"released"``, the free body after the axle is removed). Methods:
:func:`methods` (``mechviz simulate --list-methods``). Bad input raises ``ValueError`` naming
the argument; a run that blows up raises :class:`dynamics.IntegrationError`.
"""

from __future__ import annotations

import argparse
import dataclasses
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from . import cyclotron, disk, hoop
from .integrators import methods_for
from .simulation import Simulation
from .systems import Cyclotron, DrivenDisk, Hoop, ReleasedDisk

SYSTEM_NAMES = ("cyclotron", "hoop", "disk")
_PARAMS = {
    "cyclotron": cyclotron.CyclotronParams,
    "hoop": hoop.HoopParams,
    "disk": disk.DiskParams,
}

__all__ = ["SYSTEM_NAMES", "Run", "analyze", "methods", "parameters", "simulate"]


@dataclass(frozen=True)
class Run:
    """A finished run sampled at ``len(t)`` times.

    ``states`` is ``(K, d)`` for one initial state and ``(K, N, d)`` for an ensemble of ``N``;
    ``energy``, ``energy_error`` (relative, ``(E - E0)/|E0|``) and ``error`` (against the exact
    solution, or a DOP853 reference at ``rtol = atol = 1e-12`` where there is none; ``None`` if
    not measured) drop the last axis likewise."""

    system: str
    method: str
    step: str
    params: dict[str, float]
    columns: tuple[str, ...]
    t: np.ndarray
    states: np.ndarray
    energy: np.ndarray
    energy_error: np.ndarray
    error: np.ndarray | None
    reference: str | None  # "exact", "reference" or None: what ``error`` is measured against
    steps: int
    rhs_evaluations: int  # what is counted depends on the method: ``Method.counts``
    invariants: dict[str, np.ndarray] = field(default_factory=dict)

    def column(self, name: str) -> np.ndarray:
        """One state variable over time, e.g. ``run.column("theta1")``."""
        if name not in self.columns:
            raise ValueError(f"name must be one of {', '.join(self.columns)}; got {name!r}")
        return self.states[..., self.columns.index(name)]

    def to_dataframe(self):
        """A pandas DataFrame, one row per sample (and ensemble member, column ``member``):
        ``t``, the state variables, ``energy``, ``energy_error`` and ``error``."""
        try:
            import pandas as pd
        except ImportError:
            raise ImportError(
                "to_dataframe needs pandas: pip install pandas (or pip install 'mechviz[notebook]')"
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
        return pd.DataFrame(data)

    def summary(self) -> dict[str, Any]:
        """Method, step, work and final errors as a JSON-ready dict."""
        out: dict[str, Any] = {
            "system": self.system, "method": self.method, "step": self.step,
            "t_end": float(self.t[-1]), "steps": self.steps,
            "rhs_evaluations": self.rhs_evaluations,
            "final_energy_error": float(np.max(np.abs(self.energy_error[-1]))),
            "max_energy_error": float(np.max(np.abs(self.energy_error))),
        }  # fmt: skip
        if self.error is not None:
            out[f"final_error_vs_{self.reference}"] = float(np.max(self.error[-1]))
        return out


def parameters(system: str, **params: float) -> dict[str, float]:
    """The physical parameters of ``system`` with the defaults filled in (``ValueError`` for an
    unknown name or a bad value)."""
    return dataclasses.asdict(_params(_check_system(system), params))


def methods(system: str, motion: Literal["driven", "released"] = "released") -> list[str]:
    """Names of the methods that apply to ``system``."""
    return [m.name for m in methods_for(_adapter(_check_system(system), {}, motion).name)]


def analyze(system: str, *, speed: float = 1.0, **params: float) -> dict[str, Any]:
    """The seed's analytic results for ``system`` (what ``mechviz analyze SYSTEM --json``
    prints): cyclotron gyrofrequency, period, radius for ``speed`` [m/s], canonical momentum and
    effective potential; disk inertia tensor, principal moments and axes, bearing forces; hoop
    normal-mode frequencies, periods and shapes."""
    from .cli import PARAM_FLAGS, CliError
    from .cli import analyze as _analyze

    system = _check_system(system)
    _params(system, params)  # names and values checked here, with the argument's name
    ns = argparse.Namespace(speed=speed, **{n: params.get(n) for n in PARAM_FLAGS[system].values()})
    try:
        return _analyze(system, ns)
    except CliError as exc:
        raise ValueError(str(exc).replace("--", "", 1)) from None


def simulate(
    system: str,
    *,
    method: str = "rk4",
    t_end: float,
    dt: float | None = None,
    rtol: float | None = None,
    atol: float | None = None,
    samples: int = 501,
    state: Any = None,
    motion: Literal["driven", "released"] = "released",
    speed: float | None = None,
    modes: tuple[float, float] | None = None,
    extra_spin: tuple[float, float, float] = (0.0, 0.0, 0.0),
    reference: Literal["auto", "exact"] | None = "auto",
    **params: float,
) -> Run:
    """Run ``system`` with ``method`` to ``t_end`` [s] and sample it ``samples`` times (first
    and last included; a fixed-step sample falls on the last step at or before its time).

    The start: ``state`` (``(d,)`` or an ensemble ``(N, d)``, layout :attr:`Run.columns`), or
    the cyclotron's circle of transverse ``speed`` [m/s] (default 1), the hoop's ``modes``
    (amplitudes of mode 1 and mode 2 [rad], at rest; default hanging at rest), the released
    disk's ``extra_spin`` [rad/s] (disk-frame components) on top of its spin about the axle.
    ``params`` are the system's physical parameters (:func:`parameters`). ``dt`` is required for
    fixed-step methods, ``rtol`` (default 1e-9) and ``atol`` (default ``rtol``, in the state's
    units: a motion much smaller than 1 is then held to ``atol``, not to ``rtol`` of itself) are
    for adaptive ones. ``reference`` as in
    :class:`dynamics.Simulation` (``None`` skips the error measurement, which for systems
    without an exact solution runs a tight DOP853 beside the method)."""
    system = _check_system(system)
    sysm = _adapter(system, params, motion, extra_spin)
    p = sysm.params
    if state is None:
        if system == "cyclotron":
            state = cyclotron.circular_orbit_state(p, 1.0 if speed is None else speed)
        elif system == "hoop" and modes is not None:
            state = hoop.mode_state(p, tuple(modes))
    elif speed is not None or modes is not None:
        raise ValueError("state gives the whole start; leave out speed and modes")
    if speed is not None and system != "cyclotron":
        raise ValueError("speed is for the cyclotron only")
    if modes is not None and system != "hoop":
        raise ValueError("modes is for the hoop only")
    if samples < 2:
        raise ValueError(f"samples must be at least 2, got {samples}")
    sim = Simulation(sysm, method, dt=dt, rtol=rtol, atol=atol, state=state, reference=reference)
    K = int(samples)
    single = np.asarray(sim.state0).shape[0] == 1 and (state is None or np.ndim(state) == 1)
    ts, S, E, EE, ERR, INV = [], [], [], [], [], []
    for k, t in enumerate(np.linspace(0.0, float(t_end), K)):
        if k:
            sim.advance_to(float(t), final=k == K - 1)
        s = sim.sample()
        ts.append(s.t)
        S.append(s.state)
        E.append(s.energy)
        EE.append(s.energy_error)
        ERR.append(s.error)
        INV.append(s.invariants or {})

    def stack(xs):
        a = np.stack(xs)
        return a[:, 0] if single else a

    err = None if ERR[0] is None else stack(ERR)
    inv = {name: stack([i[name] for i in INV]) for name in INV[0]}
    return Run(
        system=sysm.name, method=sim.method.name, step=sim.step_label(),
        params=dataclasses.asdict(p), columns=tuple(sysm.state_names),
        t=np.asarray(ts), states=stack(S), energy=stack(E), energy_error=stack(EE), error=err,
        reference=sim.reference_kind, steps=sim.steps, rhs_evaluations=sim.nfev, invariants=inv,
    )  # fmt: skip


# --------------------------------------------------------------------------- helpers
def _check_system(system: str) -> str:
    if system not in SYSTEM_NAMES:
        raise ValueError(f"system must be one of {', '.join(SYSTEM_NAMES)}; got {system!r}")
    return system


def _params(system: str, params: dict[str, float]):
    cls = _PARAMS[system]
    names = [f.name for f in dataclasses.fields(cls)]
    unknown = sorted(set(params) - set(names))
    if unknown:
        raise ValueError(
            f"{unknown[0]} is not a parameter of the {system}; choose from {', '.join(names)}"
        )
    return cls(**params)


def _adapter(system: str, params: dict[str, float], motion: str, extra_spin=(0.0, 0.0, 0.0)):
    p = _params(system, params)
    if system == "cyclotron":
        return Cyclotron(p)
    if system == "hoop":
        return Hoop(p)
    if motion == "driven":
        if any(extra_spin):
            raise ValueError("extra_spin is for motion='released' only")
        return DrivenDisk(p)
    if motion != "released":
        raise ValueError(f"motion must be 'driven' or 'released'; got {motion!r}")
    return ReleasedDisk(p, tuple(float(x) for x in extra_spin))
