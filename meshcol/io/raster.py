"""A small offscreen rasterizer: triangles to an RGB image with a z-buffer, on the CPU.

No display, no OpenGL, no browser: what ``--snapshots`` draws its pictures with on a CI
machine. An orthographic camera looks at a box from a fixed diagonal direction (so that any
up axis shows three sides); triangles are flat shaded (two-sided Lambert with an ambient
term) and depth tested per pixel (edge functions over each triangle's pixel box; triangles
smaller than a pixel are splatted at their centre, nearest first), which follows the
standard half-space rasterization of Pineda (1988) as in Akenine-Möller et al., *Real-Time
Rendering*, 4th ed., 23.1. The fill, a loop over triangles and their pixels, is the core's
(``raster_fill_triangles``); shading, projection and the splat of small triangles are numpy.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from meshcol._native import core

__all__ = ["Camera", "Raster", "hex_rgb", "view_across"]

#: Direction the camera looks from (towards the target), before normalisation.
VIEW_FROM = np.array([1.0, -1.35, 0.9])
#: Light direction (from the surface towards the light), before normalisation.
LIGHT_FROM = np.array([0.45, -0.6, 1.0])
AMBIENT = 0.35
#: A mirrored view this close to vertical (sine of its angle to the vertical) is not used.
VERTICAL_VIEW = 0.2
#: Triangles drawn one by one at most; the rest (smallest first) are splatted.
MAX_FILLED = 60_000


def hex_rgb(color: str) -> tuple[int, int, int]:
    """``#rrggbb`` to ``(r, g, b)``."""
    value = color.lstrip("#")
    return int(value[0:2], 16), int(value[2:4], 16), int(value[4:6], 16)


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


