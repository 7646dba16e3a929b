"""A fourth system defined in the test suite only: the spherical pendulum, in the three pieces the
product asks of a system (its equations, the driver's adapter, its description), registered with
:func:`mechviz.dynamics.registry.register` by the tests that use it (:func:`registered`).

A point on a rod of length ``l`` [m] under gravity ``g`` [m/s^2], per unit mass, in spherical
angles: ``theta`` [rad] from the downward vertical, ``phi`` [rad] about it, ``omega = theta'``,
``nu = phi'`` [rad/s]. From ``L = l^2 (theta'^2 + sin^2 theta phi'^2) / 2 + g l cos theta``::

    theta'' = sin theta cos theta phi'^2 - (g / l) sin theta
    phi''   = -2 cos theta theta' phi' / sin theta

regular away from the poles; with ``L_z = l^2 sin^2 theta phi' != 0`` the motion keeps off them
(the centrifugal barrier). Conserved: ``E = l^2 (omega^2 + sin^2 theta nu^2) / 2 - g l cos theta``
[J/kg] and ``L_z`` [m^2/s], neither of them a state component.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import sympy as sp

from mechviz.dynamics import params as _v
from mechviz.dynamics.codegen.equations import Equations
from mechviz.dynamics.forms import SystemForms
from mechviz.dynamics.registry import Registration, register
from mechviz.dynamics.spec import Setting, SystemSpec, param
from mechviz.dynamics.systems import Adapter

NAME = "spherical-pendulum"


def spherical_pendulum() -> Equations:
    th, ph, om, nu = sp.symbols("theta phi omega nu", real=True)
    length, g = sp.symbols("l g", positive=True)
    return Equations(
        "spherical_pendulum",
        (th, ph, om, nu),
        (length, g),
        (
            om,
            nu,
            sp.sin(th) * sp.cos(th) * nu**2 - g / length * sp.sin(th),
            -2 * sp.cos(th) * om * nu / sp.sin(th),
        ),
    )


EQ = spherical_pendulum()
#: Its compiled forms, generated from :data:`EQ` (compiled on first call).
FORMS = SystemForms.from_equations(EQ)


@dataclass(frozen=True)
class PendulumParams:
    """Rod length ``length`` [m] and ``gravity`` [m/s^2], both positive."""

    length: float = 1.3
    gravity: float = 9.81

    def __post_init__(self) -> None:
        _v.coerce(self, dict.fromkeys(("length", "gravity"), _v.positive))

    def kernel_params(self) -> np.ndarray:
        """``[l, g]``, the order of :data:`EQ`'s parameters."""
        return np.array([self.length, self.gravity])


