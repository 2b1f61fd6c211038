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
from meshcol.io.polygons import triangulate_polygons

if TYPE_CHECKING:
    from meshcol.io.mesh_formats import MeshNode

__all__ = ["read_off", "read_off_file", "triangulate_polygons"]

_KEYWORD = re.compile(r"^(?P<st>ST)?(?P<c>C)?(?P<n>N)?(?P<four>4)?(?P<dim>n)?OFF$")


def read_off_file(file: Path, source: str) -> list[MeshNode]:
    """The one mesh node of an OFF file, named after the file (none when it has no faces):
    the reader of :data:`meshcol.io.mesh_formats.FORMATS`."""
    vertices, faces = read_off(read_bytes(file, source), source)
    return [(file.stem, np.eye(4), vertices, faces, ())] if len(faces) else []


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
