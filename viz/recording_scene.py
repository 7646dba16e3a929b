"""Scene drawing for recordings: the recorder's own minimal scenes of the three systems.

The recorder drives a :class:`Driver`: something that advances the demo's runs, applies its
scripted events, reports :class:`dynamics.Sample` s and draws a frame into a viser server. The
driver here (:class:`FallbackDriver`) owns its :class:`viz.recording.Run` s and draws simple
geometry of its own; it is what ``mechviz record`` uses when the viewer's exhibit layer
(:mod:`viz.exhibit` and the ``viz.scene_*`` modules) is not available.

World conventions follow the viewer: +z up, metres. The hoop swings in the x-z plane (the
dynamics' y is the world's z), the disk keeps the dynamics' disk frame (axle along +y). Trails
are chunked as VISER_NOTES section 8 recommends: full chunks are frozen as their own
line-segment nodes and only the open chunk is rewritten, so playback memory grows by one chunk
per ``CHUNK`` frames instead of one whole trail per frame.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import trimesh

from dynamics import IntegrationError, cyclotron, disk

CHUNK = 30  # frames per trail chunk
RUN_COLOURS = ((235, 70, 40), (40, 170, 255), (80, 200, 90))
BEAM = (250, 190, 40)
GHOST = (170, 170, 170)
COMPARE_OFFSET = 3.0  # [m] along +x between runs shown side by side
DIVERGED = 24.0  # |E - E0| / |E0| beyond this is a blow-up (as in the viewer, viz.exhibit)


def _u8(c) -> np.ndarray:
    return np.asarray(c, dtype=np.uint8)


def _quat_y(angle: float) -> np.ndarray:
    """Unit quaternion (w, x, y, z) of a rotation by ``angle`` about +y."""
    return np.array([math.cos(0.5 * angle), 0.0, math.sin(0.5 * angle), 0.0])


def _quat_from_matrix(r: np.ndarray) -> np.ndarray:
    return disk._matrix_to_quaternion(r)


class ChunkedTrail:
    """A trail of ``M`` points per frame (all members in one node per chunk), capped."""

    def __init__(self, scene, name: str, colour, *, cap_chunks: int, thickness: float = 2.0):
        self.scene, self.name, self.colour = scene, name, _u8(colour)
        self.cap, self.thickness = cap_chunks, thickness
        self.open: list[np.ndarray] = []
        self.frozen: list[Any] = []
        self.count = 0
        self.handle = None

    def _segments(self, pts: list[np.ndarray]) -> np.ndarray:
        a = np.stack(pts[:-1]).reshape(-1, 3)
        b = np.stack(pts[1:]).reshape(-1, 3)
        return np.stack([a, b], axis=1).astype(np.float32)

    def add(self, points: np.ndarray) -> None:
        self.open.append(np.asarray(points, dtype=float).reshape(-1, 3))
        if len(self.open) < 2:
            return
        segs = self._segments(self.open)
        if self.handle is None:
            self.handle = self.scene.add_line_segments(
                f"{self.name}/open", segs, colors=self.colour, thickness=self.thickness,
                thickness_units="screen",
            )  # fmt: skip
        else:
            self.handle.points = segs
        if len(self.open) > CHUNK:
            self.count += 1
            frozen = self.scene.add_line_segments(
                f"{self.name}/c{self.count:05d}", segs, colors=self.colour,
                thickness=self.thickness, thickness_units="screen",
            )  # fmt: skip
            self.frozen.append(frozen)
            if len(self.frozen) > self.cap:
                self.frozen.pop(0).remove()
            self.open = self.open[-1:]
            self.handle.points = np.zeros((1, 2, 3), np.float32)


class Drawer:
    """Base of the fallback drawers: ``draw(frame)`` makes handle assignments only."""

    def __init__(self, server, demo, labels: list[str]):
        self.server, self.scene, self.demo, self.labels = server, server.scene, demo, labels
        from .recording import params_for

        self.p = params_for(demo)

    def offset(self, i: int) -> np.ndarray:
        return np.array([COMPARE_OFFSET * i, 0.0, 0.0])

    def label(self, i: int, label: str, position) -> None:
        from dynamics import get_method

        if len(self.labels) > 1:
            self.scene.add_label(f"/labels/{i}", get_method(label.split()[0]).title,
                                 position=tuple(position))  # fmt: skip


class CyclotronDrawer(Drawer):
    def __init__(self, server, demo, labels, first):
        super().__init__(server, demo, labels)
        s = self.scene
        grid = np.array([(x, y) for x in (-2.0, 0.0, 2.0) for y in (-2.0, 0.0, 2.0)])
        for i in range(len(labels)):
            o = self.offset(i)
            pts = np.array([[[x, y, -0.5], [x, y, 0.3]] for x, y in grid]) * [0.8, 0.8, 1] + o
            s.add_arrows(f"/field/{i}", pts.astype(np.float32), colors=(120, 140, 255),
                         shaft_radius=0.01, head_radius=0.03, head_length=0.08)  # fmt: skip
            self.label(i, labels[i], o + [0.0, 0.0, 0.6])
        sphere = trimesh.creation.icosphere(subdivisions=2, radius=0.07)
        self.bodies, self.trails, self.rings, self.centres = [], [], [], []
        for i, lbl in enumerate(labels):
            n = len(first[lbl])
            colour = RUN_COLOURS[i] if n == 1 else BEAM
            colours = np.tile(_u8(colour), (n, 1))
            if n > 1:  # a beam: a colour per speed
                colours = np.array(
                    [[int(255 * c) for c in _ramp(j / max(n - 1, 1))] for j in range(n)], np.uint8
                )
            self.bodies.append(
                s.add_batched_meshes_simple(
                    f"/charges/{i}",
                    sphere.vertices,
                    sphere.faces,
                    batched_wxyzs=np.tile([1.0, 0.0, 0.0, 0.0], (n, 1)),
                    batched_positions=first[lbl][:, :3] + self.offset(i),
                    batched_colors=colours,
                    lod="off",
                )
            )
            self.trails.append(
                ChunkedTrail(s, f"/trails/{i}", colour, cap_chunks=40, thickness=2.0)
            )
            if n == 1:
                self.rings.append(self._ring(i, first[lbl][0]))
                self.centres.append(
                    s.add_icosphere(f"/centre/{i}", radius=0.03, color=(255, 255, 255),
                                    position=tuple(self._centre(first[lbl][0]) + self.offset(i)))
                )  # fmt: skip
            else:
                self.rings.append(None)
                self.centres.append(None)

    def _centre(self, state) -> np.ndarray:
        c = cyclotron.guiding_centre(self.p, state)
        return np.array([c[0], c[1], 0.0])

    def _ring(self, i: int, state):
        """The circle theory predicts for this state (faint), in the plane z = 0."""
        r = cyclotron.larmor_radius(self.p, state)
        ang = np.linspace(0.0, 2 * math.pi, 97)
        c = self._centre(state) + self.offset(i)
        pts = np.stack([c[0] + r * np.cos(ang), c[1] + r * np.sin(ang), np.zeros_like(ang)], 1)
        segs = np.stack([pts[:-1], pts[1:]], 1).astype(np.float32)
        return self.scene.add_line_segments(f"/predicted/{i}", segs, colors=(200, 200, 200),
                                            thickness=1.0, thickness_units="screen")  # fmt: skip

    def draw(self, frame) -> None:
        for i, lbl in enumerate(self.labels):
            st = frame.states[lbl]
            pos = st[:, :3] + self.offset(i)
            self.bodies[i].batched_positions = pos
            self.trails[i].add(pos)
            if frame.fired and self.rings[i] is not None:
                self.rings[i].remove()
                self.rings[i] = self._ring(i, st[0])
                self.centres[i].position = tuple(self._centre(st[0]) + self.offset(i))


def _ramp(x: float) -> tuple[float, float, float]:
    """Blue to yellow to red."""
    return (min(1.0, 2 * x), 0.35 + 0.5 * (1 - abs(2 * x - 1)), max(0.0, 1 - 2 * x))


class DiskDrawer(Drawer):
    def __init__(self, server, demo, labels, first):
        super().__init__(server, demo, labels)
        p, s = self.p, self.scene
        R = p.radius
        self.released = demo.motion == "released"
        body = s.add_frame("/disk", show_axes=False)
        self.body = body
        plate = trimesh.creation.cylinder(radius=R, height=0.04 * R, sections=64)
        s.add_mesh_simple("/disk/plate", plate.vertices, plate.faces, color=(90, 160, 210),
                          position=(0.0, R, 0.0))  # fmt: skip
        s.add_icosphere("/disk/bead", radius=0.08 * R, color=(220, 40, 160),
                        position=tuple(disk.bead_position(p)))  # fmt: skip
        s.add_icosphere("/disk/cm", radius=0.04 * R, color=(255, 255, 255),
                        position=tuple(disk.centre_of_mass(p)))  # fmt: skip
        # The axle's line in the body (after release it is just a painted diameter).
        rod = trimesh.creation.cylinder(
            radius=0.02 * R, segment=[[0, -0.3 * R, 0], [0, 2.3 * R, 0]]
        )
        s.add_mesh_simple("/disk/axle", rod.vertices, rod.faces, color=(150, 150, 150))
        if not self.released:
            for nm, y in (("A", 0.0), ("B", 2 * R)):
                s.add_box(
                    f"/bearings/{nm}",
                    color=(110, 110, 110),
                    dimensions=(0.12 * R, 0.12 * R, 0.12 * R),
                    position=(0.0, y, 0.0),
                )
                s.add_label(f"/bearings/{nm}/label", nm, position=(0.12 * R, 0.0, 0.12 * R))
            self.forces = s.add_arrows("/forces", np.zeros((2, 2, 3), np.float32),
                                       colors=(240, 60, 60), shaft_radius=0.02,
                                       head_radius=0.05, head_length=0.1)  # fmt: skip
        self.vectors = s.add_arrows(
            "/vectors",
            np.zeros((2, 2, 3), np.float32),
            colors=np.array([[40, 200, 90], [250, 170, 30]], np.uint8),
            shaft_radius=0.015,
            head_radius=0.04,
            head_length=0.08,
        )
        self.force_scale = 0.6 / max(disk.axle_force_amplitude(p), 1e-12)  # longest arrow 0.6 R

    def draw(self, frame) -> None:
        p = self.p
        st = frame.states[self.labels[0]][0]
        if self.released:
            rot, a_pos = disk.released_pose(
                p, st, frame.t, self.demo.initial.get("extra_spin", (0, 0, 0))
            )
            # Follow the centre of mass (it drifts off at w x r_cm): draw in its rest frame.
            w0 = p.omega * disk.AXLE + np.asarray(self.demo.initial.get("extra_spin", (0, 0, 0)))
            a_pos = a_pos - frame.t * np.cross(w0, disk.centre_of_mass(p))
            moments = disk.free_kernel_params(p)
            R_q = disk.quaternion_to_matrix(st[3:7])
            w_space = R_q @ st[:3]
            L_space = R_q @ (moments * st[:3])
            origin = a_pos + rot @ disk.centre_of_mass(p)
        else:
            angle = st[0]
            rot = disk.rotation_about_axle(angle)
            a_pos = np.zeros(3)
            w_space = st[1] * disk.AXLE
            L_space = disk.angular_momentum(p, frame.t)
            origin = np.zeros(3)
            fa, fb = disk.bearing_force_a(p, frame.t), disk.bearing_force_b(p, frame.t)
            A, B = disk.axle_points(p)
            k = self.force_scale
            self.forces.points = np.array([[A, A + k * fa], [B, B + k * fb]], np.float32)
        self.body.wxyz = _quat_from_matrix(rot)
        self.body.position = tuple(a_pos)
        sw = 1.0 / max(np.linalg.norm(w_space), 1e-12)
        sl = 1.2 / max(np.linalg.norm(L_space), 1e-12)
        self.vectors.points = np.array(
            [[origin, origin + sw * w_space], [origin, origin + sl * L_space]], np.float32
        )


class HoopDrawer(Drawer):
    def __init__(self, server, demo, labels, first):
        super().__init__(server, demo, labels)
        s, a = self.scene, self.p.radius
        ring = trimesh.creation.torus(major_radius=a, minor_radius=0.025 * a,
                                      major_sections=64, minor_sections=10)  # fmt: skip
        ring.apply_transform(trimesh.transformations.rotation_matrix(math.pi / 2, [1, 0, 0]))
        bead = trimesh.creation.icosphere(subdivisions=2, radius=0.07 * a)
        self.hoops, self.beads, self.trails = [], [], []
        ghosts = [False] + ([True] if demo.ghost == "linear" else [])
        for i, lbl in enumerate(labels):
            o = self.offset(i)
            s.add_icosphere(
                f"/pivot/{i}", radius=0.04 * a, color=(230, 230, 230), position=tuple(o)
            )
            self.label(i, lbl, o + [0.0, 0.0, 0.3])
            for g in ghosts:
                colour = GHOST if g else (200, 120, 50)
                tag = f"{i}{'g' if g else ''}"
                body = s.add_frame(f"/hoop/{tag}", show_axes=False, position=tuple(o))
                s.add_mesh_simple(
                    f"/hoop/{tag}/ring",
                    ring.vertices,
                    ring.faces,
                    color=colour,
                    position=(0.0, 0.0, -a),
                    opacity=0.35 if g else None,
                )
                spoke = np.array([[[0, 0, 0], [0, 0, -2 * a]]], np.float32)
                s.add_line_segments(f"/hoop/{tag}/spoke", spoke, colors=colour, thickness=1.0,
                                    thickness_units="screen")  # fmt: skip
                b = s.add_mesh_simple(f"/beads/{tag}", bead.vertices, bead.faces,
                                      color=GHOST if g else RUN_COLOURS[i],
                                      opacity=0.35 if g else None)  # fmt: skip
                self.hoops.append(body)
                self.beads.append(b)
            self.trails.append(ChunkedTrail(s, f"/trails/{i}", RUN_COLOURS[i], cap_chunks=4))
        if demo.ghost == "linear":
            s.add_label("/labels/ghost", "linear theory (grey)", position=(0.6, 0.0, 0.3))

    def _pose(self, st, o):
        a = self.p.radius
        th1, th2 = st[0], st[1]
        centre = o + a * np.array([math.sin(th1), 0.0, -math.cos(th1)])
        bead = centre + a * np.array([math.sin(th2), 0.0, -math.cos(th2)])
        return _quat_y(-th1), bead

    def draw(self, frame) -> None:
        per = 2 if self.demo.ghost == "linear" else 1
        for i, lbl in enumerate(self.labels):
            o = self.offset(i)
            q, bead = self._pose(frame.states[lbl][0], o)
            self.hoops[per * i].wxyz = q
            self.beads[per * i].position = tuple(bead)
            self.trails[i].add(bead[None, :])
            if per == 2 and frame.ghost is not None:
                qg, bg = self._pose(frame.ghost[0], o)
                self.hoops[per * i + 1].wxyz = qg
                self.beads[per * i + 1].position = tuple(bg)


DRAWERS = {"cyclotron": CyclotronDrawer, "disk": DiskDrawer, "hoop": HoopDrawer}


class FallbackDriver:
    """Runs the demo with :class:`viz.recording.Run` s and draws it with the drawers above."""

    kind = "recording-scene"

    def __init__(self, server, demo):
        from . import recording as rec

        self.demo = demo
        system = rec.system_for(demo)
        self.system = system
        s0 = rec.initial_state(demo, system)
        self.runs = [
            rec.Run(lbl, system, m, dt, rtol, s0) for lbl, m, dt, rtol in rec.run_specs(demo)
        ]
        self.labels = [r.label for r in self.runs]
        first = {r.label: r.sim.state.copy() for r in self.runs}
        self.drawer = DRAWERS[demo.exhibit](server, demo, self.labels, first)
        self.camera = fallback_camera(demo, np.atleast_2d(first[self.labels[0]]))

    def advance_to(self, t: float) -> None:
        for r in self.runs:
            r.advance_to(t)

    def apply(self, ev) -> dict[str, Any]:
        from .recording import apply_event

        return {r.label: apply_event(self.demo, self.system, r, ev) for r in self.runs}

    def samples(self) -> dict[str, Any]:
        out = {r.label: r.sample() for r in self.runs}
        for r in self.runs:
            grown = float(np.max(np.abs(out[r.label].energy_error)))
            if not math.isfinite(grown) or grown > DIVERGED:
                sim = r.sim
                raise IntegrationError(
                    sim.method.name, sim.step_label(), r.t,
                    f"diverged: the energy changed by a factor {1 + grown:.3g}",
                )  # fmt: skip
        return out

    def steps(self) -> dict[str, tuple[int, int, str | None]]:
        return {
            r.label: (
                r.steps_before + r.sim.steps,
                r.nfev_before + r.sim.nfev,
                r.sim.reference_kind,
            )
            for r in self.runs
        }

    def draw(self, frame) -> None:
        self.drawer.draw(frame)


def fallback_camera(demo, first: np.ndarray):
    """``(position, look_at)`` that frames this module's drawing of ``demo``."""
    compare = demo.compare is not None
    if demo.exhibit == "cyclotron":
        if compare:
            return (1.5, -6.0, 7.0), (1.5, 0.0, 0.0)
        if len(first) > 1:
            from .recording import params_for

            pr = params_for(demo)
            c = np.array([cyclotron.guiding_centre(pr, st)[:2] for st in first])
            r = np.array([cyclotron.larmor_radius(pr, st) for st in first])
            lo, hi = (c - r[:, None]).min(axis=0), (c + r[:, None]).max(axis=0)
            mid = 0.5 * (lo + hi)
            height = 1.3 * float(np.max(hi - lo)) + 1.0
            return (float(mid[0]), float(mid[1]) - 0.5, height), (float(mid[0]), float(mid[1]), 0.0)
        if demo.events:
            return (0.0, -0.5, 6.0), (0.0, 0.0, 0.0)
        return (4.5, -4.5, 3.0), (0.0, 0.0, 1.5)
    if demo.exhibit == "disk":
        if demo.motion == "released":
            return (5.0, -5.0, 3.5), (0.0, 1.0, 0.0)
        return (4.0, -3.0, 3.0), (0.0, 1.0, 0.0)
    if compare:
        return (1.5, -7.0, -1.5), (1.5, 0.0, -1.3)
    return (0.0, -6.0, -1.2), (0.0, 0.0, -1.2)


def make_driver(server, demo, *, prefer: str = "auto"):
    """The driver that draws ``demo``: the viewer's exhibits when available (``prefer`` "auto"
    or "exhibit"), else this module's :class:`FallbackDriver` ("fallback")."""
    if prefer in ("auto", "exhibit"):
        try:
            from . import recording_exhibits
        except ImportError:
            if prefer == "exhibit":
                raise
        else:
            driver = recording_exhibits.driver_for(server, demo)
            if driver is not None:
                return driver
            if prefer == "exhibit":
                raise ValueError(f"the viewer has no exhibit that can play {demo.name}")
    return FallbackDriver(server, demo)