def invariants(p: PendulumParams, states: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(E, L_z)`` [J/kg, m^2/s] of states ``(..., 4)``."""
    s = np.asarray(states, dtype=float)
    l, g = p.length, p.gravity
    th, om, nu = s[..., 0], s[..., 2], s[..., 3]
    sin = np.sin(th)
    return 0.5 * l * l * (om**2 + sin**2 * nu**2) - g * l * np.cos(th), l * l * sin**2 * nu


def start_state(tilt: float, swing: float, precession: float) -> np.ndarray:
    """At ``theta = tilt`` [rad], ``phi = 0``, with rates ``swing`` and ``precession`` [rad/s]."""
    return np.array([tilt, 0.0, swing, precession])


#: The default start: a tilted, precessing swing (theta between about 0.6 and 1.6 rad).
START = (1.0, 0.3, 1.7)


@dataclass(frozen=True)
class SphericalPendulum(Adapter):
    """The spherical pendulum as the driver sees it; its compiled forms are its own."""

    params: PendulumParams = PendulumParams()
    name = NAME
    sys_id = FORMS
    state_names = ("theta", "phi", "omega", "nu")
    state_labels: ClassVar[dict[str, str]] = {
        "theta": "polar angle θ [rad]",
        "phi": "azimuth φ [rad]",
        "omega": "rate θ' [rad/s]",
        "nu": "rate φ' [rad/s]",
    }
    quantity_labels: ClassVar[dict[str, str]] = {"Lz": "L_z per unit mass [m²/s]"}
    amplitude = ("rad", "tilt θ0, precessing at 0.7 of the conical rate [rad]", (0.2, 1.2))

    def amplitude_state(self, a: float) -> np.ndarray:
        """Tilted by ``a`` [rad] at rest in theta, precessing at 0.7 of the rate of the conical
        pendulum at that tilt (``sqrt(g / (l cos a))``): it nutates below ``a``."""
        rate = math.sqrt(self.params.gravity / (self.params.length * math.cos(a)))
        return start_state(a, 0.0, 0.7 * rate)

    def default_state(self) -> np.ndarray:
        return start_state(*START)

    def energy(self, states: np.ndarray) -> np.ndarray:
        return invariants(self.params, states)[0]

    def energy_floor(self) -> float:
        """``-g l``: hanging at rest."""
        return -self.params.gravity * self.params.length

    def energy_above_floor(self, states: np.ndarray) -> np.ndarray:
        """``E + g l`` as ``l^2 (omega^2 + sin^2 theta nu^2) / 2 + 2 g l sin^2(theta / 2)``
        (no cancellation at small swings)."""
        s = np.asarray(states, dtype=float)
        l, g = self.params.length, self.params.gravity
        th, om, nu = s[..., 0], s[..., 2], s[..., 3]
        kinetic = 0.5 * l * l * (om**2 + np.sin(th) ** 2 * nu**2)
        return kinetic + 2.0 * g * l * np.sin(0.5 * th) ** 2

    def fastest_frequency(self, state: np.ndarray | None = None) -> float:
        """The small swing's ``sqrt(g / l)``, or the fastest rate of the state if higher."""
        s = np.atleast_2d(self.default_state() if state is None else state)
        rate = float(np.abs(s[:, 2:4]).max(initial=0.0))
        return max(math.sqrt(self.params.gravity / self.params.length), rate)

    def time_scale(self, states: np.ndarray) -> float:
        return 2.0 * math.pi / self.fastest_frequency(states)

    def invariants(self, states: np.ndarray) -> dict[str, np.ndarray]:
        energy, lz = invariants(self.params, states)
        return {"energy": energy, "Lz": lz}

    def quantities(self, states: np.ndarray) -> dict[str, np.ndarray]:
        return {"Lz": invariants(self.params, states)[1]}

    def has_exact(self, state0: np.ndarray) -> bool:
        return False

    def exact(self, state0: np.ndarray, t: float) -> np.ndarray | None:
        return None

    def error(self, y: np.ndarray, ref: np.ndarray) -> np.ndarray:
        d = np.linalg.norm(np.asarray(y) - ref, axis=-1)
        return d / np.maximum(np.linalg.norm(ref, axis=-1), 1e-300)


def _tilt(name: str, value) -> float:
    v = _v.finite(name, value)
    if not 0.0 < v < math.pi:
        raise _v.SettingError(name, f"{name} must be strictly between 0 and pi rad, got {value!r}")
    return v


def _precession(name: str, value) -> float:
    v = _v.nonzero(name, value)
    return _v.finite(name, v)


def _build(p: PendulumParams, start: dict) -> tuple[SphericalPendulum, np.ndarray]:
    return SphericalPendulum(p), start_state(start["tilt"], start["swing"], start["precession"])


def _analysis(p: PendulumParams) -> dict:
    w = math.sqrt(p.gravity / p.length)
    return {"small_swing_frequency": w, "small_swing_period": 2 * math.pi / w}


SPEC = SystemSpec(
    name=NAME,
    title="Spherical pendulum",
    Params=PendulumParams,
    params=(
        param("length", "Length l", "m", span=(0.1, 2.0)),
        param("gravity", "Gravity g", "m/s²", span=(1e-2, 1e3)),
    ),
    start=(
        Setting("tilt", "Tilt θ0", "rad", START[0], _tilt, "start angle from the vertical [rad]"),
        Setting("swing", "Swing rate θ'0", "rad/s", START[1], _v.finite, "start θ' [rad/s]"),
        Setting(
            "precession",
            "Precession rate φ'0",
            "rad/s",
            START[2],
            _precession,
            "start φ' [rad/s] (nonzero: L_z keeps the motion off the poles)",
        ),
    ),
    build=_build,
    default_method=lambda start: "rk4",
    dt=1 / 120,
    analysis=_analysis,
)


def registered() -> Registration:
    """The spherical pendulum registered (undo with the result, or use it in ``with``)."""
    return register(SPEC, (SphericalPendulum,))
