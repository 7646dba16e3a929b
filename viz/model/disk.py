"""The spinning disk's model: a disk with a bead on its rim, turned about an axle along a
diameter, headless.

*Driven*: the exact uniform rotation (``mechviz.dynamics.DrivenDisk``, method ``exact``), whose bearing
forces (``mechviz.dynamics.disk.bearing_force_a/b``) the motion's dL/dt measures. *Released*: the axle is
removed at ``t = 0`` and the free body tumbles (``mechviz.dynamics.ReleasedDisk``, integrated by the chosen
method); the wobble's growth rate and the polhode's period are measured from the motion. The view
is :class:`mechviz.viz.scene.disk.DiskExhibit`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from mechviz import dynamics
from mechviz.dynamics import disk as dk
from mechviz.dynamics import measure
from mechviz.dynamics.registry import DISK

from .base import ExhibitConfig, ExhibitModel, Motion, finite_numbers
from .figures import figure, keep
from .plot import Curve
from .traces import Traces

MODES = DISK.setting("motion").choices


@dataclass(frozen=True)
class DiskConfig(ExhibitConfig):
    """Settings of the disk exhibit: ``mode`` "driven" (the exact uniform rotation; ``method``
    is not used) or "released" (the free body, integrated by ``method``), ``extra_spin`` [rad/s]
    added at release in the disk frame (seeds the tumble), ``follow_cm`` (a view option: draw
    the released body in the frame moving with its centre of mass)."""

    system_name: ClassVar[str] = dynamics.ReleasedDisk.name
    spec: ClassVar[dynamics.SystemSpec] = DISK
    #: The keys of a demo file's [initial] table for this exhibit.
    demo_initial_keys: ClassVar[frozenset[str]] = frozenset({"extra_spin"})

    # The method when released: RK4 at one step per frame, the cheapest keeping the on-screen
    # error below 1e-3 of the exhibit over 10 minutes (docs/bench/defaults.md).
    method: str = DISK.default_method({"motion": "released"})
    dt: float = DISK.dt
    params: dict = field(default_factory=DISK.default_params)
    mode: str = DISK.setting("motion").default
    extra_spin: tuple = DISK.setting("extra_spin").default
    follow_cm: bool = True

    def _validate(self) -> None:
        DISK.setting("motion").check(self.mode)
        finite_numbers("extra_spin", self.extra_spin, 3)


def principal_axes_for(p: dk.DiskParams, mode: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(moments, axes (rows), origin)`` in the disk frame: about A (the origin) when driven,
    about the centre of mass when released."""
    if mode == "driven":
        moments, axes = dk.principal_axes(p)
        return moments, axes, np.zeros(3)
    moments, axes = dk.principal_axes_cm(p)
    return moments, axes, dk.centre_of_mass(p)


