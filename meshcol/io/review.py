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
import hashlib
import html
import importlib.util
import os
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
        """The page (raises :class:`ReviewTooLargeError` over the stated limits)."""
        if len(self.bodies) > MAX_REVIEW_BODIES:
            raise ReviewTooLargeError(
                f"review page: {len(self.bodies):,} bodies is over the limit of "
                f"{MAX_REVIEW_BODIES:,} a browser can show; review a part of the scene"
            )
        script = viewer_script()
        notes = list(self.notes) + self._simplify()
        centre, extent = self._centre_and_radius()
        radius = float(np.linalg.norm(extent))
        shift = np.eye(4)
        shift[:3, 3] = -centre
        geometries = [
            {
                "p": _b64(g.vertices.astype(np.float32)),
                "i": _b64(g.faces.astype(np.uint32)),
                "full": g.simplified_from,
            }
            for g in self._geometries
        ]
        objects = [
            {
                "g": o["g"],
                "m": np.round((shift @ o["pose"]).T.reshape(-1), 12).tolist(),
                "group": o["group"],
                "color": o["color"],
                "opacity": o["opacity"],
                "body": o["body"],
                "name": o["name"],
                "wire": o["wire"],
            }
            for o in self._objects
        ]
        lines = [
            {
                "p": _b64((line["p"].reshape(-1, 3) - centre).astype(np.float32)),
                "group": line["group"],
                "color": line["color"],
                "body": line["body"],
            }
            for line in self._lines
        ]
        points = [
            {
                "p": _b64((item["p"] - centre).astype(np.float32)),
                "group": item["group"],
                "color": item["color"],
                "labels": item["labels"],
            }
            for item in self._points
        ]
        rows = [
            {
                "cells": r["cells"],
                "bodies": r["bodies"],
                "points": None if r["points"] is None else (r["points"] - centre).tolist(),
                "normal": None if r["normal"] is None else r["normal"].tolist(),
                "label": r["label"],
                "severity": r["severity"],
                "group": r["group"],
            }
            for r in self._rows
        ]
        data = {
            "command": self.command,
            "title": self.title,
            "units": self.units,
            "notes": notes,
            "info": [[k, v] for k, v in self.info],
            "bodies": self.bodies,
            "groups": self.groups,
            "centre": centre.tolist(),
            "radius": radius,
            "extent": extent.tolist(),
            "geometries": geometries,
            "objects": objects,
            "lines": lines,
            "points": points,
            "table": {"title": self._table_title, "columns": self._columns, "rows": rows},
            "highlight": HIGHLIGHT,
            "witness": WITNESS,
            "normal": NORMAL,
        }
        payload = dumps_json(data, compact=True, sort_keys=False, non_finite="error")
        # inside <script>: "</" would end the element early
        payload = payload.replace("</", "<\\/")
        page = (
            _TEMPLATE.replace("@TITLE@", html.escape(f"meshcol {self.command}: {self.title}"))
            .replace("@VIEWER@", script.replace("</script", "<\\/script"))
            .replace("@DATA@", payload)
            .replace("@APP@", _APP)
        )
        size = len(page.encode("utf-8"))
        if size > MAX_REVIEW_BYTES:
            raise ReviewTooLargeError(
                f"review page: {size / 1e6:.0f} MB is over the limit of "
                f"{MAX_REVIEW_BYTES / 1e6:.0f} MB; review a part of the scene"
            )
        return page


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


