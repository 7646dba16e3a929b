"""Cyclotron exhibit: a charge in a uniform magnetic field along +z.

Shows the field as arrows, the charge with a capped trail of its helix, its guiding centre and
the circle theory predicts for its current energy (radius ``sqrt(2 m E_perp) / (|q| B)``). A radial
kick moves the circle at once (``dynamics.cyclotron.radial_kick``); a beam of charges with a spread
of speeds, advanced in one batched call, shows that every orbit has the same period. Coordinates
are the dynamics' own, relative to the exhibit's origin; the height along B is shown modulo
``config.height`` so the helix stays in view (the trail is broken where it wraps).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

import dynamics
from dynamics import cyclotron as cy

from . import geometry as geo
from .defaults import DEFAULTS
from .exhibit import Exhibit, check_method, fmt, make_simulation, positive


@dataclass(frozen=True)
class CyclotronConfig:
    """Settings of the cyclotron exhibit (defaults: ``DEFAULTS["cyclotron"]``)."""

    method: str = "exact"
    dt: float = 0.01
    rtol: float = 1e-9
    params: dict = field(default_factory=lambda: dict(DEFAULTS["cyclotron"]["params"]))
    speed: float = 1.0
    vz: float = 0.05
    beam: bool = False
    beam_size: int = 16
    beam_speeds: tuple = (0.25, 1.75)
    kick: float = 0.5
    compare_method: str | None = None
    trail_cap: int = 600
    height: float = 2.0

    @classmethod
    def from_defaults(cls, **overrides) -> CyclotronConfig:
        d = {
            k: v
            for k, v in DEFAULTS["cyclotron"].items()
            if k in {f.name for f in dataclasses.fields(cls)}
        }
        d["params"] = dict(d["params"])
        d.update(overrides)
        return cls(**d)

    def physics(self) -> cy.CyclotronParams:
        return cy.CyclotronParams(**self.params)

    def validate(self) -> None:
        self.physics()  # ValueError naming the parameter
        check_method("cyclotron", self.method)
        check_method("cyclotron", self.compare_method, "compare_method")
        positive("dt", self.dt)
        if not 0.0 < float(self.rtol) < 1.0:
            raise ValueError(f"rtol must be in (0, 1), got {self.rtol!r}")
        positive("speed", self.speed)
        if not math.isfinite(float(self.vz)):
            raise ValueError(f"vz must be finite, got {self.vz!r}")
        if not (isinstance(self.beam_size, int) and 1 <= self.beam_size <= 1000):
            raise ValueError(f"beam_size must be an integer in 1..1000, got {self.beam_size!r}")
        lo, hi = (positive("beam_speeds", v) for v in self.beam_speeds)
        if lo > hi:
            raise ValueError(f"beam_speeds must be (low, high), got {self.beam_speeds!r}")
        positive("height", self.height)
        if int(self.trail_cap) < 2:
            raise ValueError(f"trail_cap must be at least 2, got {self.trail_cap!r}")


class CyclotronExhibit(Exhibit):
    """The charge, its theory circle, optional comparison method and optional beam."""

    key = "cyclotron"
    title = "Cyclotron"
    Config = CyclotronConfig
    chart_series = ("energy", "error", "energy_compare", "error_compare")

    # ------------------------------------------------------------------ scene (built once)
    def _build(self) -> None:
        s, r, H = self.scene, self.root, self.config.height
        s.add_frame(r, show_axes=False, position=self.origin)
        self.label = s.add_label(
            f"{r}/label",
            "Cyclotron: charge in a uniform field B",
            position=(0.0, 0.0, H + 0.5),
            anchor="bottom-center",
        )
        self.field_arrows = s.add_arrows(
            f"{r}/field",
            self._field_points(1.0),
            colors=geo.FIELD,
            shaft_radius=0.012,
            head_radius=0.045,
            head_length=0.12,
        )
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
            f"{r}/theory_circle",
            geo.circle_segments(1.0),
            colors=np.array((255, 255, 255), np.uint8),
            thickness=1.5,
            thickness_units="screen",
        )
        self.trail = geo.ChunkedTrail(s, f"{r}/trail", geo.TRAIL, cap=self.config.trail_cap)
        self.compare_trail = geo.ChunkedTrail(
            s, f"{r}/compare_trail", geo.COMPARE, cap=self.config.trail_cap
        )
        self.beam_node = None
        self._ring_radius = 1.0
        self._body_positions = np.zeros((3, 3))

    def _field_points(self, sign: float) -> np.ndarray:
        H = self.config.height
        pts = []
        for x in (-1.6, 0.0, 1.6):
            for y in (-1.6, 0.0, 1.6):
                a, b = (0.0, H) if sign > 0 else (H, 0.0)
                pts.append([[x, y, a], [x, y, b]])
        return np.asarray(pts, np.float32)

    # ------------------------------------------------------------------ simulations
    def initial_state(self) -> np.ndarray:
        return cy.circular_orbit_state(self.config.physics(), self.config.speed, vz=self.config.vz)

    def beam_states(self) -> np.ndarray:
        c, p = self.config, self.config.physics()
        speeds = np.linspace(c.beam_speeds[0], c.beam_speeds[1], c.beam_size)
        s0 = cy.circular_orbit_state(p, c.speed, vz=c.vz)
        out = np.tile(s0, (c.beam_size, 1))
        # every charge starts at the same point with the same direction, at its own speed
        direction = s0[3:5] / np.hypot(s0[3], s0[4])
        out[:, 3:5] = speeds[:, None] * direction
        return out

    def _start(
        self, state=None, compare_state=None, t_offset: float = 0.0, keep_beam=False
    ) -> None:
        c = self.config
        p = c.physics()
        system = dynamics.Cyclotron(p)
        s0 = self.initial_state() if state is None else state
        sim = make_simulation(system, c.method, c.dt, c.rtol, s0)
        cmp_ = None
        if c.compare_method:
            cs0 = s0 if compare_state is None else compare_state
            cmp_ = make_simulation(system, c.compare_method, c.dt, c.rtol, cs0)
        beam = self.beam if keep_beam else None
        if c.beam and beam is None:
            beam = make_simulation(
                system, c.method, c.dt, c.rtol, self.beam_states(), reference=None
            )
        # --- nothing above touched the exhibit; install
        self.params = p
        self.sim, self.compare = sim, cmp_
        self.beam = beam if c.beam else None
        if not keep_beam:
            self._reset_common()
            self.trail.clear()
            self.compare_trail.clear()
            self.field_arrows.points = self._field_points(math.copysign(1.0, p.field))
            self._rebuild_beam_node()
            self.bodies.batched_scales = np.array([1.0, 1.0 if cmp_ is not None else 0.0, 0.5])
            self.compare_trail.visible = cmp_ is not None
        self._sample = self._compare_sample = None
        self.t_offset = t_offset
        st = self.state
        self.theory_centre = cy.guiding_centre(p, st)
        self.theory_radius = cy.orbit_radius(p, 0.5 * p.mass * (st[3] ** 2 + st[4] ** 2))
        self._phase = 0.0
        self._phase_t0 = self.t
        self._v_prev = st[3:5].copy()
        if self.beam is not None and not keep_beam:
            self._beam_phase = np.zeros(c.beam_size)
            self._beam_v_prev = self.beam.state[:, 3:5].copy()
            self._beam_t0 = self.beam.t
        self._r_meas = float(np.hypot(*(st[:2] - self.theory_centre[:2])))
        self.trail.lift()
        self.compare_trail.lift()

    def _rebuild_beam_node(self) -> None:
        if self.beam_node is not None:
            self.beam_node.remove()
            self.beam_node = None
        if self.beam is None:
            return
        n = len(self.beam.state)
        sphere = geo.sphere_mesh(0.045, 1)
        t = np.linspace(0.0, 1.0, n)[:, None]
        colors = ((1 - t) * np.array([255, 230, 60]) + t * np.array([255, 110, 20])).astype(
            np.uint8
        )
        self.beam_node = self.scene.add_batched_meshes_simple(
            f"{self.root}/beam",
            sphere.vertices,
            sphere.faces,
            batched_wxyzs=np.tile([1.0, 0.0, 0.0, 0.0], (n, 1)),
            batched_positions=self._display(self.beam.state[:, :3]),
            batched_colors=colors,
            lod="off",
        )

    def _extra_simulations(self):
        return [self.beam] if self.beam is not None else []

    # ------------------------------------------------------------------ measurements
    @staticmethod
    def _turn(v_prev: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Signed angle from v_prev to v (arrays (..., 2))."""
        cross = v_prev[..., 0] * v[..., 1] - v_prev[..., 1] * v[..., 0]
        dot = (v_prev * v).sum(axis=-1)
        return np.arctan2(cross, dot)

    def _after_advance(self) -> None:
        st = self.state
        self._phase += float(self._turn(self._v_prev, st[3:5]))
        self._v_prev = st[3:5].copy()
        self._r_meas = float(np.hypot(*(st[:2] - self.theory_centre[:2])))
        if self.beam is not None:
            v = self.beam.state[:, 3:5]
            self._beam_phase += self._turn(self._beam_v_prev, v)
            self._beam_v_prev = v.copy()

    def measured_gyrofrequency(self) -> float | None:
        span = self.t - self._phase_t0
        return abs(self._phase) / span if span > 0 else None

    def beam_gyrofrequencies(self) -> np.ndarray | None:
        if self.beam is None or self.beam.t - self._beam_t0 <= 0:
            return None
        return np.abs(self._beam_phase) / (self.beam.t - self._beam_t0)

    # ------------------------------------------------------------------ commands
    def _ops_hint(self) -> str:
        return ", kick"

    def _apply_op(self, op, args: dict) -> str:
        if op != "kick":
            return super()._apply_op(op, args)
        dv = float(args.get("dv", self.config.kick))
        if not math.isfinite(dv):
            raise ValueError(f"dv must be finite, got {dv!r}")
        p = self.params
        new, centre, radius = cy.radial_kick(p, self.sample.state[0], dv)
        cnew = None
        if self.compare is not None:
            cnew = cy.radial_kick(p, self.compare_sample.state[0], dv)[0]
        t = self.t
        self._start(new, cnew, t_offset=t, keep_beam=True)
        cx, cy_ = centre[0], centre[1]
        return f"kick dv = {dv:g} m/s: new circle radius {radius:.4g} m about ({cx:.3g}, {cy_:.3g})"

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
            self.beam_node.batched_positions = self._display(self.beam.state[:, :3])

    @property
    def camera(self):
        o = self.origin
        return (tuple(o + (0.0, -5.2, 3.6)), tuple(o + (0.0, 0.0, 0.8)))

    # ------------------------------------------------------------------ readout
    def readout(self) -> str:
        p, smp = self.params, self.sample
        w_th = cy.gyrofrequency(p)
        w_me = self.measured_gyrofrequency()
        lines = [
            f"**t = {self.t:.2f} s** · {self.method_line(self.sim)}",
            "",
            "| quantity | theory | measured |",
            "|---|---|---|",
            f"| gyrofrequency \\|q\\|B/m [rad/s] | {fmt(w_th)} | {fmt(w_me) if w_me else '—'} |",
            f"| period 2π/ω [s] | {fmt(2 * math.pi / w_th)} | {fmt(2 * math.pi / w_me) if w_me else '—'} |",
            f"| radius √(2mE)/(\\|q\\|B) [m] | {fmt(self.theory_radius)} | {fmt(self._r_meas)} |",
            f"| energy error \\|ΔE/E₀\\| | 0 | {float(np.max(np.abs(smp.energy_error))):.2e} |",
            f"| error vs exact | 0 | {float(np.max(smp.error)) if smp.error is not None else 0.0:.2e} |",
        ]
        c = self.compare_sample
        if c is not None:
            lines.append(
                f"\nComparison {self.method_line(self.compare)} (blue): |ΔE/E₀| = "
                f"{float(np.max(np.abs(c.energy_error))):.2e}, error {float(np.max(c.error)):.2e}"
            )
        wb = self.beam_gyrofrequencies()
        if wb is not None:
            lines.append(
                f"\nBeam of {len(wb)} charges, speeds {self.config.beam_speeds[0]:g}–"
                f"{self.config.beam_speeds[1]:g} m/s: ω from {fmt(wb.min())} to {fmt(wb.max())} rad/s "
                "(same period for all)"
            )
        lines.append(f"\nSteps {smp.steps}, RHS evaluations {smp.nfev}.")
        if self.failure:
            lines.append(f"\n**Paused:** {self.failure}")
        return "\n".join(lines)
