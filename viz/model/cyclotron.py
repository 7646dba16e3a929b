"""The cyclotron's model: a charge in a uniform magnetic field along +z, headless.

The charge starts on a circle (or from a whole state), optionally with a comparison method and a
beam of charges from the same point with a spread of speeds, advanced in one batched call. A
radial kick (``mechviz.dynamics.cyclotron.radial_kick``) changes the state at the current time without
restarting the run; the circle theory predicts moves at once, and the estimators start a new
segment of samples. The kick's strength is a setting of the next kick only, and the beam comes
and goes while the run goes on: switched on, its charges leave from where the charge is then, in
its direction, at the beam's speeds. The view is :class:`mechviz.viz.scene.cyclotron.CyclotronExhibit`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from mechviz import dynamics
from mechviz.dynamics import cyclotron as cy
from mechviz.dynamics import measure
from mechviz.dynamics.registry import CYCLOTRON

from .base import ExhibitConfig, ExhibitModel, Motion, finite_numbers, positive
from .commands import Command, Kick, Reset, Set
from .figures import figure, keep
from .hooks import CHART_COLOURS, demo_value, mark_periods
from .plot import Curve, well_axes
from .traces import Traces


@dataclass(frozen=True)
class CyclotronConfig(ExhibitConfig):
    """Settings of the cyclotron exhibit.

    The charge starts on the circle of transverse ``speed`` [m/s] about ``centre`` (x, y) [m] with
    ``vz`` [m/s] along B, unless ``state`` gives the whole initial state (x, y, z, vx, vy, vz).
    ``beam``: ``beam_size`` more charges from the same point in the same direction, at speeds
    spread evenly over ``beam_speeds`` [m/s]. ``compare_method`` runs beside the main one, with
    ``compare_dt`` / ``compare_rtol`` if given (else the main run's). ``kick`` [m/s] is the
    radial kick the Kick button gives."""

    system_name: ClassVar[str] = dynamics.Cyclotron.name
    spec: ClassVar[dynamics.SystemSpec] = CYCLOTRON
    #: The keys of a demo file's [initial] table for this exhibit.
    demo_initial_keys: ClassVar[frozenset[str]] = frozenset(
        {"speed", "vz", "centre", "beam", "speeds", "state"}
    )

    method: str = CYCLOTRON.default_method({})
    dt: float = CYCLOTRON.dt
    params: dict = field(default_factory=CYCLOTRON.default_params)
    speed: float = CYCLOTRON.setting("speed").default
    vz: float = CYCLOTRON.setting("vz").default
    centre: tuple = CYCLOTRON.setting("centre").default
    state: tuple | None = None
    beam: bool = False
    beam_size: int = 16
    beam_speeds: tuple = (0.25, 1.75)
    kick: float = 0.5
    compare_method: str | None = None
    compare_dt: float | None = None
    compare_rtol: float | None = None
    trail_cap: int = 600
    height: float = 2.0

    def _validate(self) -> None:
        positive("speed", self.speed)
        finite_numbers("vz", (self.vz,), 1)
        finite_numbers("centre", self.centre, 2)
        if self.state is not None:
            s = finite_numbers("state", self.state, 6)
            if s[3] == 0.0 and s[4] == 0.0:
                raise ValueError("state must have a transverse velocity (vx, vy not both 0)")
        if not (isinstance(self.beam_size, int) and 1 <= self.beam_size <= 1000):
            raise ValueError(
                f"beam_size must be a whole number from 1 to 1000, got {self.beam_size!r}"
            )
        lo, hi = (
            positive("beam_speeds", v) for v in finite_numbers("beam_speeds", self.beam_speeds, 2)
        )
        if lo > hi:
            raise ValueError(f"beam_speeds must be (low, high), got {self.beam_speeds!r}")
        finite_numbers("kick", (self.kick,), 1)
        positive("height", self.height)

    def initial_state(self) -> np.ndarray:
        if self.state is not None:
            return np.array(self.state, dtype=float)
        return cy.circular_orbit_state(self.physics(), self.speed, self.centre, self.vz)

    def beam_states(self, s0: np.ndarray | None = None) -> np.ndarray:
        """(beam_size, 6): every charge at the start point (or at the state ``s0``'s point),
        moving the same way, at its speed."""
        s0 = self.initial_state() if s0 is None else np.asarray(s0, float)
        speeds = np.linspace(self.beam_speeds[0], self.beam_speeds[1], self.beam_size)
        out = np.tile(s0, (self.beam_size, 1))
        direction = s0[3:5] / math.hypot(s0[3], s0[4])
        out[:, 3:5] = speeds[:, None] * direction
        return out


class CyclotronModel(ExhibitModel):
    """The charge, its theory circle, optional comparison method and optional beam."""

    title = "Cyclotron"
    name = "Cyclotron"
    Config = CyclotronConfig
    view_fields = frozenset({"kick"})  # the strength of the next kick: nothing moves yet
    live_fields = frozenset({"beam", "beam_size", "beam_speeds"})
    commands = (Reset, Set, Kick)
    origin = (-3.95, 1.7, 0.0)
    frame_cost_compare = "boris"
    demo_keys: ClassVar[dict[str, str]] = {
        **{k: f"initial.{k}" for k in ("speed", "vz", "centre", "state")},
        "beam_size": "initial.beam",
        "beam_speeds": "initial.speeds",
    }

    # ------------------------------------------------------------------ hooks (see .hooks)
    @classmethod
    def demo_settings(cls, initial: dict[str, Any], demo: Any, params: dict[str, Any]) -> dict:
        kw: dict[str, Any] = {k: initial[k] for k in ("speed", "vz", "centre") if k in initial}
        if "state" in initial:
            kw["state"] = tuple(initial["state"])
        if "beam" in initial:
            kw["beam"], kw["beam_size"] = True, initial["beam"]
        if "speeds" in initial:
            kw["beam_speeds"] = initial["speeds"]
        return kw

    @classmethod
    def shortest_period(cls, demo: Any, result: dict, extra_spin: bool = True) -> float | None:
        return result["period"]

    @classmethod
    def check_recording_start(cls, demo: Any, config: Any, span: float) -> None:
        """The kinetic energy, the orbit radius and the distance covered in the recording, the
        scripted kicks' speeds added, all finite; else the keys whose speed makes it so."""
        p = config.physics()
        speeds = _demo_speeds(demo, config)

        def bad(v: dict[str, float]) -> str | None:
            total = sum(v.values())
            with np.errstate(all="ignore"):
                checks = {
                    "the kinetic energy": 0.5 * p.mass * total * total,
                    "the orbit radius": p.mass * total / abs(p.charge * p.field),
                    "the distance covered": total * span,
                }
            return next((name for name, x in checks.items() if not math.isfinite(x)), None)

        what = bad(speeds)
        if what is None:
            return
        keys = [k for k in speeds if "." in k or "[" in k]
        blamed = [k for k in keys if bad({**speeds, k: 1.0}) is None] or keys
        shown = ", ".join(f"{k} = {demo_value(demo, k)}" for k in blamed) or "the start"
        raise ValueError(f"{shown}: {what} would be beyond the largest double")

    @classmethod
    def draw_motion_chart(cls, ax: Any, demo: Any, tr: Any, params: Any) -> None:
        """x against time for each run, the predicted period and each kick's predicted x range."""
        t = tr.times[tr.main]
        for lbl, c in zip(tr.states, CHART_COLOURS, strict=False):
            X = tr.states[lbl]
            for j in range(X.shape[1]):
                ax.plot(
                    tr.times[lbl],
                    X[:, j, 0],
                    color=c,
                    lw=1,
                    alpha=0.8 if X.shape[1] == 1 else 0.5,
                    label=f"x, {lbl}" if j == 0 else None,
                )
        mark_periods(ax, cy.period(params), t[-1], "predicted period 2 pi m / |qB|")
        for entry in tr.event_log:
            ax.axvline(
                entry["t"], color="k", lw=1.5, label=f"{entry['action']} (dv = {entry['dv']:g} m/s)"
            )
            eff = entry["effects"][tr.main]
            cx = eff["predicted_centre"][0][0]
            r = eff["predicted_radius"][0]
            for yv in (cx - r, cx + r):
                ax.hlines(
                    yv,
                    entry["t"],
                    t[-1],
                    colors="tab:orange",
                    linestyles=":",
                    label="predicted x range after the kick" if yv == cx - r else None,
                )
        ax.set_ylabel("x [m]")

    @classmethod
    def screen_case(cls) -> tuple[str, dict[str, Any]]:
        """On screen: the distance between the computed and the exact position [m]; size: the
        orbit's diameter ``2 v / omega``."""
        c = CyclotronConfig()
        system, s0 = dynamics.Cyclotron(c.physics()), c.initial_state()

        def error(y: np.ndarray, ref: np.ndarray) -> float:
            return float(np.linalg.norm(y[:3] - ref[:3]))

        return cls.key, {
            "system": system,
            "state": s0,
            "state_note": f"speed {c.speed:g} m/s, vz {c.vz:g} m/s (the viewer's default)",
            "size": 2.0 * cy.larmor_radius(system.params, np.asarray(s0, float)),
            "error": error,
            "methods": ("exact", "boris", "rk4", "yoshida4"),
        }

    # ------------------------------------------------------------------ simulations
    def _start(self) -> None:
        c = self.config
        sim, cmp_ = self._make_runs()
        beam = None
        if c.beam:
            beam = self._make_simulation(sim.system, c.method, c.beam_states(), reference=None)
        # --- nothing above touched the model; install
        self.params = sim.system.params
        self.sim, self.compare, self.beam = sim, cmp_, beam
        self._reset_common()
        self._started()
        self._begin_segment()

    def _begin_segment(self) -> None:
        """Start the samples the estimators read: at the start, and again after a kick."""
        p, st = self.params, self.state
        self.theory_centre = cy.guiding_centre(p, st)
        self.theory_radius = cy.orbit_radius(p, 0.5 * p.mass * (st[3] ** 2 + st[4] ** 2))
        self.motion = Motion((2, 2))  # (x, y) and (vx, vy) of the charge
        self.beam_motion = None
        if self.beam is not None:
            n = len(self.beam.state)
            self.beam_motion = Motion((n, 2), maxlen=min(1800, max(64, 400_000 // n)))
        self._segment_started()
        self.forget_figures()  # another circle: measured afresh
        self.trace.clear()  # the plot's points before a kick lie in another well
        self._observe()

    def _apply_live(self, changed: set[str]) -> None:
        """The beam on, off or another one, while the run goes on: its charges leave from the
        charge's position and direction now, at the time the run is at."""
        c, sim = self.config, self.sim
        beam = None
        if c.beam:
            beam = self._make_simulation(
                sim.system, c.method, c.beam_states(self.state), reference=None
            )
            beam.t = beam.t0 = sim.t  # the system is autonomous: start it now
            beam.clock = sim.clock  # and on the main run's step grid
        self.beam = beam
        self.beam_motion = None
        if beam is not None:
            n = len(beam.state)
            self.beam_motion = Motion((n, 2), maxlen=min(1800, max(64, 400_000 // n)))
            self.beam_motion.add(beam.t, beam.state[:, 3:5])
        self.forget_figures("beam_gyrofrequencies")
        # the states kept for Rewind have the runs' widths: the kept past starts here
        self._rewind_start()
        self._beam_changed()

    def _beam_changed(self) -> None:
        """Called when the beam came, went or changed: announced (a view redraws it)."""
        self.announce("beam")

    def _rewound(self) -> None:
        # the circle theory predicts from the state shown (a kick after it is undone)
        p, st = self.params, self.state
        self.theory_centre = cy.guiding_centre(p, st)
        self.theory_radius = cy.orbit_radius(p, 0.5 * p.mass * (st[3] ** 2 + st[4] ** 2))
        super()._rewound()

    def _segment_started(self) -> None:
        """Called when the estimators' samples start afresh: announced (a view breaks its
        trails)."""
        self.announce("segment")

    def _outside(self, sim) -> str | None:
        if self.box is None:
            return None
        lo, hi = self.box
        x, y = sim.state[0, :2]
        if lo[0] <= x <= hi[0] and lo[1] <= y <= hi[1]:
            return None
        return "the charge left the exhibit"

    def _extra_simulations(self):
        return [self.beam] if self.beam is not None else []

    def runs(self) -> dict[str, dynamics.Simulation]:
        """With a beam on, a recording traces the beam as its main run."""
        out = super().runs()
        if self.beam is not None:
            out["main"] = self.beam
        return out

    # ------------------------------------------------------------------ measurements
    def _observe(self) -> None:
        st = self.state
        self.motion.add(self.t, (st[0:2], st[3:5]))
        if self.beam_motion is not None:
            self.beam_motion.add(self.beam.t, self.beam.state[:, 3:5])

    def _measure(self) -> dict:
        """Gyrofrequency and circle of the charge since its start or last kick
        (:func:`mechviz.dynamics.measure.gyrofrequency`,
        :func:`mechviz.dynamics.measure.fit_circle`), and each
        beam member's gyrofrequency."""
        t, x = self.motion.arrays()
        w_theory = cy.gyrofrequency(self.params)
        out: dict = {
            "gyrofrequency": measure.gyrofrequency(t, x[:, 1], xy=x[:, 0], expected=w_theory)
        }
        # sampled more than half a turn apart, the turn between two samples is ambiguous (the
        # estimate would be an alias): say so instead of showing it
        turn = cy.gyrofrequency(self.params) * (float(np.max(np.diff(t))) if len(t) > 1 else 0.0)
        aliased = measure.Estimate(
            None,
            f"at this frame rate: the velocity turns {turn:.3g} rad between samples, more than "
            "half a turn",
        )
        if turn > math.pi:
            out["gyrofrequency"] = aliased
        circle = measure.fit_circle(x[:, 0])
        out["radius"] = measure.Estimate(circle.value[1]) if circle else circle
        out["beam_gyrofrequencies"] = None
        if self.beam_motion is not None:
            tb, vb = self.beam_motion.arrays()
            out["beam_gyrofrequencies"] = (
                aliased if turn > math.pi else measure.gyrofrequency(tb, vb, expected=w_theory)
            )
        return out

    # ------------------------------------------------------------------ commands
    def _apply_command(self, command: Command) -> str:
        if not isinstance(command, Kick):
            return super()._apply_command(command)
        dv = float(self.config.kick if command.dv is None else command.dv)  # Kick checked it
        self.kick_effects(dv)
        centre, radius = self.theory_centre, self.theory_radius
        return (
            f"kick dv = {dv:g} m/s: new circle radius {radius:.4g} m "
            f"about ({centre[0]:.3g}, {centre[1]:.3g})"
        )

    def kick_effects(self, dv: float) -> dict[str, dict]:
        """Kick every run (and the beam) radially by ``dv`` [m/s] at the current time, without a
        restart (:meth:`mechviz.dynamics.Simulation.jump`); returns, by run, the state before and what
        theory predicts: each member's new centre and radius and the shift ``|dv| / |Omega|``."""
        p = self.params
        out = {}
        for role, sim in self.runs().items():
            before = sim.state.copy()
            kicked = [cy.radial_kick(p, s, dv) for s in before]
            out[role] = {
                "state_before": before.tolist(),
                "predicted_centre": [k[1][:2].tolist() for k in kicked],
                "predicted_radius": [k[2] for k in kicked],
                "predicted_shift": abs(dv) / abs(cy.signed_gyrofrequency(p)),
            }
        for sim in self.simulations():
            sim.jump(np.array([cy.radial_kick(p, s, dv)[0] for s in sim.state]))
        self.changed()
        self._sample = self._compare_sample = None
        self._begin_segment()
        return out

    # ------------------------------------------------------------------ the effective potential
    def well(self) -> dict:
        """:func:`well` of the charge's current state."""
        return well(self.params, self.state)

    # ------------------------------------------------------------------ plots
    @classmethod
    def plot_curves(cls, config, x: str, y: str, samples) -> list[Curve]:
        """``(r, V_eff)``: the well for the newest sample's ``p_phi`` and its level ``E_perp``
        (the path lies on the level, between the turning points); ``(x, y)``: the circle
        predicted from the newest sample (guiding centre and Larmor radius)."""
        if not len(samples):
            return []
        p, st = config.physics(), samples.states[-1]
        if (x, y) == ("r", "V_eff"):
            w = well(p, st)
            lo, hi = w["x_range"]
            return [
                Curve(w["x"], w["V"], "V_eff(r)", axes=(w["x_range"], w["y_range"])),
                Curve(np.array([lo, hi]), np.full(2, w["level"][0]), "level E⊥", dashed=True),
                Curve(
                    np.array([w["r0"]]),
                    np.array(
                        [cy.effective_potential(p, w["r0"], w["p_phi"]) if w["r0"] > 0 else np.nan]
                    ),
                    "bottom r0",
                    kw={"marker": "o", "ls": "none"},
                ),
            ]
        if (x, y) == ("x", "y"):
            centre, rho = cy.guiding_centre(p, st), cy.larmor_radius(p, st)
            phi = np.linspace(0.0, 2 * math.pi, 181)
            return [
                Curve(
                    centre[0] + rho * np.cos(phi),
                    centre[1] + rho * np.sin(phi),
                    "predicted circle",
                    dashed=True,
                ),
                Curve(
                    np.array([centre[0]]),
                    np.array([centre[1]]),
                    "guiding centre",
                    kw={"marker": "+", "ms": 9, "ls": "none"},
                ),
            ]
        return []

    @classmethod
    def pictures(cls, config) -> tuple[tuple[str, str], ...]:
        return (("r", "V_eff"), ("x", "y"))

    # ------------------------------------------------------------------ a recording's figures
    @classmethod
    def recorded_figures(cls, config, tr: Traces) -> list[dict[str, Any]]:
        """Gyrofrequency, Larmor radius and pitch (or the beam's periods), each kick's circle
        shift and new radius, and the final energy errors when two methods are compared."""
        p = config.physics()
        figs: list[dict[str, Any]] = []
        main = tr.main
        t, S = tr.times[main], tr.states[main]
        w = cy.gyrofrequency(p)
        kicks = [e["t"] for e in tr.event_log]
        pre = t < (kicks[0] if kicks else math.inf)  # before the first kick
        first = {"until": kicks[0]} if kicks else {}  # true of the motion before the first kick
        if S.shape[1] == 1:
            w_meas = measure.gyrofrequency(t[pre], S[pre, 0, 3:5], xy=S[pre, 0, :2], expected=w)
            keep(figs, "gyrofrequency", w_meas, w, "rad/s", **first)
            circle = measure.fit_circle(S[pre, 0, :2])
            radius = measure.Estimate(circle.value[1]) if circle else circle
            figs.append(figure("Larmor radius", radius, cy.larmor_radius(p, S[0, 0]), "m", **first))
            if w_meas and abs(S[0, 0, 5]) > 0:
                pitch = measure.slope(t[pre], S[pre, 0, 2]) * 2 * math.pi / w_meas.value
                figs.append(figure("helix pitch", pitch, S[0, 0, 5] * cy.period(p), "m", **first))
        else:
            rates = measure.gyrofrequency(t, S[:, :, 3:5], xy=S[:, :, :2], expected=w)
            if rates:
                periods = 2 * math.pi / np.asarray(rates.value)
                figs.append(
                    figure("shortest period in the beam", periods.min(), 2 * math.pi / w, "s")
                )
                figs.append(
                    figure("longest period in the beam", periods.max(), 2 * math.pi / w, "s")
                )
            v = np.hypot(S[0, :, 3], S[0, :, 4])
            figs.append(
                figure(
                    "speed ratio in the beam",
                    v.max() / v.min(),
                    None,
                    "",
                    "the periods agree although the speeds differ by this factor",
                )
            )
        for entry in tr.event_log:
            eff = entry["effects"][main]
            post = t > entry["t"] + 1e-9
            before = measure.fit_circle(S[pre, 0, :2])
            after = measure.fit_circle(S[post, 0, :2])
            if not before or not after:
                continue
            shift = float(np.linalg.norm(after.value[0] - before.value[0]))
            since = {"since": entry["t"]}  # true from the kick on
            figs.append(
                figure("circle shift after the kick", shift, eff["predicted_shift"], "m", **since)
            )
            figs.append(
                figure(
                    "radius after the kick",
                    after.value[1],
                    eff["predicted_radius"][0],
                    "m",
                    **since,
                )
            )
            keep(
                figs,
                "gyrofrequency after the kick",
                measure.gyrofrequency(t[post], S[post, 0, 3:5], xy=S[post, 0, :2], expected=w),
                w,
                "rad/s",
                "unchanged: the period does not depend on the energy",
                **since,
            )
        if len(tr.states) > 1:
            for label, run in tr.runs.items():
                E = tr.energy_error[label][:, 0]
                pred, note = None, ""
                if run["method"] == "euler":
                    pred = (1 + (w * run["dt"]) ** 2) ** tr.steps[label] - 1
                    note = "explicit Euler: |v|² grows by a factor 1 + (Ω dt)² every step"
                elif run["method"] in ("boris", "exact"):
                    pred, note = 0.0, "Boris keeps |v| to round-off"
                figs.append(
                    figure(
                        f"final energy error, {label}", float(E[-1]), pred, "", note, since=t[-1]
                    )
                )
        return figs


def well(p: cy.CyclotronParams, st: np.ndarray) -> dict:
    """The charge's radial motion in its effective potential: ``p_phi`` is conserved, so
    ``E_perp = p_r^2/2m + V_eff(r)`` (:func:`mechviz.dynamics.cyclotron.radial_coordinates`) and ``r``
    swings between the orbit's closest and farthest distances from the axis, where
    ``V_eff = E_perp``. Returns the chart's ``x`` (radii [m], the charge's ``r`` and the well's
    bottom ``r0`` among them), ``V`` [J], the ``level`` E_perp [J], ``point`` and ``bottom`` (V at
    r and at r0, NaN elsewhere), and ``x_range``/``y_range`` to draw."""
    p_phi = float(cy.canonical_angular_momentum(p, st))
    e_perp = 0.5 * p.mass * (st[3] ** 2 + st[4] ** 2)
    r_now = float(cy.radial_coordinates(p, st)[0])
    centre = cy.guiding_centre(p, st)
    dist, rho = math.hypot(centre[0], centre[1]), cy.larmor_radius(p, st)
    r_min, r_max = abs(dist - rho), dist + rho
    r0 = cy.effective_potential_minimum(p, p_phi) if p_phi != 0.0 else 0.0
    x_range, y_range = well_axes(r_max, e_perp)
    hi = x_range[1]
    lo = 0.02 * hi  # the wall near the axis rises far beyond the axes: cut off there
    grid = np.linspace(lo, hi, 240)
    x = np.unique(np.concatenate([grid, [r_now], [r0] if lo <= r0 <= hi else []]))
    with np.errstate(divide="ignore", invalid="ignore"):
        V = cy.effective_potential(p, x, p_phi)
    point = np.where(x == r_now, V, np.nan)
    bottom = np.where(x == r0, V, np.nan) if lo <= r0 <= hi else np.full_like(x, np.nan)
    return {
        "x": x,
        "V": V,
        "level": np.full_like(x, e_perp),
        "point": point,
        "bottom": bottom,
        "x_range": x_range,
        "y_range": y_range,
        "r": r_now,
        "r0": r0,
        "r_min": r_min,
        "r_max": r_max,
        "p_phi": p_phi,
    }


def _demo_speeds(demo: Any, config: CyclotronConfig) -> dict[str, float]:
    """The speeds by the demo key that sets them [m/s]: each one adds to the fastest charge's
    speed (an upper bound, kicks included)."""
    out: dict[str, float] = {}
    ini = demo.initial
    if ini.state is not None:
        out["initial.state"] = math.hypot(*ini.state[3:6])
    else:
        out["initial.speed" if ini.speed is not None else "speed"] = abs(config.speed)
        out["initial.vz" if ini.vz is not None else "vz"] = abs(config.vz)
    if ini.speeds is not None:
        out["initial.speeds"] = max(abs(v) for v in ini.speeds)
    for i, e in enumerate(demo.events):
        out[f"events[{i}].dv"] = abs(e.dv)
    return out
