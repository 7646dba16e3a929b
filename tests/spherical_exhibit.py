"""The fourth system's exhibit model (:mod:`spherical`), defined in the test suite only: the
viewer's headless model of the spherical pendulum, answering the hooks a recording asks
(:mod:`mechviz.viz.model.hooks`). Registered beside the system by :func:`registered`.

It draws nothing (no view: the viewer's scene is not asked for here); its runs, samples,
charts and measured figures are the product's (:class:`~mechviz.viz.model.base.ExhibitModel`).
Measured from the motion: the rate of the polar angle's swing, ``theta``'s crossings of its mean
(:func:`mechviz.dynamics.measure.crossing_frequency`), and ``L_z``, whose mean over the samples
is checked against its start.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np
import spherical
from spherical import SPEC, SphericalPendulum

from mechviz.dynamics import measure
from mechviz.dynamics.registry import Registration
from mechviz.viz.model import MODELS
from mechviz.viz.model.base import ExhibitConfig, ExhibitModel, Motion
from mechviz.viz.model.hooks import CHART_COLOURS


@dataclass(frozen=True)
class PendulumConfig(ExhibitConfig):
    """The exhibit's settings: the description's start (``tilt`` [rad], ``swing`` and
    ``precession`` [rad/s]) and an optional comparison run."""

    system_name: ClassVar[str] = SphericalPendulum.name
    spec: ClassVar = SPEC
    demo_initial_keys: ClassVar[frozenset[str]] = frozenset({"state"})

    method: str = SPEC.default_method({})
    dt: float = SPEC.dt
    params: dict = field(default_factory=SPEC.default_params)
    tilt: float = spherical.START[0]
    swing: float = spherical.START[1]
    precession: float = spherical.START[2]
    compare_method: str | None = None
    compare_dt: float | None = None
    compare_rtol: float | None = None

    def _validate(self) -> None:
        SPEC.start_values({"tilt": self.tilt, "swing": self.swing, "precession": self.precession})

    def initial_state(self) -> np.ndarray:
        return spherical.start_state(self.tilt, self.swing, self.precession)


class PendulumModel(ExhibitModel):
    title = "Spherical pendulum"
    name = "Pendulum"
    Config = PendulumConfig
    start_fields = frozenset({"tilt", "swing", "precession"})
    origin = (0.0, 4.4, 0.0)

    # ------------------------------------------------------------------ hooks (see .hooks)
    @classmethod
    def shortest_period(cls, demo: Any, result: dict, extra_spin: bool = True) -> float | None:
        return result["small_swing_period"]

    @classmethod
    def check_recording_start(cls, demo: Any, config: Any, span: float) -> None:
        """Nothing beyond the description's own checks of the start."""

    @classmethod
    def draw_motion_chart(cls, ax: Any, demo: Any, tr: Any, params: Any) -> None:
        """The polar angle of each run against time."""
        for lbl, c in zip(tr.states, CHART_COLOURS, strict=False):
            ax.plot(tr.times[lbl], tr.states[lbl][:, 0, 0], color=c, lw=1, label=f"theta, {lbl}")
        ax.set_ylabel("polar angle θ [rad]")

    @classmethod
    def pictures(cls, config) -> tuple[tuple[str, str], ...]:
        return (("theta", "omega"),)

    @classmethod
    def recorded_figures(cls, config, tr) -> list[dict[str, Any]]:
        """``L_z`` at the end against its start (conserved)."""
        from mechviz.viz.model.figures import figure

        system = SphericalPendulum(config.physics())
        S = tr.states[tr.main]
        lz = system.quantities(S[:, 0])["Lz"]
        return [figure("L_z at the end", float(lz[-1]), float(lz[0]), "m²/s", "conserved")]

    # ------------------------------------------------------------------ simulations
    def _start(self) -> None:
        self.sim, self.compare = self._make_runs()
        self._reset_common()
        self.motion = Motion((2,))  # theta and L_z
        self._started()
        self._observe()

    def _jump_to_start(self) -> None:
        s0 = self.config.initial_state()
        for sim in self.simulations():
            sim.jump(s0)
        self.changed()
        self._sample = self._compare_sample = None
        self.forget_figures()
        self.motion.clear()
        self.trace.clear()
        self._observe()

    def _observe(self) -> None:
        lz = self.sim.system.quantities(self.state)["Lz"]
        self.motion.add(self.t, np.array([self.state[0], float(lz)]))

    def _measure(self) -> dict[str, Any]:
        t, x = self.motion.arrays()
        return {
            "swing_frequency": measure.crossing_frequency(t, x[:, 0]),
            "Lz_mean": float(x[:, 1].mean()) if len(x) else math.nan,
        }


def registered() -> Registration:
    """The spherical pendulum and its model registered (undo with the result)."""
    reg = spherical.registered()
    try:
        return reg.add(MODELS, SPEC.name, PendulumModel)
    except BaseException:
        reg.unregister()
        raise
