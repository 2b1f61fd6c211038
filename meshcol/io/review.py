"""The review page: one self-contained HTML file that shows a command's scene in 3D.

The page inlines meshcat's bundled three.js viewer (``meshcat/viewer/dist/main.min.js`` of the
``meshcat`` package, the optional extra ``meshcol[review]``) and drives it with meshcat's scene
commands (``set_object`` with three.js JSON, ``set_property``, ``set_transform``), so nothing
is fetched when the page is viewed. Meshes are packed once per unique geometry (base64
float32 positions and uint32 indices) and placed by their poses; coordinates are shifted by
the scene's centre before the float32 cast, so huge coordinates keep their detail.

This module takes arrays and report rows, never a collision query: the analysis layer
(:mod:`meshcol.analysis.review`) computes what the page shows.
"""

from __future__ import annotations

import base64
import functools
import hashlib
import html
import importlib.resources
import importlib.util
import os
import re
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from meshcol.errors import MeshcolError, MissingDependencyError
from meshcol.io.report import atomic_write, dumps_json

__all__ = [
    "MAX_REVIEW_BODIES",
    "MAX_REVIEW_BYTES",
    "DISPLAY_TRIANGLES",
    "PALETTE",
    "ReviewPage",
    "ReviewTooLargeError",
    "viewer_script",
    "write_review",
]

#: Most bodies a page shows: each is a node of meshcat's scene tree (and of its controls),
#: and a browser slows to a crawl well before 10,000 of them. Over it the page is refused.
MAX_REVIEW_BODIES = 2000
#: Largest page written (bytes); over it the page is refused, never a browser-freezing file.
MAX_REVIEW_BYTES = 64 * 1024 * 1024
#: Triangles drawn over the whole page: larger meshes are simplified for display only.
DISPLAY_TRIANGLES = 400_000
#: Triangles kept at least per mesh when simplifying.
MIN_DISPLAY_TRIANGLES = 500
#: Distinct colours (decomposition parts, bodies' colliders): saturated, none of them grey.
PALETTE = (
    "#e6194b",
    "#3cb44b",
    "#ffe119",
    "#4363d8",
    "#f58231",
    "#911eb4",
    "#42d4f4",
    "#f032e6",
    "#bfef45",
    "#469990",
    "#9a6324",
    "#800000",
    "#aaffc3",
    "#808000",
    "#000075",
    "#fabed4",
)
#: Colour of the selected pair's bodies (magenta), its witness points and normal.
HIGHLIGHT = "#ff00ff"
WITNESS = "#00c000"
NORMAL = "#ff8c00"
MESH_COLOR = "#b8b8b8"


class ReviewTooLargeError(MeshcolError, ValueError):
    """The review page would be too large for a browser: nothing is written."""


def viewer_script() -> str:
    """meshcat's bundled viewer (``main.min.js``), or MissingDependencyError with the hint."""
    hint = "--html needs the meshcat viewer: pip install 'meshcol[review]'"
    try:
        spec = importlib.util.find_spec("meshcat")
    except (ImportError, ValueError):
        spec = None
    if spec is None or not spec.submodule_search_locations:
        raise MissingDependencyError(hint)
    for folder in spec.submodule_search_locations:
        path = os.path.join(folder, "viewer", "dist", "main.min.js")
        if os.path.isfile(path):
            with open(path, encoding="utf-8") as handle:
                return handle.read()
    raise MissingDependencyError(hint + " (the installed meshcat has no viewer/dist/main.min.js)")


def _b64(array: np.ndarray) -> str:
    return base64.b64encode(np.ascontiguousarray(array).tobytes()).decode("ascii")


@dataclass
class _Geometry:
    vertices: np.ndarray
    faces: np.ndarray
    simplified_from: int | None = None


