"""Cyclotron: a charge in a uniform magnetic field along +z.

Shows the field as arrows, the charge with a capped trail of its helix, its guiding centre and
the circle theory predicts for its current energy (radius ``sqrt(2 m E_perp) / |qB|``). A radial
kick (``dynamics.cyclotron.radial_kick``) changes the state at the current time without
restarting the run, and the predicted circle moves at once. A beam of charges leaving the
charge's start point in its direction, with a spread of speeds, advanced in one batched call,
shows that every orbit has the same period. Coordinates are the dynamics' own, relative to the
exhibit's origin; the height along B is drawn modulo ``config.height`` so the helix stays in
view (the trail is broken where it wraps).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

import dynamics
from dynamics import cyclotron as cy
from dynamics import measure

from .. import geometry as geo
from .base import Exhibit, ExhibitConfig, Motion, default_params, finite_numbers, fmt, positive
from .plot import Curve, Variable, common_variables


@dataclass(frozen=True)
class CyclotronConfig(ExhibitConfig):
    """Settings of the cyclotron exhibit.

    The charge starts on the circle of transverse ``speed`` [m/s] about ``centre`` (x, y) [m] with
    ``vz`` [m/s] along B, unless ``state`` gives the whole initial state (x, y, z, vx, vy, vz).
    ``beam``: ``beam_size`` more charges from the same point in the same direction, at speeds
    spread evenly over ``beam_speeds`` [m/s]. ``compare_method`` runs beside the main one, with
    ``compare_dt`` / ``compare_rtol`` if given (else the main run's). ``kick`` [m/s] is the
    radial kick the Kick button gives."""

    system_name: ClassVar[str] = "cyclotron"
    Params: ClassVar[type] = cy.CyclotronParams

    method: str = "exact"
    dt: float = 0.01
    params: dict = field(default_factory=lambda: default_params(cy.CyclotronParams()))
    speed: float = 1.0
    vz: float = 0.05
    centre: tuple = (0.0, 0.0)
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
            raise ValueError(f"beam_size must be a whole number from 1 to 1000, got {self.beam_size!r}")
        lo, hi = (positive("beam_speeds", v) for v in finite_numbers("beam_speeds", self.beam_speeds, 2))
        if lo > hi:
            raise ValueError(f"beam_speeds must be (low, high), got {self.beam_speeds!r}")
        finite_numbers("kick", (self.kick,), 1)
        positive("height", self.height)

    def initial_state(self) -> np.ndarray:
        if self.state is not None:
            return np.array(self.state, dtype=float)
        return cy.circular_orbit_state(self.physics(), self.speed, self.centre, self.vz)

    def beam_states(self) -> np.ndarray:
        """(beam_size, 6): every charge at the start point, moving the same way, at its speed."""
        s0 = self.initial_state()
        speeds = np.linspace(self.beam_speeds[0], self.beam_speeds[1], self.beam_size)
        out = np.tile(s0, (self.beam_size, 1))
        direction = s0[3:5] / math.hypot(s0[3], s0[4])
        out[:, 3:5] = speeds[:, None] * direction
        return out


class BeamTrails:
    """The recent path of every charge of a beam, in one line-segments node: ``points`` per
    charge, sampled every ``every`` frames, at most ``SEGMENTS`` segments in all (so a large
    beam costs no more to send than a small one), broken where the drawn height wraps."""

    SEGMENTS = 2400
    EVERY = 4  # frames between samples: 80 samples at 60 fps span 5.3 s, most of a period at 1x

    def __init__(self, scene, name: str, colors: np.ndarray, height: float) -> None:
        n = len(colors)
        self.k = int(max(8, min(80, self.SEGMENTS // n)))
        self.height = height
        self.points = np.full((n, self.k, 3), np.nan)
        self.frames = 0
        seg_colors = np.repeat(np.repeat(colors[:, None, None, :], self.k - 1, axis=1), 2, axis=2)
        self.node = scene.add_line_segments(
            name, np.zeros((n * (self.k - 1), 2, 3), np.float32),
            colors=seg_colors.reshape(-1, 2, 3), thickness=1.5, thickness_units="screen",
        )  # fmt: skip

    def push(self, positions: np.ndarray) -> None:
        """Sample the charges' drawn positions (n, 3) on every ``EVERY``-th call; redraw then."""
        self.frames += 1
        if (self.frames - 1) % self.EVERY:
            return
        self.points[:, :-1] = self.points[:, 1:]
        self.points[:, -1] = positions
        a, b = self.points[:, :-1], self.points[:, 1:]
        # no segment from a point not yet sampled, nor across the height's wrap-around
        cut = np.isnan(a).any(axis=-1) | (np.abs(b[..., 2] - a[..., 2]) > 0.5 * self.height)
        seg = np.stack([np.where(cut[..., None], b, a), b], axis=2)
        self.node.points = np.nan_to_num(seg).reshape(-1, 2, 3).astype(np.float32)

    def remove(self) -> None:
        self.node.remove()


class CyclotronExhibit(Exhibit):
    """The charge, its theory circle, optional comparison method and optional beam."""

    key = "cyclotron"
    title = "Cyclotron"
    name = "Cyclotron"
    icon = "ATOM"
    Config = CyclotronConfig
    chart_series = ("energy", "error", "energy_compare", "error_compare")

    # ------------------------------------------------------------------ scene (built once)
    def _build(self) -> None:
        s, r, H = self.scene, self.root, self.config.height
        s.add_frame(r, show_axes=False, position=self.origin)
        self.label = s.add_label(
            f"{r}/label", "Cyclotron: charge in a uniform field B",
            position=(0.0, 0.0, H + 0.5), anchor="bottom-center",
        )  # fmt: skip
        self.field_arrows = s.add_arrows(
            f"{r}/field", self._field_points(1.0), colors=geo.FIELD,
            shaft_radius=0.012, head_radius=0.045, head_length=0.12,
        )  # fmt: skip
        self.field_label = s.add_label(f"{r}/field_label", "B", position=(1.6, 1.6, H + 0.1))
        # one batched node: instance 0 the charge, 1 the comparison run (scale 0 while there
        # is none), 2 the guiding centre
        ball = geo.sphere_mesh(0.07)
        self.bodies = s.add_batched_meshes_simple(
            f"{r}/charges", ball.vertices, ball.faces,
            batched_wxyzs=np.tile([1.0, 0.0, 0.0, 0.0], (3, 1)), batched_positions=np.zeros((3, 3)),
            batched_scales=np.array([1.0, 0.0, 0.5]),
            batched_colors=np.array([geo.CHARGE, geo.COMPARE, geo.CENTRE], np.uint8), lod="off",
        )  # fmt: skip
        self.ring = s.add_line_segments(
            f"{r}/theory_circle", geo.circle_segments(1.0),
            colors=np.array(geo.CENTRE, np.uint8), thickness=2.0, thickness_units="screen",
        )  # fmt: skip
        self.trail = geo.ChunkedTrail(s, f"{r}/trail", geo.TRAIL, cap=self.config.trail_cap)
        self.compare_trail = geo.ChunkedTrail(
            s, f"{r}/compare_trail", geo.COMPARE, cap=self.config.trail_cap
        )
        self.beam_node = None
        self.beam_trails: BeamTrails | None = None
        self._ring_radius = 1.0
        self._body_positions = np.zeros((3, 3))

    def _field_points(self, sign: float) -> np.ndarray:
        H = self.config.height
        a, b = (0.0, H) if sign > 0 else (H, 0.0)
        return np.asarray(
            [[[x, y, a], [x, y, b]] for x in (-1.6, 0.0, 1.6) for y in (-1.6, 0.0, 1.6)],
            np.float32,
        )

    # ------------------------------------------------------------------ simulations
    def _start(self) -> None:
        c = self.config
        p = c.physics()
        system = dynamics.Cyclotron(p)
        s0 = c.initial_state()
        sim, cmp_ = self._make_runs(system, s0)
        beam = None
        if c.beam:
            beam = self._make_simulation(system, c.method, c.beam_states(), reference=None)
        # --- nothing above touched the exhibit; install
        self.params = p
        self.sim, self.compare, self.beam = sim, cmp_, beam
        self._reset_common()
        self.trail.clear()
        self.compare_trail.clear()
        self.field_arrows.points = self._field_points(math.copysign(1.0, p.field))
        self._rebuild_beam_node()
        self.bodies.batched_scales = np.array([1.0, 1.0 if cmp_ is not None else 0.0, 0.5])
        self.compare_trail.visible = cmp_ is not None
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
        self.trail.lift()
        self.compare_trail.lift()
        self.trace.clear()  # the plot's points before a kick lie in another well
        self._observe()

    def _rebuild_beam_node(self) -> None:
        if self.beam_node is not None:
            self.beam_node.remove()
            self.beam_node = None
        if self.beam_trails is not None:
            self.beam_trails.remove()
            self.beam_trails = None
        if self.beam is None:
            return
        n = len(self.beam.state)
        sphere = geo.sphere_mesh(0.045, 1)
        t = np.linspace(0.0, 1.0, n)[:, None]
        colors = ((1 - t) * np.array(geo.BEAM[0]) + t * np.array(geo.BEAM[1])).astype(np.uint8)
        self.beam_node = self.scene.add_batched_meshes_simple(
            f"{self.root}/beam", sphere.vertices, sphere.faces,
            batched_wxyzs=np.tile([1.0, 0.0, 0.0, 0.0], (n, 1)),
            batched_positions=self._display(self.beam.state[:, :3]),
            batched_colors=colors, lod="off",
        )  # fmt: skip
        self.beam_trails = BeamTrails(self.scene, f"{self.root}/beam_trails", colors, self.config.height)

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

    def measured(self) -> dict:
        """Gyrofrequency and circle of the charge since its start or last kick
        (:func:`dynamics.measure.gyrofrequency`, :func:`dynamics.measure.fit_circle`), and each
        beam member's gyrofrequency."""
        t, x = self.motion.arrays()
        out: dict = {"gyrofrequency": measure.gyrofrequency(t, x[:, 1], xy=x[:, 0])}
        circle = measure.fit_circle(x[:, 0])
        out["radius"] = measure.Estimate(circle.value[1]) if circle else circle
        out["beam_gyrofrequencies"] = None
        if self.beam_motion is not None:
            tb, vb = self.beam_motion.arrays()
            out["beam_gyrofrequencies"] = measure.gyrofrequency(tb, vb)
        return out

    # ------------------------------------------------------------------ commands
    def _ops_hint(self) -> str:
        return ", kick"

    def _apply_op(self, op, args: dict) -> str:
        if op != "kick":
            return super()._apply_op(op, args)
        dv = finite_numbers("dv", (args.get("dv", self.config.kick),), 1)[0]
        self.kick_effects(dv)
        centre, radius = self.theory_centre, self.theory_radius
        return (
            f"kick dv = {dv:g} m/s: new circle radius {radius:.4g} m "
            f"about ({centre[0]:.3g}, {centre[1]:.3g})"
        )

    def kick_effects(self, dv: float) -> dict[str, dict]:
        """Kick every run (and the beam) radially by ``dv`` [m/s] at the current time, without a
        restart (:meth:`dynamics.Simulation.jump`); returns, by run, the state before and what
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
        self.revision += 1
        self._sample = self._compare_sample = None
        self._begin_segment()
        return out

    # ------------------------------------------------------------------ drawing
    def _display(self, xyz: np.ndarray) -> np.ndarray:
        out = np.array(xyz, dtype=float)
        out[..., 2] = np.mod(out[..., 2], self.config.height)
        return out

    def display_position(self, state: np.ndarray) -> np.ndarray:
        """Where a state's charge is drawn, relative to the exhibit origin."""
        return self._display(np.asarray(state)[:3])

    def _push_trail(self, trail: geo.ChunkedTrail, pos: np.ndarray) -> None:
        last = trail.last_point
        if last is not None and abs(pos[2] - last[2]) > 0.5 * self.config.height:
            trail.lift()  # the displayed height wrapped round: no segment across the jump
        trail.push(pos)
        trail.draw()

    def draw(self) -> None:
        st = self.state
        pos = self.display_position(st)
        p = self.params
        centre = cy.guiding_centre(p, st)
        radius = cy.orbit_radius(p, 0.5 * p.mass * (st[3] ** 2 + st[4] ** 2))
        cs = self.compare_state
        cpos = self.display_position(cs) if cs is not None else pos
        bodies = self._body_positions  # reused: viser copies what it is given
        bodies[0], bodies[1] = pos, cpos
        bodies[2] = centre[0], centre[1], pos[2]
        self.bodies.batched_positions = bodies
        self._push_trail(self.trail, pos)
        if cs is not None:
            self._push_trail(self.compare_trail, cpos)
        if abs(radius - self._ring_radius) > 1e-4 * max(radius, 1e-9):
            self.ring.points = geo.circle_segments(radius)
            self._ring_radius = radius
        self.ring.position = (centre[0], centre[1], pos[2])
        if self.beam is not None and self.beam_node is not None:
            shown = self._display(self.beam.state[:, :3])
            self.beam_node.batched_positions = shown
            self.beam_trails.push(shown)

    def _extent(self):
        H = self.config.height
        return (-1.7, -1.7, 0.0), (1.7, 1.7, H + 0.3)

    @property
    def camera(self):
        o = self.origin
        return (tuple(o + (0.0, -5.2, 3.6)), tuple(o + (0.0, 0.0, 0.8)))

    # ------------------------------------------------------------------ readout
    def readout(self) -> str:
        p, smp = self.params, self.sample
        w_th = cy.gyrofrequency(p)
        m = self.measured()
        w_me = m["gyrofrequency"]
        t_me = fmt(2 * math.pi / w_me.value) if w_me else "—"
        lines = [
            f"**t = {self.t:.2f} s** · {self.method_line(self.sim)}",
            "",
            "| quantity | theory | measured |",
            "|---|---|---|",
            f"| gyrofrequency \\|qB\\|/m [rad/s] | {fmt(w_th)} | {fmt(w_me)} |",
            f"| period 2π/ω [s] | {fmt(2 * math.pi / w_th)} | {t_me} |",
            f"| radius √(2mE)/\\|qB\\| [m] | {fmt(self.theory_radius)} | {fmt(m['radius'])} |",
            f"| relative energy error | 0 | {float(np.max(np.abs(smp.energy_error))):.2e} |",
            f"| error vs exact | 0 | {float(np.max(smp.error)) if smp.error is not None else 0.0:.2e} |",
        ]
        c = self.compare_sample
        if c is not None:
            lines.append(
                f"\nComparison {self.method_line(self.compare)} (blue): relative energy error "
                f"{float(np.max(np.abs(c.energy_error))):.2e}, error {float(np.max(c.error)):.2e}"
            )
        wb = m["beam_gyrofrequencies"]
        if self.beam is not None:
            lo, hi = self.config.beam_speeds
            n = len(self.beam.state)
            if not wb:
                periods = f"periods not resolved ({wb.reason})"
            else:
                T = 2 * math.pi / np.asarray(wb.value)
                periods = (
                    f"measured periods {fmt(T.min(), 7)} to {fmt(T.max(), 7)} s, a spread of "
                    f"{T.max() - T.min():.1e} s against theory's 0 (2πm/\\|qB\\| = "
                    f"{fmt(2 * math.pi / w_th, 7)} s whatever the speed)"
                )
            lines.append(f"\nBeam of {n} charges, speeds {lo:g}–{hi:g} m/s: {periods}")
        lines.append(self.work_line())
        return "\n".join(lines)

    # ------------------------------------------------------------------ the effective potential
    def well(self) -> dict:
        """:func:`well` of the charge's current state."""
        return well(self.params, self.state)

    # ------------------------------------------------------------------ plots
    @classmethod
    def plot_variables(cls, config) -> dict[str, Variable]:
        """The state, and the radial motion of the seed's argument: ``r``, ``p_r``, ``p_phi``
        and ``V_eff(r)`` for the sample's own ``p_phi``."""
        p = config.physics()
        units = {"x": "m", "y": "m", "z": "m", "vx": "m/s", "vy": "m/s", "vz": "m/s"}
        out = common_variables({n: f"{n} [{u}]" for n, u in units.items()})

        def r(s):
            return cy.radial_coordinates(p, s.states)[0]

        def p_phi(s):
            return cy.canonical_angular_momentum(p, s.states)

        def v_eff(s):
            with np.errstate(divide="ignore", invalid="ignore"):
                return cy.effective_potential(p, r(s), p_phi(s))

        out["r"] = Variable("distance from the axis r [m]", r)
        out["p_r"] = Variable("radial momentum p_r [kg m/s]", lambda s: cy.radial_coordinates(p, s.states)[1])
        out["p_phi"] = Variable("canonical ang. momentum p_φ [kg m²/s]", p_phi)
        out["V_eff"] = Variable("V_eff(r) [J]", v_eff)
        return out

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
                Curve(w["x"], w["V"], "V_eff(r)"),
                Curve(np.array([lo, hi]), np.full(2, w["level"][0]), "level E⊥", dashed=True),
                Curve(np.array([w["r0"]]), np.array([cy.effective_potential(p, w["r0"], w["p_phi"])
                      if w["r0"] > 0 else np.nan]), "bottom r0",
                      kw={"marker": "o", "ls": "none"}),
            ]  # fmt: skip
        if (x, y) == ("x", "y"):
            centre, rho = cy.guiding_centre(p, st), cy.larmor_radius(p, st)
            phi = np.linspace(0.0, 2 * math.pi, 181)
            return [
                Curve(centre[0] + rho * np.cos(phi), centre[1] + rho * np.sin(phi),
                      "predicted circle", dashed=True),
                Curve(np.array([centre[0]]), np.array([centre[1]]), "guiding centre",
                      kw={"marker": "+", "ms": 9, "ls": "none"}),
            ]  # fmt: skip
        return []

    @classmethod
    def pictures(cls, config) -> tuple[tuple[str, str], ...]:
        return (("r", "V_eff"), ("x", "y"))

    # ------------------------------------------------------------------ GUI
    def build_panel(self, panel) -> None:
        gui, c = panel.gui, self.config
        panel.readout_and_chart(compare=True)
        panel.param_inputs({"charge": "Charge q [C]", "mass": "Mass m [kg]", "field": "Field B [T]"})
        panel.integrator_inputs(compare=True)
        with gui.add_folder("Kick and beam"):
            strength = panel.slider("kick", "Kick dv [m/s]", -1.0, 1.0, 0.05, c.kick, lambda v: None)
            kick = gui.add_button("Kick", hint="Radial velocity kick: the predicted circle moves at once")
            beam = panel.put("beam", gui.add_checkbox(
                "Beam", initial_value=c.beam, hint="Many charges, a spread of speeds"
            ))  # fmt: skip
            panel.slider("beam_size", "Beam size", 2, 200, 1, c.beam_size,
                         lambda v: panel.send({"op": "set", "beam_size": int(v)}))  # fmt: skip
        kick.on_click(lambda _: panel.send({"op": "kick", "dv": float(strength.value)}))
        panel.on(beam, lambda v: panel.send({"op": "set", "beam": bool(v)}))
        panel.plot(
            "p_φ is conserved, so r moves in the well V_eff(r) = (p_φ − qBr²/2)²/2mr² at the level "
            "E⊥ (dashed), between the turning points, at the gyrofrequency; its bottom is "
            "r0 = √(2\\|p_φ\\|/\\|qB\\|). A kick changes p_φ and redraws the well. Pick x and y "
            "for any other pair: (x, y) shows the orbit from above with the predicted circle."
        )


def well(p: cy.CyclotronParams, st: np.ndarray) -> dict:
    """The charge's radial motion in its effective potential: ``p_phi`` is conserved, so
    ``E_perp = p_r^2/2m + V_eff(r)`` (:func:`dynamics.cyclotron.radial_coordinates`) and ``r``
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
    lo = max(0.5 * r_min, 0.02 * r_max)
    hi = 1.25 * r_max + 0.05
    grid = np.linspace(lo, hi, 160)
    x = np.unique(np.concatenate([grid, [r_now], [r0] if lo <= r0 <= hi else []]))
    with np.errstate(divide="ignore", invalid="ignore"):
        V = cy.effective_potential(p, x, p_phi)
    point = np.where(x == r_now, V, np.nan)
    bottom = np.where(x == r0, V, np.nan) if lo <= r0 <= hi else np.full_like(x, np.nan)
    return {
        "x": x, "V": V, "level": np.full_like(x, e_perp), "point": point, "bottom": bottom,
        "x_range": (float(lo), float(hi)), "y_range": (0.0, 2.5 * e_perp if e_perp > 0 else 1.0),
        "r": r_now, "r0": r0, "r_min": r_min, "r_max": r_max, "p_phi": p_phi,
    }  # fmt: skip
