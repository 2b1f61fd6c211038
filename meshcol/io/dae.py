"""COLLADA (``.dae``) read by pycollada: one mesh node per scene node that holds geometry, at
its world transform, in metres.

The conventions are those of the ROS tools that show a robot to its author:

- the length unit: vertices and translations are scaled by the root ``<asset><unit
  meter="...">`` (missing: 1), as RViz (``getMeshUnitRescale`` in its ``mesh_loader.cpp``),
  MoveIt's ``geometric_shapes``, Gazebo and pybullet do; reports say ``"units": "m"``;
- ``<up_axis>`` is not applied, as RViz does not apply it (pybullet turns a ``Y_UP`` file to
  Z up: a known difference between the tools, which meshcol takes RViz's side of);
- every ``<node>`` that instantiates geometry is one node here, its triangles, polylists and
  polygons together (lines and points are not bodies), named by its ``name`` (else ``id``);
  ``<instance_node>`` is followed, up to :data:`MAX_NODE_VISITS` nodes and
  :data:`MAX_VERTICES` vertices (a file of a few nodes, each instancing the one before twice,
  expands exponentially).

The bytes are checked before pycollada parses them (with lxml, whose ``huge_tree`` parser
resolves entities): a document type declaration, where entities are declared (the billion
laughs; external entities that read other files), is refused, as is a zip archive (pycollada
would inflate a zipped COLLADA whole). Images and other files the document refers to are
never opened: only geometry is read.
"""

from __future__ import annotations

import io
import math
import re
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any
from xml.parsers import expat

import numpy as np

from meshcol.errors import InvalidMeshError
from meshcol.geometry.rotations import axis_angle_matrix
from meshcol.io.body_names import MAX_ANCESTORS
from meshcol.io.mesh_trimesh import PARSE_ERRORS
from meshcol.io.safe_read import read_input

if TYPE_CHECKING:
    from meshcol.io.mesh_formats import MeshNode

__all__ = ["MAX_NODE_VISITS", "MAX_VERTICES", "UNITS", "DaeHeader", "read_dae", "read_header"]

#: The unit COLLADA geometry is converted to, reported in the envelope's ``units``.
UNITS = "m"

#: Most scene nodes walked in one file, ``<instance_node>`` expansions included.
MAX_NODE_VISITS = 100_000

#: Most vertices of one file's bodies together, instanced geometry counted per instance
#: (1.2 GB of float64).
MAX_VERTICES = 50_000_000


@dataclass(frozen=True)
class DaeHeader:
    """What the root ``<asset>`` of a COLLADA file declares.

    Attributes
    ----------
    meter : float
        The length of the file's unit in metres (``<unit meter>``; 1 when absent), > 0.
    up_axis : str
        ``<up_axis>`` as written (``Y_UP`` when absent, as the schema says); not applied.
    """

    meter: float = 1.0
    up_axis: str = "Y_UP"


class _Done(Exception):
    """Raised by the header scan's handlers to stop expat once the root's asset is read."""


def read_header(data: bytes, source: str) -> DaeHeader:
    """The root ``<asset>``'s unit and up axis of a COLLADA document ``data``, read by expat up
    to the first element after it; InvalidMeshError ``cannot parse DAE file: ...`` for a zip
    archive, a document type declaration, XML that breaks before then, a root that is not
    ``<COLLADA>`` or a unit that is not a positive finite length.

    Notes
    -----
    The scan stops at the start of a DOCTYPE, before its internal subset is read, so no
    entity is ever declared or expanded; it reads only the prolog and the asset, whatever
    the size of the file.
    """
    if zipfile.is_zipfile(io.BytesIO(data)):
        raise _error("a zip archive (zipped COLLADA is not read; unzip the .dae)", source)
    parser = expat.ParserCreate()
    depth = 0
    path: list[str] = []
    found: dict[str, str] = {}
    text: list[str] = []

    def start(tag: str, attributes: dict[str, str]) -> None:
        nonlocal depth
        name = tag.rsplit("}", 1)[-1].rsplit(":", 1)[-1]
        if depth == 0 and name != "COLLADA":
            raise _error(f"the root element is <{name[:100]}>, not <COLLADA>", source)
        if depth == 1 and (name != "asset" or "asset" in found):
            raise _Done
        depth += 1
        path.append(name)
        if path == ["COLLADA", "asset"]:
            found["asset"] = ""
        elif path == ["COLLADA", "asset", "unit"] and "meter" in attributes:
            found["meter"] = attributes["meter"]
        text.clear()

    def end(tag: str) -> None:
        nonlocal depth
        if path == ["COLLADA", "asset", "up_axis"]:
            found["up_axis"] = "".join(text).strip()
        depth -= 1
        path.pop()
        if depth == 1 and "asset" in found:
            raise _Done

    def doctype(*_: object) -> None:
        raise _error(
            "a DOCTYPE is not read (entity declarations could expand or read files)", source
        )

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    parser.CharacterDataHandler = text.append
    parser.StartDoctypeDeclHandler = doctype
    try:
        parser.Parse(data, True)
    except _Done:
        pass
    except expat.ExpatError as error:
        raise _error(
            f"XML: {expat.ErrorString(error.code)} (line {error.lineno})", source
        ) from None
    return DaeHeader(_meter(found.get("meter"), source), found.get("up_axis") or "Y_UP")