class DiskModel(ExhibitModel):
    title = "Spinning disk"
    name = "Disk"
    Config = DiskConfig
    view_fields = frozenset({"follow_cm"})
    origin = (0.0, 1.4, 0.0)
    demo_keys: ClassVar[dict[str, str]] = {"extra_spin": "initial.extra_spin"}

    # ------------------------------------------------------------------ hooks (see .hooks)
    @classmethod
    def demo_settings(cls, initial: dict[str, Any], demo: Any, params: dict[str, Any]) -> dict:
        kw: dict[str, Any] = {"mode": demo.motion}
        if "extra_spin" in initial:
            kw["extra_spin"] = initial["extra_spin"]
        return kw

    @classmethod
    def shortest_period(cls, demo: Any, result: dict, extra_spin: bool = True) -> float | None:
        """One turn at the spin, or at the fastest extra spin at release if that is faster."""
        spin = abs(result["parameters"]["omega"])
        if extra_spin and demo.motion == "released" and demo.initial.extra_spin is not None:
            spin = max(spin, max(abs(x) for x in demo.initial.extra_spin))
        return 2 * math.pi / spin if spin else None

    @classmethod
    def draw_motion_chart(cls, ax: Any, demo: Any, tr: Any, params: Any) -> None:
        """Driven: the bearing force from dL/dt and its predicted amplitude. Released: the
        wobble's angular velocity and its predicted growth."""
        t, S = tr.times[tr.main], tr.states[tr.main]
        if demo.motion == "driven":
            F = measure.bearing_force(params, t, S[:, 0, 0], S[:, 0, 1])
            ax.plot(t, F[:, 0], color="tab:blue", label="F_B,x (from dL/dt)")
            ax.plot(t, F[:, 2], color="tab:red", label="F_B,z (from dL/dt)")
            amp = dk.axle_force_amplitude(params)
            for yv in (amp, -amp):
                label = "predicted amplitude 5/8 M R omega^2" if yv > 0 else None
                ax.axhline(yv, color="k", ls="--", lw=1, label=label)
            ax.set_ylabel("bearing force at B [N]")
            return
        w = S[:, 0, :3]
        perp = np.hypot(w[:, 0], w[:, 2])
        ax.semilogy(t, np.maximum(perp, 1e-16), color="tab:blue", label="|w_perp| (wobble)")
        ax.semilogy(t, np.abs(w[:, 1]), color="tab:green", label="|w_2| (about the axle)")
        lam = measure.wobble_growth_rate_theory(dk.free_kernel_params(params), S[0, 0, :3])
        grow = perp[0] * np.exp(lam * t)
        keep = grow < 3 * abs(w[0, 1])
        ax.semilogy(t[keep], grow[keep], "k--", lw=1, label=f"predicted growth exp({lam:.3f} t)")
        ax.set_ylabel("angular velocity [rad/s]")

    @classmethod
    def screen_case(cls) -> tuple[str, dict[str, Any]]:
        """The released disk. On screen: the rotation error times the farthest body point's
        distance from the centre of mass (which itself moves exactly); size: ``2 R``."""
        c = DiskConfig()
        p = c.physics()
        released = dynamics.ReleasedDisk(p, tuple(c.extra_spin))
        rim = np.array([[0.0, 0.0, 0.0], [0.0, 2.0, 0.0], [1.0, 1.0, 0.0], [-1.0, 1.0, 0.0]])
        reach = float(np.max(np.linalg.norm(rim * p.radius - dk.centre_of_mass(p), axis=1)))
        _, frame = dk._principal_frame_cm(p)

        def error(y: np.ndarray, ref: np.ndarray) -> float:
            r1 = dk.quaternion_to_matrix(y[3:7]) @ frame.T
            r2 = dk.quaternion_to_matrix(ref[3:7]) @ frame.T
            return float(np.linalg.norm(r1 - r2, 2) * reach)

        note = f"omega {p.omega:g} rad/s, extra spin {c.extra_spin} rad/s (the viewer's default)"
        return f"{cls.key}-released", {
            "system": released,
            "state": released.default_state(),
            "state_note": note,
            "size": 2.0 * p.radius,
            "error": error,
            "methods": ("splitting", "rk4", "yoshida4"),
        }

    # ------------------------------------------------------------------ simulations
    def _start(self) -> None:
        c = self.config
        p = c.physics()
        if c.mode == "driven":
            system = dynamics.DrivenDisk(p)
            sim = self._make_simulation(system, "exact", system.default_state())
        else:
            system = dynamics.ReleasedDisk(p, tuple(float(x) for x in c.extra_spin))
            sim = self._make_simulation(system, c.method, system.default_state())
        self.params = p
        self.sim, self.compare = sim, None
        self._reset_common()
        self._pose_cache = None  # (sim, t, config, (rotation, A)) of the last pose() call
        self.force_amplitude = dk.axle_force_amplitude(p)
        # Driven: L is fixed in the body (dynamics gives it at t = 0, when the disk frame is the
        # space frame); the pose turns it with the sampled rotation R(t).
        self.body_L = dk.angular_momentum(p, 0.0)
        # driven: (angle, omega) for the bearing force; released: body angular velocity
        self.motion = Motion((2,) if c.mode == "driven" else (3,))
        self._started()
        self._observe()

    # ------------------------------------------------------------------ kinematics from dynamics
    def pose(self, sample: dynamics.Sample | None = None):
        """``(rotation disk->space, position of A in space)`` of the current state (or of the
        given sample)."""
        if sample is not None:
            return self._pose_of(sample.state[0], sample.t)
        sim, cached = self.sim, self._pose_cache
        if (
            cached is not None
            and cached[0] is sim
            and cached[1] == sim.t
            and cached[2] is self.config
        ):
            return cached[3]  # a frame asks several times for the pose of one state
        pose = self._pose_of(sim.state[0], sim.t)
        self._pose_cache = (sim, sim.t, self.config, pose)
        return pose

    def _pose_of(self, st: np.ndarray, t: float):
        if self.config.mode == "driven":
            return dk.rotation_about_axle(st[0]), np.zeros(3)
        spin = tuple(float(x) for x in self.config.extra_spin)
        # follow_cm: the centre of mass stays where it was at release (its drift w0 x r_cm is
        # uniform), i.e. the pose at t = 0 with the current orientation.
        return dk.released_pose(self.params, st, 0.0 if self.config.follow_cm else t, spin)

    def vectors_space(self):
        """Angular velocity and angular momentum (space frame) and the point they are drawn from."""
        p, st = self.params, self.state
        rot, a = self.pose()
        if self.config.mode == "driven":
            return p.omega * dk.AXLE, rot @ self.body_L, a
        moments = dk.free_kernel_params(p)
        omega = dk.quaternion_to_matrix(st[3:7]) @ st[:3]
        L = dk.free_angular_momentum_space(moments, st)
        return omega, L, a + rot @ dk.centre_of_mass(p)

    def _rewound(self) -> None:
        self._pose_cache = None  # the same time may hold another state once gone back
        super()._rewound()

    def _observe(self) -> None:
        st = self.state
        self.motion.add(self.t, st[:2] if self.config.mode == "driven" else st[:3])

    def growth_rate_theory(self) -> float:
        """Linear growth rate [1/s] of the wobble from the release state (released only)."""
        return measure.wobble_growth_rate_theory(
            self.sim.system.kernel_params(), self.sim.state0[0]
        )

    def _measure(self) -> dict:
        """Driven: the bearing force amplitude at B from dL/dt of the sampled motion
        (:func:`mechviz.dynamics.measure.bearing_force_amplitude`); released: the wobble's growth rate
        (:func:`mechviz.dynamics.measure.wobble_growth_rate`)."""
        t, x = self.motion.arrays()
        if self.config.mode == "driven":
            return {
                "bearing_force": measure.bearing_force_amplitude(self.params, t, x[:, 0], x[:, 1])
            }
        middle = int(np.argsort(dk.free_kernel_params(self.params))[1])
        period = self.polhode_period()
        expected = 2 * math.pi / period if 0.0 < period < math.inf else None
        freq = (
            measure.crossing_frequency(t, x[:, middle], expected=expected)
            if len(t)
            else measure.unresolved("no samples")
        )
        return {
            "growth_rate": measure.wobble_growth_rate(t, x),
            # the component on the intermediate axis is sn or cn: two zero crossings a period
            "polhode_period": measure.Estimate(2 * math.pi / freq.value) if freq else freq,
        }

    def polhode_period(self) -> float:
        """The polhode's period [s] from the Jacobi elliptic solution (released only)."""
        return dk.polhode_period(self.sim.system.kernel_params(), self.state[:3])

    # ------------------------------------------------------------------ plots
    @classmethod
    def system_for(cls, config) -> str:
        return "driven-disk" if config.mode == "driven" else "free-body"

    @classmethod
    def plot_curves(cls, config, x: str, y: str, samples) -> list[Curve]:
        """Released, two components of ``w``: the polhode's exact projection. ``E`` and ``|L|``
        fixed, eliminating ``w_k`` leaves the conic ``sum_(i != k) I_i (I_k - I_i) w_i^2 =
        2E I_k - L^2``: an ellipse, or along the intermediate axis a hyperbola, whose asymptotes
        are the separatrix. Driven, ``(Lx, Lz)``: the circle L's tip sweeps about the axle."""
        if not len(samples):
            return []
        p = config.physics()
        if config.mode == "driven":
            if (x, y) != ("Lx", "Lz"):
                return []
            body = dk.inertia_tensor(p) @ (p.omega * dk.AXLE)
            rho = math.hypot(body[0], body[2])
            phi = np.linspace(0.0, 2 * math.pi, 181)
            return [Curve(rho * np.cos(phi), rho * np.sin(phi), "L's cone", dashed=True)]
        names = ("w1", "w2", "w3")
        if x not in names or y not in names or x == y:
            return []
        moments = dk.free_kernel_params(p)
        w = samples.states[-1, :3]
        two_e = float(np.sum(moments * w * w))
        l2 = float(np.sum((moments * w) ** 2))
        i, j = names.index(x), names.index(y)
        k = 3 - i - j
        a, b = moments[i] * (moments[k] - moments[i]), moments[j] * (moments[k] - moments[j])
        c = two_e * moments[k] - l2
        reach = math.sqrt(two_e / float(moments.min()))  # no component of w is larger
        return [Curve(*_conic(a, b, c, reach), "exact polhode", dashed=True)]

    @classmethod
    def pictures(cls, config) -> tuple[tuple[str, str], ...]:
        return (("Lx", "Lz"),) if config.mode == "driven" else (("w2", "w3"), ("w1", "w3"))

    def stability_text(self) -> str:
        if self.config.mode == "driven":
            return (
                "<small>Driven: the exact uniform rotation, no step. The method and dt apply "
                "once the disk is released.</small>"
            )
        return super().stability_text()

    # ------------------------------------------------------------------ a recording's figures
    @classmethod
    def recorded_figures(cls, config, tr: Traces) -> list[dict[str, Any]]:
        """Driven: the spin rate and the bearing force's amplitude and frequency from dL/dt of
        the motion. Released: the wobble's growth rate and the change of |L|."""
        p = config.physics()
        if config.mode == "driven":
            return cls._driven_figures(tr, p)
        return cls._released_figures(tr, p)

    @staticmethod
    def _driven_figures(tr: Traces, p) -> list[dict[str, Any]]:
        t, S = tr.times[tr.main], tr.states[tr.main]
        figs = [figure("spin rate", measure.slope(t, S[:, 0, 0]), p.omega, "rad/s")]
        keep(
            figs,
            "bearing force amplitude at B",
            measure.bearing_force_amplitude(p, t, S[:, 0, 0], S[:, 0, 1]),
            dk.axle_force_amplitude(p),
            "N",
            "from d L / dt of the simulated motion; seed: 5/8 M R omega^2",
        )
        if len(t) >= 3:
            F = measure.bearing_force(p, t, S[:, 0, 0], S[:, 0, 1])
            keep(
                figs,
                "bearing force frequency",
                measure.crossing_frequency(t, F[:, 0], expected=p.omega),
                p.omega,
                "rad/s",
            )
        return figs

    @staticmethod
    def _released_figures(tr: Traces, p) -> list[dict[str, Any]]:
        t, S = tr.times[tr.main], tr.states[tr.main]
        moments = dk.free_kernel_params(p)
        figs: list[dict[str, Any]] = []
        keep(
            figs,
            "wobble growth rate",
            measure.wobble_growth_rate(t, S[:, 0, :3]),
            measure.wobble_growth_rate_theory(moments, S[0, 0, :3]),
            "1/s",
            "spin about the intermediate axis: w_perp grows as exp(rate t)",
        )
        L = np.linalg.norm(dk.free_angular_momentum_space(moments, S[:, 0]), axis=-1)
        figs.append(
            figure(
                "final |L| change",
                abs(L[-1] - L[0]) / L[0],
                0.0,
                "",
                "torque-free: |L| is conserved",
                since=float(t[-1]),
            )
        )
        return figs


