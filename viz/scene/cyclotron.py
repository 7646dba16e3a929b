"""Cyclotron: a charge in a uniform magnetic field along +z.

Shows the field as arrows, the charge with a capped trail of its helix, its guiding centre and
the circle theory predicts for its current energy (radius ``sqrt(2 m E_perp) / |qB|``). A radial
kick (``mechviz.dynamics.cyclotron.radial_kick``) changes the state at the current time without
restarting the run, and the predicted circle moves at once. A beam of charges leaving the
charge's start point in its direction, with a spread of speeds, advanced in one batched call,
shows that every orbit has the same period. Coordinates are the dynamics' own, relative to the
exhibit's origin; the height along B is drawn modulo ``config.height`` so the helix stays in
view (the trail is broken where it wraps).
"""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np

from mechviz.dynamics import cyclotron as cy

from .. import geometry as geo
from ..model.commands import Kick
from ..model.cyclotron import CyclotronConfig, CyclotronModel, well  # noqa: F401  (re-exported)
from .base import Event, Exhibit, against_theory, fmt


class BeamTrails:
    """The recent path of every charge of a beam, in one line-segments node: ``points`` per
    charge, sampled every ``every`` frames, at most ``SEGMENTS`` segments in all (so a large
    beam costs no more to send than a small one), broken where the drawn height wraps."""

    SEGMENTS = 2400
    EVERY = 4  # frames between samples: 80 samples at 60 fps span 5.3 s, most of a period at 1x

    def __init__(self, scene, name: str, colors: np.ndarray, height: float, box=None) -> None:
        n = len(colors)
        self.box = box  # (lo, hi) where trails are drawn
        self.k = int(max(8, min(80, self.SEGMENTS // n)))
        self.height = height
        self.points = np.full((n, self.k, 3), np.nan)
        self.frames = 0
        seg_colors = np.repeat(np.repeat(colors[:, None, None, :], self.k - 1, axis=1), 2, axis=2)
        self.node = geo.lines(
            scene,
            name,
            np.zeros((n * (self.k - 1), 2, 3), np.float32),
            seg_colors.reshape(-1, 2, 3),
            1.5,
        )

    def push(self, positions: np.ndarray) -> None:
        """Sample the charges' drawn positions (n, 3) on every ``EVERY``-th call; redraw then."""
        self.frames += 1
        if (self.frames - 1) % self.EVERY:
            return
        self.points[:, :-1] = self.points[:, 1:]
        self.points[:, -1] = positions
        if self.box is not None:  # a charge outside the exhibit draws no trail there
            lo, hi = self.box
            self.points[:, -1][np.any((positions < lo) | (positions > hi), axis=-1)] = np.nan
        a, b = self.points[:, :-1], self.points[:, 1:]
        # no segment from a point not yet sampled, nor across the height's wrap-around
        cut = np.isnan(a).any(axis=-1) | (np.abs(b[..., 2] - a[..., 2]) > 0.5 * self.height)
        seg = np.stack([np.where(cut[..., None], b, a), b], axis=2)
        self.node.points = np.nan_to_num(seg).reshape(-1, 2, 3).astype(np.float32)

    def remove(self) -> None:
        self.node.remove()


class CyclotronExhibit(Exhibit):
    """The cyclotron drawn: the charge with its trail, the predicted circle, the field, the
    comparison run and the beam."""

    model_type = CyclotronModel
    icon = "ATOM"
    caption = "every orbit takes 2πm/|q|B, whatever its speed"
    listens: ClassVar[dict[Event, str]] = {
        "started": "_started",
        "segment": "_segment_started",
        "rewound": "_rewound",
        "beam": "_beam_changed",
    }

    def stage_plot(self):
        # x swings at the gyrofrequency: its period is the figure the stage measures
        return "charge's x [m]", (("x", geo.CHARGE),)

    # ------------------------------------------------------------------ scene (built once)
    def _build(self) -> None:
        s, r, H = self.scene, self.root, self.model.config.height
        s.add_frame(r, show_axes=False, position=self.origin)
        self.label = s.add_label(
            f"{r}/label",
            "Cyclotron: charge in a field B",
            # above the back edge: seen from the top it lies beyond the orbit, not across it
            position=(0.0, 1.7, H + 0.5),
            anchor="bottom-center",
            # hidden behind what stands in front of it (the hoop's chaos map, seen from the
            # hoop's view), as the exhibit itself is
            depth_test=True,
        )
        self.field_arrows = s.add_arrows(
            f"{r}/field",
            self._field_points(1.0),
            colors=geo.FIELD,
            shaft_radius=0.012,
            head_radius=0.045,
            head_length=0.12,
        )
        self.field_label = s.add_label(f"{r}/field_label", "field B", position=(-1.6, 1.6, H + 0.1))
        # one batched node: instance 0 the charge, 1 the comparison run (scale 0 while there
        # is none), 2 the guiding centre
        ball = geo.sphere_mesh(0.07)
        colors = [geo.CHARGE, geo.COMPARE, geo.CENTRE]
        self.bodies = geo.instances(
            s, f"{r}/charges", ball, colors, scales=np.array([1.0, 0.0, 0.5])
        )
        self.ring = geo.lines(s, f"{r}/theory_circle", geo.circle_segments(1.0), geo.CENTRE, 2.0)
        # the orbit before the last kick, faint: the kick's shift of the circle stays in view
        self.ghost_ring = geo.lines(
            s, f"{r}/orbit_before_kick", geo.circle_segments(1.0), geo.GHOST, 1.5, visible=False
        )
        self._drawn_circle: tuple | None = None  # (centre x, y, radius, height) last drawn
        self.trail = geo.ChunkedTrail(s, f"{r}/trail", geo.TRAIL, cap=self.model.config.trail_cap)
        self.compare_trail = geo.ChunkedTrail(
            s, f"{r}/compare_trail", geo.COMPARE, cap=self.model.config.trail_cap
        )
        self.beam_node = None
        self.beam_trails: BeamTrails | None = None
        self._ring_radius = 1.0
        self._body_positions = np.zeros((3, 3))

    def _field_points(self, sign: float) -> np.ndarray:
        H = self.model.config.height
        a, b = (0.0, H) if sign > 0 else (H, 0.0)
        return np.asarray(
            [[[x, y, a], [x, y, b]] for x in (-1.6, 0.0, 1.6) for y in (-1.6, 0.0, 1.6)],
            np.float32,
        )

    def _started(self) -> None:
        p, cmp_ = self.model.params, self.model.compare
        self.ghost_ring.visible = False  # a new start has no orbit before a kick
        self._drawn_circle = None
        self.trail.clear()
        self.compare_trail.clear()
        self.field_arrows.points = self._field_points(math.copysign(1.0, p.field))
        self._rebuild_beam_node()
        self.bodies.batched_scales = np.array([1.0, 1.0 if cmp_ is not None else 0.0, 0.5])
        self.compare_trail.visible = cmp_ is not None
        self._segment_started()  # the trails' box (the model's next announcement says it again)

    def _segment_started(self) -> None:
        self.trail.lift()
        self.compare_trail.lift()
        # trails are drawn inside the exhibit and the circles its runs are on now (a kick may
        # send one beyond the exhibit's edge): a spiral growing out of them stops at the edge
        box = self._trail_box()
        self.trail.box = self.compare_trail.box = box
        if self.beam_trails is not None:
            self.beam_trails.box = box
        if self._drawn_circle is not None:  # a kick: keep the old orbit
            x, y, radius, z = self._drawn_circle
            self.ghost_ring.points = geo.circle_segments(radius)
            self.ghost_ring.position = (x, y, z)
            self.ghost_ring.visible = True

    def _rewound(self) -> None:
        # gone back in the run: the next points start new pieces (no line back across the
        # path already drawn); the beam's short trails start afresh
        self.trail.lift()
        self.compare_trail.lift()
        self.trail.box = self.compare_trail.box = box = self._trail_box()
        if self.beam_trails is not None:
            self.beam_trails.points[:] = np.nan
            self.beam_trails.box = box

    def _beam_changed(self) -> None:
        self._rebuild_beam_node()

    def _rebuild_beam_node(self) -> None:
        if self.beam_node is not None:
            self.beam_node.remove()
            self.beam_node = None
        if self.beam_trails is not None:
            self.beam_trails.remove()
            self.beam_trails = None
        if self.model.beam is None:
            return
        n = len(self.model.beam.state)
        sphere = geo.sphere_mesh(0.045, 1)
        t = np.linspace(0.0, 1.0, n)[:, None]
        colors = ((1 - t) * np.array(geo.BEAM[0]) + t * np.array(geo.BEAM[1])).astype(np.uint8)
        self.beam_node = geo.instances(
            self.scene,
            f"{self.root}/beam",
            sphere,
            colors,
            positions=self._display(self.model.beam.state[:, :3]),
        )
        self.beam_trails = BeamTrails(
            self.scene,
            f"{self.root}/beam_trails",
            colors,
            self.model.config.height,
        )

    # ------------------------------------------------------------------ drawing
    def _display(self, xyz: np.ndarray) -> np.ndarray:
        out = np.array(xyz, dtype=float)
        out[..., 2] = np.mod(out[..., 2], self.model.config.height)
        return out

    def display_position(self, state: np.ndarray) -> np.ndarray:
        """Where a state's charge is drawn, relative to the exhibit origin."""
        return self._display(np.asarray(state)[:3])

    def _push_trail(self, trail: geo.ChunkedTrail, pos: np.ndarray) -> None:
        last = trail.last_point
        if last is not None and abs(pos[2] - last[2]) > 0.5 * self.model.config.height:
            trail.lift()  # the displayed height wrapped round: no segment across the jump
        trail.push(pos)
        trail.draw()

    def draw(self) -> None:
        st = self.model.state
        pos = self.display_position(st)
        p = self.model.params
        centre = cy.guiding_centre(p, st)
        radius = cy.orbit_radius(p, 0.5 * p.mass * (st[3] ** 2 + st[4] ** 2))
        cs = self.model.compare_state
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
        self._drawn_circle = (float(centre[0]), float(centre[1]), float(radius), float(pos[2]))
        if self.model.beam is not None and self.beam_node is not None:
            shown = self._display(self.model.beam.state[:, :3])
            self.beam_node.batched_positions = shown
            self.beam_trails.push(shown)

    def _trail_box(self) -> tuple[np.ndarray, np.ndarray] | None:
        """The exhibit's box grown to hold the circle every run (beam members included) is on
        (``None``: drawn anywhere, the exhibit alone)."""
        if not self.bounded:
            return None
        lo, hi = (np.array(v, float) for v in self._extent())
        p = self.model.params
        for sim in self.model.simulations():
            for s in sim.state:
                c, r = cy.guiding_centre(p, s)[:2], 1.01 * cy.larmor_radius(p, s)
                lo[:2], hi[:2] = np.minimum(lo[:2], c - r), np.maximum(hi[:2], c + r)
        return lo.astype(np.float32), hi.astype(np.float32)

    def _extent(self):
        H = self.model.config.height
        # up to the title above the field (its text stands on H + 0.5): framed, it is in the picture
        return (-1.7, -1.7, 0.0), (1.7, 1.7, H + 0.8)

    @property
    def camera(self):
        o = self.origin
        return (tuple(o + (0.0, -5.2, 3.6)), tuple(o + (0.0, 0.0, 0.8)))

    # ------------------------------------------------------------------ readout
    def key_figures(self) -> list[tuple[str, str]]:
        m = self.model.measured()
        w_th = cy.gyrofrequency(self.model.params)
        return [
            ("ω", against_theory(m["gyrofrequency"], "rad/s", w_th)),
            ("r", against_theory(m["radius"], "m", self.model.theory_radius)),
            *super().key_figures(),
        ]

    def readout(self) -> str:
        p, smp = self.model.params, self.model.sample
        w_th = cy.gyrofrequency(p)
        m = self.model.measured()
        w_me = m["gyrofrequency"]
        t_me = fmt(2 * math.pi / w_me.value) if w_me else "—"
        lines = [
            f"**t = {self.model.t:.2f} s** · {self.model.method_line(self.model.sim)}",
            "",
            "| quantity | theory | measured |",
            "|---|---|---|",
            f"| gyrofrequency \\|qB\\|/m [rad/s] | {fmt(w_th)} | {fmt(w_me)} |",
            f"| period 2π/ω [s] | {fmt(2 * math.pi / w_th)} | {t_me} |",
            f"| radius √(2mE)/\\|qB\\| [m] | {fmt(self.model.theory_radius)} | {fmt(m['radius'])} |",
            f"| relative energy error | 0 | {float(np.max(np.abs(smp.energy_error))):.2e} |",
            f"| error vs exact | 0 | {float(np.max(smp.error)) if smp.error is not None else 0.0:.2e} |",
        ]
        c = self.model.compare_sample
        if c is not None:
            lines.append(
                f"\nComparison {self.model.method_line(self.model.compare)} (blue): relative energy error "
                f"{float(np.max(np.abs(c.energy_error))):.2e}, error {float(np.max(c.error)):.2e}"
            )
        wb = m["beam_gyrofrequencies"]
        if self.model.beam is not None:
            lo, hi = self.model.config.beam_speeds
            n = len(self.model.beam.state)
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
        lines.append(self.model.work_line())
        return "\n".join(lines)

    # ------------------------------------------------------------------ GUI
    def build_panel(self, panel) -> None:
        gui, c = panel.gui, self.model.config
        panel.readout_and_chart(compare=True)
        panel.param_inputs()
        panel.integrator_inputs(compare=True)
        with gui.add_folder("Kick and beam"):
            panel.slider(
                "kick",
                "Kick dv [m/s]",
                -1.0,
                1.0,
                0.05,
                c.kick,
                lambda v: panel.change(kick=float(v)),
            )
            kick = gui.add_button(
                "Kick", hint="Radial velocity kick: the predicted circle moves at once"
            )
            beam = panel.put(
                "beam",
                gui.add_checkbox(
                    "Beam", initial_value=c.beam, hint="Many charges, a spread of speeds"
                ),
            )
            panel.slider(
                "beam_size",
                "Beam size",
                2,
                200,
                1,
                c.beam_size,
                # a whole number goes as one; 2.5 is refused by the config, named
                lambda v: panel.change(beam_size=int(v) if float(v).is_integer() else v),
            )

        def give_kick(_event) -> None:
            panel.app.typing.left()  # the person left any box typed in (text not entered stays so)
            panel.send(Kick())  # dv: the kick in force when the command is applied

        kick.on_click(give_kick)
        panel.on(beam, lambda v: panel.change(beam=bool(v)))
        panel.plot(
            "p_φ is conserved, so r moves in the well V_eff(r) = (p_φ − qBr²/2)²/2mr² at the level "
            "E⊥ (dashed), between the turning points, at the gyrofrequency; its bottom is "
            "r0 = √(2\\|p_φ\\|/\\|qB\\|). A kick changes p_φ and redraws the well. Pick x and y "
            "for any other pair: (x, y) shows the orbit from above with the predicted circle."
        )