def read_dae(file: Path, source: str) -> list[MeshNode]:
    """The mesh nodes of a COLLADA file, in metres (:func:`read_header`'s unit): one per scene
    node that holds triangles, in document order (depth first), named after the node."""
    data = read_input(source, "mesh")
    header = read_header(data, source)
    return _mesh_nodes(_document(data, source), header.meter, source)


def _document(data: bytes, source: str) -> Any:
    """pycollada's document of ``data``: broken references and unsupported elements skipped
    (what trimesh does), materials never bound, every other failure InvalidMeshError."""
    import collada

    class GeometryOnly(collada.Collada):
        # The path pycollada 0.9 caches on the document to find an <instance_geometry>'s
        # materials: one that finds none, so that a material missing from the library (a
        # Blender export of anymal_foot.dae) does not drop the geometry with it, as assimp
        # (RViz) keeps it. An older pycollada without the cache binds materials as before.
        _geomnode_mat_xpath = "{meshcol}geometry-only"

    try:
        document = GeometryOnly(
            io.BytesIO(data), ignore=[collada.common.DaeError], aux_file_loader=_no_file
        )
    except (collada.common.DaeError, collada.scene.DaeInstanceNotLoadedError) as error:
        raise _error(_detail(error), source) from None
    except RecursionError:
        raise _error("elements nested too deeply", source) from None
    except (*PARSE_ERRORS, SyntaxError) as error:  # lxml's XMLSyntaxError is a SyntaxError
        raise _error(_detail(error), source) from None
    for problem in document.errors:
        if not isinstance(problem, collada.common.DaeUnsupportedError) and not (
            isinstance(problem, collada.common.DaeBrokenRefError)
            and problem.msg.startswith(_BESIDE)
        ):
            raise _error(_detail(problem), source)
    return document


#: The beginnings of pycollada's messages of broken references to what meshcol does not read
#: (materials, effects, images, cameras, lights, skins and morphs, auxiliary files): skipped.
#: Any other error (a geometry or node missing, indices beyond a source, a primitive without
#: its inputs) refuses the file: a collider that silently loses a part is a wrong answer.
_BESIDE = (
    "Effect",
    "Material",
    "Missing surface",
    "Missing image",
    "Camera",
    "Light",
    "Controller",
    "Auxiliar",
    "Trying to load",
    "Input in",
    "Weights input",
    "Base source of morph",
    "Targeted geometry",
    "Source geometry for skin",
    "Invalid source attribute of skin",
)

#: A float that is not finite, as C's strtod reads it (pycollada turns NaN into 0).
_NON_FINITE = re.compile(r"(?i)nan|inf")


def _mesh_nodes(document: Any, meter: float, source: str) -> list[MeshNode]:
    """Every scene node of ``document`` with triangles, depth first in document order, as
    ``(name, world matrix, vertices, faces, ancestors' names)``, its translation and vertices
    scaled by ``meter`` (the file's unit in metres: a scale applied outermost, so the node
    matrix keeps its rotation and the loader bakes nothing)."""
    from collada.scene import GeometryNode, Node, NodeNode

    nodes: list[MeshNode] = []
    scene = document.scene
    roots = [] if scene is None else list(scene.nodes)
    stack: list[tuple[Any, np.ndarray, tuple[str, ...]]] = [
        (node, np.eye(4), ()) for node in reversed(roots)
    ]
    visits = vertex_count = 0
    finite: dict[int, bool] = {}
    while stack:
        node, parent, above = stack.pop()
        if not isinstance(node, Node):
            continue  # cameras, lights, controllers
        visits += 1
        if visits > MAX_NODE_VISITS:
            raise _error(f"the scene expands to over {MAX_NODE_VISITS:,} nodes", source)
        try:
            matrix = parent @ _node_matrix(node.node if isinstance(node, NodeNode) else node)
            geometry = [child for child in node.children if isinstance(child, GeometryNode)]
            vertices, faces = _triangles(geometry, finite, source)
        except InvalidMeshError:
            raise
        except PARSE_ERRORS as error:
            raise _error(_detail(error), source) from None
        named = node.node if isinstance(node, NodeNode) else node
        if len(faces):
            vertex_count += len(vertices)
            if vertex_count > MAX_VERTICES:
                raise _error(f"the scene expands to over {MAX_VERTICES:,} vertices", source)
            name = named.name or named.id or (geometry[0].geometry.name or geometry[0].geometry.id)
            world = matrix.copy()
            world[:3, 3] *= meter
            nodes.append((str(name or "node"), world, vertices * meter, faces, above))
        children = [child for child in node.children if isinstance(child, Node)]
        inside = (*above, str(named.name or named.id or "node"))[-MAX_ANCESTORS:]
        stack.extend((child, matrix, inside) for child in reversed(children))
    return nodes


