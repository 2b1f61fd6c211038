"""Snapshots: one PNG per violation, drawn offscreen from a review page (``--snapshots DIR``).

The review page (:class:`meshcol.io.review.ReviewPage`) already holds what a reviewer wants to
see of each row: the bodies, the witness points, the normal and the depth label. A snapshot
is one row of it drawn by the CPU rasterizer of :mod:`meshcol.io.raster` (no display, no
browser): the row's bodies framed and drawn in their own colours (the first
:data:`PAIR_COLORS`, the second blue), every other body faded behind them, the row's findings
(open edges, crossing faces) over them, each witness point a green disc, the normal an orange
arrow from the first point, and a caption (the case, its rule and numbers). Pillow writes the
PNG and draws the text (``pip install 'meshcol[snapshots]'``).
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from meshcol.errors import MissingDependencyError
from meshcol.io.raster import Camera, Raster, hex_rgb, view_across
from meshcol.io.review import ReviewPage

__all__ = [
    "COLLIDER_COLOR",
    "PAIR_COLORS",
    "SUBJECT_COLOR",
    "WITNESS_COLOR",
    "NORMAL_COLOR",
    "Shot",
    "ShotPage",
    "pillow",
    "render_shots",
    "shot_page",
]

#: The colours of the bodies a picture is about, in the row's order (red, blue).
PAIR_COLORS = ("#e6194b", "#4363d8")
#: The colour of a picture's one body (an inspected mesh): blue, apart from the findings'
#: red edges and magenta faces.
SUBJECT_COLOR = "#4363d8"
#: Witness points (green discs) and the normal (an orange arrow).
WITNESS_COLOR = "#00c000"
NORMAL_COLOR = "#ff8c00"
#: A collider's edges over its mesh (hull's hull, fit's primitive): green.
COLLIDER_COLOR = "#3cb44b"
#: Two faces of a collider meeting at less than this angle (radians) show no edge between
#: them (a polygon's triangulation is not drawn).
FEATURE_ANGLE = 1e-3
#: Other bodies: grey, faded towards the white background.
CONTEXT_COLOR = "#b8b8b8"
CONTEXT_FADE = 0.55
WIDTH, HEIGHT = 800, 600
WITNESS_RADIUS = 6
#: The normal arrow's length as a fraction of the image's height.
ARROW = 0.22
#: A body this many times larger (bounding-box diagonal) than the other is framed only
#: around the contact.
DWARFS = 4.0
HINT = "--snapshots needs Pillow: pip install 'meshcol[snapshots]'"


def pillow() -> Any:
    """The PIL package, or MissingDependencyError with the install hint."""
    try:
        import PIL.Image
        import PIL.ImageDraw
        import PIL.ImageFont
    except ImportError:
        raise MissingDependencyError(HINT) from None
    return PIL


@dataclass(frozen=True)
class Shot:
    """One picture to draw: the page row whose bodies are ``bodies`` (names, in the row's
    order), saved as ``name`` (a file name), captioned ``title`` and ``caption``;
    ``outline`` a group of the page whose meshes of those bodies are drawn as edges over
    them (the ``hulls`` of hull and fit: the collider on its mesh)."""

    bodies: tuple[str, ...]
    name: str
    title: str
    caption: str = ""
    outline: str | None = None


def file_name(index: int, text: str) -> str:
    """``003-crate--table.png``: the index, then the text's letters and digits."""
    slug = re.sub(r"[^A-Za-z0-9._-]+", "-", text).strip("-.")[:60] or "case"
    return f"{index:03d}-{slug}.png"


def _posed(mesh: Mapping[str, Any]) -> np.ndarray:
    """The mesh's vertices in the world frame, ``(n, 3)``."""
    pose = np.asarray(mesh["pose"], dtype=np.float64)
    vertices = np.asarray(mesh["vertices"], dtype=np.float64).reshape(-1, 3)
    return vertices @ pose[:3, :3].T + pose[:3, 3]


def _world(mesh: Mapping[str, Any]) -> np.ndarray:
    return _posed(mesh)[np.asarray(mesh["faces"], dtype=np.int64)]


def _in_frame(tris: np.ndarray, camera: Camera) -> np.ndarray:
    """Which of ``tris`` ``(n, 3, 3)`` have a box that meets the camera's."""
    high = np.maximum(np.maximum(tris[:, 0], tris[:, 1]), tris[:, 2])
    low = np.minimum(np.minimum(tris[:, 0], tris[:, 1]), tris[:, 2])
    return np.all((high >= camera.low) & (low <= camera.high), axis=1)