@dataclass
class ReviewPage:
    """What one review page shows, built up by the analysis layer and written once.

    Parameters
    ----------
    command : str
        ``check``, ``sweep``, ``decompose``, ``hull`` or ``inspect``.
    title : str
        The page's heading (the inputs).
    units : str or None
        The scene's units, shown beside every number.

    Notes
    -----
    Every ``add_*`` method takes world coordinates (``pose`` world-from-local); ``group`` is
    a toggle of the legend (``meshes``, ``colliders``, ``findings``, ...); ``body`` (an index
    of :meth:`add_body`) ties an object to a body so that choosing a pair highlights it.
    """

    command: str
    title: str
    units: str | None = None
    notes: list[str] = field(default_factory=list)
    info: list[tuple[str, str]] = field(default_factory=list)
    bodies: list[str] = field(default_factory=list)
    groups: dict[str, dict[str, Any]] = field(default_factory=dict)
    _geometries: list[_Geometry] = field(default_factory=list)
    _geometry_index: dict[bytes, int] = field(default_factory=dict)
    _objects: list[dict[str, Any]] = field(default_factory=list)
    _lines: list[dict[str, Any]] = field(default_factory=list)
    _points: list[dict[str, Any]] = field(default_factory=list)
    _rows: list[dict[str, Any]] = field(default_factory=list)
    _columns: list[str] = field(default_factory=list)
    _table_title: str = ""

    def group(self, name: str, label: str, color: str, visible: bool = True) -> None:
        """Declare a legend entry (a toggle for every object of ``name``)."""
        self.groups.setdefault(name, {"label": label, "color": color, "visible": visible})

    def add_body(self, name: str) -> int:
        """Register a body; returns its index for ``body=`` and for pairs."""
        self.bodies.append(name)
        return len(self.bodies) - 1

    def add_mesh(
        self,
        vertices: Any,
        faces: Any,
        pose: Any = None,
        *,
        group: str = "meshes",
        color: str = MESH_COLOR,
        opacity: float = 1.0,
        body: int = -1,
        name: str = "",
        wireframe: bool = False,
    ) -> None:
        """A triangle mesh in its local frame at ``pose`` (identical geometry is stored once)."""
        v = np.ascontiguousarray(vertices, dtype=np.float64).reshape(-1, 3)
        f = np.ascontiguousarray(faces, dtype=np.int64).reshape(-1, 3)
        if len(v) == 0 or len(f) == 0:
            return
        key = hashlib.blake2b(v.tobytes() + b"|" + f.tobytes(), digest_size=16).digest()
        index = self._geometry_index.get(key)
        if index is None:
            index = len(self._geometries)
            self._geometries.append(_Geometry(v, f))
            self._geometry_index[key] = index
        matrix = np.eye(4) if pose is None else np.asarray(pose, dtype=np.float64).reshape(4, 4)
        self._objects.append(
            {
                "g": index,
                "pose": matrix,
                "group": group,
                "color": color,
                "opacity": float(opacity),
                "body": int(body),
                "name": name,
                "wire": bool(wireframe),
            }
        )

    def add_lines(self, segments: Any, *, group: str, color: str, body: int = -1) -> None:
        """Line segments, ``(n, 2, 3)`` world points (edges, paths, arrows' shafts)."""
        s = np.asarray(segments, dtype=np.float64).reshape(-1, 2, 3)
        if len(s):
            self._lines.append({"p": s, "group": group, "color": color, "body": int(body)})

    def add_points(
        self, points: Any, *, group: str, color: str, labels: list[str] | None = None
    ) -> None:
        """Marked points (``(n, 3)`` world), optionally labelled."""
        p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        p = p[np.isfinite(p).all(axis=1)]
        if len(p):
            self._points.append({"p": p, "group": group, "color": color, "labels": labels or []})

    def table(self, title: str, columns: list[str]) -> None:
        """The table of rows (pairs, hits, parts, bodies) beside the view."""
        self._table_title, self._columns = title, list(columns)

    def add_row(
        self,
        cells: list[Any],
        *,
        bodies: tuple[int, ...] = (),
        points: Any = None,
        normal: Any = None,
        label: str = "",
        severity: str = "",
        group: str | None = None,
    ) -> None:
        """One row; choosing it frames ``bodies``, highlights them, marks ``points`` (witness
        points, contact point), draws ``normal`` as an arrow from the first point and shows
        ``label``; ``group`` is shown only while the row is chosen (a time-of-impact pose)."""
        pts = None if points is None else np.asarray(points, dtype=np.float64).reshape(-1, 3)
        nrm = None if normal is None else np.asarray(normal, dtype=np.float64).reshape(3)
        self._rows.append(
            {
                "cells": [_cell(c) for c in cells],
                "bodies": list(bodies),
                "points": pts,
                "normal": nrm,
                "label": label,
                "severity": severity,
                "group": group,
            }
        )

    # -- reading (the offscreen snapshots, io.snapshots) -----------------------------------

    def rows(self) -> list[dict[str, Any]]:
        """The table's rows as added: ``cells``, ``bodies`` (indices of :attr:`bodies`),
        ``points``, ``normal``, ``label``, ``severity``, ``group``."""
        return list(self._rows)

    def meshes(self) -> list[dict[str, Any]]:
        """Every mesh as added, with its geometry: ``vertices`` and ``faces`` (local frame),
        ``pose``, ``group``, ``color``, ``opacity``, ``body`` (-1: none), ``name``."""
        return [
            {
                **obj,
                "vertices": self._geometries[obj["g"]].vertices,
                "faces": self._geometries[obj["g"]].faces,
            }
            for obj in self._objects
        ]

    def lines(self) -> list[dict[str, Any]]:
        """Every set of line segments as added: ``p`` ``(n, 2, 3)`` world, ``group``,
        ``color``, ``body``."""
        return list(self._lines)

    # -- writing ------------------------------------------------------------------------

    def _centre_and_radius(self) -> tuple[np.ndarray, np.ndarray]:
        lows, highs = [], []
        for obj in self._objects:
            v = self._geometries[obj["g"]].vertices
            lo, hi = v.min(axis=0), v.max(axis=0)
            corners = np.array(np.meshgrid(*zip(lo, hi))).reshape(3, -1).T
            world = corners @ obj["pose"][:3, :3].T + obj["pose"][:3, 3]
            lows.append(world.min(axis=0))
            highs.append(world.max(axis=0))
        for item in (*self._lines, *self._points):
            p = item["p"].reshape(-1, 3)
            lows.append(p.min(axis=0))
            highs.append(p.max(axis=0))
        if not lows:
            return np.zeros(3), np.ones(3)
        lo, hi = np.min(lows, axis=0), np.max(highs, axis=0)
        extent = 0.5 * (hi - lo)
        if not np.linalg.norm(extent) > 0:
            extent = np.ones(3)
        return 0.5 * (lo + hi), extent

    def _simplify(self) -> list[str]:
        """Simplify the largest geometries for display so the page stays within
        :data:`DISPLAY_TRIANGLES`; returns the notes the page shows."""
        uses = np.zeros(len(self._geometries), dtype=np.int64)
        for obj in self._objects:
            uses[obj["g"]] += 1
        sizes = np.array([len(g.faces) for g in self._geometries], dtype=np.int64)
        total = int((sizes * uses).sum())
        if total <= DISPLAY_TRIANGLES:
            return []
        # one scale for every mesh over the floor: each keeps the same share of its triangles
        scale = DISPLAY_TRIANGLES / total
        try:
            import fast_simplification
        except ImportError:
            fast_simplification = None
        simplified = 0
        for index in np.argsort(-sizes):
            geometry = self._geometries[index]
            target = max(MIN_DISPLAY_TRIANGLES, int(len(geometry.faces) * scale))
            if len(geometry.faces) <= target:
                break
            reduction = 1.0 - target / len(geometry.faces)
            if fast_simplification is not None:
                points, faces = fast_simplification.simplify(
                    geometry.vertices.astype(np.float32), geometry.faces.astype(np.int32), reduction
                )
            else:  # keep every k-th triangle: holes, but the page stays light
                step = int(np.ceil(len(geometry.faces) / target))
                points, faces = geometry.vertices, geometry.faces[::step]
            if len(faces):
                self._geometries[index] = _Geometry(
                    np.asarray(points, dtype=np.float64),
                    np.asarray(faces, dtype=np.int64),
                    len(geometry.faces),
                )
                simplified += 1
        if not simplified:
            return []
        how = "fast-simplification" if fast_simplification is not None else "face sampling"
        return [
            f"{simplified} of {len(self._geometries)} meshes are shown simplified ({how}) to "
            f"stay within {DISPLAY_TRIANGLES:,} triangles; every number comes from the full "
            "meshes."
        ]

    def to_html(self) -> str:
        """The page (raises :class:`ReviewTooLargeError` over the stated limits): the
        viewer, the scene centred and packed (:meth:`_payload`), filled into the page's
        template (:func:`_fill`)."""
        self._check_body_count()
        script = viewer_script()
        notes = list(self.notes) + self._simplify()
        centre, extent = self._centre_and_radius()
        payload = dumps_json(
            self._payload(notes, centre, extent), compact=True, sort_keys=False, non_finite="error"
        )
        page = _fill(
            title=html.escape(f"meshcol {self.command}: {self.title}"),
            viewer=script.replace("</script", "<\\/script"),
            data=payload.replace("</", "<\\/"),  # inside <script>: "</" would end it early
        )
        _check_page_size(page)
        return page

    def _check_body_count(self) -> None:
        if len(self.bodies) > MAX_REVIEW_BODIES:
            raise ReviewTooLargeError(
                f"review page: {len(self.bodies):,} bodies is over the limit of "
                f"{MAX_REVIEW_BODIES:,} a browser can show; review a part of the scene"
            )

    def _payload(self, notes: list[str], centre: np.ndarray, extent: np.ndarray) -> dict:
        """What the page's script reads (``meshcol-data``): every coordinate shifted by
        ``-centre`` before the float32 cast, so huge coordinates keep their detail."""
        shift = np.eye(4)
        shift[:3, 3] = -centre
        return {
            "command": self.command,
            "title": self.title,
            "units": self.units,
            "notes": notes,
            "info": [[k, v] for k, v in self.info],
            "bodies": self.bodies,
            "groups": self.groups,
            "centre": centre.tolist(),
            "radius": float(np.linalg.norm(extent)),
            "extent": extent.tolist(),
            "geometries": [_geometry_entry(g) for g in self._geometries],
            "objects": [_object_entry(o, shift) for o in self._objects],
            "lines": [_line_entry(line, centre) for line in self._lines],
            "points": [_point_entry(item, centre) for item in self._points],
            "table": {
                "title": self._table_title,
                "columns": self._columns,
                "rows": [_row_entry(r, centre) for r in self._rows],
            },
            "highlight": HIGHLIGHT,
            "witness": WITNESS,
            "normal": NORMAL,
        }


