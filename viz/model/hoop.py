"""The hoop's model: a hoop swinging in its own plane about a pivot on its rim, a bead sliding on
it without friction, headless.

Beside the nonlinear motion, linear theory from the same start (``mechviz.dynamics.hoop.linear_solution``)
gives the ghost. Both normal-mode frequencies are measured from the motion: the angles are
projected on the mode shapes and each modal coordinate is timed between its zero crossings
(:mod:`mechviz.dynamics.measure`). The view is :class:`mechviz.viz.scene.hoop.HoopExhibit`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from mechviz import dynamics
from mechviz.dynamics import hoop as hp
from mechviz.dynamics import measure
from mechviz.dynamics.registry import HOOP
from mechviz.dynamics.systems import HOOP_MODES

from .base import ExhibitConfig, ExhibitModel, Motion, finite_numbers
from .figures import figure, keep
from .hooks import CHART_COLOURS, mark_periods
from .plot import Curve
from .traces import Traces

MODES = ("mode 1", "mode 2", "mix", "custom")


@dataclass(frozen=True)
class HoopConfig(ExhibitConfig):
    """Settings of the hoop exhibit. The start: ``mode`` "mode 1" or "mode 2" (that normal mode
    alone at ``amplitude`` [rad], its largest angle), "mix" (both at half of it) or "custom"
    (``angles`` (theta1, theta2) [rad], at rest); ``state`` (theta1, theta2, theta1', theta2')
    overrides them all. ``compare_method`` runs beside the main one with ``compare_dt`` /
    ``compare_rtol`` if given; ``ghost`` draws linear theory from the same start."""

    system_name: ClassVar[str] = dynamics.Hoop.name
    spec: ClassVar[dynamics.SystemSpec] = HOOP
    #: The keys of a demo file's [initial] table for this exhibit.
    demo_initial_keys: ClassVar[frozenset[str]] = frozenset({"modes", "state"})

    # RK4 at one step per frame: as cheap as it gets below 1e-3 over 10 minutes
    # (docs/bench/defaults.md)
    method: str = HOOP.default_method({})
    dt: float = HOOP.dt
    params: dict = field(default_factory=HOOP.default_params)
    # The description's default start: both modes at rest, each at half the amplitude ("mix")
    mode: str = "mix"
    amplitude: float = HOOP_MODES[0] + HOOP_MODES[1]
    angles: tuple = (0.4, -0.3)
    state: tuple | None = None
    compare_method: str | None = None
    compare_dt: float | None = None
    compare_rtol: float | None = None
    ghost: bool = True
    trail_cap: int = 240

    def _validate(self) -> None:
        if self.mode not in MODES:
            raise ValueError(f"mode must be one of {', '.join(MODES)}; got {self.mode!r}")
        (a,) = finite_numbers("amplitude", (self.amplitude,), 1)
        if abs(a) >= 3.0:
            raise ValueError(f"amplitude must be an angle below 3 rad, got {self.amplitude!r}")
        if any(abs(x) >= math.pi for x in finite_numbers("angles", self.angles, 2)):
            raise ValueError(f"angles must be two angles in (-pi, pi) rad, got {self.angles!r}")
        if self.state is not None:
            finite_numbers("state", self.state, 4)

    def initial_state(self) -> np.ndarray:
        if self.state is not None:
            return np.array(self.state, dtype=float)
        p, a = self.physics(), float(self.amplitude)
        if self.mode == "mode 1":
            return hp.mode_state(p, (a, 0.0))
        if self.mode == "mode 2":
            return hp.mode_state(p, (0.0, a))
        if self.mode == "mix":
            return hp.mode_state(p, (0.5 * a, 0.5 * a))
        return np.array([float(self.angles[0]), float(self.angles[1]), 0.0, 0.0])


class HoopModel(ExhibitModel):
    title = "Hoop with bead"
    name = "Hoop"
    Config = HoopConfig
    start_fields = frozenset({"mode", "amplitude", "angles", "state"})
    origin = (2.4, -3.4, 0.0)
    frame_cost_compare = "rk4"
    demo_keys: ClassVar[dict[str, str]] = {"state": "initial.state", "amplitude": "initial.modes"}

    # ------------------------------------------------------------------ hooks (see .hooks)
    @classmethod
    def demo_settings(cls, initial: dict[str, Any], demo: Any, params: dict[str, Any]) -> dict:
        """The linear ghost, and the start: a state as given, else the mode amplitudes as the
        panel's modes where they are one (a single mode, or both equal), else as a state."""
        kw: dict[str, Any] = {"ghost": demo.ghost == "linear"}
        if "state" in initial:
            kw.update(mode="custom", state=tuple(initial["state"]))
        elif "modes" in initial:
            a1, a2 = initial["modes"]
            if a2 == 0.0:
                kw.update(mode="mode 1", amplitude=a1)
            elif a1 == 0.0:
                kw.update(mode="mode 2", amplitude=a2)
            elif a1 == a2:
                kw.update(mode="mix", amplitude=2 * a1)
            else:
                p = hp.HoopParams(**params)
                kw.update(mode="custom", state=tuple(hp.mode_state(p, (a1, a2)).tolist()))
        return kw

    @classmethod
    def shortest_period(cls, demo: Any, result: dict, extra_spin: bool = True) -> float | None:
        return min(result["mode_periods"])

    @classmethod
    def check_recording_start(cls, demo: Any, config: Any, span: float) -> None:
        """Mode amplitudes below 3 rad (small swings, as the exhibit's own amplitude) and a
        start state of finite energy."""
        ini = demo.initial
        if ini.modes is not None:
            for i, a in enumerate(ini.modes):
                if not abs(a) < 3.0:
                    raise ValueError(f"initial.modes[{i}] must be an angle below 3 rad, got {a!r}")
        if ini.state is not None:
            with np.errstate(all="ignore"):
                energy = dynamics.Hoop(config.physics()).energy(np.asarray(ini.state))
            if not math.isfinite(float(np.ravel(energy)[0])):
                raise ValueError(
                    f"initial.state = {list(ini.state)}: the initial energy would be beyond "
                    "the largest double"
                )

    @classmethod
    def draw_motion_chart(cls, ax: Any, demo: Any, tr: Any, params: Any) -> None:
        """Two methods: the energy drift is the point. One: both angles against time, the linear
        ghost and the predicted period of the mode the start is mostly in."""
        if len(tr.states) > 1:
            for lbl, c in zip(tr.states, CHART_COLOURS, strict=False):
                ax.plot(tr.times[lbl], 100 * tr.energy_error[lbl][:, 0], color=c, lw=1, label=lbl)
            ax.axhline(0.0, color="k", ls="--", lw=0.8, label="exact: energy conserved")
            ax.set_ylabel("relative energy error [%]")
            return
        t = tr.times[tr.main]
        freqs, shapes = hp.normal_modes(params)
        for lbl, c in zip(tr.states, CHART_COLOURS, strict=False):
            X = tr.states[lbl]
            ax.plot(tr.times[lbl], X[:, 0, 0], color=c, lw=1, label=f"theta1 (hoop), {lbl}")
            ax.plot(
                tr.times[lbl], X[:, 0, 1], color=c, lw=1, ls="-.", label=f"theta2 (bead), {lbl}"
            )
        if tr.ghost is not None:
            ax.plot(tr.t, tr.ghost[:, 0, 0], color="0.5", lw=1, ls="--", label="linear theory")
        amps = measure.modal_coordinates(tr.states[tr.main][0, 0, :2], shapes)
        k = int(np.argmax(np.abs(amps)))
        label = f"predicted period of mode {k + 1} (linear)"
        mark_periods(ax, 2 * math.pi / freqs[k], t[-1], label)
        if k == 0 and abs(amps[1]) < 1e-12 and abs(amps[0]) > 0.2:
            mark_periods(
                ax,
                hp.mode1_period(params, abs(float(amps[0]))),
                t[-1],
                "predicted period, exact (finite amplitude)",
                color="tab:purple",
            )
        ax.set_ylabel("angle [rad]")

    @classmethod
    def screen_case(cls) -> tuple[str, dict[str, Any]]:
        """On screen: the larger of the errors of the hoop's centre and of the bead [m]; size:
        the hoop's diameter ``2 a``."""
        c = HoopConfig()
        p = c.physics()

        def error(y: np.ndarray, ref: np.ndarray) -> float:
            c1, b1 = hp.positions(p, y)
            c2, b2 = hp.positions(p, ref)
            return float(max(np.linalg.norm(c1 - c2), np.linalg.norm(b1 - b2)))

        note = f"mode {c.mode!r}, amplitude {c.amplitude:g} rad (the viewer's default)"
        return cls.key, {
            "system": dynamics.Hoop(p),
            "state": c.initial_state(),
            "state_note": note,
            "size": 2.0 * p.radius,
            "error": error,
            "methods": ("verlet", "rk4", "yoshida4"),
        }

    # ------------------------------------------------------------------ simulations
    def _start(self) -> None:
        sim, cmp_ = self._make_runs()
        self.params = p = sim.system.params
        self.sim, self.compare = sim, cmp_
        self._reset_common()
        self.mode_frequencies, self.shapes = hp.normal_modes(p)
        self.motion = Motion((2,))  # the angles
        self._started()
        self._observe()

    def ghost_state(self) -> np.ndarray:
        """Linear theory from the run's start (or last jump) at the current time."""
        return hp.linear_solution(self.params, self.sim.state0[0], self.sim.t - self.sim.t0)

    def _jump_to_start(self) -> None:
        s0 = self.config.initial_state()
        for sim in self.simulations():
            sim.jump(s0)
        self.changed()
        self._sample = self._compare_sample = None
        self._jumped()
        self.forget_figures()
        self.motion.clear()
        self.trace.clear()
        self._observe()

    def _jumped(self) -> None:
        """Called when the runs jump to a new start: announced (a view breaks its trails)."""
        self.announce("jumped")

    def modal_coordinates(self, state) -> np.ndarray:
        return measure.modal_coordinates(np.asarray(state, float)[:2], self.shapes)

    def _observe(self) -> None:
        self.motion.add(self.t, self.state[:2])

    def _measure(self) -> dict:
        """Both normal-mode frequencies from the sampled angles
        (:func:`mechviz.dynamics.measure.mode_frequencies`)."""
        t, angles = self.motion.arrays()
        return {
            "mode_frequencies": measure.mode_frequencies(
                t, angles, self.shapes, expected=self.mode_frequencies
            )
        }

    def modal_history(self, points: int = 600) -> tuple[np.ndarray, ...]:
        """``(t, q1, q2, q1_linear, q2_linear)`` over the samples since the start (at most
        ``points`` of them, evenly thinned): the angles' coordinates on the two mode shapes, and
        linear theory's from the same start (each a cosine at its mode's frequency)."""
        t, angles = self.motion.arrays()
        if len(t) > points:
            keep = np.linspace(0, len(t) - 1, points).round().astype(int)
            t, angles = t[keep], angles[keep]
        q = measure.modal_coordinates(angles, self.shapes)
        sim = self.sim
        ghost = hp.linear_solution(self.params, sim.state0[0], t - sim.t0)[:, :2]
        g = measure.modal_coordinates(ghost, self.shapes)
        return t, q[:, 0], q[:, 1], g[:, 0], g[:, 1]

    # ------------------------------------------------------------------ plots
    @classmethod
    def plot_curves(cls, config, x: str, y: str, samples) -> list[Curve]:
        """Configuration space ``(theta1, theta2)``: the mode lines (1, 1) and (m, -(M + m)).
        A phase portrait ``(theta_i, theta_i')``: the separatrix of the pendulum mode 1 reduces
        to, ``theta' = +-2 omega_1 cos(theta / 2)``, and, for a motion on the mode-1 set
        (``theta1 = theta2``), its exact orbit ``theta'^2 = 2 (e + omega_1^2 cos theta)``."""
        p = config.physics()
        freqs, shapes = hp.normal_modes(p)
        pair = {x, y}
        if pair == {"theta1", "theta2"}:
            out = []
            for k, shape in enumerate(shapes):
                u = np.asarray(shape) / np.abs(shape).max() * math.pi
                line = np.array([-u, u])
                cols = (0, 1) if x == "theta1" else (1, 0)
                out.append(Curve(line[:, cols[0]], line[:, cols[1]], f"mode {k + 1} line"))
            return out
        if (x, y) not in (("theta1", "omega1"), ("theta2", "omega2")):
            return []
        w1 = float(freqs[0])
        th = np.linspace(-math.pi, math.pi, 361)
        top = 2 * w1 * np.cos(th / 2)
        out = [
            Curve(np.concatenate([th, th[::-1]]), np.concatenate([top, -top[::-1]]), "separatrix"),
        ]
        if len(samples):
            s = samples.states[-1]
            # on the mode-1 set, to what an integrator keeps of it (the set is unstable at
            # large amplitude: round-off grows off it by about 1e-9 over a 3 rad swing)
            if abs(s[0] - s[1]) < 1e-6 and abs(s[2] - s[3]) < 1e-6:
                e = 0.5 * s[2] ** 2 - w1 * w1 * math.cos(s[0])
                with np.errstate(invalid="ignore"):
                    v = np.sqrt(2 * (e + w1 * w1 * np.cos(th)))
                out.append(
                    Curve(
                        np.concatenate([th, th[::-1]]),
                        np.concatenate([v, -v[::-1]]),
                        "exact pendulum orbit",
                        dashed=True,
                    )
                )
        return out

    @classmethod
    def pictures(cls, config) -> tuple[tuple[str, str], ...]:
        return (("theta1", "omega1"), ("theta1", "theta2"))

    def initial_mode_amplitudes(self) -> np.ndarray:
        """The start's coordinates on the two mode shapes [rad]."""
        return self.modal_coordinates(self.sim.state0[0])

    # ------------------------------------------------------------------ a recording's figures
    @classmethod
    def recorded_figures(cls, config, tr: Traces) -> list[dict[str, Any]]:
        """Both normal-mode frequencies against linear theory (and mode 1's exact period at a
        finite amplitude); the energy errors when two methods are compared."""
        p = config.physics()
        figs: list[dict[str, Any]] = []
        freqs, shapes = hp.normal_modes(p)
        t, S = tr.times[tr.main], tr.states[tr.main]
        if len(tr.states) > 1:  # two methods: the energy drift is the point
            for label in tr.states:
                E = tr.energy_error[label][:, 0]
                end = float(t[-1])  # true of the whole run: known at its end
                figs.append(
                    figure(f"final energy error, {label}", float(E[-1]), None, "", since=end)
                )
                figs.append(
                    figure(
                        f"largest |energy error|, {label}",
                        float(np.abs(E).max()),
                        None,
                        "",
                        since=end,
                    )
                )
            return figs
        amps = measure.modal_coordinates(S[0, 0, :2], shapes)
        measured = measure.mode_frequencies(t, S[:, 0, :2], shapes, expected=freqs)
        for k in (0, 1):
            keep(
                figs,
                f"mode {k + 1} frequency",
                measured[k],
                freqs[k],
                "rad/s",
                theory="linear theory",
            )
        a1 = abs(float(amps[0]))
        if measured[0] and abs(amps[1]) < 1e-12 and a1 > 0.2:
            figs.append(
                figure(
                    "mode 1 frequency at this amplitude",
                    measured[0],
                    2 * math.pi / hp.mode1_period(p, a1),
                    "rad/s",
                    "rigid-pendulum period 4 K(sin²(A/2)) / ω₁",
                    theory="exact pendulum period",
                )
            )
        return figs