class _PageMeshes:
    """A page's meshes, listed once a drawing, and each one's world box: the meshes a
    picture's frame can show are then one comparison of arrays, where every picture used to
    pose every mesh of the scene. A box holds every vertex (NaN left out), so it holds each
    triangle's; a mesh without faces has an empty box (it draws nothing)."""

    def __init__(self, page: Any) -> None:
        self.meshes: list[Mapping[str, Any]] = page.meshes()
        self.low = np.full((len(self.meshes), 3), np.inf)
        self.high = np.full((len(self.meshes), 3), -np.inf)
        for n, mesh in enumerate(self.meshes):
            if len(mesh["faces"]):
                world = _posed(mesh)
                self.low[n] = np.fmin.reduce(world, axis=0, initial=np.inf)
                self.high[n] = np.fmax.reduce(world, axis=0, initial=-np.inf)

    def near(self, camera: Camera) -> np.ndarray:
        """The indices, in order, of the meshes whose box meets ``camera``'s."""
        meets = (self.high >= camera.low) & (self.low <= camera.high)
        return np.flatnonzero(meets.all(axis=1))


def _box(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    points = points.reshape(-1, 3)
    return points.min(axis=0), points.max(axis=0)


def _frame(
    bodies: Sequence[Sequence[np.ndarray]], points: np.ndarray, extras: Sequence[np.ndarray]
) -> tuple[np.ndarray, np.ndarray]:
    """The box a picture frames: every body of the row whole, with the witness points and
    extras (findings); but when one body dwarfs the other (:data:`DWARFS`: a crate on a
    100 m floor), the small one whole and the witness points with half its size around them,
    so that the contact is seen, not the floor. Padded by 8%."""
    boxes = [_box(np.concatenate([t.reshape(-1, 3) for t in tris])) for tris in bodies if tris]
    sizes = [float(np.linalg.norm(high - low)) for low, high in boxes]
    if len(points) and len(boxes) > 1 and max(sizes) > DWARFS * max(min(sizes), 1e-12):
        low, high = boxes[int(np.argmin(sizes))]
        reach = 0.5 * max(min(sizes), 1e-9)
        low = np.minimum(low, points.min(axis=0) - reach)
        high = np.maximum(high, points.max(axis=0) + reach)
    else:
        corners = [b for box in boxes for b in box]
        parts = [p.reshape(-1, 3) for p in (*corners, points, *extras)]
        low, high = _box(np.concatenate([p for p in parts if p.size]))
    pad = 0.08 * max(float(np.linalg.norm(high - low)), 1e-9)
    return low - pad, high + pad


def _smaller_side(bodies: Sequence[Sequence[np.ndarray]]) -> float:
    """+1 when the row's second body is the smaller (bounding-box diagonal), else -1: the
    side a picture looks from (:func:`meshcol.io.raster.view_across`)."""
    sizes = []
    for tris in bodies:
        if not tris:
            return 1.0
        low, high = _box(np.concatenate([t.reshape(-1, 3) for t in tris]))
        sizes.append(float(np.linalg.norm(high - low)))
    return 1.0 if len(sizes) < 2 or sizes[1] <= sizes[0] else -1.0


def _font(size: int) -> Any:
    font = pillow().ImageFont
    try:
        return font.load_default(size=size)
    except TypeError:  # Pillow < 10.1: one bitmap size
        return font.load_default()


def _paint(
    page_meshes: _PageMeshes,
    ids: Sequence[int],
    own: Sequence[tuple[Mapping[str, Any], np.ndarray]],
    camera: Camera,
) -> Raster:
    """The triangles: the context faded (where near the frame), then the row's bodies in
    their colours over it, then the row's findings faces."""
    raster = Raster(camera)
    meshes = page_meshes.meshes
    for n in page_meshes.near(camera):
        mesh = meshes[n]
        if mesh["group"] != "meshes" or mesh["body"] in ids:
            continue
        tris = _world(mesh)
        raster.triangles(tris[_in_frame(tris, camera)], hex_rgb(CONTEXT_COLOR), fade=CONTEXT_FADE)
    raster.depth[:] = -np.inf  # the row's bodies are drawn over the context, never hidden
    for mesh, tris in own:
        slot = min(list(ids).index(mesh["body"]), len(PAIR_COLORS) - 1)
        raster.triangles(tris, hex_rgb(SUBJECT_COLOR if len(ids) == 1 else PAIR_COLORS[slot]))
    for mesh in meshes:
        if mesh["body"] in ids and mesh["group"] == "findings":
            raster.triangles(_world(mesh), hex_rgb(mesh["color"]))
    return raster


def _marks(
    draw: Any, camera: Camera, lines: Sequence[Mapping[str, Any]], points: np.ndarray, normal: Any
) -> None:
    """Over the triangles: findings lines, the normal's arrow, the witness points."""
    for line in lines:
        for a, b in camera.project(line["p"])[:, :, :2]:
            draw.line([tuple(a), tuple(b)], fill=hex_rgb(line["color"]), width=3)
    projected = camera.project(points)[:, :2] if len(points) else np.zeros((0, 2))
    if len(projected) and normal is not None and np.all(np.isfinite(normal)):
        _arrow(draw, camera, points[0], np.asarray(normal, dtype=np.float64))
    r = WITNESS_RADIUS
    for x, y in projected:
        draw.ellipse([x - r, y - r, x + r, y + r], fill=hex_rgb(WITNESS_COLOR), outline=(0, 0, 0))


def _own_meshes(meshes: Sequence[Mapping[str, Any]], row: Mapping[str, Any]) -> list[dict]:
    """The meshes of the row's bodies as the picture shows them: the row's own group when it
    has one (sweep's bodies at the time of impact, each the body whose geometry it shares),
    else the bodies where the scene has them."""
    ids = list(row["bodies"])
    placed = [m for m in meshes if m["body"] in ids and m["group"] == "meshes"]
    group = row.get("group")
    if not group:
        return [dict(m) for m in placed]
    geometry = {m["g"]: m["body"] for m in placed}
    posed = [
        {**m, "body": geometry[m["g"]]}
        for m in meshes
        if m["group"] == group and m["g"] in geometry
    ]
    return posed or [dict(m) for m in placed]


@dataclass(frozen=True)
class _Layout:
    """What a picture of one row draws: the row's bodies (their meshes, posed), the lines
    over them, the witness points and the camera that frames them."""

    ids: list[int]
    own: list[tuple[dict, np.ndarray]]
    lines: list[Mapping[str, Any]]
    points: np.ndarray
    camera: Camera


def _layout(
    page: Any, row: Mapping[str, Any], shot: Shot, meshes: Sequence[Mapping[str, Any]]
) -> _Layout:
    ids = list(row["bodies"])
    own = [(m, _world(m)) for m in _own_meshes(meshes, row)]
    lines = [line for line in page.lines() if line["body"] in ids]
    if shot.outline is not None:
        lines += [
            {"p": edges, "color": COLLIDER_COLOR, "body": m["body"]}
            for m in meshes
            if m["body"] in ids and m["group"] == shot.outline
            for edges in [_feature_edges(m)]
            if len(edges)
        ]
    points = row["points"] if row["points"] is not None else np.zeros((0, 3))
    by_body = [[t for m, t in own if m["body"] == i] for i in ids]
    low, high = _frame(by_body, points, [line["p"] for line in lines])
    view = view_across(row["normal"], _smaller_side(by_body))
    return _Layout(ids, own, lines, points, Camera(low, high, WIDTH, HEIGHT, view_from=view))


def _draw_row(
    page: Any, row: Mapping[str, Any], shot: Shot, path: str, page_meshes: _PageMeshes
) -> None:
    PIL = pillow()
    layout = _layout(page, row, shot, page_meshes.meshes)
    camera = layout.camera
    raster = _paint(page_meshes, layout.ids, layout.own, camera)
    image = PIL.Image.fromarray(raster.pixels, "RGB")
    draw = PIL.ImageDraw.Draw(image)
    _marks(draw, camera, layout.lines, layout.points, row["normal"])
    _caption(draw, shot, row, page, bool(len(layout.points)))
    image.save(path, format="PNG", optimize=False)


def _feature_edges(mesh: Mapping[str, Any]) -> np.ndarray:
    """``(n, 2, 3)`` world segments: the mesh's edges where its faces meet at an angle
    (every boundary edge too), so that a hull shows its polygons, not their triangles."""
    tris = _world(mesh)
    faces = np.asarray(mesh["faces"], dtype=np.int64)
    normals = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-300)
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    owner = np.tile(np.arange(len(faces)), 3)
    ordered = np.sort(edges, axis=1)
    _, first, inverse, counts = np.unique(
        ordered, axis=0, return_index=True, return_inverse=True, return_counts=True
    )
    inverse = inverse.reshape(-1)
    keep = counts != 2
    two = np.flatnonzero(counts == 2)
    if len(two):
        # the two faces of each shared edge: the first occurrence and the other one
        second = np.full(len(counts), -1, dtype=np.int64)
        rows = np.flatnonzero(np.arange(len(edges)) != first[inverse])
        second[inverse[rows]] = rows
        cosine = np.einsum("ij,ij->i", normals[owner[first[two]]], normals[owner[second[two]]])
        keep[two] = cosine < np.cos(FEATURE_ANGLE)
    chosen = edges[first[keep]]
    pose = np.asarray(mesh["pose"], dtype=np.float64)
    world = np.asarray(mesh["vertices"], dtype=np.float64) @ pose[:3, :3].T + pose[:3, 3]
    return world[chosen]


