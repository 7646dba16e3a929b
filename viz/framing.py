"""Where a video's or a still's camera stands: a named preset or a position, framed on the exhibit.

World coordinates are the scene's (metres, +z up). A camera is a position, a point looked at and
a vertical field of view (radians); :func:`frame` places it on a line of sight so that the
exhibit's bounding box fills a chosen share of the picture's height (never overflowing its width)
and sits in the middle of the part of the picture the words leave free. The projection is
three.js's: a pinhole camera, +z up, square pixels.

``--camera`` takes a preset (:data:`PRESETS`) or a position ``X,Y,Z`` (looking at the exhibit's
centre), optionally ``X,Y,Z:LX,LY,LZ`` to name the point looked at as well.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

FOV = math.radians(40.0)  # vertical: little perspective distortion, labels stay upright
FILL = 1.0  # share of the free height the box fills (the box is drawn loosely round the exhibit)
LABEL_ROOM = 0.12  # the exhibits' title labels stand above their boxes: this share of its height
PRESETS = {
    "exhibit": "the exhibit's own view (the viewer's preset), framed",
    "front": "level, from in front (-y), framed",
    "side": "level, from the right (+x), framed",
    "top": "straight down, +y up the picture, framed",
    "recorded": "the recording's own camera, unchanged (the viewer's camera for a session)",
}
_DIRECTIONS = {  # unit vector from the point looked at to the camera, for the level presets
    "front": (0.0, -1.0, 0.12),
    "side": (1.0, 0.0, 0.12),
    "top": (0.0, -0.002, 1.0),
}

Vec = tuple[float, float, float]


@dataclass(frozen=True)
class Camera:
    """A camera for the player page: ``position`` and ``look_at`` [m], ``fov`` vertical [rad];
    ``None`` everywhere means the recording's own camera."""

    position: Vec | None = None
    look_at: Vec | None = None
    fov: float | None = None

    def __post_init__(self) -> None:
        for name in ("position", "look_at"):
            v = getattr(self, name)
            if v is not None:
                v = tuple(float(x) for x in v)
                object.__setattr__(self, name, v)
            if v is not None and not (len(v) == 3 and all(math.isfinite(x) for x in v)):
                raise ValueError(f"camera: {name} must be three finite numbers, got {v!r}")
        if self.fov is not None and not 0.05 < self.fov < 3.0:
            raise ValueError(f"camera: fov must be in (0.05, 3) rad, got {self.fov!r}")
        if self.position is not None and self.look_at is not None:
            if math.dist(self.position, self.look_at) < 1e-6:
                raise ValueError("camera: the position and the point looked at coincide")

    def query(self) -> dict[str, str]:
        """URL parameters of viser's client that set this camera (they override the recorded
        initial camera)."""
        out = {}
        if self.position is not None:
            out["initialCameraPosition"] = _csv(self.position)
            out["initialCameraUp"] = "0,0,1"
        if self.look_at is not None:
            out["initialCameraLookAt"] = _csv(self.look_at)
        if self.fov is not None:
            out["initialCameraFov"] = f"{self.fov:.6g}"
        return out

    def as_dict(self) -> dict:
        return {"position": self.position, "look_at": self.look_at, "fov": self.fov}


@dataclass(frozen=True)
class Request:
    """What ``--camera`` asked for: a preset name, or a position (and maybe a point looked at)."""

    preset: str | None = None
    position: Vec | None = None
    look_at: Vec | None = None


def _csv(v) -> str:
    return ",".join(f"{float(x):.6g}" for x in v)


_NUM = r"\s*[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?\s*"
_VEC = rf"({_NUM}),({_NUM}),({_NUM})"


def parse_camera(text: str) -> Request:
    """``--camera`` text: a preset name or ``X,Y,Z[:LX,LY,LZ]`` (``ValueError`` otherwise)."""
    word = text.strip().lower()
    if word in PRESETS:
        return Request(preset=word)
    m = re.fullmatch(_VEC + rf"(?::{_VEC})?", text)
    if m is None:
        raise ValueError(
            f"choose a preset ({', '.join(PRESETS)}) or a position X,Y,Z[:LX,LY,LZ] in metres, "
            f"got {text!r}"
        )
    g = [float(x) for x in m.groups() if x is not None]
    if not all(math.isfinite(x) for x in g):
        raise ValueError(f"the numbers must be finite, got {text!r}")
    pos = (g[0], g[1], g[2])
    look = (g[3], g[4], g[5]) if len(g) == 6 else None
    if look is not None and math.dist(pos, look) < 1e-6:
        raise ValueError("the position and the point looked at coincide")
    return Request(position=pos, look_at=look)


def axes(position, target) -> tuple[np.ndarray, ...]:
    """Camera axes (right, up, forward) for +z up; looking straight down, +y is up."""
    fwd = np.asarray(target, float) - np.asarray(position, float)
    fwd = fwd / np.linalg.norm(fwd)
    right = np.cross(fwd, (0.0, 0.0, 1.0))
    if np.linalg.norm(right) < 1e-6:
        right = np.array([1.0, 0.0, 0.0])
    right = right / np.linalg.norm(right)
    up = np.cross(right, fwd)
    return right, up, fwd