_TEMPLATE = """<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>@TITLE@</title>
<style>
html, body { margin: 0; height: 100%; overflow: hidden; font: 13px/1.35 system-ui, sans-serif; }
#side { position: absolute; left: 0; top: 0; bottom: 0; width: 460px; overflow: auto;
  box-sizing: border-box; padding: 10px 12px; background: #fafafa; border-right: 1px solid #ccc; }
#meshcat-pane { position: absolute; left: 460px; right: 0; top: 0; bottom: 0; overflow: hidden; }
h1 { font-size: 15px; margin: 0 0 6px; word-break: break-all; }
h2 { font-size: 13px; margin: 12px 0 4px; }
table { border-collapse: collapse; width: 100%; }
td, th { font-size: 12px; padding: 2px 4px; border-bottom: 1px solid #e4e4e4; text-align: left;
  white-space: nowrap; }
#rows tr { cursor: pointer; }
#rows tr:hover { background: #eef; }
#rows tr.chosen { background: #fdf; }
tr.violation td:first-child { border-left: 4px solid #d00; }
.swatch { display: inline-block; width: 11px; height: 11px; border: 1px solid #555;
  vertical-align: middle; margin-right: 4px; }
.note { color: #7a4b00; background: #fff4dc; padding: 4px 6px; margin: 4px 0; }
#label { position: absolute; pointer-events: none; background: rgba(255,255,255,.9);
  border: 1px solid #f0f; padding: 1px 5px; font-weight: 600; display: none; z-index: 5; }
#status { color: #666; }
#tablewrap { max-height: 55vh; overflow: auto; }
</style>
</head>
<body>
<div id="side">
<h1 id="heading"></h1>
<div id="status">loading&hellip;</div>
<table id="info"></table>
<div id="notes"></div>
<h2>Legend (click to show or hide)</h2>
<div id="legend"></div>
<h2 id="tabletitle"></h2>
<div id="tablewrap"><table><thead id="head"></thead><tbody id="rows"></tbody></table></div>
<p style="color:#666">Drag: orbit &middot; right-drag: pan &middot; wheel: zoom.
Viewer: meshcat (three.js), inlined.</p>
</div>
<div id="meshcat-pane"></div>
<div id="label"></div>
<script>
window.meshcolErrors = [];
window.addEventListener("error", function (e) {
  window.meshcolErrors.push(String(e.message));
  document.title = "meshcol-error: " + e.message;
  document.documentElement.setAttribute("data-error", String(e.message));
});
(function () {  // console errors count too (a viewer that fails quietly)
  var original = console.error;
  console.error = function () {
    var text = Array.prototype.join.call(arguments, " ");
    window.meshcolErrors.push(text);
    document.documentElement.setAttribute("data-console-error", text.slice(0, 200));
    return original.apply(console, arguments);
  };
})();
</script>
<script>@VIEWER@</script>
<script id="meshcol-data" type="application/json">@DATA@</script>
<script>@APP@</script>
</body>
</html>
"""