def _arrow(draw: Any, camera: Camera, origin: np.ndarray, normal: np.ndarray) -> None:
    right, up, _ = camera.axes
    direction = np.array([normal @ right, -(normal @ up)])
    length = float(np.linalg.norm(direction))
    if length < 1e-6:  # along the view: a ring shows it points at the viewer
        x, y = camera.project(origin)[:2]
        draw.ellipse([x - 14, y - 14, x + 14, y + 14], outline=hex_rgb(NORMAL_COLOR), width=3)
        return
    direction /= length
    start = camera.project(origin)[:2]
    end = start + direction * ARROW * camera.height
    color = hex_rgb(NORMAL_COLOR)
    draw.line([tuple(start), tuple(end)], fill=color, width=4)
    side = np.array([-direction[1], direction[0]])
    head = [
        tuple(end),
        tuple(end - 16 * direction + 7 * side),
        tuple(end - 16 * direction - 7 * side),
    ]
    draw.polygon(head, fill=color)


def _caption(draw: Any, shot: Shot, row: Mapping[str, Any], page: Any, witnesses: bool) -> None:
    big, small = _font(18), _font(14)
    lines = [(shot.title, big, (0, 0, 0))]
    label = shot.caption or row["label"]
    if label:
        lines.append((label, small, (40, 40, 40)))
    y = 8
    for text, font, color in lines:
        box = draw.textbbox((10, y), text, font=font)
        draw.rectangle([box[0] - 4, box[1] - 3, box[2] + 4, box[3] + 3], fill=(255, 255, 255))
        draw.text((10, y), text, fill=color, font=font)
        y = box[3] + 8
    legend = f"meshcol {page.command}: " + " / ".join(shot.bodies)
    legend += "; green: witness points; orange: normal" if witnesses else ""
    if page.command == "inspect":
        legend += "; red: open edges; orange: non-manifold; magenta: crossing faces"
    if shot.outline is not None:
        legend += "; green: the collider's edges"
    draw.text((10, HEIGHT - 22), legend[:120], fill=(90, 90, 90), font=small)


