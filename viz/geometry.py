"""Shared geometry for the exhibits: trimesh meshes built once, a capped chunked trail, helpers.

Conventions: the world is viser's, +z up, metres. Meshes are created here once per exhibit and
afterwards only moved (``position`` / ``wxyz`` / ``batched_*`` assignments). Quaternions are
``(w, x, y, z)`` and always unit length (viser does not normalise them).
"""

from __future__ import annotations

import math
from collections import deque

import numpy as np

from .interrupts import sigint_held

with sigint_held():  # trimesh swallows a KeyboardInterrupt raised while it imports
    import trimesh


def lines(scene, name: str, segments, colors, thickness: float, **kwargs):
    """viser line segments ``(N, 2, 3)`` [m] under ``name``, ``thickness`` in screen pixels (a
    line reads the same at every zoom and on a projector); ``colors`` one RGB, or one per point."""
    return scene.add_line_segments(
        name,
        segments,
        colors=np.asarray(colors, np.uint8),
        thickness=thickness,
        thickness_units="screen",
        **kwargs,
    )


def instances(scene, name: str, mesh, colors, **batched):
    """One viser node drawing ``len(colors)`` copies of ``mesh`` (one draw call), unrotated, at
    the origin until moved; ``batched``: further ``batched_*`` values by their short names
    (``scales``, ``opacities``, ``positions``)."""
    n = len(colors)
    kwargs = {"wxyzs": np.tile([1.0, 0.0, 0.0, 0.0], (n, 1)), "positions": np.zeros((n, 3))}
    kwargs.update(batched)
    return scene.add_batched_meshes_simple(
        name,
        mesh.vertices,
        mesh.faces,
        batched_colors=np.asarray(colors, np.uint8),
        lod="off",
        **{f"batched_{k}": v for k, v in kwargs.items()},
    )


# Colour palette (RGB uint8) shared by all exhibits. Mid-tones: every colour keeps a contrast of
# at least 3:1 (the WCAG threshold for graphics) against the light theme's white background and
# the dark theme's near-black one (BACKGROUNDS), so nothing vanishes on a projector in either.
BACKGROUNDS = {"light": (255, 255, 255), "dark": (33, 34, 38)}
CHARGE = (235, 70, 40)
COMPARE = (20, 130, 220)
BEAM = ((205, 120, 0), (205, 70, 25))  # slowest and fastest member of a beam
FIELD = (100, 120, 240)
DISK = (70, 140, 200)
RIM = (0, 150, 160)
BEAD = (220, 40, 160)
AXLE = (125, 125, 135)
STAND = (120, 120, 130)
FORCE = (240, 60, 60)
OMEGA = (20, 160, 70)
MOMENTUM = (210, 120, 0)
TORQUE = (170, 100, 30)  # dL/dt
HOOP = (190, 110, 40)
GHOST = (140, 140, 160)
TRAIL = (235, 95, 40)
CENTRE = (160, 92, 225)  # guiding centre, centre of mass, pivot, the predicted circle
AXES_RGB = ((230, 60, 60), (30, 160, 50), (60, 110, 240))
PALETTE = {
    "charge ball": CHARGE,
    "compare": COMPARE,
    "beam slow": BEAM[0],
    "beam fast": BEAM[1],
    "field": FIELD,
    "disk face": DISK,
    "rim": RIM,
    "bead": BEAD,
    "axle": AXLE,
    "stand": STAND,
    "force": FORCE,
    "omega": OMEGA,
    "momentum": MOMENTUM,
    "torque": TORQUE,
    "hoop ring": HOOP,
    "ghost": GHOST,
    "trail": TRAIL,
    "centre": CENTRE,
    **{f"axis {k + 1}": c for k, c in enumerate(AXES_RGB)},
}


def contrast(a, b) -> float:
    """WCAG contrast ratio of two sRGB colours (1 to 21)."""

    def luminance(c) -> float:
        lin = [
            v / 12.92 if v <= 0.03928 else ((v + 0.055) / 1.055) ** 2.4 for v in np.asarray(c) / 255
        ]
        return 0.2126 * lin[0] + 0.7152 * lin[1] + 0.0722 * lin[2]

    hi, lo = sorted((luminance(a), luminance(b)), reverse=True)
    return (hi + 0.05) / (lo + 0.05)


# ----------------------------------------------------------------------------- meshes
def disk_mesh(radius: float, thickness: float, sections: int = 64) -> trimesh.Trimesh:
    """A flat disk centred at the origin, normal along +z."""
    return trimesh.creation.cylinder(radius=radius, height=thickness, sections=sections)