_APP = r"""
(function () {
"use strict";
var data = JSON.parse(document.getElementById("meshcol-data").textContent);
var THREE = MeshCat.THREE;
var units = data.units ? " " + data.units : "";
var viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));
viewer.renderer.setPixelRatio(1);
var cmd = function (c) { viewer.handle_command(c); };
cmd({type: "set_property", path: "/Background", property: "top_color", value: [1, 1, 1]});
cmd({type: "set_property", path: "/Background", property: "bottom_color", value: [0.85, 0.85, 0.87]});
cmd({type: "set_property", path: "/Grid", property: "visible", value: false});
cmd({type: "set_property", path: "/Axes", property: "visible", value: false});

function decode(text, Kind) {
  var raw = atob(text), bytes = new Uint8Array(raw.length);
  for (var i = 0; i < raw.length; i++) bytes[i] = raw.charCodeAt(i);
  return new Kind(bytes.buffer);
}
var colorInt = function (hex) { return parseInt(hex.slice(1), 16); };
var uid = 0;
var id = function () { uid += 1; return "meshcol-" + uid; };
function objectJson(type, geometry, material, matrix) {
  var g = id(), m = id();
  geometry.uuid = g; material.uuid = m;
  return {metadata: {version: 4.5, type: "Object"}, geometries: [geometry], materials: [material],
          object: {uuid: id(), type: type, geometry: g, material: m,
                   matrix: matrix || [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]}};
}
function material(type, color, opacity, extra) {
  var m = {type: type, color: colorInt(color), side: 2, transparent: opacity < 1,
           opacity: opacity, depthWrite: opacity >= 1};
  for (var k in extra || {}) m[k] = extra[k];
  return m;
}
var positions = data.geometries.map(function (g) { return decode(g.p, Float32Array); });
var indices = data.geometries.map(function (g) { return decode(g.i, Uint32Array); });
var byBody = {};  // body index -> list of THREE objects
var paths = [];
function place(path, json, body) {
  cmd({type: "set_object", path: path, object: json});
  var node = viewer.scene_tree.find(path.split("/").filter(Boolean).concat(["<object>"]));
  var obj = node.object;
  obj.castShadow = false; obj.receiveShadow = false;
  if (body >= 0) { (byBody[body] = byBody[body] || []).push(obj); }
  paths.push(path);
  return obj;
}
data.objects.forEach(function (o, k) {
  var geometry = {type: "BufferGeometry", data: {
    attributes: {position: {itemSize: 3, type: "Float32Array", array: positions[o.g],
                            normalized: false}},
    index: {type: "Uint32Array", array: indices[o.g]}}};
  // translucent overlays drawn a hair in front of the surface they cover (no z-fighting)
  var mat = material("MeshPhongMaterial", o.color, o.opacity,
                     {wireframe: o.wire, shininess: 10, flatShading: true,
                      polygonOffset: o.opacity < 1 || o.group !== "meshes",
                      polygonOffsetFactor: -1, polygonOffsetUnits: -1});
  var obj = place("/meshcol/" + o.group + "/" + k, objectJson("Mesh", geometry, mat, o.m), o.body);
  obj.userData.baseColor = colorInt(o.color);
  if (o.opacity < 1) obj.renderOrder = 1;
});
data.lines.forEach(function (l, k) {
  var geometry = {type: "BufferGeometry", data: {attributes: {position: {itemSize: 3,
    type: "Float32Array", array: decode(l.p, Float32Array), normalized: false}}}};
  place("/meshcol/" + l.group + "/lines" + k,
        objectJson("LineSegments", geometry, material("LineBasicMaterial", l.color, 1)), l.body);
});
var pointSize = Math.max(data.radius * 0.012, 1e-9);
data.points.forEach(function (p, k) {
  var geometry = {type: "BufferGeometry", data: {attributes: {position: {itemSize: 3,
    type: "Float32Array", array: decode(p.p, Float32Array), normalized: false}}}};
  place("/meshcol/" + p.group + "/points" + k, objectJson("Points", geometry,
        material("PointsMaterial", p.color, 1, {size: 7, sizeAttenuation: false})), -1);
});

// legend: one toggle per group
var legend = document.getElementById("legend");
Object.keys(data.groups).forEach(function (name) {
  var g = data.groups[name];
  var row = document.createElement("label");
  row.style.display = "block";
  var box = document.createElement("input");
  box.type = "checkbox"; box.checked = g.visible; box.dataset.group = name;
  box.onchange = function () {
    cmd({type: "set_property", path: "/meshcol/" + name, property: "visible", value: box.checked});
  };
  if (!g.visible) box.onchange();
  row.appendChild(box);
  row.insertAdjacentHTML("beforeend", '<span class="swatch" style="background:' + g.color +
                         '"></span>');
  row.appendChild(document.createTextNode(g.label));
  legend.appendChild(row);
});

// side panel
document.getElementById("heading").textContent = "meshcol " + data.command + ": " + data.title;
var info = document.getElementById("info");
data.info.forEach(function (kv) {
  var tr = info.insertRow(); tr.insertCell().textContent = kv[0];
  tr.insertCell().textContent = kv[1];
});
var unitsRow = info.insertRow(); unitsRow.insertCell().textContent = "units";
unitsRow.insertCell().textContent = data.units || "(not declared)";
data.notes.forEach(function (text) {
  var div = document.createElement("div"); div.className = "note"; div.textContent = text;
  document.getElementById("notes").appendChild(div);
});

// camera: frame a box (world), keeping the view direction
function frame(box) {
  var centre = box.getCenter(new THREE.Vector3());
  var r = Math.max(box.getSize(new THREE.Vector3()).length() * 0.5, data.radius * 1e-6, 1e-9);
  var cam = viewer.camera, parent = cam.parent;
  parent.updateMatrixWorld(true);
  var target = parent.worldToLocal(centre.clone());
  var dir = cam.position.clone().sub(viewer.controls.target);
  if (dir.lengthSq() === 0 || !isFinite(dir.lengthSq())) dir.set(1, 0.6, 1);
  dir.normalize();
  var distance = r / Math.sin(cam.fov * Math.PI / 360) * 1.1;
  viewer.controls.target.copy(target);
  cam.position.copy(target).add(dir.multiplyScalar(distance));
  cam.near = Math.max(distance - 3 * r, distance * 1e-4, 1e-12) * 0.5;
  cam.far = distance + 3 * data.radius + 3 * r;
  cam.updateProjectionMatrix();
  viewer.controls.update();
  viewer.set_dirty();
}
viewer.camera.position.set(1.5, 1.0, 1.5);
viewer.controls.target.set(0, 0, 0);
viewer.scene.updateMatrixWorld(true);
var whole = new THREE.Box3(new THREE.Vector3().fromArray(data.extent).negate(),
                           new THREE.Vector3().fromArray(data.extent))
  .applyMatrix4(viewer.scene.matrixWorld);
frame(whole);
viewer.controls.minDistance = 0;
viewer.controls.maxDistance = Infinity;

// the table; choosing a row frames and highlights its bodies
var head = document.getElementById("head"), rowsEl = document.getElementById("rows");
document.getElementById("tabletitle").textContent = data.table.title;
if (data.table.columns.length) {
  var hr = head.insertRow();
  ["#"].concat(data.table.columns).forEach(function (c) {
    var th = document.createElement("th"); th.textContent = c; hr.appendChild(th);
  });
}
var trs = [];
data.table.rows.forEach(function (row, i) {
  var tr = rowsEl.insertRow();
  if (row.severity === "violation") tr.className = "violation";
  [i].concat(row.cells).forEach(function (c) { tr.insertCell().textContent = c; });
  tr.onclick = function () { location.hash = "pair=" + i; };
  trs.push(tr);
});
var marks = null, chosen = -1, labelPoint = null, label = document.getElementById("label");
var rowGroups = {};
data.table.rows.forEach(function (r) { if (r.group) rowGroups[r.group] = true; });
function setGroup(name, visible) {
  cmd({type: "set_property", path: "/meshcol/" + name, property: "visible", value: visible});
}
Object.keys(rowGroups).forEach(function (g) { setGroup(g, false); });
function choose(i) {
  if (i === chosen) return;
  if (chosen >= 0) {
    var before = data.table.rows[chosen];
    trs[chosen].classList.remove("chosen");
    before.bodies.forEach(function (b) {
      (byBody[b] || []).forEach(function (o) {
        if (o.material.color && o.userData.baseColor !== undefined)
          o.material.color.setHex(o.userData.baseColor);
        if (o.material.emissive) o.material.emissive.setHex(0);
      });
    });
    if (before.group) setGroup(before.group, false);
  }
  if (marks) { viewer.scene.remove(marks); marks = null; }
  chosen = i; labelPoint = null; label.style.display = "none";
  if (i < 0 || i >= data.table.rows.length) { chosen = -1; frame(whole); return; }
  var row = data.table.rows[i];
  trs[i].classList.add("chosen");
  trs[i].scrollIntoView({block: "nearest"});
  if (row.group) setGroup(row.group, true);
  var box = new THREE.Box3();
  viewer.scene.updateMatrixWorld(true);
  row.bodies.forEach(function (b) {
    (byBody[b] || []).forEach(function (o) {
      if (o.material.color) o.material.color.setHex(colorInt(data.highlight));
      if (o.material.emissive) o.material.emissive.setHex(0x550055);
      box.expandByObject(o);
    });
  });
  marks = new THREE.Group();
  var size = Math.max(box.isEmpty() ? data.radius : box.getSize(new THREE.Vector3()).length(),
                      1e-9);
  if (row.points) {
    row.points.forEach(function (p) {
      var s = new THREE.Mesh(new THREE.SphereGeometry(size * 0.015, 16, 12),
                             new THREE.MeshBasicMaterial({color: colorInt(data.witness),
                                                          depthTest: false}));
      s.position.set(p[0], p[1], p[2]); s.renderOrder = 10; marks.add(s);
      box.expandByPoint(s.position.clone().applyMatrix4(viewer.scene.matrixWorld));
    });
    labelPoint = new THREE.Vector3().fromArray(row.points[0]);
    if (row.points.length > 1)
      labelPoint.add(new THREE.Vector3().fromArray(row.points[1])).multiplyScalar(0.5);
  }
  if (row.normal && row.points) {
    var n = new THREE.Vector3().fromArray(row.normal);
    if (n.lengthSq() > 0) {
      var arrow = new THREE.ArrowHelper(n.normalize(), new THREE.Vector3().fromArray(row.points[0]),
                                        size * 0.25, colorInt(data.normal), size * 0.06,
                                        size * 0.03);
      arrow.traverse(function (o) { if (o.material) { o.material.depthTest = false; }
                                    o.renderOrder = 11; });
      marks.add(arrow);
    }
  }
  viewer.scene.add(marks);
  if (row.label) { label.textContent = row.label; label.style.display = "block"; }
  if (!box.isEmpty()) frame(box);
  viewer.set_dirty();
}
function fromHash() {
  var m = /pair=(\d+)/.exec(location.hash);
  choose(m ? parseInt(m[1], 10) : -1);
}
window.addEventListener("hashchange", fromHash);
fromHash();

// the label follows its point
var pane = document.getElementById("meshcat-pane");
function follow() {
  if (labelPoint) {
    // meshcat turns its scene (z up); the page's coordinates are the scene's
    var p = labelPoint.clone().applyMatrix4(viewer.scene.matrixWorld).project(viewer.camera);
    var rect = viewer.renderer.domElement.getBoundingClientRect();
    label.style.left = (rect.left + (p.x + 1) / 2 * rect.width + 12) + "px";
    label.style.top = (rect.top + (1 - p.y) / 2 * rect.height - 12) + "px";
  }
  requestAnimationFrame(follow);
}
follow();
var status = document.getElementById("status");
status.textContent = data.bodies.length + " bodies, " + data.objects.length + " meshes drawn";
document.documentElement.setAttribute("data-meshcol-ready", String(data.objects.length));
})();
"""
