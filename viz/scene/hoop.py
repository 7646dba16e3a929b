"""Hoop-with-bead exhibit: a hoop swinging in its own plane about a pivot on its rim, a bead
sliding on it without friction.

The dynamics' swing plane (x right, y up, pivot at the origin, gravity along -y) is drawn in the
world's x-z plane: ``(x, y)_plane -> (x, 0, y) + pivot`` with the pivot ``2a + 0.4`` m above the
exhibit origin. Beside the nonlinear motion the linear-theory motion from the same initial state
(``mechviz.dynamics.hoop.linear_solution``) is drawn as a faint ghost, so the difference at large amplitude
shows. Both normal-mode frequencies are measured from the motion: the angles are projected on the
mode shapes and each modal coordinate is timed between its zero crossings (:mod:`mechviz.dynamics.measure`).
"""

from __future__ import annotations

import functools
import math
from typing import ClassVar

import numpy as np

from mechviz.dynamics import floquet
from mechviz.dynamics import hoop as hp
from mechviz.dynamics.results import EXACT_FLOW

from .. import geometry as geo
from ..model.hoop import MODES, HoopConfig, HoopModel  # noqa: F401  (re-exported)
from .atlas_map import MAP_SIZE, add_maps
from .base import Event, Exhibit, against_theory, error_text, fmt


@functools.lru_cache(maxsize=64)
def _floquet(p: hp.HoopParams, amplitude: float) -> float:
    """Mode 1's largest Floquet multiplier (a run over one period: worked out once per swing)."""
    return floquet.mode1_floquet_multiplier(p, amplitude)


COMPARE_OFFSET = np.array([2.8, 0.0, 0.0])
# Configuration space, drawn as a square standing left of the stand: theta1 across, theta2 up.
CONFIG_SIZE = 1.0  # m, the square's side
# m from the exhibit origin (times the hoop radius in x): its right edge clear of the hoop,
# which reaches 2a from the pivot whatever its swing
CONFIG_CENTRE = np.array([-2.75, 0.0, 0.9])
CONFIG_TITLE = "θ1 → θ2 ↑ configuration"
MODE_COLOURS = ((230, 60, 60), (60, 110, 240))  # mode 1 and mode 2 directions (geo.AXES_RGB)


class ConfigurationSpace:
    """The motion in the (theta1, theta2) plane: the run's path (bead colour) and linear
    theory's (ghost), with the two mode-shape directions through the origin, (1, 1) for mode 1
    and (m, -(M + m)) for mode 2 (:func:`mechviz.dynamics.hoop.normal_modes`). A start on a mode line
    stays on it at small amplitude; at large amplitude the path leaves it."""

    def __init__(self, scene, root: str, centre: np.ndarray, cap: int, bounded: bool) -> None:
        self.scene, self.root, self.centre = scene, root, centre
        # one frame over the square's nodes, so that the stage shows or hides them together
        self.node = scene.add_frame(root, show_axes=False)
        half = 0.5 * CONFIG_SIZE
        c = [(-half, 0, -half), (half, 0, -half), (half, 0, half), (-half, 0, half)]
        frame = np.array([[c[k], c[(k + 1) % 4]] for k in range(4)], np.float32)
        axes = np.array([[(-half, 0, 0), (half, 0, 0)], [(0, 0, -half), (0, 0, half)]], np.float32)
        geo.lines(
            scene,
            f"{root}/frame",
            np.concatenate([frame, axes]) + centre.astype(np.float32),
            geo.AXLE,
            1.0,
        )
        self.modes = geo.lines(
            scene,
            f"{root}/modes",
            np.zeros((2, 2, 3), np.float32),
            np.repeat(np.array(MODE_COLOURS, np.uint8)[:, None, :], 2, axis=1),
            2.0,
        )
        # its names: the title (naming the axes) under the square, each mode line at its upper
        # end (placed in start(): they depend on the masses), mode 1 right, mode 2 left of it
        c0 = centre.astype(float)
        self.title = scene.add_label(
            f"{root}/label_title",
            CONFIG_TITLE,
            position=c0 + (-half, 0, -half - 0.03),
            anchor="top-left",
        )
        self.mode_labels = [
            scene.add_label(f"{root}/label_mode1", "mode 1", anchor="bottom-left"),
            scene.add_label(f"{root}/label_mode2", "mode 2", anchor="bottom-right"),
        ]
        # the paths are drawn inside the square only: where the angles grow without bound (the
        # bead going round, or a diverging method) they leave it, not the exhibit
        box = (centre - (half, 0.0, half), centre + (half, 0.0, half)) if bounded else None
        self.path = geo.ChunkedTrail(scene, f"{root}/path", geo.BEAD, cap=cap, box=box)
        self.ghost = geo.ChunkedTrail(scene, f"{root}/ghost_path", geo.GHOST, cap=cap, box=box)
        self.scale = 1.0

    def start(self, shapes: np.ndarray, angles0: np.ndarray, ghost: bool) -> None:
        """New axes for a new start: the square spans +-1.25 times the start's largest angle
        (at least 0.05 rad); the mode lines are clipped to the square."""
        reach = max(0.05, 1.25 * float(np.abs(angles0).max()))
        self.scale = 0.5 * CONFIG_SIZE / reach
        lines = []
        for shape in shapes:
            u = np.asarray(shape, float) / np.abs(shape).max()  # reaches the square's edge
            lines.append([self.point(-reach * u), self.point(reach * u)])
        self.modes.points = np.asarray(lines, np.float32)
        # mode 1 at its upper right end; mode 2 at its upper end, reaching left (clear of mode 1)
        for label, (a, b) in zip(self.mode_labels, lines, strict=True):
            top = a if a[2] > b[2] else b
            label.position = top + (0.0, 0.0, 0.02)
        self.path.clear()
        self.ghost.clear()
        self.ghost.visible = ghost

    def point(self, angles) -> np.ndarray:
        th = np.asarray(angles, float)
        return self.centre + self.scale * np.array([th[0], 0.0, th[1]])

    def push(self, angles, ghost_angles) -> None:
        self.path.push(self.point(angles))
        self.path.draw()
        if self.ghost.visible:
            self.ghost.push(self.point(ghost_angles))
            self.ghost.draw()