def torus_mesh(major_radius: float, minor_radius: float) -> trimesh.Trimesh:
    """A ring in the x-y plane (axis +z) centred at the origin: the hoop."""
    return trimesh.creation.torus(
        major_radius=major_radius, minor_radius=minor_radius, major_sections=64, minor_sections=12
    )


def rod_between(a, b, radius: float, sections: int = 16) -> trimesh.Trimesh:
    """A cylinder from point ``a`` to point ``b``."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    return trimesh.creation.cylinder(radius=radius, segment=np.stack([a, b]), sections=sections)


def sphere_mesh(radius: float, subdivisions: int = 2) -> trimesh.Trimesh:
    return trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius)


def circle_segments(radius: float, n: int = 96, centre=(0.0, 0.0, 0.0)) -> np.ndarray:
    """A circle in a plane parallel to x-y as (n, 2, 3) float32 line segments."""
    ang = np.linspace(0.0, 2.0 * math.pi, n + 1)
    pts = np.stack([radius * np.cos(ang), radius * np.sin(ang), np.zeros_like(ang)], axis=1)
    pts = pts + np.asarray(centre, float)
    return np.stack([pts[:-1], pts[1:]], axis=1).astype(np.float32)


# ----------------------------------------------------------------------------- rotations
def quat_from_matrix(r: np.ndarray) -> np.ndarray:
    """Unit quaternion (w, x, y, z), ``w >= 0``, of a proper rotation matrix."""
    m = np.asarray(r, float).tolist()  # plain floats: a 3x3 is cheaper in Python than in numpy
    tr = m[0][0] + m[1][1] + m[2][2]
    if tr > 0.0:
        s = 2.0 * math.sqrt(1.0 + tr)
        q = [0.25 * s, (m[2][1] - m[1][2]) / s, (m[0][2] - m[2][0]) / s, (m[1][0] - m[0][1]) / s]
    else:
        i = max(range(3), key=lambda n: m[n][n])  # the first largest diagonal entry
        j, k = (i + 1) % 3, (i + 2) % 3
        s = 2.0 * math.sqrt(max(1.0 + m[i][i] - m[j][j] - m[k][k], 1e-300))
        q = [0.0, 0.0, 0.0, 0.0]
        q[0] = (m[k][j] - m[j][k]) / s
        q[1 + i] = 0.25 * s
        q[1 + j] = (m[j][i] + m[i][j]) / s
        q[1 + k] = (m[k][i] + m[i][k]) / s
    n = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    if q[0] < 0.0:
        n = -n
    return np.array([q[0] / n, q[1] / n, q[2] / n, q[3] / n])


def matrix_from_quat(wxyz) -> np.ndarray:
    """The rotation matrix of a unit quaternion (w, x, y, z)."""
    w, x, y, z = (float(c) for c in wxyz)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def quat_about_axis(axis, angle: float) -> np.ndarray:
    axis = np.asarray(axis, float)
    axis = axis / np.linalg.norm(axis)
    h = 0.5 * angle
    return np.concatenate([[math.cos(h)], math.sin(h) * axis])


# ----------------------------------------------------------------------------- trail
def clip_segment(a, b, lo, hi) -> np.ndarray:
    """The end of the segment from ``a`` (inside the box ``lo``..``hi``) towards ``b``, cut where
    it leaves the box (``b`` itself if it does not)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    d = b - a
    s = 1.0
    with np.errstate(divide="ignore", invalid="ignore"):
        for k in range(3):
            if d[k] > 0:
                s = min(s, (hi[k] - a[k]) / d[k])
            elif d[k] < 0:
                s = min(s, (lo[k] - a[k]) / d[k])
    return a + max(s, 0.0) * d


