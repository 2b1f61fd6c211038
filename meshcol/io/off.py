"""Object File Format (OFF) reader: vertices and polygon faces, triangulated.

The format as Geomview's ``OFF(5)`` page defines it: an optional header keyword
``[ST][C][N][4][n]OFF`` (texture coordinates, colours, normals, homogeneous coordinates,
an explicit dimension), then ``vertices faces edges``, one vertex per line (coordinates first,
then whatever normal, colour and texture values the keyword announces), and one face per line
(``k i1 ... ik`` followed by an optional colour). ``#`` starts a comment anywhere.

What is read, and what is refused (never truncated silently):

- 3-D coordinates (``OFF``, ``nOFF`` with dimension 3); the trailing normal, colour and
  texture values of a vertex line and the colour of a face line are ignored;
- homogeneous coordinates (``4OFF``, ``4nOFF`` with dimension 3): ``x y z w`` divided by
  ``w``; a vertex with ``w = 0`` (a point at infinity) is an error naming its line;
- any other dimension (``4OFF`` is 3-D homogeneous, ``nOFF 4`` is 4-D): refused;
- ``BINARY`` files: refused;
- polygon faces of any size: convex ones by a fan from their first corner, others (and any
  polygon whose turning is not that of a simple convex polygon) by ear clipping in the plane
  of their Newell normal; faces with fewer than three corners are errors.

The text is decoded as Latin-1, which maps every byte: OFF data are ASCII numbers, so a
comment in any encoding loads, and random bytes fail as a number that does not parse.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from meshcol.errors import InvalidMeshError
from meshcol.io.mesh_trimesh import read_bytes

if TYPE_CHECKING:
    from meshcol.io.mesh_formats import MeshNode

__all__ = ["read_off", "read_off_file", "triangulate_polygons"]

_KEYWORD = re.compile(r"^(?P<st>ST)?(?P<c>C)?(?P<n>N)?(?P<four>4)?(?P<dim>n)?OFF$")


def read_off_file(file: Path, source: str) -> list[MeshNode]:
    """The one mesh node of an OFF file, named after the file (none when it has no faces):
    the reader of :data:`meshcol.io.mesh_formats.FORMATS`."""
    vertices, faces = read_off(read_bytes(file, source), source)
    return [(file.stem, np.eye(4), vertices, faces)] if len(faces) else []


def read_off(data: bytes, source: str) -> tuple[np.ndarray, np.ndarray]:
    """Parse an OFF file's bytes.

    Parameters
    ----------
    data : bytes
        The whole file.
    source : str
        The path, for error messages.

    Returns
    -------
    vertices : (n, 3) float64
        Homogeneous coordinates already divided by ``w``.
    faces : (m, 3) int64
        Triangles; polygon ``f`` gives ``k - 2`` consecutive triangles in face order.

    Raises
    ------
    InvalidMeshError
        One line naming the problem and the line of the file: an unknown header, a count
        or number that does not parse, too few vertex coordinates or face indices, an index
        out of range, a point at infinity, an unsupported dimension, binary OFF.
    """
    lines = _content_lines(data.decode("latin-1"), source)
    header = _header(lines, source)
    n_vertices = _integer(header.counts[0], "vertex count", header.count_line, source)
    n_faces = _integer(header.counts[1], "face count", header.count_line, source)
    first = header.next_line
    if first + n_vertices + n_faces > len(lines):
        raise _error(
            f"the header announces {n_vertices} vertices and {n_faces} faces but only "
            f"{len(lines) - first} lines follow",
            header.count_line,
            source,
        )
    vertex_lines = lines[first : first + n_vertices]
    face_lines = lines[first + n_vertices : first + n_vertices + n_faces]
    vertices = _vertices(vertex_lines, header.homogeneous, source)
    corners, sizes = _faces(face_lines, n_vertices, source)
    return vertices, triangulate_polygons(vertices, corners, sizes)


def _content_lines(text: str, source: str) -> list[tuple[int, list[str]]]:
    """``(line number, tokens)`` of every line with content, comments removed."""
    lines = []
    for number, line in enumerate(text.splitlines(), start=1):
        tokens = line.split("#", 1)[0].split()
        if tokens:
            lines.append((number, tokens))
    if not lines:
        raise InvalidMeshError("cannot parse OFF file: the file is empty", source)
    return lines


@dataclass(frozen=True)
class _Header:
    homogeneous: bool  # 4OFF: x y z w per vertex
    counts: list[str]  # the vertex, face (and edge) counts, as tokens
    count_line: int  # the line they are on
    next_line: int  # index (into the content lines) of the first vertex line


def _header(lines: list[tuple[int, list[str]]], source: str) -> _Header:
    """The keyword (optional), its dimension, and the counts that follow it."""
    number, tokens = lines[0]
    match = _KEYWORD.match(tokens[0])
    if match is None:
        if tokens[0].upper().endswith("OFF"):
            raise _error(f"unknown OFF header keyword {tokens[0][:40]!r}", number, source)
        return _counted(_Header(False, tokens, number, 1), source)  # the keyword is optional
    homogeneous = match["four"] is not None
    cursor, rest = 0, tokens[1:]
    dimension = 3
    if match["dim"] is not None:
        if not rest:
            cursor += 1
            if cursor >= len(lines):
                raise _error("missing the dimension after nOFF", number, source)
            number, rest = lines[cursor]
        dimension = _integer(rest[0], "dimension", number, source)
        rest = rest[1:]
    if rest and rest[0].upper() == "BINARY":
        raise _error("binary OFF is not supported (convert it to text OFF)", number, source)
    if dimension != 3:
        kind = "homogeneous " if homogeneous else ""
        raise _error(
            f"{kind}{dimension}-dimensional OFF is not supported (only 3-D coordinates)",
            number,
            source,
        )
    if rest:
        return _counted(_Header(homogeneous, rest, number, cursor + 1), source)
    cursor += 1
    if cursor >= len(lines):
        raise _error("missing the vertex, face and edge counts", number, source)
    count_line, counts = lines[cursor]
    return _counted(_Header(homogeneous, counts, count_line, cursor + 1), source)


def _counted(header: _Header, source: str) -> _Header:
    if len(header.counts) < 2:
        raise _error("expected the vertex, face and edge counts", header.count_line, source)
    return header


def _vertices(
    vertex_lines: list[tuple[int, list[str]]], homogeneous: bool, source: str
) -> np.ndarray:
    """(n, 3) float64 coordinates, homogeneous ones divided by ``w``; every one finite."""
    coordinates = 4 if homogeneous else 3
    vertices = np.empty((len(vertex_lines), coordinates), dtype=np.float64)
    for k, (number, tokens) in enumerate(vertex_lines):
        if len(tokens) < coordinates:
            raise _error(
                f"vertex {k} has {len(tokens)} coordinates, expected {coordinates}", number, source
            )
        try:
            vertices[k] = [float(t) for t in tokens[:coordinates]]
        except ValueError:
            raise _error(
                f"vertex {k}: expected numbers, got {' '.join(tokens[:coordinates])[:60]!r}",
                number,
                source,
            ) from None
    if homogeneous:
        w = vertices[:, 3]
        zero = np.flatnonzero(w == 0.0)
        if len(zero):
            line = vertex_lines[zero[0]][0]
            raise _error(f"vertex {zero[0]} has w = 0 (a point at infinity)", line, source)
        vertices = vertices[:, :3] / w[:, None]
    if not np.isfinite(vertices).all():
        bad = int(np.flatnonzero(~np.isfinite(vertices).all(axis=1))[0])
        raise _error(f"vertex {bad} is not finite", vertex_lines[bad][0], source)
    return vertices


def _faces(
    face_lines: list[tuple[int, list[str]]], n_vertices: int, source: str
) -> tuple[np.ndarray, np.ndarray]:
    """Every polygon's corners, one after the other, and each polygon's size."""
    sizes = np.empty(len(face_lines), dtype=np.int64)
    corners: list[list[int]] = []
    for k, (number, tokens) in enumerate(face_lines):
        indices = _face(k, number, tokens, n_vertices, source)
        sizes[k] = len(indices)
        corners.append(indices)
    flat = np.fromiter(
        (i for face in corners for i in face), dtype=np.int64, count=int(sizes.sum())
    )
    return flat, sizes


def _face(k: int, number: int, tokens: list[str], n_vertices: int, source: str) -> list[int]:
    """The vertex indices of face ``k`` (its line ``number``), checked."""
    size = _integer(tokens[0], f"face {k} corner count", number, source)
    if size < 3:
        raise _error(f"face {k} has {size} corners (a face needs at least 3)", number, source)
    if len(tokens) < size + 1:
        raise _error(
            f"face {k} announces {size} corners but lists {len(tokens) - 1}", number, source
        )
    try:
        indices = [int(t) for t in tokens[1 : size + 1]]
    except ValueError:
        raise _error(
            f"face {k}: expected vertex indices, got {' '.join(tokens[1 : size + 1])[:60]!r}",
            number,
            source,
        ) from None
    low, high = min(indices), max(indices)
    if low < 0 or high >= n_vertices:
        bad = low if low < 0 else high
        raise _error(
            f"face {k}: vertex index {bad} is out of range (the file has {n_vertices} "
            f"vertices, indexed from 0)",
            number,
            source,
        )
    return indices


def triangulate_polygons(
    vertices: np.ndarray, corners: np.ndarray, sizes: np.ndarray
) -> np.ndarray:
    """Triangles of polygon faces, in face order.

    Parameters
    ----------
    vertices : (n, 3) float
    corners : (sum(sizes),) int
        Every polygon's vertex indices, one polygon after the other.
    sizes : (m,) int
        Corners of each polygon (>= 3).

    Returns
    -------
    (sum(sizes) - 2 m, 3) int64
        Polygon ``f``'s ``sizes[f] - 2`` triangles, consecutive, winding kept.

    Notes
    -----
    Polygons of the same size are handled together. A polygon is convex when, in the plane
    of its Newell normal, every turn has the same sign and the turns add up to one full turn
    (a pentagram turns twice): those are split by a fan from their first corner. The others
    are ear clipped (Eberly, "Triangulation by Ear Clipping", 2002) in that plane; a polygon
    without area has no ears and is fanned.
    """
    vertices = np.asarray(vertices, dtype=np.float64)
    corners = np.asarray(corners, dtype=np.int64)
    sizes = np.asarray(sizes, dtype=np.int64)
    starts = np.zeros(len(sizes), dtype=np.int64)
    np.cumsum(sizes[:-1], out=starts[1:])
    first_triangle = starts - 2 * np.arange(len(sizes), dtype=np.int64)
    out = np.empty((int(sizes.sum()) - 2 * len(sizes), 3), dtype=np.int64)
    for size in np.unique(sizes).tolist():
        which = np.flatnonzero(sizes == size)
        polygons = corners[starts[which][:, None] + np.arange(size)]  # (p, size)
        rows = first_triangle[which][:, None] + np.arange(size - 2)  # (p, size - 2)
        if size == 3:
            out[rows[:, 0]] = polygons
            continue
        fan = np.stack(
            [
                np.repeat(polygons[:, :1], size - 2, axis=1),
                polygons[:, 1:-1],
                polygons[:, 2:],
            ],
            axis=2,
        )  # (p, size - 2, 3)
        convex = _convex(vertices[polygons])
        out[rows[convex].ravel()] = fan[convex].reshape(-1, 3)
        for p in np.flatnonzero(~convex).tolist():
            out[rows[p]] = _ear_clip(vertices, polygons[p])
    return out


def _plane_coordinates(points: np.ndarray) -> np.ndarray:
    """(..., k, 2) coordinates of polygons (..., k, 3) in the plane of their Newell normal,
    oriented so that a counter-clockwise turn about the normal is positive."""
    nxt = np.roll(points, -1, axis=-2)
    normal = np.stack(
        [
            np.sum((points[..., 1] - nxt[..., 1]) * (points[..., 2] + nxt[..., 2]), axis=-1),
            np.sum((points[..., 2] - nxt[..., 2]) * (points[..., 0] + nxt[..., 0]), axis=-1),
            np.sum((points[..., 0] - nxt[..., 0]) * (points[..., 1] + nxt[..., 1]), axis=-1),
        ],
        axis=-1,
    )
    axis = np.argmax(np.abs(normal), axis=-1)  # drop the dominant axis
    u = (axis + 1) % 3
    v = (axis + 2) % 3
    pu = np.take_along_axis(points, u[..., None, None].repeat(points.shape[-2], -2), -1)[..., 0]
    pv = np.take_along_axis(points, v[..., None, None].repeat(points.shape[-2], -2), -1)[..., 0]
    sign = np.where(np.take_along_axis(normal, axis[..., None], -1)[..., 0] < 0, -1.0, 1.0)
    return np.stack([pu, pv * sign[..., None]], axis=-1)


def _convex(points: np.ndarray) -> np.ndarray:
    """(p,) bool: polygons (p, k, 3) that are strictly convex and simple."""
    uv = _plane_coordinates(points)
    edge = np.roll(uv, -1, axis=-2) - uv
    prev = np.roll(edge, 1, axis=-2)
    turn = prev[..., 0] * edge[..., 1] - prev[..., 1] * edge[..., 0]
    if points.shape[-2] <= 4:
        # k left turns, each under half a turn, add up to less than k/2 turns: for k <= 4
        # that is one turn exactly (a pentagram's two need k >= 5), so the sum needs no check
        return np.all(turn > 0, axis=-1)
    angle = np.arctan2(turn, np.sum(prev * edge, axis=-1))
    total = np.sum(angle, axis=-1)
    return np.all(turn > 0, axis=-1) & (np.abs(total - 2 * np.pi) < 1e-6)


def _ear_clip(vertices: np.ndarray, polygon: np.ndarray) -> np.ndarray:
    """(k - 2, 3) triangles of one simple polygon, by ear clipping in its plane."""
    uv = _plane_coordinates(vertices[polygon][None])[0]
    remaining = list(range(len(polygon)))
    triangles = []

    def cross(o: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
        return float((a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]))

    while len(remaining) > 3:
        n = len(remaining)
        for k in range(n):
            i, j, m = remaining[k - 1], remaining[k], remaining[(k + 1) % n]
            a, b, c = uv[i], uv[j], uv[m]
            if cross(a, b, c) <= 0:
                continue  # a reflex or flat corner is not an ear
            inside = False
            for r in remaining:
                if r in (i, j, m):
                    continue
                p = uv[r]
                if cross(a, b, p) >= 0 and cross(b, c, p) >= 0 and cross(c, a, p) >= 0:
                    inside = True
                    break
            if not inside:
                triangles.append((i, j, m))
                del remaining[k]
                break
        else:
            break  # no ear: no area (or not simple); fan what is left
    triangles.extend(
        (remaining[0], remaining[t], remaining[t + 1]) for t in range(1, len(remaining) - 1)
    )
    return polygon[np.asarray(triangles, dtype=np.int64)]


def _integer(token: str, what: str, line: int, source: str) -> int:
    try:
        value = int(token)
    except ValueError:
        raise _error(f"{what}: expected an integer, got {token[:40]!r}", line, source) from None
    if value < 0:
        raise _error(f"{what} is negative ({value})", line, source)
    return value


def _error(message: str, line: int, source: str) -> InvalidMeshError:
    return InvalidMeshError(f"cannot parse OFF file: line {line}: {message}", source)
