"""Framing a camera on a box: where to stand so a world box fills a share of the page's height.

viser's camera is a pinhole with a vertical field of view (:data:`FOV`, 75 degrees by default)
and +z up; the page is ``width`` x ``height`` pixels, of which the GUI panel, docked on the right,
covers the last ``panel_px`` (:data:`PANEL_PX` at the panel width the app configures, 0 when it is
collapsed). :func:`frame` puts a box's eight corners in the middle of the part of the page the
panel leaves free, as large as ``fill`` of the height allows without leaving that part sideways;
:func:`project` is the same camera's map from world to page pixels (what a test measures).
"""

from __future__ import annotations

import math

import numpy as np

from ..framing import axes, corners

FOV = 1.3089969389957472  # rad: viser's default vertical field of view (75 degrees)
PANEL_PX = 340  # px: the right edge of the page viser's panel covers ("medium" width, margins)
SIDE_MARGIN = 0.02  # of the free width kept clear on each side


def basis(position, look_at) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Forward, right and up unit vectors of a camera at ``position`` looking at ``look_at``."""
    r, u, f = axes(position, look_at)
    return f, r, u


def project(points, position, look_at, width: int, height: int, fov: float = FOV) -> np.ndarray:
    """Page pixels ``(x right, y down)`` of world ``points`` (N, 3); NaN behind the camera."""
    f, r, u = basis(position, look_at)
    d = np.atleast_2d(np.asarray(points, float)) - np.asarray(position, float)
    z = d @ f
    t = math.tan(fov / 2)
    with np.errstate(divide="ignore", invalid="ignore"):
        nx = (d @ r) / (z * t * width / height)
        ny = (d @ u) / (z * t)
    out = np.stack([(nx + 1) / 2 * width, (1 - ny) / 2 * height], axis=1)
    out[z <= 1e-9] = np.nan
    return out


def frame(lo, hi, direction, *args, **kw) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """``(position, look_at)`` of a camera looking along ``direction`` at the box ``lo``..``hi``
    [m] so that the box's picture is ``fill`` of the page's height (less if it would not fit
    the free width) and centred in the part of the page left of the panel (the arguments of
    :func:`frame_points`)."""
    return frame_points(corners(lo, hi), direction, *args, **kw)


def frame_points(
    pts,
    direction,
    width: int = 1280,
    height: int = 800,
    *,
    fill: float = 0.7,
    panel_px: int = PANEL_PX,
    fov: float = FOV,
    region: tuple[float, float, float, float] | None = None,
) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """:func:`frame` for any world points (N, 3) [m]: the corners of several boxes are framed
    by their own picture, not by the larger box that holds them all. ``region`` = ``(x0, y0,
    x1, y1)`` [page px] is the part of the page the picture goes in (default: left of the
    panel, the whole height); ``fill`` is then a share of its height."""
    pts = np.asarray(pts, float)
    centre = pts.mean(axis=0)
    f = np.asarray(direction, float) / np.linalg.norm(direction)
    if region is None:
        region = (0.0, 0.0, float(max(width - panel_px, 1)), float(height))
    rx0, ry0, rx1, ry1 = region
    free, free_h = max(rx1 - rx0, 1.0), max(ry1 - ry0, 1.0)
    offset = np.zeros(3)

    def view(dist):
        target = centre + offset
        return target - dist * f, target

    def middle(dist):
        xy = project(pts, *view(dist), width, height, fov)
        return (xy.min(axis=0) + xy.max(axis=0)) / 2

    def size(dist):
        xy = project(pts, *view(dist), width, height, fov)
        if np.isnan(xy).any():
            return math.inf, math.inf
        return np.ptp(xy[:, 0]), np.ptp(xy[:, 1])

    for _ in range(3):
        # the distance: bisection on the larger of the two shares (the picture shrinks with it)
        near, far = 1e-3, 1e3
        for _ in range(60):
            d = math.sqrt(near * far)
            w, h = size(d)
            if max(h / (fill * free_h), w / ((1 - 2 * SIDE_MARGIN) * free)) > 1:
                near = d
            else:
                far = d
        d = far
        # then slide the camera so the picture's middle is the free part's middle (Newton's
        # method: the near corners move faster than the far ones, so the rate is measured)
        _, r, u = basis(*view(d))
        for _ in range(3):
            mid = middle(d)
            step = 0.01 * d
            jac = np.empty((2, 2))
            for k, axis in enumerate((r, u)):
                offset = offset + step * axis
                jac[:, k] = (middle(d) - mid) / step
                offset = offset - step * axis
            want = np.array([(rx0 + rx1) / 2, (ry0 + ry1) / 2])
            move = np.linalg.solve(jac, want - mid)
            offset = offset + move[0] * r + move[1] * u
    position, target = view(d)
    return tuple(float(v) for v in position), tuple(float(v) for v in target)


def share(lo, hi, position, look_at, width: int, height: int, fov: float = FOV):
    """``(height share, x0, x1, y0, y1)`` of the box's picture on the page (pixels)."""
    xy = project(corners(lo, hi), position, look_at, width, height, fov)
    x0, y0 = xy.min(axis=0)
    x1, y1 = xy.max(axis=0)
    return (y1 - y0) / height, x0, x1, y0, y1
