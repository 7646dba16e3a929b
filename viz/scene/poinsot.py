"""Poinsot's construction for the released disk, drawn beside the disk's exhibit
(:mod:`mechviz.viz.scene.disk`), and the disk frame's mapping to the world both draw with.

World mapping: the dynamics' disk frame (axle along +y) is drawn with the axle vertical and the
disk facing the default camera at ``t = 0``: world ``(x, y, z) = lift + P (x, y, z)_disk`` with
``P`` sending disk ``x -> x``, ``y -> z``, ``z -> -y`` (a proper rotation), ``lift = (0, 0, 0.4)``
above the exhibit origin.
"""

from __future__ import annotations

import math

import numpy as np

from mechviz.dynamics import disk as dk

from .. import geometry as geo

P = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])  # disk frame -> world
LIFT = np.array([0.0, 0.0, 0.4])
NAMES = "Poinsot: inertia ellipsoid + polhode,\ninvariable plane (⊥ L) + herpolhode"
STAGE_NAMES = "Poinsot: ellipsoid rolls\non the plane ⊥ L"  # short: large on the stage
# Poinsot's picture on the disk's stage, in disk radii
STAGE_DISTANCE = 1.0  # the plane's distance from the ellipsoid's centre (half its height)
STAGE_GAP = 1.2  # clear of the disk's box in perspective (the arrows reach its edges)
# On the stage the picture is turned about the camera's horizontal, L tipped towards the hall:
# with L up, the plane is seen edge on and the picture is as flat as the plane's distance
# (the ellipsoid lies along the plane); tipped, its long axis shows in the height too.
STAGE_TIP = math.radians(50.0)
STAGE_TILT = np.array(
    [
        [1.0, 0.0, 0.0],
        [0.0, math.cos(STAGE_TIP), -math.sin(STAGE_TIP)],
        [0.0, math.sin(STAGE_TIP), math.cos(STAGE_TIP)],
    ]
)


