"""Spinning-disk exhibit: a disk with a bead on its rim, turned about an axle along a diameter.

*Driven*: the exact uniform rotation (``mechviz.dynamics.DrivenDisk``, method ``exact``); the bearing
forces at A and B (``mechviz.dynamics.disk.bearing_force_a/b``) are drawn as arrows that turn with the
disk, scaled to their magnitude, beside the angular velocity (along the axle) and the angular
momentum about A (not along it: that is why the bearings must push). *Released*: the axle is
removed at ``t = 0`` and the free body tumbles (``mechviz.dynamics.ReleasedDisk``, integrated by the chosen
method); drawn by default in the frame moving with its centre of mass, with Poinsot's
construction (:mod:`mechviz.viz.scene.poinsot`).

World mapping (:data:`mechviz.viz.scene.poinsot.P`): the dynamics' disk frame (axle along
+y) is drawn with the axle vertical and the disk facing the default camera at ``t = 0``: world
``(x, y, z) = lift + P (x, y, z)_disk`` with ``P`` sending disk ``x -> x``, ``y -> z``,
``z -> -y`` (a proper rotation), ``lift = (0, 0, 0.4)`` above the exhibit origin.
"""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np

from mechviz.dynamics import disk as dk

from .. import geometry as geo
from ..model.disk import MODES, DiskConfig, DiskModel, principal_axes_for  # noqa: F401
from .base import Event, Exhibit, against_theory, error_text, fmt
from .poinsot import LIFT, P, PoinsotPicture, to_world

AXIS_NAMES = ("(red)", "(green)", "(blue)")  # the principal axes' arrows, geo.AXES_RGB
TITLE = "Spinning disk with a bead"
# The disk's opacity: driven, nearly solid; released, the Poinsot ellipsoid at the centre of
# mass shows through it.
DISK_OPACITY = {"driven": 0.85, "released": 0.3}