def _conic(
    a: float, b: float, c: float, reach: float, n: int = 721
) -> tuple[np.ndarray, np.ndarray]:
    """Points of ``a x^2 + b y^2 = c``: an ellipse (one closed curve) or a hyperbola (both
    branches, split by NaN, out to ``reach`` from the centre), or nothing (NaN)."""
    if a < 0 and b < 0:
        a, b, c = -a, -b, -c
    if a > 0 and b > 0:
        if c <= 0:
            return np.full(1, np.nan), np.full(1, np.nan)
        phi = np.linspace(0.0, 2 * math.pi, n)
        return math.sqrt(c / a) * np.cos(phi), math.sqrt(c / b) * np.sin(phi)
    if a == 0 or b == 0 or c == 0:  # degenerate: the asymptotes themselves
        if a * b >= 0:
            return np.full(1, np.nan), np.full(1, np.nan)
        s = math.sqrt(-a / b)
        u = np.linspace(-reach, reach, 3)
        return np.concatenate([u, [np.nan], u]), np.concatenate([s * u, [np.nan], -s * u])
    vertex = math.sqrt(abs(c / a)) if (a > 0) == (c > 0) else math.sqrt(abs(c / b))
    u = np.linspace(-1.0, 1.0, n) * (math.acosh(max(1.0, reach / vertex)) + 0.1)
    nan = [np.nan]
    if (a > 0) == (c > 0):  # branches open along x
        px, py = math.sqrt(c / a) * np.cosh(u), math.sqrt(-c / b) * np.sinh(u)
        return np.concatenate([px, nan, -px]), np.concatenate([py, nan, py])
    px, py = math.sqrt(-c / a) * np.sinh(u), math.sqrt(c / b) * np.cosh(u)
    return np.concatenate([px, nan, px]), np.concatenate([py, nan, -py])