def _shot_rows(page: Any, shots: Sequence[Shot]) -> Iterator[tuple[Shot, Mapping[str, Any]]]:
    """Each shot whose bodies are a row of ``page`` (either order), and that row."""
    rows: dict[tuple[str, ...], Mapping[str, Any]] = {}
    for row in page.rows():
        key = tuple(page.bodies[i] for i in row["bodies"])
        rows.setdefault(key, row)
    for shot in shots:
        found = rows.get(shot.bodies) or rows.get(tuple(reversed(shot.bodies)))
        if found is not None:
            yield shot, found


def render_shots(page: ReviewPage | ShotPage, shots: Sequence[Shot], folder: str) -> dict[str, str]:
    """Draw each shot whose bodies are a row of ``page`` (a review page, or the part of one
    :func:`shot_page` keeps) into ``folder``; returns shot name -> file path. A shot whose
    bodies are no row of the page is skipped."""
    pillow()
    written: dict[str, str] = {}
    page_meshes = _PageMeshes(page)
    for shot, row in _shot_rows(page, shots):
        path = os.path.join(folder, shot.name)
        _draw_row(page, row, shot, path, page_meshes)
        written[shot.name] = path
    return written


# --- what pictures need of a page, kept apart from it -------------------------------------------

#: The fields of meshes, lines and rows that are arrays (float64; ``faces`` int64).
_ARRAYS = ("vertices", "faces", "pose", "p", "points", "normal")