def _geometry_entry(g: _Geometry) -> dict[str, Any]:
    return {
        "p": _b64(g.vertices.astype(np.float32)),
        "i": _b64(g.faces.astype(np.uint32)),
        "full": g.simplified_from,
    }


def _object_entry(o: dict[str, Any], shift: np.ndarray) -> dict[str, Any]:
    return {
        "g": o["g"],
        "m": np.round((shift @ o["pose"]).T.reshape(-1), 12).tolist(),
        "group": o["group"],
        "color": o["color"],
        "opacity": o["opacity"],
        "body": o["body"],
        "name": o["name"],
        "wire": o["wire"],
    }


def _line_entry(line: dict[str, Any], centre: np.ndarray) -> dict[str, Any]:
    return {
        "p": _b64((line["p"].reshape(-1, 3) - centre).astype(np.float32)),
        "group": line["group"],
        "color": line["color"],
        "body": line["body"],
    }


def _point_entry(item: dict[str, Any], centre: np.ndarray) -> dict[str, Any]:
    return {
        "p": _b64((item["p"] - centre).astype(np.float32)),
        "group": item["group"],
        "color": item["color"],
        "labels": item["labels"],
    }


def _row_entry(r: dict[str, Any], centre: np.ndarray) -> dict[str, Any]:
    return {
        "cells": r["cells"],
        "bodies": r["bodies"],
        "points": None if r["points"] is None else (r["points"] - centre).tolist(),
        "normal": None if r["normal"] is None else r["normal"].tolist(),
        "label": r["label"],
        "severity": r["severity"],
        "group": r["group"],
    }


