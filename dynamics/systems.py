"""The three systems as the driver sees them: state layout, compiled id, invariants, exact flow.

Each adapter wraps a parameter dataclass from its physics module and adds nothing physical of its
own; it only tells :class:`mechviz.dynamics.simulation.Simulation` how to treat the system.

Besides the state layout, energy, invariants and exact flow, each adapter gives the driver two
scales: ``energy_floor()``, the lowest energy the system can have (at rest in its stable
equilibrium), and ``energy_above_floor(states)``, ``E - floor`` evaluated directly (not as that
difference, which would cancel at small motions), so that the relative energy error
``(E - E0) / (E0 - floor)`` measures the energy that moves, to round-off at any amplitude, and
not an arbitrary zero of the potential; and ``time_scale(states)``, the shortest period of the
motion [s], from which the driver estimates the steps of an adaptive run.

Each adapter also names the quantities its theory is told in, beyond the state
(``quantity_labels``: name -> label with the unit; ``quantities(states)``): the charge's distance
from the axis, radial and canonical angular momentum and effective potential, the hoop's modal
coordinates, the disk's angular momentum in space. The API's runs, the recordings' CSV and the
viewer's plots all take them from here.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from . import cyclotron, disk, hoop, measure
from .forms import is_given
from .ids import CYCLOTRON, DRIVEN_DISK, FREE_BODY, HOOP, NAMES

#: The default starts, shared by the adapters and the descriptions below: the cyclotron's
#: (speed [m/s], centre (x, y) [m], vz [m/s]), the hoop's mode amplitudes [rad], the disk's
#: extra spin at release [rad/s] (disk frame; it seeds the tumble).
CYCLOTRON_START = (1.0, (0.0, 0.0), 0.05)
HOOP_MODES = (0.25, 0.25)
DISK_EXTRA_SPIN = (0.0, 0.0, 0.02)


def _period(omega: float) -> float:
    """``2 pi / |omega|`` [s]; infinite for no rotation (and for an |omega| that underflows)."""
    w = abs(float(omega))
    return 2.0 * np.pi / w if w > 0.0 else float("inf")


class _Adapter:
    """What every adapter has unless it says more.

    Which methods apply follows from two facts a system states about itself: ``closed_form``
    (its exact flow is known from every state: the ``exact`` method) and ``symmetric_step``
    (the name of its own symmetric second-order step, which ``yoshida4`` composes; ``None``
    when it has none). Every system with a compiled right-hand side (``sys_id``) takes the
    general methods.
    """

    #: The system's name (from its compiled id, :data:`mechviz.dynamics.ids.NAMES`, or its own
    #: forms' name, unless it says one) and its parameter dataclass (the type of its default
    #: ``params``): both derived when the adapter is defined.
    name: ClassVar[str]
    Params: ClassVar[type]
    #: Each state component's label with its unit, in state order (a plot's axis, a CSV
    #: column's description); the names alone unless the system says more.
    state_labels: ClassVar[dict[str, str]] = {}
    closed_form: ClassVar[bool] = False
    symmetric_step: ClassVar[str | None] = None
    #: Where a method in this system's variables keeps less structure than its label (method
    #: name -> (structure kept, why)), and how a step's structure is measured here: "canonical"
    #: (symplecticity in :meth:`canonical_maps`' variables) or "lie-poisson" (a free rigid body).
    method_structure: ClassVar[dict[str, tuple[tuple[str, ...], str]]] = {}
    structure_check: ClassVar[str] = "canonical"
    #: Whether the stability atlas's chaos map (:mod:`mechviz.dynamics.atlas.grid`) covers this
    #: system's start plane.
    chaos_map: ClassVar[bool] = False

    def canonical_maps(self):
        """``(to_canonical, from_canonical)``: the state to canonical ``(q, p)`` and back."""
        raise NotImplementedError(f"{self.name} states no canonical variables")

    #: The one-amplitude family of starts the stability atlas sweeps: its unit, its axis label
    #: and the default range of amplitudes (see :meth:`amplitude_state`).
    amplitude: ClassVar[tuple[str, str, tuple[float, float]] | None] = None

    #: The quantities beyond the state, by name (a column of the API's runs and of a recording's
    #: CSV): the label with its unit, as a plot's axis shows it.
    quantity_labels: ClassVar[dict[str, str]] = {}

    def quantities(self, states: np.ndarray) -> dict[str, np.ndarray]:
        """Each of :attr:`quantity_labels` for states ``(..., d)``, shaped ``(...)``."""
        return {}

    def __init_subclass__(cls, **kwargs) -> None:
        super().__init_subclass__(**kwargs)
        # a subclass of an adapter keeps what it does not say anew
        if "name" not in cls.__dict__ and "sys_id" in cls.__dict__:
            sys_id = cls.__dict__["sys_id"]
            cls.name = sys_id.name if is_given(sys_id) else NAMES[sys_id]
        if "params" in cls.__dict__:
            cls.Params = type(cls.__dict__["params"])
        labels = cls.__dict__.get("state_labels") or {n: n for n in cls.state_names}
        if tuple(labels) != tuple(cls.state_names):
            raise TypeError(f"{cls.__name__}: state_labels must name {cls.state_names} in order")
        cls.state_labels = labels

    def kernel_params(self) -> np.ndarray:
        """The parameters as the compiled kernels take them (the physics module's layout)."""
        return self.params.kernel_params()

    def report(self, t: float) -> dict[str, list[float]]:
        """Figures beyond the state for a run's summary at time ``t`` [s]: none."""
        return {}


#: The base of every adapter, a registered system's too (:func:`mechviz.dynamics.registry.
#: register`). Besides what :class:`_Adapter` defaults, an adapter states ``params`` (a frozen
#: parameter dataclass with ``kernel_params()``, or its own :meth:`~_Adapter.kernel_params`),
#: ``sys_id`` (a compiled id of the shipped tables, a
#: :class:`~mechviz.dynamics.forms.SystemForms` of its own, or None for no compiled form),
#: ``state_names``, and ``default_state``, ``energy``, ``energy_floor``, ``energy_above_floor``,
#: ``time_scale``, ``fastest_frequency``, ``invariants``, ``has_exact``, ``exact`` and ``error``
#: (as the three systems' below).
Adapter = _Adapter


def _relative(y: np.ndarray, ref: np.ndarray) -> np.ndarray:
    d = np.linalg.norm(np.asarray(y) - ref, axis=-1)
    return d / np.maximum(np.linalg.norm(ref, axis=-1), 1e-300)


@dataclass(frozen=True)
class Cyclotron(_Adapter):
    """Charge in a uniform field along +z (:mod:`mechviz.dynamics.cyclotron`): state ``(x, y, z, vx, vy,
    vz)`` [m, m/s]; its exact flow is a helix, known from every state (the ``exact`` method)."""

    params: cyclotron.CyclotronParams = cyclotron.CyclotronParams()

    def canonical_maps(self):
        return cyclotron.canonical_maps(self.params)

    sys_id = CYCLOTRON
    state_names = cyclotron.STATE_NAMES
    state_labels: ClassVar[dict[str, str]] = {
        n: f"{n} [{'m' if n[0] != 'v' else 'm/s'}]" for n in cyclotron.STATE_NAMES
    }
    closed_form = True
    symmetric_step = "boris"
    amplitude = ("m/s", "speed across the field [m/s]", (0.1, 2.0))

    def default_state(self) -> np.ndarray:
        """The start of :data:`CYCLOTRON`: the circle of transverse speed 1 m/s about the axis."""
        return cyclotron.circular_orbit_state(self.params, *CYCLOTRON_START)

    def energy(self, states: np.ndarray) -> np.ndarray:
        return cyclotron.energy(self.params, states)

    def energy_floor(self) -> float:
        """0: the energy is all kinetic."""
        return 0.0

    def energy_above_floor(self, states: np.ndarray) -> np.ndarray:
        return self.energy(states)

    def time_scale(self, states: np.ndarray) -> float:
        """The gyro-period ``2 pi m / |qB|``."""
        return _period(cyclotron.gyrofrequency(self.params))

    def fastest_frequency(self, state: np.ndarray | None = None) -> float:
        """The gyrofrequency ``|q B / m|`` [rad/s], from any state."""
        return cyclotron.gyrofrequency(self.params)

    def amplitude_state(self, a: float) -> np.ndarray:
        """At the origin moving along +y at speed ``a`` [m/s] across the field."""
        out = np.zeros(6)
        out[4] = a
        return out

    def invariants(self, states: np.ndarray) -> dict[str, np.ndarray]:
        return {
            "energy": self.energy(states),
            "canonical_angular_momentum": cyclotron.canonical_angular_momentum(self.params, states),
        }

    quantity_labels: ClassVar[dict[str, str]] = {
        "r": "distance from the axis r [m]",
        "p_r": "radial momentum p_r [kg m/s]",
        "p_phi": "canonical ang. momentum p_φ [kg m²/s]",
        "V_eff": "V_eff(r) [J]",
    }

    def quantities(self, states: np.ndarray) -> dict[str, np.ndarray]:
        """The radial motion of the seed's argument: ``r``, ``p_r``, ``p_phi`` and
        ``V_eff(r)`` for each state's own ``p_phi`` (infinite on the axis, ``r = 0``)."""
        r, p_r = cyclotron.radial_coordinates(self.params, states)
        p_phi = cyclotron.canonical_angular_momentum(self.params, states)
        with np.errstate(divide="ignore", invalid="ignore"):
            v_eff = cyclotron.effective_potential(self.params, r, p_phi)
        return {"r": r, "p_r": p_r, "p_phi": p_phi, "V_eff": v_eff}

    def has_exact(self, state0: np.ndarray) -> bool:
        """Always: the helix is closed form from any state."""
        return True

    def exact(self, state0: np.ndarray, t: float) -> np.ndarray | None:
        return cyclotron.exact_solution(self.params, state0, t)

    def error(self, y: np.ndarray, ref: np.ndarray) -> np.ndarray:
        d = np.linalg.norm(np.asarray(y) - ref, axis=-1)
        return d / np.linalg.norm(ref[..., [0, 1, 3, 4]], axis=-1)


@dataclass(frozen=True)
class Hoop(_Adapter):
    """Bead on a hanging hoop (:mod:`mechviz.dynamics.hoop`)."""

    method_structure: ClassVar[dict[str, tuple[tuple[str, ...], str]]] = {
        "midpoint": (
            ("symmetric",),
            "not symplectic: applied to (theta, theta'), not canonical variables",
        ),
    }

    def canonical_maps(self):
        return hoop.canonical_maps(self.params)

    params: hoop.HoopParams = hoop.HoopParams()
    sys_id = HOOP
    state_names = hoop.STATE_NAMES
    state_labels: ClassVar[dict[str, str]] = {
        "theta1": "hoop angle θ1 [rad]",
        "theta2": "bead angle θ2 [rad]",
        "omega1": "hoop rate θ1' [rad/s]",
        "omega2": "bead rate θ2' [rad/s]",
    }
    symmetric_step = "verlet"
    chaos_map = True
    amplitude = ("rad", "amplitude A of each normal mode [rad]", (0.01, 1.5))

    def default_state(self) -> np.ndarray:
        """The start of :data:`HOOP`: both normal modes, at rest."""
        return hoop.mode_state(self.params, HOOP_MODES)

    def energy(self, states: np.ndarray) -> np.ndarray:
        return hoop.energy(self.params, states)

    def energy_floor(self) -> float:
        """The energy hanging at rest, ``-(M + 2m) g a`` (the potential's zero is at the pivot)."""
        return float(hoop.energy(self.params, np.zeros(4)))

    def energy_above_floor(self, states: np.ndarray) -> np.ndarray:
        """The energy above hanging at rest, without cancellation (:func:`hoop.energy_above_rest`)."""
        return hoop.energy_above_rest(self.params, states)

    def time_scale(self, states: np.ndarray) -> float:
        """The period of the faster normal mode, or the time the fastest angle takes to turn
        once if that is shorter (a hoop set whirling)."""
        # the array's own max, not np.max: the wrapper costs more than a few states' work
        rate = float(np.abs(np.atleast_2d(states)[:, 2:4]).max(initial=0.0))
        return min(_period(hoop.mode_frequencies(self.params)[1]), _period(rate))

    def fastest_frequency(self, state: np.ndarray | None = None) -> float:
        """The higher normal mode ``sqrt((1 + m/M) g / a)`` [rad/s] (the linearisation about
        hanging at rest, whatever the state)."""
        return float(hoop.normal_modes(self.params)[0][-1])

    def amplitude_state(self, a: float) -> np.ndarray:
        """Both normal modes at amplitude ``a`` [rad], at rest."""
        return hoop.mode_state(self.params, (a, a))

    def invariants(self, states: np.ndarray) -> dict[str, np.ndarray]:
        return {"energy": self.energy(states)}

    quantity_labels: ClassVar[dict[str, str]] = {
        "q1": "mode-1 coordinate q1 [rad]",
        "q2": "mode-2 coordinate q2 [rad]",
    }

    def quantities(self, states: np.ndarray) -> dict[str, np.ndarray]:
        """The angles on the two normal-mode shapes (:func:`mechviz.dynamics.measure.modal_coordinates`)."""
        angles = np.asarray(states, dtype=float)[..., :2]
        shapes = hoop.normal_modes(self.params)[1]
        q = measure.modal_coordinates(angles.reshape(-1, 2), shapes).reshape(angles.shape)
        return {"q1": q[..., 0], "q2": q[..., 1]}

    def has_exact(self, state0: np.ndarray) -> bool:
        """Whether :meth:`exact` has a closed form from ``state0``."""
        return self.exact(state0, 0.0) is not None

    def exact(self, state0: np.ndarray, t: float) -> np.ndarray | None:
        """Closed form only on the mode-1 manifold (the whole body a rigid pendulum)."""
        s0 = np.atleast_2d(state0)
        if not all(hoop.on_mode1_manifold(s) for s in s0):
            return None
        try:
            out = np.stack([hoop.mode1_exact_solution(self.params, s, t) for s in s0])
        except ValueError:  # over the top: no libration in closed form, use the reference
            return None
        return out if np.ndim(state0) == 2 else out[0]

    def error(self, y: np.ndarray, ref: np.ndarray) -> np.ndarray:
        return _relative(y, ref)


@dataclass(frozen=True)
class ReleasedDisk(_Adapter):
    """The disk with its bead after the axle is removed: a free rigid body (:mod:`mechviz.dynamics.disk`)."""

    structure_check: ClassVar[str] = "lie-poisson"
    method_structure: ClassVar[dict[str, tuple[tuple[str, ...], str]]] = {
        "midpoint": (
            ("symmetric",),
            "not Lie-Poisson: applied to (omega, q); it keeps |L| and E, quadratic in omega",
        ),
    }

    params: disk.DiskParams = disk.DiskParams()
    extra_spin: tuple[float, float, float] = (0.0, 0.0, 0.0)  # disk frame [rad/s], at release
    sys_id = FREE_BODY
    state_names = disk.FREE_STATE_NAMES
    # 1, 2, 3: the principal axes about the centre of mass, smallest moment first
    state_labels: ClassVar[dict[str, str]] = {
        **{f"w{k}": f"body ω{'₁₂₃'[k - 1]} [rad/s]" for k in (1, 2, 3)},
        **{f"q{k}": f"quaternion q{k}" for k in range(4)},
    }
    symmetric_step = "splitting"
    amplitude = ("rad/s", "extra spin (A, 0, A) at release [rad/s]", (0.0, 1.0))

    def kernel_params(self) -> np.ndarray:
        return disk.free_kernel_params(self.params)

    def default_state(self) -> np.ndarray:
        return disk.released_initial_state(self.params, self.extra_spin)

    def energy(self, states: np.ndarray) -> np.ndarray:
        return disk.free_energy(self.kernel_params(), states)

    def energy_floor(self) -> float:
        """0: the energy is all rotational (no gravity acts on the free body)."""
        return 0.0

    def energy_above_floor(self, states: np.ndarray) -> np.ndarray:
        return self.energy(states)

    def time_scale(self, states: np.ndarray) -> float:
        """The period of the fastest body-frame angular velocity component."""
        w = np.abs(np.atleast_2d(states)[:, :3])
        return _period(float(w.max()) if w.size else 0.0)

    def fastest_frequency(self, state: np.ndarray | None = None) -> float:
        """The spectral radius [rad/s] of the Jacobian of the right-hand side at ``state``
        (default: the start at release), by central differences: the tumble has no single
        frequency, and the linearisation is what a step has to resolve."""
        y0 = np.asarray(self.default_state() if state is None else state, dtype=float)
        from .integrators.kernels import RHS  # numba: not needed to run the disk

        p = self.kernel_params()
        rhs = RHS[self.sys_id]
        d = y0.size
        jac = np.empty((d, d))
        fp, fm = np.empty(d), np.empty(d)
        for j in range(d):
            e = 1e-6 * max(1.0, abs(y0[j]))
            yp, ym = y0.copy(), y0.copy()
            yp[j] += e
            ym[j] -= e
            rhs(yp, p, fp)
            rhs(ym, p, fm)
            jac[:, j] = (fp - fm) / (2 * e)
        return float(np.max(np.abs(np.linalg.eigvals(jac))))

    def amplitude_state(self, a: float) -> np.ndarray:
        """Released with the extra spin ``(a, 0, a)`` [rad/s] (disk frame)."""
        return disk.released_initial_state(self.params, (a, 0.0, a))

    def invariants(self, states: np.ndarray) -> dict[str, np.ndarray]:
        L = disk.free_angular_momentum_space(self.kernel_params(), states)
        return {
            "energy": self.energy(states),
            "angular_momentum": L,
            "angular_momentum_norm": np.linalg.norm(L, axis=-1),
        }

    quantity_labels: ClassVar[dict[str, str]] = {
        f"L{a}": f"L_{a} about CM [kg m²/s]" for a in "xyz"
    }

    def quantities(self, states: np.ndarray) -> dict[str, np.ndarray]:
        """The angular momentum about the centre of mass in space (conserved)."""
        L = disk.free_angular_momentum_space(self.kernel_params(), states)
        return {f"L{a}": L[..., k] for k, a in enumerate("xyz")}

    def has_exact(self, state0: np.ndarray) -> bool:
        return False

    def exact(self, state0: np.ndarray, t: float) -> np.ndarray | None:
        return None

    def error(self, y: np.ndarray, ref: np.ndarray) -> np.ndarray:
        return _relative(y, ref)


@dataclass(frozen=True)
class DrivenDisk(_Adapter):
    """The disk turned uniformly about its axle: exact, state ``(angle, omega)``."""

    params: disk.DiskParams = disk.DiskParams()
    name = DRIVEN_DISK
    sys_id = None
    state_names = ("angle", "omega")
    state_labels: ClassVar[dict[str, str]] = {
        "angle": "angle about the axle [rad]",
        "omega": "spin ω [rad/s]",
    }
    closed_form = True

    def kernel_params(self) -> np.ndarray:
        return np.array([self.params.omega])

    def default_state(self) -> np.ndarray:
        return np.array([0.0, self.params.omega])

    def energy(self, states: np.ndarray) -> np.ndarray:
        w = np.asarray(states)[..., 1]
        return 0.5 * disk.inertia_tensor(self.params)[1, 1] * w * w

    def energy_floor(self) -> float:
        """0: the energy is all rotational."""
        return 0.0

    def energy_above_floor(self, states: np.ndarray) -> np.ndarray:
        return self.energy(states)

    def time_scale(self, states: np.ndarray) -> float:
        """The period of the spin ``2 pi / |omega|``."""
        return _period(self.params.omega)

    def fastest_frequency(self, state: np.ndarray | None = None) -> float:
        """The spin ``|omega|`` [rad/s]."""
        return abs(self.params.omega)

    def invariants(self, states: np.ndarray) -> dict[str, np.ndarray]:
        return {"energy": self.energy(states)}

    quantity_labels: ClassVar[dict[str, str]] = {f"L{a}": f"L_{a} about A [kg m²/s]" for a in "xyz"}

    def quantities(self, states: np.ndarray) -> dict[str, np.ndarray]:
        """The angular momentum about A in space: its tip circles the axle."""
        s = np.asarray(states, dtype=float)
        L = disk.rotation_about_axle(s[..., 0]) @ (disk.inertia_tensor(self.params) @ disk.AXLE)
        L = L * s[..., 1, None]
        return {f"L{a}": L[..., k] for k, a in enumerate("xyz")}

    def has_exact(self, state0: np.ndarray) -> bool:
        return True

    def exact(self, state0: np.ndarray, t: float) -> np.ndarray:
        s0 = np.asarray(state0, dtype=float)
        out = s0.copy()
        out[..., 0] = s0[..., 0] + s0[..., 1] * t
        return out

    def error(self, y: np.ndarray, ref: np.ndarray) -> np.ndarray:
        return _relative(y, ref)

    def report(self, t: float) -> dict[str, list[float]]:
        """The bearing forces [N] at time ``t`` [s], for a run's summary."""
        return {
            "bearing_force_b": disk.bearing_force_b(self.params, t).tolist(),
            "bearing_force_a": disk.bearing_force_a(self.params, t).tolist(),
        }


System = Cyclotron | Hoop | ReleasedDisk | DrivenDisk

# Every system by the name the methods and the driver know it by (the one registry,
# :mod:`mechviz.dynamics.registry`, looks them up by name).
SYSTEMS: dict[str, type] = {s.name: s for s in (Cyclotron, Hoop, ReleasedDisk, DrivenDisk)}

#: Each system's kernel parameters, by the adapter's identity. An adapter of these kinds is
#: frozen, so they never change: a new run or solver of a system already seen takes the same
#: array instead of working it out again. The entry holds the adapter, so that its identity is
#: not reused while it is stored. The array is shared: the compiled kernels only read it.
_KERNEL_PARAMS: dict[int, tuple[System, np.ndarray]] = {}
_FROZEN_KINDS = frozenset((Cyclotron, Hoop, ReleasedDisk, DrivenDisk))


def shared_kernel_params(system: System) -> np.ndarray:
    """``system.kernel_params()`` as a contiguous float64 array, worked out once per adapter of
    the four kinds above (another kind, a subclass included, every time). Not to be written."""
    entry = _KERNEL_PARAMS.get(id(system))
    if entry is not None and entry[0] is system:
        return entry[1]
    p = np.ascontiguousarray(system.kernel_params(), dtype=np.float64)
    if type(system) in _FROZEN_KINDS:
        if len(_KERNEL_PARAMS) >= 1024:  # a scan over parameters: keep the table bounded
            _KERNEL_PARAMS.clear()
        _KERNEL_PARAMS[id(system)] = (system, p)
    return p