@dataclass(frozen=True)
class Camera:
    """An orthographic camera framing the box ``low``..``high`` in a ``width`` x ``height``
    image with ``margin`` (a fraction of the image) around it; world z is up when the view
    allows it."""

    low: np.ndarray
    high: np.ndarray
    width: int = 640
    height: int = 480
    margin: float = 0.12
    #: Direction the camera looks from; None: :data:`VIEW_FROM`.
    view_from: np.ndarray | None = None

    @property
    def axes(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(right, up, towards the viewer), orthonormal, world frame."""
        back = _unit(VIEW_FROM if self.view_from is None else np.asarray(self.view_from))
        right = _unit(np.cross(np.array([0.0, 0.0, 1.0]), back))
        up = np.cross(back, right)
        return right, up, back

    @property
    def scale(self) -> float:
        """Pixels per world unit: the box's projection fits inside the margins."""
        right, up, _ = self.axes
        corners = np.array(np.meshgrid(*zip(self.low, self.high))).reshape(3, -1).T
        centre = 0.5 * (self.low + self.high)
        x = np.abs((corners - centre) @ right).max()
        y = np.abs((corners - centre) @ up).max()
        usable = 1.0 - 2.0 * self.margin
        sx = usable * self.width / (2 * x) if x > 0 else np.inf
        sy = usable * self.height / (2 * y) if y > 0 else np.inf
        s = min(sx, sy)
        return float(s) if np.isfinite(s) else 1.0

    def project(self, points: np.ndarray) -> np.ndarray:
        """World points ``(..., 3)`` to ``(..., 3)``: pixel x, pixel y (down), depth (larger
        is nearer the viewer)."""
        right, up, back = self.axes
        p = np.asarray(points, dtype=np.float64) - 0.5 * (self.low + self.high)
        s = self.scale
        x = p @ right * s + 0.5 * self.width
        y = 0.5 * self.height - p @ up * s
        return np.stack([x, y, p @ back], axis=-1)


class Raster:
    """An RGB image and its depth buffer; draw triangles, then read :attr:`pixels`."""

    def __init__(self, camera: Camera, background: tuple[int, int, int] = (255, 255, 255)):
        self.camera = camera
        self.pixels = np.empty((camera.height, camera.width, 3), dtype=np.uint8)
        self.pixels[:] = background
        self.depth = np.full((camera.height, camera.width), -np.inf)

    def triangles(self, world: np.ndarray, color: tuple[int, int, int], fade: float = 0.0) -> None:
        """Draw ``(n, 3, 3)`` world triangles of one colour, flat shaded; ``fade`` in [0, 1)
        blends the colour towards white (context drawn behind what matters)."""
        world = np.asarray(world, dtype=np.float64).reshape(-1, 3, 3)
        if not len(world):
            return
        normals = np.cross(world[:, 1] - world[:, 0], world[:, 2] - world[:, 0])
        length = np.linalg.norm(normals, axis=1)
        keep = length > 0
        world, normals = world[keep], normals[keep] / length[keep, None]
        light = np.abs(normals @ _unit(LIGHT_FROM))
        shade = AMBIENT + (1.0 - AMBIENT) * light
        base = np.asarray(color, dtype=np.float64)
        colors = shade[:, None] * base[None, :]
        colors = colors * (1.0 - fade) + 255.0 * fade
        colors = np.clip(np.rint(colors), 0, 255).astype(np.uint8)
        screen = self.camera.project(world)
        self._draw(screen, colors)

    def _draw(self, screen: np.ndarray, colors: np.ndarray) -> None:
        h, w = self.depth.shape
        lo = np.floor(screen[:, :, :2].min(axis=1)).astype(np.int64)
        hi = np.ceil(screen[:, :, :2].max(axis=1)).astype(np.int64)
        visible = (hi[:, 0] >= 0) & (hi[:, 1] >= 0) & (lo[:, 0] < w) & (lo[:, 1] < h)
        area = (hi - lo).prod(axis=1)
        order = np.flatnonzero(visible & (area > 1))
        if len(order) > MAX_FILLED:
            order = order[np.argsort(-area[order], kind="stable")[:MAX_FILLED]]
        filled = np.zeros(len(screen), dtype=bool)
        filled[order] = True
        core.raster_fill_triangles(
            self.depth,
            self.pixels,
            np.ascontiguousarray(screen),
            np.ascontiguousarray(colors),
            lo,
            hi,
            order.astype(np.int64, copy=False),
        )
        small = np.flatnonzero(visible & ~filled)
        if len(small):
            self._splat(screen[small].mean(axis=1), colors[small])

    def _splat(self, centres: np.ndarray, colors: np.ndarray) -> None:
        h, w = self.depth.shape
        x = np.floor(centres[:, 0]).astype(np.int64)
        y = np.floor(centres[:, 1]).astype(np.int64)
        inside = (x >= 0) & (x < w) & (y >= 0) & (y < h)
        x, y, z, colors = x[inside], y[inside], centres[inside, 2], colors[inside]
        order = np.argsort(z, kind="stable")  # nearest last: its write wins
        x, y, z, colors = x[order], y[order], z[order], colors[order]
        nearer = z > self.depth[y, x]
        x, y, z, colors = x[nearer], y[nearer], z[nearer], colors[nearer]
        self.depth[y, x] = z
        self.pixels[y, x] = colors


def view_across(normal: np.ndarray | None, toward: float = 1.0) -> np.ndarray:
    """A direction to look from that sees a contact of ``normal`` (from body a to body b)
    from the side of the body that could be hidden: ``toward`` +1 for b (the smaller one),
    -1 for a. :data:`VIEW_FROM` when it already looks from that side (or there is no usable
    normal); else :data:`VIEW_FROM` mirrored across the contact plane, so that the view
    keeps its angle to the contact (a wall no longer hides the bullet that hits it)."""
    if normal is None or not np.all(np.isfinite(normal)):
        return VIEW_FROM
    n = np.asarray(normal, dtype=np.float64)
    length = float(np.linalg.norm(n))
    if length < 1e-12:
        return VIEW_FROM
    side = toward * n / length
    along = float(VIEW_FROM @ side)
    if along >= 0:
        return VIEW_FROM
    mirrored = VIEW_FROM - 2.0 * along * side
    up = float(np.linalg.norm(np.cross([0.0, 0.0, 1.0], mirrored)))
    if up < VERTICAL_VIEW * float(np.linalg.norm(mirrored)):
        return VIEW_FROM  # straight down or up: no up axis to frame with
    return mirrored