class PoinsotPicture:
    """Poinsot's construction for the released disk (:func:`mechviz.dynamics.disk.poinsot`), drawn at
    the centre of mass: the inertia ellipsoid turning with the body, the invariable plane fixed
    in space (normal to L), the polhode traced on the ellipsoid and the herpolhode on the plane.
    Lengths are 1/sqrt(kg m^2) times ``scale`` [m], chosen so the longest semi-axis is 0.6 R."""

    def __init__(self, scene, root: str) -> None:
        self.scene, self.root = scene, root
        self.frame = scene.add_frame(f"{root}/poinsot", show_axes=False, visible=False)
        # the names, in one label fixed in space under the ellipsoid (text turning with the
        # body, or riding on the moving contact point, would pile up on screen)
        self.names = [
            scene.add_label(
                f"{root}/poinsot_label",
                NAMES,
                anchor="top-right",
                visible=False,
            ),
        ]
        self.plane_frame = scene.add_frame(
            f"{root}/invariable_plane", show_axes=False, visible=False
        )
        self.ellipsoid = None
        self.polhode = geo.ChunkedTrail(scene, f"{root}/poinsot/polhode", geo.CENTRE, cap=900)
        self.herpolhode = geo.ChunkedTrail(
            scene, f"{root}/invariable_plane/herpolhode", geo.MOMENTUM, cap=900
        )
        self.scale = 1.0
        self.radius = 1.0
        self.plane_radius = 0.9  # [m]
        self.half = np.full(3, 0.6)  # half the sides [m] of the box the staged picture is in
        self.tilt = np.eye(3)  # world -> the picture's world (turned on the stage)
        self.staged = False  # on the stage: large, beside the disk (at home: small, at the CM)
        self._started = None  # the last start's arguments (a move to or from the stage redraws)

    def beside(self, radius: float) -> np.ndarray:
        """The staged picture's centre (relative to the exhibit origin) [m]: right of the
        disk's box, its back level with the box's back (nearer the hall, so larger), its
        lowest point half a radius above the disk's lowest (its names hang there, inside the
        exhibit's box)."""
        hx, hy, hz = self.half
        x = 1.4 * radius + STAGE_GAP * radius + hx
        return np.array([x, 1.4 * radius - hy, LIFT[2] + 0.5 * radius + hz])

    def stage(self, staged: bool) -> None:
        """Large beside the disk on its stage, small at the centre of mass elsewhere (the
        curves start afresh at the new size)."""
        if staged != self.staged:
            self.staged = staged
            if self._started is not None:
                self.start(*self._started)

    def start(self, moments: np.ndarray, radius: float, shown: bool, state=None) -> None:
        """A new run: ``moments`` [kg m^2] the principal ones, ``state`` the free body's (the
        plane's distance sizes the staged picture; ``None`` while driven)."""
        self._started = (moments, radius, shown, state)
        semi = 1.0 / np.sqrt(moments)
        # at home: inside the disk, the longest semi-axis 0.6 R
        self.scale = 0.6 * radius / float(semi.max())
        self.plane_radius = 0.9 * radius
        if self.staged and state is not None:
            # on stage: the picture's height is the plane's distance from the centre, twice
            # (the ellipsoid touches the plane, and is symmetric about its centre): that sets
            # its size, as tall as a third of the page beside the disk
            pc = dk.poinsot(moments, state)
            self.scale = STAGE_DISTANCE * radius / pc["distance"]
            a, d = float(semi.max()) * self.scale, STAGE_DISTANCE * radius
            # the herpolhode stays within sqrt(a^2 - d^2) of the foot of L
            self.plane_radius = max(1.05 * math.sqrt(max(a * a - d * d, 0.0)), 0.6 * a)
            n = np.abs(STAGE_TILT @ to_world(pc["normal"]))
            across = np.sqrt(np.maximum(1.0 - n * n, 0.0))
            # along each axis: the plane's rim, and the ellipsoid (d along n, a across it)
            rim = d * n + self.plane_radius * across
            self.half = np.maximum(rim, np.sqrt((d * n) ** 2 + (a * across) ** 2))
            self.tilt = STAGE_TILT
        else:
            self.half = np.full(3, 0.6 * radius)
            self.tilt = np.eye(3)
        if self.ellipsoid is not None:
            self.ellipsoid.remove()
        mesh = geo.sphere_mesh(1.0, 3)
        mesh.apply_scale(semi * self.scale)
        self._shape = np.asarray(mesh.vertices, float)  # the ellipsoid's own points [m]
        self.ellipsoid = self.scene.add_mesh_simple(
            f"{self.root}/poinsot/ellipsoid",
            mesh.vertices,
            mesh.faces,
            color=geo.CENTRE,
            opacity=0.35,
        )
        plane = geo.disk_mesh(self.plane_radius, 0.004 * radius)
        self.scene.add_mesh_simple(
            f"{self.root}/invariable_plane/plane",
            plane.vertices,
            plane.faces,
            color=geo.MOMENTUM,
            opacity=0.25,
        )
        self.polhode.clear()
        self.herpolhode.clear()
        self.frame.visible = self.plane_frame.visible = shown
        self.radius = radius
        for h in self.names:
            h.visible = shown
            h.text = STAGE_NAMES if self.staged else NAMES
            h.anchor = "top-center" if self.staged else "top-right"

    def draw(self, pc: dict, cm_world: np.ndarray) -> None:
        """``pc`` from :func:`mechviz.dynamics.disk.poinsot`; ``cm_world`` the centre of mass (world,
        relative to the exhibit origin): the picture's centre, except on stage (beside)."""
        if self.staged:
            cm_world = self.beside(self.radius)
        self.frame.position = cm_world
        tilt = self.tilt
        self.frame.wxyz = geo.quat_from_matrix(tilt @ P @ pc["rotation"])
        n = tilt @ to_world(pc["normal"])
        turn = _z_onto(n)  # the plane's own z along n; the plane sits at its distance along n
        offset = n * pc["distance"] * self.scale
        self.plane_frame.wxyz = geo.quat_from_matrix(turn)
        self.plane_frame.position = cm_world + offset
        # under the ellipsoid, reaching left (the hoop's labels stand to the right)
        self.names[0].position = cm_world + (
            (0.0, -self.half[1], -self.half[2])  # the box's near lower edge: under it all
            if self.staged
            else (0.3 * self.radius, 0.0, -0.65 * self.radius)
        )
        self.polhode.push(pc["contact_body"] * self.scale)
        self.polhode.draw()
        # the herpolhode in the plane's own coordinates (the plane is fixed while L is)
        self.herpolhode.push(turn.T @ (tilt @ to_world(pc["contact_space"]) * self.scale - offset))
        self.herpolhode.draw()

    def picture_points(self) -> np.ndarray:
        """Points [m] of the picture as drawn, relative to the exhibit origin: the ellipsoid's
        surface and the plane's rim (what a test projects to measure it on the page)."""
        turn = geo.matrix_from_quat(self.frame.wxyz)
        body = self._shape @ turn.T + np.asarray(self.frame.position, float)
        phi = np.linspace(0.0, 2 * np.pi, 64, endpoint=False)
        rim = self.plane_radius * np.column_stack([np.cos(phi), np.sin(phi), np.zeros_like(phi)])
        plane = geo.matrix_from_quat(self.plane_frame.wxyz)
        rim = rim @ plane.T + np.asarray(self.plane_frame.position, float)
        return np.concatenate([body, rim])


def _z_onto(n: np.ndarray) -> np.ndarray:
    """A rotation matrix taking +z onto the unit vector ``n`` (Rodrigues' formula)."""
    z = np.array([0.0, 0.0, 1.0])
    v, c = np.cross(z, n), float(z @ n)
    if c < -1.0 + 1e-12:
        return np.diag([1.0, -1.0, -1.0])
    vx = np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
    return np.eye(3) + vx + vx @ vx / (1.0 + c)


def to_world(v) -> np.ndarray:
    """Disk/space-frame vector(s) (..., 3) -> world vector(s), relative to the exhibit origin."""
    return np.asarray(v, float) @ P.T