class HoopExhibit(Exhibit):
    """The hoop drawn: the hoop and its bead, the linear-theory ghost, the comparison run and
    the configuration-space square."""

    model_type = HoopModel
    listens: ClassVar[dict[Event, str]] = {
        "started": "_started",
        "rewound": "_rewound",
        "jumped": "_jumped",
    }
    icon = "CIRCLE"
    caption = "(θ1, θ2) left, chaos map above it (click)"

    def stage_plot(self):
        # in the colours of the hoop and the bead, the two bodies the angles turn
        return "θ1, θ2 [rad]", (("theta1", geo.HOOP), ("theta2", geo.BEAD))

    def _build(self) -> None:
        s, r = self.scene, self.root
        s.add_frame(r, show_axes=False, position=self.origin)
        self.label = s.add_label(f"{r}/label", "Bead on a hanging hoop", anchor="bottom-center")
        self._built_radius = None

    def _build_body(self, p: hp.HoopParams) -> None:
        s, r, a = self.scene, self.root, p.radius
        self._built_radius = a
        self.pivot_local = np.array([0.0, 0.0, 2.0 * a + 0.4])
        zp = self.pivot_local[2]
        self.label.position = (0.0, 0.0, zp + 0.45)
        # a small gallows holding the pivot
        post = geo.rod_between((-0.9 * a, 0.25, 0.0), (-0.9 * a, 0.25, zp + 0.08), 0.03)
        beam = geo.rod_between((-0.9 * a, 0.25, zp + 0.08), (0.0, 0.25, zp + 0.08), 0.03)
        pin = geo.rod_between((0.0, 0.25, zp), (0.0, -0.1, zp), 0.02)
        stand = geo.trimesh.util.concatenate([post, beam, pin])
        s.add_mesh_simple(f"{r}/stand", stand.vertices, stand.faces, color=geo.STAND)
        s.add_icosphere(f"{r}/pivot", radius=0.05, color=geo.CENTRE, position=self.pivot_local)
        # one batched node per shape: instance 0 the hoop, 1 the linear-theory ghost, 2 the
        # comparison method (scale 0 while there is none)
        ring = geo.torus_mesh(a, 0.025 * a)
        ring.apply_transform(geo.trimesh.transformations.rotation_matrix(math.pi / 2, (1, 0, 0)))
        bead = geo.sphere_mesh(0.08 * a)
        shapes = (("rings", ring, geo.HOOP, 0.45), ("beads", bead, geo.BEAD, 0.5))
        self.rings, self.beads = (
            geo.instances(
                s,
                f"{r}/{name}",
                mesh,
                [colour, geo.GHOST, geo.COMPARE],
                scales=np.array([1.0, 1.0, 0.0]),
                opacities=np.array([1.0, ghost_opacity, 1.0]),
            )
            for name, mesh, colour, ghost_opacity in shapes
        )
        self.cmp_label = s.add_label(
            f"{r}/compare_label",
            "",
            position=self.pivot_local + COMPARE_OFFSET + (0.0, 0.0, 0.3),
            visible=False,
            anchor="bottom-center",
        )
        if hasattr(self, "trail"):
            self.trail.clear()
            self.cmp_trail.clear()
        self.trail = geo.ChunkedTrail(s, f"{r}/trail", geo.BEAD, cap=self.model.config.trail_cap)
        if not hasattr(self, "config_space"):
            self.config_space = ConfigurationSpace(
                s,
                f"{r}/configuration_space",
                CONFIG_CENTRE * (a, 1.0, 1.0),
                cap=1200,
                bounded=self.bounded,
            )
        self.cmp_trail = geo.ChunkedTrail(
            s, f"{r}/compare_trail", geo.COMPARE, cap=self.model.config.trail_cap
        )

    def _started(self) -> None:
        c, p, cmp_ = self.model.config, self.model.params, self.model.compare
        if self._built_radius != p.radius:
            self._build_body(p)
        self.trail.clear()
        self.cmp_trail.clear()
        self.cmp_label.visible = cmp_ is not None
        scales = np.array([1.0, 1.0 if c.ghost else 0.0, 1.0 if cmp_ is not None else 0.0])
        self.rings.batched_scales = scales
        self.beads.batched_scales = scales
        if cmp_ is not None:
            self.cmp_label.text = f"{c.compare_method} (blue)"
        self.config_space.start(self.model.shapes, self.model.sim.state0[0, :2], c.ghost)

    def _rewound(self) -> None:
        # gone back in the run: the next points start new pieces (no line back across the
        # path already drawn)
        for trail in (self.trail, self.cmp_trail, self.config_space.path, self.config_space.ghost):
            trail.lift()

    def _jumped(self) -> None:
        self.config_space.start(
            self.model.shapes, self.model.sim.state0[0, :2], self.model.config.ghost
        )
        self.trail.lift()
        self.cmp_trail.lift()

    # ------------------------------------------------------------------ geometry from dynamics
    def plane_to_local(self, xy) -> np.ndarray:
        xy = np.asarray(xy, float)
        out = np.empty(xy.shape[:-1] + (3,))
        out[..., 0] = xy[..., 0]
        out[..., 1] = 0.0
        out[..., 2] = xy[..., 1]
        out += self.pivot_local
        return out

    def poses(self, state) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(hoop wxyz, hoop centre, bead)`` relative to the exhibit origin for one state (4,),
        or for a stack of states (..., 4): shapes (..., 4), (..., 3), (..., 3)."""
        st = np.asarray(state, float)
        centre, bead = hp.positions(self.model.params, st)
        # an anticlockwise plane rotation (towards +x from straight down) is a turn about world -y
        half = 0.5 * st[..., 0]
        q = np.zeros(st.shape[:-1] + (4,))
        q[..., 0] = np.cos(half)
        q[..., 2] = -np.sin(half)
        return q, self.plane_to_local(centre), self.plane_to_local(bead)

    def refresh_panel(self, panel) -> None:
        chart = panel.w.get("hoop.modes_chart")
        if chart is None or len(self.model.motion) < 2:
            return
        data = self.model.modal_history()
        # the window the chart selector shows (as far back as the motion's samples reach)
        window = float(getattr(panel.app, "chart_window", 10.0))
        first = int(np.searchsorted(data[0], data[0][-1] - window))
        data = tuple(np.asarray(d)[first:] for d in data)
        chart.data = data
        top = 1.3 * max(float(np.abs(np.concatenate(data[1:3])).max()), 1e-6)
        top = 10 ** (math.ceil(4 * math.log10(top)) / 4)  # steps of a quarter decade: steady
        panel.keep_time_axis("modes_chart", float(data[0][-1]), window, (-top, top))

    # ------------------------------------------------------------------ drawing
    def draw(self) -> None:
        # instance 0 the run, 1 the linear-theory ghost, 2 the comparison (or the run again)
        c = self.model.compare_state
        states = np.empty((3, 4))
        states[0] = self.model.state
        states[1] = self.model.ghost_state()
        states[2] = c if c is not None else states[0]
        q, centre, bead = self.poses(states)  # one vectorised call for the three instances
        if c is not None:
            centre[2] += COMPARE_OFFSET
            bead[2] += COMPARE_OFFSET
        self.rings.batched_wxyzs = q
        self.rings.batched_positions = centre
        self.beads.batched_positions = bead
        self.trail.push(bead[0])
        self.trail.draw()
        self.config_space.push(states[0, :2], states[1, :2])
        if c is not None:
            self.cmp_trail.push(bead[2])
            self.cmp_trail.draw()

    def on_stage(self, shown: bool) -> None:
        # the configuration square and the chaos map explain the hoop on its own stage; at
        # home, between the disk and the hoop, they would read as part of neither
        if hasattr(self, "config_space"):
            self.config_space.node.visible = shown
        maps = getattr(self, "maps_view", None)  # the maps come with the GUI
        if maps is not None:
            maps.show(shown)

    @property
    def home_bounds(self):
        a = self.model.params.radius  # the hoop, its gallows and a comparison run beside it
        right = COMPARE_OFFSET[0] if self.model.compare is not None else 0.0
        lo, hi = (-1.1 * a, -0.3, 0.0), (1.1 * a + right, 0.3, self.pivot_local[2] + 0.1)
        return self.origin + np.asarray(lo, float), self.origin + np.asarray(hi, float)

    def _extent(self):
        a = self.model.params.radius
        right = COMPARE_OFFSET[0] if self.model.compare is not None else 0.0
        left = CONFIG_CENTRE[0] * a - 0.5 * CONFIG_SIZE
        top = self.pivot_local[2] + 0.1
        if hasattr(self, "maps_view"):  # the chaos map stands above the configuration square
            top = max(top, self.maps_view.centre_local[2] + 0.5 * MAP_SIZE + 0.3)  # + its title
        return (left, -0.3, 0.0), (1.1 * a + right, 0.3, top)

    @property
    def camera(self):
        o = self.origin + (0.5 * COMPARE_OFFSET if self.model.compare is not None else 0.0)
        dist = 6.0 if self.model.compare is None else 8.0
        return (tuple(o + (0.0, -dist, 1.6)), tuple(o + (0.0, 0.0, 1.3)))

    def stage_labels(self) -> list:
        maps = getattr(self, "maps_view", None)  # the maps come with the GUI
        return [maps.title] if maps is not None else []

    # ------------------------------------------------------------------ readout
    def key_figures(self) -> list[tuple[str, str]]:
        freqs, meas = self.model.mode_frequencies, self.model.measured()["mode_frequencies"]
        return [
            *((f"ω{k + 1}", against_theory(meas[k], "rad/s", freqs[k])) for k in (0, 1)),
            *super().key_figures(),
        ]

    def readout(self) -> str:
        p, smp, c = self.model.params, self.model.sample, self.model.config
        freqs = self.model.mode_frequencies
        meas = self.model.measured()["mode_frequencies"]
        lines = [
            f"**t = {self.model.t:.2f} s** · {self.model.method_line(self.model.sim)} · {c.mode}",
            "",
            "| normal mode | ω linear theory [rad/s] | ω measured [rad/s] |",
            "|---|---|---|",
            f"| 1: in phase, √(g/2a) | {fmt(freqs[0])} | {fmt(meas[0])} |",
            f"| 2: out of phase, √((1+m/M)g/a) | {fmt(freqs[1])} | {fmt(meas[1])} |",
        ]
        if c.mode == "mode 1" and 0 < abs(c.amplitude) < math.pi:
            w_nl = 2 * math.pi / hp.mode1_period(p, abs(float(c.amplitude)))
            lines.append(
                f"| 1 at amplitude {abs(c.amplitude):.3g} rad (exact, elliptic) | {fmt(w_nl)} | |"
            )
            lam = _floquet(p, abs(float(c.amplitude)))
            verdict = (
                "stable" if lam < 1 + 1e-4 else f"unstable: a departure grows {lam:.3g}x a period"
            )
            lines.append(f"| mode 1's largest Floquet multiplier at this amplitude | {verdict} | |")
        kind = self.model.sim.reference_kind or "—"
        lines += [
            f"| relative energy error | 0 | {float(np.max(np.abs(smp.energy_error))):.2e} |",
            f"| error vs {'exact (mode 1)' if kind == EXACT_FLOW else 'DOP853 reference'} | 0 "
            f"| {error_text(smp)} |",
            "",
            "Grey ghost: linear theory from the same start." if c.ghost else "",
        ]
        cs = self.model.compare_sample
        if cs is not None:
            lines.append(
                f"\nComparison {self.model.method_line(self.model.compare)} (blue, right): "
                "relative energy error "
                f"{float(np.max(np.abs(cs.energy_error))):.2e}"
            )
        lines.append(self.model.work_line())
        return "\n".join(lines)

    # ------------------------------------------------------------------ GUI
    def build_panel(self, panel) -> None:
        gui, c = panel.gui, self.model.config
        # at the top of the tab: the way to the chaos map (its pictures are further down)
        look = gui.add_button("Look at the map", icon=panel.viser.Icon.MAP)
        look.on_click(lambda event: self.maps_view.look_clicked(event))
        panel.readout_and_chart(compare=True)
        with gui.add_folder("Initial condition"):
            mode = panel.put("mode", gui.add_dropdown("Mode", options=MODES, initial_value=c.mode))
            panel.slider(
                "amplitude",
                "Amplitude [rad]",
                0.05,
                2.5,
                0.05,
                float(c.amplitude),
                lambda v: panel.change(amplitude=float(v)),
            )

            def angle(k):
                def apply(x):
                    angles = list(self.model.config.angles)  # read in the loop thread when applied
                    angles[k] = x
                    panel.change(mode="custom", angles=tuple(angles))

                return apply

            for k in (0, 1):
                panel.number(
                    f"th{k + 1}",
                    f"θ{k + 1} (custom) [rad]",
                    c.angles[k],
                    angle(k),
                    current=lambda k=k: self.model.config.angles[k],
                    lo=-3.14,
                    hi=3.14,
                )
        panel.on(mode, lambda v: panel.change(mode=v))
        panel.plot(
            "Mode 1 (θ1 = θ2) is exactly a pendulum, θ'' = −ω₁² sin θ with ω₁ = √(g/2a): its "
            "phase portrait (θ1, θ1') stays on the orbit of its energy, inside the separatrix "
            "θ' = ±2ω₁ cos(θ/2) (it swings) or outside it (it goes over the top). Pick θ2 "
            "against θ1 for configuration space with the two mode lines."
        )
        with gui.add_folder("Normal-mode coordinates"):
            gui.add_markdown(
                "<small>The angles on the two mode shapes: θ = q1 (1, 1) + q2 (mode 2's shape). "
                "Solid: the motion; dashed: linear theory, each a cosine at its own frequency "
                "(the table gives both). At small amplitude they agree.</small>"
            )
            u = panel.viser.uplot
            panel.put(
                "modes_chart",
                gui.add_uplot(
                    data=tuple(np.zeros(2) for _ in range(5)),
                    series=(
                        u.Series(label="t [s]"),
                        u.Series(label="q1 [rad]", stroke="#e63c3c", width=1.5),
                        u.Series(label="q2 [rad]", stroke="#3c6ef0", width=1.5),
                        u.Series(label="q1 linear", stroke="#e63c3c", width=1.0, dash=[4, 3]),
                        u.Series(label="q2 linear", stroke="#3c6ef0", width=1.0, dash=[4, 3]),
                    ),
                    scales={"x": u.Scale(time=False), "y": u.Scale(auto=False, range=(-1.0, 1.0))},
                    legend=u.Legend(live=False),  # names only: no "--" for a value at no cursor
                    aspect=1.6,
                ),
            )
        panel.param_inputs()
        panel.integrator_inputs(compare=True)
        self.maps_view = add_maps(panel, self)  # the chaos and stability maps

    def sync_panel(self, panel) -> None:
        for k, x in enumerate(self.model.config.angles):  # never into a box the person is typing in
            panel.show(f"th{k + 1}", x)