def _check_page_size(page: str) -> None:
    size = len(page.encode("utf-8"))
    if size > MAX_REVIEW_BYTES:
        raise ReviewTooLargeError(
            f"review page: {size / 1e6:.0f} MB is over the limit of "
            f"{MAX_REVIEW_BYTES / 1e6:.0f} MB; review a part of the scene"
        )


#: The page's own files (package data, shipped in the wheel): the HTML skeleton with its
#: @NAME@ slots, its style sheet, the script that records errors, and the page's script.
ASSETS = {"page": "page.html", "style": "page.css", "errors": "errors.js", "app": "app.js"}
_SLOT = re.compile(r"@([A-Z]+)@")


@functools.lru_cache(maxsize=1)
def review_assets() -> dict[str, str]:
    """The text of each of :data:`ASSETS` (``meshcol/io/review_assets/``), read once."""
    folder = importlib.resources.files("meshcol.io").joinpath("review_assets")
    return {key: folder.joinpath(name).read_text(encoding="utf-8") for key, name in ASSETS.items()}


def _fill(title: str, viewer: str, data: str) -> str:
    """The page: each @NAME@ slot of the skeleton filled in one pass (a title or a body name
    holding ``@DATA@`` stays as it is)."""
    assets = review_assets()
    values = {
        "TITLE": title,
        "STYLE": assets["style"],
        "ERRORS": assets["errors"],
        "VIEWER": viewer,
        "DATA": data,
        "APP": assets["app"],
    }
    return _SLOT.sub(lambda match: values[match.group(1)], assets["page"])


def _cell(value: Any) -> Any:
    if isinstance(value, (bool, np.bool_)):
        return "yes" if value else "no"
    if isinstance(value, (float, np.floating)):
        if not np.isfinite(value):
            return ""
        return float(f"{float(value):.6g}")
    if isinstance(value, (int, np.integer)):
        return int(value)
    return "" if value is None else str(value)


def write_review(path: str | os.PathLike[str], page: ReviewPage) -> int:
    """Write ``page`` to ``path`` atomically; returns its size in bytes."""
    text = page.to_html()
    atomic_write(path, text)
    return len(text.encode("utf-8"))