class DiskExhibit(Exhibit):
    """The disk drawn: the body with its bead, the axle and bearings, omega, L and the forces
    while driven, the Poinsot construction once released."""

    model_type = DiskModel
    listens: ClassVar[dict[Event, str]] = {"started": "_started", "rewound": "_rewound"}
    icon = "DISC"
    caption = "L is not along ω: held, the bearings push; free, it tumbles"

    def _build(self) -> None:
        s, r = self.scene, self.root
        s.add_frame(r, show_axes=False, position=self.origin)
        self.poinsot = PoinsotPicture(s, r)
        self.label = s.add_label(
            f"{r}/label",
            TITLE,
            # above the highest ω's label reaches as the released disk tumbles
            position=(0.0, 0.0, 3.1),
            anchor="bottom-center",
            # hidden behind what stands in front of it (the hoop's chaos map, seen from the
            # hoop's view), as the exhibit itself is
            depth_test=True,
        )
        # omega, L and, while driven, dL/dt = omega x L drawn at L's tip (the torque the
        # bearings must supply; L's tip sweeps the rim of a cone about the axle, drawn too)
        self.vectors = s.add_arrows(
            f"{r}/vectors",
            np.zeros((3, 2, 3), np.float32),
            colors=np.array([geo.OMEGA, geo.MOMENTUM, geo.TORQUE], np.uint8),
            shaft_radius=0.02,
            head_radius=0.06,
            head_length=0.14,
        )
        self.cone_rim = geo.lines(
            s, f"{r}/L_cone_rim", np.zeros((1, 2, 3), np.float32), geo.MOMENTUM, 1.5
        )
        self.forces = s.add_arrows(
            f"{r}/bearing_forces",
            np.zeros((2, 2, 3), np.float32),
            colors=geo.FORCE,
            shaft_radius=0.025,
            head_radius=0.07,
            head_length=0.16,
        )
        # ω's label sits above its tip and L's hangs below its own: L's tip is always lower (it
        # has a part across the axle), so the two never cover each other as L turns.
        self.vector_labels = [
            s.add_label(f"{r}/vector_label_ω", "ω", anchor="bottom-center"),
            s.add_label(f"{r}/vector_label_L", "L", anchor="top-center"),
        ]
        self._built_radius = self._built_masses = None

    def _build_body(self, p: dk.DiskParams) -> None:
        s, r, R = self.scene, self.root, p.radius
        self._built_radius = R
        body = f"{r}/body"
        self.body = s.add_frame(body, show_axes=False)
        disk = geo.disk_mesh(R, 0.04 * R)
        disk.apply_translation(dk.disk_centre(p))
        self.disk_node = s.add_mesh_simple(
            f"{body}/disk",
            disk.vertices,
            disk.faces,
            color=geo.DISK,
            opacity=DISK_OPACITY["driven"],
        )
        rim = geo.circle_segments(1.004 * R, 96)  # just outside the edge: seen from both sides
        rim[..., 1] += R  # centred on the disk centre (0, R, 0)
        self.rim_node = geo.lines(s, f"{body}/rim", rim, geo.RIM, 2.5)
        self.bead_node = s.add_icosphere(
            f"{body}/bead", radius=0.09 * R, color=geo.BEAD, position=dk.bead_position(p)
        )
        self.cm_node = s.add_icosphere(
            f"{body}/centre_of_mass",
            radius=0.05 * R,
            color=geo.CENTRE,
            position=dk.centre_of_mass(p),
        )
        # axle (space-fixed in driven mode) and its two bearings
        a, b = dk.axle_points(p)
        ext = np.array([0.0, 0.25 * R, 0.0])
        rod = geo.rod_between(LIFT + to_world(a - ext), LIFT + to_world(b + ext), 0.025 * R)
        self.axle_node = s.add_mesh_simple(f"{r}/axle", rod.vertices, rod.faces, color=geo.AXLE)
        self.bearings = []
        for name, pt in (("A", a), ("B", b)):
            ring = geo.torus_mesh(0.08 * R, 0.025 * R)
            ring.apply_translation(LIFT + to_world(pt))
            self.bearings.append(
                s.add_mesh_simple(f"{r}/bearing_{name}", ring.vertices, ring.faces, color=geo.AXLE)
            )
            self.bearings.append(
                s.add_label(
                    f"{r}/bearing_{name}/label",
                    name,
                    position=LIFT + to_world(pt) + (0.15 * R, 0.0, 0.0),
                )
            )
        # In driven motion the bearing forces and L turn with the body: their labels are body
        # children placed once (at t = 0 the disk frame is the space frame), so frames only
        # move the arrows themselves.
        # Of the vectors fixed in the turning body only L is labelled (the red arrows at the
        # bearings are the forces, said in the readout): more moving text would overlap.
        self.body_labels = [s.add_label(f"{body}/label_L", "L", anchor="top-center")]
        self._build_axes(p, self.model.config.mode)

    def _build_axes(self, p: dk.DiskParams, mode: str) -> None:
        """The principal axes and their moments: about A while the axle holds the disk, about the
        centre of mass once it is released (those govern the tumble), drawn from that point."""
        body, R = f"{self.root}/body", p.radius
        moments, axes, origin = principal_axes_for(p, mode)
        mr2 = p.disk_mass * R * R
        length = 1.3 * R
        pts = np.stack([np.tile(origin, (3, 1)), origin + axes * length], axis=1).astype(np.float32)
        self.axes_node = self.scene.add_arrows(
            f"{body}/principal_axes",
            pts,
            colors=np.array(geo.AXES_RGB, np.uint8),
            shaft_radius=0.012 * R,
            head_radius=0.04 * R,
            head_length=0.1 * R,
        )
        # Named by colour under the exhibit's title, in the sky above it: text tied to the
        # turning axes would pile up on screen, and at the floor in front of the disk the
        # first view puts the hoop's chaos map over it.
        self.axes_text = ", ".join(
            f"I{k + 1} {name} {moments[k] / mr2:.4g}" for k, name in enumerate(AXIS_NAMES)
        )
        about = "A" if mode == "driven" else "the centre of mass"
        self.label.text = f"{TITLE}\nprincipal moments about {about} [MR²]:\n{self.axes_text}"
        self._built_masses = (p.disk_mass, p.bead_mass, R, mode)

    def _started(self) -> None:
        c, p = self.model.config, self.model.params
        L_body = self.model.body_L  # L fixed in the driven body (at t = 0, in space)
        if self._built_radius != p.radius:
            self._build_body(p)
        elif self._built_masses != (p.disk_mass, p.bead_mass, p.radius, c.mode):
            self._build_axes(p, c.mode)
        driven = c.mode == "driven"
        self.disk_node.opacity = DISK_OPACITY[c.mode]
        self.axle_node.visible = driven
        for h in self.bearings:
            h.visible = driven
        self.forces.visible = driven
        for h in self.body_labels:
            h.visible = driven
        self.force_scale = (
            0.8 * p.radius / self.model.force_amplitude if self.model.force_amplitude > 0 else 0.0
        )
        L0 = np.linalg.norm(dk.angular_momentum(p, 0.0))
        self.omega_scale = 1.2 * p.radius / abs(p.omega)
        self.momentum_scale = 1.2 * p.radius / L0 if L0 > 0 else 0.0
        a, b = dk.axle_points(p)
        # Driven: forces and L are fixed in the body (dynamics gives them at t = 0, when the
        # disk frame is the space frame); a frame turns them with the sampled rotation R(t).
        self._body_fa = dk.bearing_force_a(p, 0.0)
        self._body_fb = dk.bearing_force_b(p, 0.0)
        # what a driven frame draws, apart from the turning: world points of A and B, the fixed
        # omega arrow, and the body-fixed vectors scaled to their arrows (columns: L, F_A, F_B)
        self._driven_a = LIFT + to_world(a)
        self._driven_b = LIFT + to_world(b)
        self._driven_omega_tip = LIFT + to_world(p.omega * dk.AXLE * self.omega_scale)
        self._body_arrows = np.stack(
            [
                L_body * self.momentum_scale,
                self._body_fa * self.force_scale,
                self._body_fb * self.force_scale,
            ],
            axis=1,
        )
        self._vector_points = np.zeros((3, 2, 3), np.float32)  # reused by every frame
        # dL/dt = omega x L, fixed in the body too: drawn at L's tip, at the length L's tip moves
        # in one radian of turn (so it is tangent to the cone's rim and as long as its radius)
        self._body_dL = np.cross(p.omega * dk.AXLE, L_body) / abs(p.omega) * self.momentum_scale
        phi = np.linspace(0.0, 2 * np.pi, 97)
        rim = LIFT + to_world(np.einsum("kij,j->ki", dk.rotation_about_axle(phi), L_body))
        rim = LIFT + (rim - LIFT) * self.momentum_scale
        self.cone_rim.points = np.stack([rim[:-1], rim[1:]], axis=1).astype(np.float32)
        self.cone_rim.visible = driven
        self._force_points = np.zeros((2, 2, 3), np.float32)
        self.body_labels[0].position = a + dk.angular_momentum(p, 0.0) * self.momentum_scale
        self.vector_labels[0].position = (
            LIFT + to_world(a + p.omega * dk.AXLE * self.omega_scale) + (0.0, 0.0, 0.1 * p.radius)
        )
        self.vector_labels[1].visible = not driven
        self.poinsot.start(
            dk.free_kernel_params(p),
            p.radius,
            shown=not driven,
            state=None if driven else self.model.state,
        )
        self.body.position = LIFT  # A stays put while driven

    def _rewound(self) -> None:
        # gone back in the run: the next points start new pieces of the Poinsot curves
        self.poinsot.polhode.lift()
        self.poinsot.herpolhode.lift()

    def body_pose_world(self):
        """``(wxyz, position)`` of the body node relative to the exhibit origin."""
        rot, a = self.model.pose()
        return geo.quat_from_matrix(P @ rot), LIFT + to_world(a)

    # ------------------------------------------------------------------ drawing
    def draw(self) -> None:
        if self.model.config.mode == "driven":
            self._draw_driven()
            return
        wxyz, pos = self.body_pose_world()
        self.body.wxyz = wxyz
        self.body.position = pos
        omega, L, base = self.model.vectors_space()
        b0 = LIFT + to_world(base)
        # a run whose energy grows (explicit Euler) lengthens them: drawn up to the exhibit's
        # edge, not across a neighbour
        tips = [
            b0 + to_world(v) * s for v, s in ((omega, self.omega_scale), (L, self.momentum_scale))
        ]
        if self.bounded:
            tips = [geo.clip_segment(b0, tip, *self._extent()) for tip in tips]
        pts = self._vector_points
        pts[:, 0] = b0
        pts[0, 1], pts[1, 1] = tips
        pts[2, 1] = b0  # no dL/dt arrow: the free body has no torque
        self.vectors.points = pts
        for h, tip in zip(self.vector_labels, tips, strict=True):  # both move with the tumble
            h.position = tip
        self.poinsot.draw(dk.poinsot(self.model.sim.system.kernel_params(), self.model.state), b0)

    def _draw_driven(self) -> None:
        """The uniform rotation about the axle: A stays put and omega is fixed; L and the
        bearing forces are fixed in the body and turn with it (one matrix product)."""
        rot, _ = self.model.pose()
        turn = P @ rot  # disk frame -> world
        self.body.wxyz = geo.quat_from_matrix(turn)
        L, fa, fb = (turn @ self._body_arrows).T
        a, b = self._driven_a, self._driven_b
        pts = self._vector_points  # drawn from A, which is the body node's origin at LIFT
        pts[:2, 0] = LIFT
        pts[0, 1] = self._driven_omega_tip
        pts[1, 1] = LIFT + L
        pts[2, 0] = LIFT + L
        pts[2, 1] = LIFT + L + turn @ self._body_dL
        self.vectors.points = pts
        f = self._force_points
        f[0, 0], f[0, 1] = a, a + fa
        f[1, 0], f[1, 1] = b, b + fb
        self.forces.points = f

    def _extent(self):
        R = self.model.params.radius
        return (-1.4 * R, -1.4 * R, 0.0), (1.4 * R, 1.4 * R, LIFT[2] + 2.3 * R)

    @property
    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """The disk's box, and on its stage once released, Poinsot's picture beside it."""
        lo, hi = super().bounds
        if self.poinsot.staged and self.model.config.mode == "released":
            lo2, hi2 = self.poinsot_bounds()
            lo, hi = np.minimum(lo, lo2), np.maximum(hi, hi2)
        return lo, hi

    def poinsot_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """World box [m] of Poinsot's picture on the stage (with room for its names below)."""
        R = self.model.params.radius
        c, h = self.world(self.poinsot.beside(R)), self.poinsot.half
        return c - h, c + h

    def on_stage(self, shown: bool) -> None:
        self.poinsot.stage(shown)
        self.to_draw = True  # drawn again where it now stands (the model did not change)

    @property
    def camera(self):
        o = self.origin
        return (tuple(o + (0.8, -5.0, 2.8)), tuple(o + (0.0, 0.0, 1.4)))

    def stage_plot(self):
        if self.model.config.mode == "driven":  # L's tip circles the axle: what the bearings turn
            return "L_x [kg m²/s]", (("Lx", geo.MOMENTUM),)
        # in the principal axes' colours: the intermediate one's (green) flips in a tumble
        return "ω₁,₂,₃ [rad/s]", tuple((f"w{k + 1}", geo.AXES_RGB[k]) for k in range(3))

    # ------------------------------------------------------------------ readout
    def key_figures(self) -> list[tuple[str, str]]:
        m = self.model
        if m.config.mode == "driven":
            meas = m.measured()["bearing_force"]
            force = against_theory(meas, "N", m.force_amplitude)
            return [("|F_B|", force), ("t", f"{m.t:.1f} s")]
        meas = m.measured()
        return [
            (
                "polhode period",
                against_theory(meas["polhode_period"], "s", m.polhode_period()),
            ),
            *super().key_figures(),
        ]

    def readout(self) -> str:
        m = self.model
        p, smp = m.params, m.sample
        about = "A" if m.config.mode == "driven" else "the centre of mass"
        lines = [f"**t = {m.t:.2f} s** · {m.config.mode}"]
        lines.append(
            f"· {m.method_line(m.sim)}"
            if m.config.mode == "released"
            else "· exact uniform rotation"
        )
        lines += [
            "",
            "| quantity | theory | measured |",
            "|---|---|---|",
            f"| principal moments about {about} [MR²] | {self.axes_text} | — |",
        ]
        if m.config.mode == "driven":
            meas = m.measured()["bearing_force"]
            net = float(np.linalg.norm(dk.net_bearing_force(p, smp.t)))
            lines += [
                f"| bearing force amplitude \\|F_B\\| = m R ω²/2 [N] | {fmt(m.force_amplitude)} "
                f"| {fmt(meas)} |",
            ]
            if math.isclose(p.bead_mass, 1.25 * p.disk_mass):  # the seed's bead
                lines.append("| (the seed's 5/8 M R ω², for its bead m = 5M/4) | | |")
            lines.append(f"| \\|F_A + F_B\\| = (M+m) ω² ρ_cm [N] | {fmt(net)} | |")
            lines.append(
                f"\nRed arrows at A and B: the bearing forces, 1 m ↔ {1 / self.force_scale:.3g} N. Measured: "
                "\\|ŷ × dL/dt\\| / 2R, with dL/dt from central differences of the sampled L(t) "
                "divided by their known factor sin θ/θ (θ half the turn between the two samples)."
            )
        else:
            _, L, _ = m.vectors_space()
            rot, _ = m.pose()
            axle = rot @ dk.AXLE
            cos_axle = float(axle @ L / max(np.linalg.norm(L), 1e-300))
            meas = m.measured()
            lines += [
                f"| relative energy error | 0 | {float(np.max(np.abs(smp.energy_error))):.2e} |",
                f"| error vs DOP853 reference | 0 | {error_text(smp)} |",
                f"| \\|L\\| about CM [kg m²/s] | conserved | {fmt(float(np.linalg.norm(L)), 8)} |",
                f"| axle · L̂ (tumble: ±1 flips) | — | {cos_axle:+.3f} |",
                f"| wobble growth rate [1/s] | {fmt(m.growth_rate_theory())} "
                f"| {fmt(meas['growth_rate'])} |",
                f"| polhode period 4K(k)/λ [s] | {fmt(m.polhode_period())} "
                f"| {fmt(meas['polhode_period'])} |",
            ]
            lines.append(
                "\nSpin about the intermediate principal axis is unstable: "
                "the small extra spin grows into a tumble."
            )
        lines.append(m.work_line())
        return "\n".join(lines)

    # ------------------------------------------------------------------ GUI
    def sync_panel(self, panel) -> None:
        panel.show("spin", float(self.model.config.extra_spin[2]))

    def build_panel(self, panel) -> None:
        gui, c = panel.gui, self.model.config
        panel.readout_and_chart(compare=False)
        with gui.add_folder("Motion"):
            mode = panel.put(
                "mode", gui.add_dropdown("Motion", options=MODES, initial_value=c.mode)
            )
            panel.slider(
                "spin",
                "Extra spin at release [rad/s]",
                0.0,
                0.5,
                0.01,
                float(c.extra_spin[2]),
                lambda v: panel.change(extra_spin=(0.0, 0.0, float(v))),
                current=lambda: float(self.model.config.extra_spin[2]),
                hint="Spin about the disk normal added at release: seeds the tumble",
            )
            follow = panel.put(
                "follow_cm", gui.add_checkbox("Follow centre of mass", initial_value=c.follow_cm)
            )
        panel.on(mode, lambda v: panel.change(mode=v))
        panel.on(follow, lambda v: panel.change(follow_cm=bool(v)))
        panel.plot(
            "Released: the angular velocity in the body's principal frame about the centre of "
            "mass (axes 1, 2, 3 from the smallest moment to the largest). E and \\|L\\| are "
            "conserved, so its tip runs on the polhode, where the energy ellipsoid meets the "
            "sphere of \\|L\\|; seen along the intermediate axis it is a hyperbola whose "
            "asymptotes are the separatrix the tumble follows. Driven: L about A, whose tip "
            "circles the axle."
        )
        panel.param_inputs()
        panel.integrator_inputs(compare=False)