class ChunkedTrail:
    """A polyline trail with a capped length, drawn as frozen chunks plus one open chunk.

    Every ``chunk`` segments the open chunk is frozen (its node is never touched again) and a
    new node starts; the oldest chunk node is removed once the trail holds more than ``cap``
    segments. Each frame therefore rewrites at most one small node, which keeps live frames cheap
    and recordings small (a recording stores every message, so rewriting a whole long trail each
    frame would store the trail once per frame). ``push(p)`` appends a point; ``lift()`` makes
    the next point start a new piece (no segment joins them, e.g. when a display coordinate wraps).
    Call :meth:`draw` once per frame (inside the caller's ``server.atomic()``). ``box`` (low and
    high corners, in the trail's coordinates) bounds what is drawn: a point outside it is not
    drawn and the trail is lifted there, so a run that spirals away (explicit Euler) is seen
    growing up to its exhibit's edge and never draws across a neighbour.

    The open chunk lives in one preallocated ``(chunk, 2, 3)`` float32 buffer: pushing a point
    writes into it and drawing assigns a view of it (viser copies what it is given), so a frame
    allocates no trail arrays; a full chunk is copied once, when it is frozen.
    """

    def __init__(
        self,
        scene,
        name: str,
        color,
        *,
        cap: int = 600,
        chunk: int = 60,
        thickness: float = 2.0,
        visible: bool = True,
        box=None,
    ) -> None:
        self.scene, self.name = scene, name
        self.box = box  # (lo, hi): where points are drawn (None: anywhere)
        self.color = np.asarray(color, np.uint8)
        self.cap, self.chunk, self.thickness = int(cap), int(chunk), float(thickness)
        self._frozen: deque = deque()  # (handle, n_segments)
        self._open_handle = None
        self._buf = np.empty((self.chunk, 2, 3), np.float32)  # the open chunk's segments
        self._n_open = 0  # segments in the buffer
        self._full: list[np.ndarray] = []  # chunks filled since the last draw, oldest first
        self._p = np.empty(3, np.float32)  # scratch: the point being pushed
        self._last = np.empty(3, np.float32)
        self._has_last = False
        self._dirty = False
        self._counter = 0
        self._visible = visible
        self._frozen_segments = 0

    @property
    def n_segments(self) -> int:
        return self._frozen_segments + self.chunk * len(self._full) + self._n_open

    @property
    def n_nodes(self) -> int:
        return len(self._frozen) + (self._open_handle is not None)

    @property
    def last_point(self) -> np.ndarray | None:
        """The newest point (``None`` after :meth:`lift` or :meth:`clear`)."""
        return self._last.copy() if self._has_last else None

    def push(self, point) -> None:
        p = self._p
        p[:] = point
        if self.box is not None and not (
            np.all(p >= self.box[0]) and np.all(p <= self.box[1])  # NaN fails both: not drawn
        ):
            self._has_last = False
            return
        if self._has_last and p.tobytes() != self._last.tobytes():
            if self._n_open == self.chunk:  # full: hand it to draw() and start afresh
                self._full.append(self._buf.copy())
                self._n_open = 0
            seg = self._buf[self._n_open]
            seg[0] = self._last
            seg[1] = p
            self._n_open += 1
            self._dirty = True
        self._last[:] = p
        self._has_last = True

    def lift(self) -> None:
        self._has_last = False

    def clear(self) -> None:
        for handle, _ in self._frozen:
            handle.remove()
        self._frozen.clear()
        self._frozen_segments = 0
        if self._open_handle is not None:
            self._open_handle.remove()
            self._open_handle = None
        self._full.clear()
        self._n_open = 0
        self._has_last = False
        self._dirty = False

    @property
    def visible(self) -> bool:
        return self._visible

    @visible.setter
    def visible(self, value: bool) -> None:
        self._visible = bool(value)
        for handle, _ in self._frozen:
            handle.visible = self._visible
        if self._open_handle is not None:
            self._open_handle.visible = self._visible

    def _new_node(self, segments: np.ndarray):
        self._counter += 1
        name = f"{self.name}/c{self._counter:06d}"
        return lines(
            self.scene, name, segments.copy(), self.color, self.thickness, visible=self._visible
        )

    def _write_open(self, segments: np.ndarray) -> None:
        if self._open_handle is None:
            self._open_handle = self._new_node(segments)
        else:
            self._open_handle.points = segments

    def _freeze(self) -> None:
        self._frozen.append((self._open_handle, self.chunk))
        self._frozen_segments += self.chunk
        self._open_handle = None

    def draw(self) -> None:
        if not self._dirty:
            return
        self._dirty = False
        for full in self._full:  # chunks that filled up since the last draw
            self._write_open(full)
            self._freeze()
        self._full.clear()
        if self._n_open:
            self._write_open(self._buf[: self._n_open])
            if self._n_open == self.chunk:  # the open chunk is full: freeze it
                self._freeze()
                self._n_open = 0
        while self._frozen and self.n_segments > self.cap:
            handle, n = self._frozen.popleft()
            handle.remove()
            self._frozen_segments -= n
