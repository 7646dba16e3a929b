"""The three systems as the driver sees them: state layout, compiled id, invariants, exact flow.

Each adapter wraps a parameter dataclass from its physics module and adds nothing physical of its
own; it only tells :class:`dynamics.simulation.Simulation` how to treat the system.

Besides the state layout, energy, invariants and exact flow, each adapter gives the driver two
scales: ``energy_floor()``, the lowest energy the system can have (at rest in its stable
equilibrium), so that the relative energy error ``(E - E0) / (E0 - floor)`` measures the energy
that moves and not an arbitrary zero of the potential; and ``time_scale(states)``, the shortest
period of the motion [s], from which the driver estimates the steps of an adaptive run.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import cyclotron, disk, hoop
from .integrators import kernels


def _period(omega: float) -> float:
    """``2 pi / |omega|`` [s]; infinite for no rotation (and for an |omega| that underflows)."""
    w = abs(float(omega))
    return 2.0 * np.pi / w if w > 0.0 else float("inf")


def _relative(y: np.ndarray, ref: np.ndarray) -> np.ndarray:
    d = np.linalg.norm(np.asarray(y) - ref, axis=-1)
    return d / np.maximum(np.linalg.norm(ref, axis=-1), 1e-300)


@dataclass(frozen=True)
class Cyclotron:
    """Charge in a uniform field (:mod:`dynamics.cyclotron`)."""

    params: cyclotron.CyclotronParams = cyclotron.CyclotronParams()
    name = "cyclotron"
    sys_id = kernels.CYCLOTRON
    state_names = cyclotron.STATE_NAMES

    def kernel_params(self) -> np.ndarray:
        return self.params.kernel_params()

    def default_state(self) -> np.ndarray:
        return np.array([1.0, 0.0, 0.0, 0.0, 1.0, 0.1])

    def energy(self, states: np.ndarray) -> np.ndarray:
        return cyclotron.energy(self.params, states)

    def energy_floor(self) -> float:
        """0: the energy is all kinetic."""
        return 0.0

    def time_scale(self, states: np.ndarray) -> float:
        """The gyro-period ``2 pi m / |qB|``."""
        return _period(cyclotron.gyrofrequency(self.params))

    def invariants(self, states: np.ndarray) -> dict[str, np.ndarray]:
        return {
            "energy": self.energy(states),
            "canonical_angular_momentum": cyclotron.canonical_angular_momentum(self.params, states),
        }

    def has_exact(self, state0: np.ndarray) -> bool:
        """Always: the helix is closed form from any state."""
        return True

    def exact(self, state0: np.ndarray, t: float) -> np.ndarray | None:
        return cyclotron.exact_solution(self.params, state0, t)

    def error(self, y: np.ndarray, ref: np.ndarray) -> np.ndarray:
        d = np.linalg.norm(np.asarray(y) - ref, axis=-1)
        return d / np.linalg.norm(ref[..., [0, 1, 3, 4]], axis=-1)


@dataclass(frozen=True)
class Hoop:
    """Bead on a hanging hoop (:mod:`dynamics.hoop`)."""

    params: hoop.HoopParams = hoop.HoopParams()
    name = "hoop"
    sys_id = kernels.HOOP
    state_names = hoop.STATE_NAMES

    def kernel_params(self) -> np.ndarray:
        return self.params.kernel_params()

    def default_state(self) -> np.ndarray:
        return hoop.mode_state(self.params, (0.3, 0.0))

    def energy(self, states: np.ndarray) -> np.ndarray:
        return hoop.energy(self.params, states)

    def energy_floor(self) -> float:
        """The energy hanging at rest, ``-(M + 2m) g a`` (the potential's zero is at the pivot)."""
        return float(hoop.energy(self.params, np.zeros(4)))

    def time_scale(self, states: np.ndarray) -> float:
        """The period of the faster normal mode, or the time the fastest angle takes to turn
        once if that is shorter (a hoop set whirling)."""
        rate = float(np.max(np.abs(np.atleast_2d(states)[:, 2:4]), initial=0.0))
        return min(_period(hoop.normal_modes(self.params)[0][-1]), _period(rate))

    def invariants(self, states: np.ndarray) -> dict[str, np.ndarray]:
        return {"energy": self.energy(states)}

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
class ReleasedDisk:
    """The disk with its bead after the axle is removed: a free rigid body (:mod:`dynamics.disk`)."""

    params: disk.DiskParams = disk.DiskParams()
    extra_spin: tuple[float, float, float] = (0.0, 0.0, 0.0)
    name = "free-body"
    sys_id = kernels.FREE_BODY
    state_names = disk.FREE_STATE_NAMES

    def kernel_params(self) -> np.ndarray:
        return disk.free_kernel_params(self.params)

    def default_state(self) -> np.ndarray:
        return disk.released_initial_state(self.params, self.extra_spin)

    def energy(self, states: np.ndarray) -> np.ndarray:
        return disk.free_energy(self.kernel_params(), states)

    def energy_floor(self) -> float:
        """0: the energy is all rotational (no gravity acts on the free body)."""
        return 0.0

    def time_scale(self, states: np.ndarray) -> float:
        """The period of the fastest body-frame angular velocity component."""
        w = np.abs(np.atleast_2d(states)[:, :3])
        return _period(float(np.max(w)) if w.size else 0.0)

    def invariants(self, states: np.ndarray) -> dict[str, np.ndarray]:
        L = disk.free_angular_momentum_space(self.kernel_params(), states)
        return {
            "energy": self.energy(states),
            "angular_momentum": L,
            "angular_momentum_norm": np.linalg.norm(L, axis=-1),
        }

    def has_exact(self, state0: np.ndarray) -> bool:
        return False

    def exact(self, state0: np.ndarray, t: float) -> np.ndarray | None:
        return None

    def error(self, y: np.ndarray, ref: np.ndarray) -> np.ndarray:
        return _relative(y, ref)


@dataclass(frozen=True)
class DrivenDisk:
    """The disk turned uniformly about its axle: exact, state ``(angle, omega)``."""

    params: disk.DiskParams = disk.DiskParams()
    name = "driven-disk"
    sys_id = None
    state_names = ("angle", "omega")

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

    def time_scale(self, states: np.ndarray) -> float:
        """The period of the spin ``2 pi / |omega|``."""
        return _period(self.params.omega)

    def invariants(self, states: np.ndarray) -> dict[str, np.ndarray]:
        return {"energy": self.energy(states)}

    def has_exact(self, state0: np.ndarray) -> bool:
        return True

    def exact(self, state0: np.ndarray, t: float) -> np.ndarray:
        s0 = np.asarray(state0, dtype=float)
        out = s0.copy()
        out[..., 0] = s0[..., 0] + s0[..., 1] * t
        return out

    def error(self, y: np.ndarray, ref: np.ndarray) -> np.ndarray:
        return _relative(y, ref)


System = Cyclotron | Hoop | ReleasedDisk | DrivenDisk

# Every system by the name the methods and the driver know it by (``Method.systems``).
SYSTEMS: dict[str, type] = {s.name: s for s in (Cyclotron, Hoop, ReleasedDisk, DrivenDisk)}
