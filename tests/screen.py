"""Where the scene's labels land on the screen, computed from the scene graph and a camera.

viser draws labels in WebGL, so the page holds no boxes to measure; this module projects each
visible label's anchor through a pinhole camera (viser's: vertical field of view ``FOV``, +z up)
onto a page of ``width`` x ``height`` pixels and gives it the box its text takes there (viser's
screen-size labels are about ``CHAR_PX`` wide per character and ``LINE_PX`` tall per unit of
``font_screen_scale``, the same in CSS pixels on every page: measured on screenshots at
1280x800 and, at scale 3, 1920x1080). The nodes are the viewer's own handles
(``app.scene_nodes()``): viser has no public list of them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

FOV = 1.3089969389957472  # rad, viser's default vertical field of view (75 degrees)
CHAR_PX = 6.5
LINE_PX = 16.0


def _rotate(wxyz, v) -> np.ndarray:
    w, x, y, z = (float(c) for c in wxyz)
    q = np.array([x, y, z])
    v = np.asarray(v, float)
    return v + 2.0 * np.cross(q, np.cross(q, v) + w * v)


@dataclass(frozen=True)
class Box:
    name: str
    text: str
    x0: float
    y0: float
    x1: float
    y1: float

    # the corners of what the box holds when it is not the whole box (an image seen in
    # perspective is a convex quadrilateral), in order round it
    outline: tuple[tuple[float, float], ...] | None = None
    # distance from the camera [m]: a label's anchor, an image's farthest corner; a label that
    # is depth-tested is hidden where an image nearer the camera stands in front of it
    depth: float = 0.0
    depth_tested: bool = False

    def corners(self) -> np.ndarray:
        if self.outline is not None:
            return np.asarray(self.outline, float)
        return np.array(
            [(self.x0, self.y0), (self.x1, self.y0), (self.x1, self.y1), (self.x0, self.y1)]
        )

    def hides(self, other: Box) -> bool:
        return self.outline is not None and other.depth_tested and other.depth > self.depth

    def overlaps(self, other: Box) -> bool:
        if self.hides(other) or other.hides(self):
            return False
        if not (
            self.x0 < other.x1 and other.x0 < self.x1 and self.y0 < other.y1 and other.y0 < self.y1
        ):
            return False
        if self.outline is None and other.outline is None:
            return True
        # two convex outlines are apart when some edge's normal separates them
        a, b = self.corners(), other.corners()
        for poly in (a, b):
            edges = np.roll(poly, -1, axis=0) - poly
            for n in np.stack([-edges[:, 1], edges[:, 0]], axis=1):
                pa, pb = a @ n, b @ n
                if pa.max() <= pb.min() or pb.max() <= pa.min():
                    return False
        return True


def world_point(handles: dict, name: str, local=(0.0, 0.0, 0.0)) -> tuple[np.ndarray, bool]:
    """World position of the point ``local`` of node ``name`` (in the node's own frame) and
    whether the node and every ancestor are visible."""
    parts = name.strip("/").split("/")
    p, visible = np.asarray(local, float), True
    chain = ["/" + "/".join(parts[: k + 1]) for k in range(len(parts))]
    # compose from the node up: x_parent = R x_child + t
    for path in reversed(chain):
        h = handles.get(path)
        if h is None:
            continue
        visible = visible and bool(getattr(h, "visible", True))
        p = _rotate(getattr(h, "wxyz", (1.0, 0.0, 0.0, 0.0)), p) + np.asarray(h.position, float)
    return p, visible


def project(point, position, look_at, width: int, height: int) -> tuple[float, float] | None:
    f = np.asarray(look_at, float) - np.asarray(position, float)
    f /= np.linalg.norm(f)
    r = np.cross(f, (0.0, 0.0, 1.0))
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    d = np.asarray(point, float) - np.asarray(position, float)
    zc = d @ f
    if zc <= 0:
        return None
    t = math.tan(FOV / 2)
    nx = (d @ r) / (zc * t * width / height)
    ny = (d @ u) / (zc * t)
    return (nx + 1) / 2 * width, (1 - ny) / 2 * height


def label_boxes(handles: dict, camera, width: int = 1280, height: int = 800) -> list[Box]:
    """Screen boxes of every visible, non-empty label of ``handles`` (name -> handle) for
    ``camera`` = (position, look_at) (several lines of text: as wide as the longest, one line
    height each)."""
    out = []
    # a snapshot: the app's loop adds nodes (trail pieces) while this reads
    for name, h in list(handles.items()):
        if type(h).__name__ != "LabelHandle" or not h.text:
            continue
        p, visible = world_point(handles, name)
        if not visible:
            continue
        xy = project(p, *camera, width, height)
        if xy is None:
            continue
        size = float(getattr(h, "font_screen_scale", 1.0))  # px per unit, whatever the page
        lines = h.text.split("\n")
        w, hgt = size * (CHAR_PX * max(len(t) for t in lines) + 6), size * LINE_PX * len(lines)
        x, y = xy
        vert, horiz = h.anchor.split("-")
        x0 = {"left": x, "center": x - w / 2, "right": x - w}[horiz]
        y0 = {"top": y, "center": y - hgt / 2, "bottom": y - hgt}[vert]
        depth = float(np.linalg.norm(p - np.asarray(camera[0], float)))
        tested = bool(getattr(h, "depth_test", False))
        out.append(Box(name, h.text, x0, y0, x0 + w, y0 + hgt, None, depth, tested))
    return out


def image_boxes(handles: dict, camera, width: int = 1280, height: int = 800) -> list[Box]:
    """Screen boxes of every visible image of ``handles`` (name -> handle), each with its
    outline (its four corners projected; an image lies in its node's x-y plane, centred on
    the node)."""
    out = []
    # a snapshot: the app's loop adds nodes (trail pieces) while this reads
    for name, h in list(handles.items()):
        if type(h).__name__ != "ImageHandle":
            continue
        w, hgt = 0.5 * float(h.render_width), 0.5 * float(h.render_height)
        # round the image: (-,-), (+,-), (+,+), (-,+)
        corners = [
            world_point(handles, name, (sx * w, sy * hgt, 0.0))
            for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))
        ]
        if not corners[0][1]:
            continue
        xy = [project(p, *camera, width, height) for p, _ in corners]
        if any(c is None for c in xy):
            continue
        # seen edge-on (the top view of a standing image) it is a line and hides nothing
        normal = np.cross(corners[1][0] - corners[0][0], corners[3][0] - corners[0][0])
        sight = corners[0][0] - np.asarray(camera[0], float)
        if abs(normal @ sight) < 0.1 * np.linalg.norm(normal) * np.linalg.norm(sight):
            continue
        xs, ys = zip(*xy, strict=True)
        depth = max(float(np.linalg.norm(p - np.asarray(camera[0], float))) for p, _ in corners)
        out.append(Box(name, f"image {name}", min(xs), min(ys), max(xs), max(ys), tuple(xy), depth))
    return out


def overlapping(boxes: list[Box]) -> list[tuple[str, str]]:
    return [(a.text, b.text) for i, a in enumerate(boxes) for b in boxes[i + 1 :] if a.overlaps(b)]