def project(position, target, fov: float, aspect: float, points) -> np.ndarray:
    """Normalised device coordinates ``(x, y)`` in [-1, 1] of world ``points`` (N, 3) seen from
    ``position`` looking at ``target``; ``aspect`` is width / height."""
    p, t = np.asarray(position, float), np.asarray(target, float)
    right, up, fwd = axes(p, t)
    d = np.asarray(points, float) - p
    z = d @ fwd
    if np.any(z <= 1e-9):
        return np.full((len(d), 2), np.inf)
    f = 1.0 / math.tan(fov / 2)
    return np.stack([(d @ right) * f / (z * aspect), (d @ up) * f / z], axis=1)


def corners(lo, hi) -> np.ndarray:
    """The eight corners (8, 3) of the box from ``lo`` to ``hi``."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    return np.array(
        [[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]
    )


def frame(
    bounds,
    direction,
    *,
    aspect: float,
    fov: float = FOV,
    fill: float = FILL,
    band: tuple[float, float] = (0.0, 0.0),
) -> Camera:
    """The camera looking along ``-direction`` (from the box towards the camera: ``direction``)
    whose picture holds the box ``bounds = (lo, hi)`` filling ``fill`` of the height left free
    between ``band = (top, bottom)`` (shares of the height covered by words) and at most 94 % of
    the width, centred in that free part."""
    lo, hi = np.array(bounds[0], float), np.array(bounds[1], float)
    hi[2] += LABEL_ROOM * (hi[2] - lo[2])
    pts = corners(lo, hi)
    centre = pts.mean(axis=0)
    d = np.asarray(direction, float)
    d = d / np.linalg.norm(d)
    top, bottom = band
    free = max(1.0 - top - bottom, 0.2)
    want_mid = bottom - top  # NDC y (+1 at the top) of the free part's middle
    target = centre.copy()
    dist = float(np.linalg.norm(pts - centre, axis=1).max()) * 3.0 + 1e-3
    for _ in range(6):
        # the distance at which the box's height fills the free part (and its width fits)
        lo_d, hi_d = 1e-3, dist * 50.0
        for _ in range(60):
            mid = 0.5 * (lo_d + hi_d)
            xy = project(target + d * mid, target, fov, aspect, pts)
            h = (xy[:, 1].max() - xy[:, 1].min()) / 2
            w = (xy[:, 0].max() - xy[:, 0].min()) / 2
            fits = np.all(np.isfinite(xy)) and h <= fill * free and w <= 0.94
            lo_d, hi_d = (lo_d, mid) if fits else (mid, hi_d)
        dist = hi_d
        # slide the point looked at so the box's middle sits in the free part's middle
        xy = project(target + d * dist, target, fov, aspect, pts)
        off_x = (xy[:, 0].max() + xy[:, 0].min()) / 2
        off_y = (xy[:, 1].max() + xy[:, 1].min()) / 2 - want_mid
        right, up, _ = axes(target + d * dist, target)
        half_h = dist * math.tan(fov / 2)
        target = target + right * off_x * half_h * aspect + up * off_y * half_h
    position = target + d * dist
    return Camera(tuple(map(float, position)), tuple(map(float, target)), float(fov))


def resolve(
    request: Request | None,
    *,
    bounds=None,
    view: tuple[Vec, Vec] | None = None,
    recorded: Camera | None = None,
    aspect: float,
    band: tuple[float, float] = (0.0, 0.0),
) -> Camera:
    """The camera for ``request`` (``None``: the default: the ``recorded`` camera of a live
    session when there is one, else the exhibit's ``view = (position, look_at)`` framed on its
    ``bounds``, else the recording's own). Presets need the bounds (``ValueError`` naming what
    is missing)."""
    if request is not None:
        preset = request.preset
    else:  # a live session: what the viewer saw; a demo: its exhibit, framed
        preset = "recorded" if recorded is not None or not bounds else "exhibit"
    if request is not None and request.position is not None:
        look = request.look_at
        if look is None:
            if bounds is not None:
                look = tuple(map(float, corners(*bounds).mean(axis=0)))
            elif recorded is not None and recorded.look_at is not None:
                look = recorded.look_at
            else:
                look = (0.0, 0.0, 0.0)
        return Camera(request.position, look, FOV)
    if preset == "recorded":
        return recorded or Camera()
    if bounds is None:
        raise ValueError(
            f"the preset {preset!r} frames a demo's exhibit, and this recording names none (no "
            "manifest beside it): give a position X,Y,Z[:LX,LY,LZ] or 'recorded'"
        )
    if preset == "exhibit":
        if view is None:
            direction = _DIRECTIONS["front"]
        else:
            direction = np.asarray(view[0], float) - np.asarray(view[1], float)
    else:
        direction = _DIRECTIONS[preset]
    return frame(bounds, direction, aspect=aspect, band=band)