@dataclass(frozen=True)
class ShotPage:
    """The part of a review page that some shots draw, as :func:`render_shots` reads a page
    (``command``, ``bodies``, :meth:`rows`, :meth:`meshes`, :meth:`lines`): the shots' rows,
    every mesh of their bodies, the other meshes a picture shows behind them (those with a
    triangle in its frame) and their bodies' lines. The pictures drawn from it are those
    drawn from the page, pixel for pixel; it is JSON values (:meth:`to_data`), so a job's
    cached result keeps it and ``meshcol ci --snapshots`` draws without running the job."""

    command: str
    bodies: tuple[str, ...]
    kept_rows: tuple[Mapping[str, Any], ...]
    kept_meshes: tuple[Mapping[str, Any], ...]
    kept_lines: tuple[Mapping[str, Any], ...]

    def rows(self) -> list[Mapping[str, Any]]:
        return list(self.kept_rows)

    def meshes(self) -> list[Mapping[str, Any]]:
        return list(self.kept_meshes)

    def lines(self) -> list[Mapping[str, Any]]:
        return list(self.kept_lines)

    def to_data(self) -> dict[str, Any]:
        """JSON values (arrays as nested lists: float64 round-trips exactly)."""
        return {
            "command": self.command,
            "bodies": list(self.bodies),
            "rows": [{**_plain(r), "cells": []} for r in self.kept_rows],  # not drawn
            "meshes": [_plain(m) for m in self.kept_meshes],
            "lines": [_plain(line) for line in self.kept_lines],
        }

    @classmethod
    def from_data(cls, data: Mapping[str, Any]) -> ShotPage:
        """The page :meth:`to_data` gave. Raises KeyError, TypeError or ValueError on
        anything else."""
        return cls(
            str(data["command"]),
            tuple(str(b) for b in data["bodies"]),
            tuple(
                {**_arrays(r), "bodies": tuple(int(i) for i in r["bodies"])} for r in data["rows"]
            ),
            tuple(_arrays(m) for m in data["meshes"]),
            tuple(_arrays(line) for line in data["lines"]),
        )


def _plain(item: Mapping[str, Any]) -> dict[str, Any]:
    return {
        k: (np.asarray(v).tolist() if k in _ARRAYS and v is not None else v)
        for k, v in item.items()
    }


def _arrays(item: Mapping[str, Any]) -> dict[str, Any]:
    out = dict(item)
    for key in _ARRAYS:
        if out.get(key) is not None:
            out[key] = np.asarray(out[key], dtype=np.int64 if key == "faces" else np.float64)
    return out


def shot_page(page: ReviewPage, shots: Sequence[Shot]) -> ShotPage:
    """What drawing ``shots`` needs of ``page`` (:class:`ShotPage`): a page of 3,000 bodies
    is kept as the few a failing pair's picture shows."""
    page_meshes = _PageMeshes(page)
    meshes = page_meshes.meshes
    body = np.array([mesh["body"] for mesh in meshes], dtype=np.int64)
    group_of = np.array([mesh["group"] for mesh in meshes], dtype=object)
    rows: dict[int, Mapping[str, Any]] = {}
    kept: set[int] = set()
    bodies: set[int] = set()
    for shot, row in _shot_rows(page, shots):
        rows.setdefault(id(row), row)
        layout = _layout(page, row, shot, meshes)
        bodies.update(layout.ids)
        group = row.get("group")
        own = np.isin(body, layout.ids) | (bool(group) & (group_of == group))
        kept.update(np.flatnonzero(own).tolist())
        # another body's mesh: kept when the picture shows some of it behind
        for n in page_meshes.near(layout.camera).tolist():
            mesh = meshes[n]
            if (
                n not in kept
                and mesh["group"] == "meshes"
                and _in_frame(_world(mesh), layout.camera).any()
            ):
                kept.add(n)
    return ShotPage(
        page.command,
        tuple(page.bodies),
        tuple(rows.values()),
        tuple(meshes[n] for n in sorted(kept)),
        tuple(line for line in page.lines() if line["body"] in bodies),
    )