def _node_matrix(node: Any) -> np.ndarray:
    """The (4, 4) transform of a ``<node>``, its transforms multiplied in document order, in
    double precision: pycollada's own ``matrix`` is single (a 90-degree ``<rotate>`` there
    has a cosine of -4.4e-8 and a 0.99999994 on its axis, which is not a rotation)."""
    from collada.scene import RotateTransform, ScaleTransform, TranslateTransform

    matrix = np.eye(4)
    for transform in node.transforms:
        step = np.eye(4)
        if isinstance(transform, TranslateTransform):
            step[:3, 3] = (transform.x, transform.y, transform.z)
        elif isinstance(transform, ScaleTransform):
            step[:3, :3] = np.diag([transform.x, transform.y, transform.z])
        elif isinstance(transform, RotateTransform):
            axis = [transform.x, transform.y, transform.z]
            step[:3, :3] = axis_angle_matrix(axis, math.radians(float(transform.angle)))
        else:  # <matrix> (its own 16 numbers), <lookat>, <skew>: pycollada's matrix
            step = np.asarray(transform.matrix, dtype=np.float64).reshape(4, 4)
        matrix = matrix @ step
    return matrix


def _triangles(
    geometry_nodes: list[Any], finite: dict[int, bool], source: str
) -> tuple[np.ndarray, np.ndarray]:
    """The triangles of every primitive of ``geometry_nodes`` (triangles, polylists and
    polygons fan-triangulated by pycollada; lines skipped): ``(vertices (n, 3), faces (m, 3))``
    in the node's frame. ``finite``: :func:`_finite`'s answers so far."""
    from collada.polylist import Polylist
    from collada.triangleset import TriangleSet

    vertices: list[np.ndarray] = []
    faces: list[np.ndarray] = []
    base = 0
    for geometry_node in geometry_nodes:
        for primitive in geometry_node.geometry.primitives:
            if isinstance(primitive, Polylist):  # Polygons too
                primitive = primitive.triangleset()
            if not isinstance(primitive, TriangleSet) or primitive.vertex is None:
                continue
            index = np.asarray(primitive.vertex_index, dtype=np.int64).reshape(-1, 3)
            if len(index) == 0:
                continue
            if not _finite(primitive.sources["VERTEX"][0][4], finite):
                raise InvalidMeshError("mesh has non-finite vertex coordinates", source)
            vertices.append(np.asarray(primitive.vertex, dtype=np.float64).reshape(-1, 3))
            faces.append(index + base)
            base += len(vertices[-1])
    if not faces:
        return np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64)
    return np.concatenate(vertices), np.concatenate(faces)


def _finite(positions: Any, finite: dict[int, bool]) -> bool:
    """Whether the text of the ``<float_array>`` of a positions source has only finite
    numbers (pycollada reads NaN as 0, silently), remembered in ``finite`` by source."""
    key = id(positions)
    if key not in finite:
        arrays = [child for child in positions.xmlnode if str(child.tag).endswith("float_array")]
        texts = [array.text or "" for array in arrays]
        # every spelling of NaN and infinity has an n: the plain search is at memory speed
        finite[key] = not any(
            ("n" in text or "N" in text) and _NON_FINITE.search(text) for text in texts
        )
    return finite[key]


def _meter(value: str | None, source: str) -> float:
    """The unit's length in metres from its ``meter`` attribute (None: 1)."""
    if value is None:
        return 1.0
    try:
        meter = float(value)
    except ValueError:
        meter = math.nan
    if not (math.isfinite(meter) and meter > 0.0):
        raise _error(f"<unit meter={value[:40]!r}> is not a positive finite length", source)
    return meter


def _no_file(name: str) -> None:
    """pycollada's loader of the files a document refers to: none is read (geometry only)."""
    del name


def _detail(error: BaseException) -> str:
    text = str(getattr(error, "msg", error)).strip()  # pycollada's without its class name
    return (text.splitlines()[0] if text else type(error).__name__)[:200]


def _error(problem: str, source: str) -> InvalidMeshError:
    return InvalidMeshError(f"cannot parse DAE file: {problem}", source)
