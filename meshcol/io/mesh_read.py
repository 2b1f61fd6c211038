"""Load mesh files (OBJ, STL, PLY, OFF, glTF, GLB, FBX, COLLADA, USD) as rigid bodies,
geometry only.

A file may hold several bodies: OBJ objects (or groups, when the file has no objects), STL
solids, glTF mesh nodes. Each becomes one :class:`meshcol.types.Body` whose vertices are in its
local frame with any scale, shear or mirror of the scene graph baked in, and whose
``pose`` is the rigid rest of the node's world matrix.

Materials, textures, normals and UVs are never loaded: a textured file loads without Pillow,
and vertices split along UV or normal seams are merged back by position.

Many files are read at once (:func:`read_meshes`) into a :class:`MeshFiles` mapping, which
keeps the core's packed arrays when every file is one object and builds a file's Body only
when asked for: a manifest of 100,000 unique assets takes their arrays in bulk
(:func:`lone_objects`).
"""

from __future__ import annotations

import contextlib
import dataclasses
import os
from collections.abc import Iterator, Mapping, MutableMapping, Sequence
from dataclasses import dataclass
from operator import itemgetter
from pathlib import Path

import numpy as np

from meshcol.errors import InputFileError, InvalidMeshError
from meshcol.io.body_names import file_body_names
from meshcol.io.collision_names import GodotHint, godot_hint
from meshcol.io.mesh_formats import (
    MESH_EXTENSIONS,
    MeshFormat,
    MeshNode,
    check_file,
    mesh_format,
)
from meshcol.io.physics_bodies import BodyGroup, axis_turn, choose_collider, scaled_primitive
from meshcol.types import Body, PartPrimitive, Scene

__all__ = [
    "MAX_COORDINATE",
    "MeshFiles",
    "PackedObjects",
    "load_file_scene",
    "MESH_EXTENSIONS",
    "check_magnitude",
    "file_identities",
    "load_mesh",
    "load_meshes",
    "lone_objects",
    "read_meshes",
    "merge_vertices",
    "node_body_names",
    "split_rigid",
]

# A matrix whose linear part is orthonormal to this tolerance is taken as rigid as it is,
# so exact rotations (and identity) stay exact instead of going through an SVD.
_RIGID_TOL = 1e-12

#: Largest coordinate magnitude accepted anywhere (file vertices, and world coordinates after a
#: manifest's scale, pose and motion). Beyond it the 1e-8 merge grid of vertex positions
#: overflows 64-bit integers (at 9.2e10) and the float64 spacing of coordinates (2e-6 at 1e10)
#: is coarser than any contact tolerance; volumes and normals overflow long before 1e308.
MAX_COORDINATE = 1e10


def check_magnitude(values: np.ndarray, what: str, source: str | None) -> None:
    """Raise :class:`InvalidMeshError` when a value of ``values`` exceeds
    :data:`MAX_COORDINATE` in magnitude, naming the first such value (``what`` says whose)."""
    values = np.asarray(values, dtype=np.float64)
    over = np.abs(values) > MAX_COORDINATE
    if over.any():
        first = np.argwhere(over)[0]
        where = f" {int(first[0]) + 1}" if values.ndim == 2 else ""
        raise InvalidMeshError(
            f"{what}{where} has coordinate {values[tuple(first)]:.6g}, beyond the limit of "
            f"+/-{MAX_COORDINATE:g}",
            source,
        )


# Vertices closer than this (per coordinate, absolute) are merged: trimesh's own merge
# tolerance (trimesh.constants.tol.merge), so watertightness agrees with trimesh's processing.
_MERGE_DIGITS = 8


def load_mesh(path: str | os.PathLike[str], *, merge: bool = True) -> list[Body]:
    """Load every body of one mesh file.

    Parameters
    ----------
    path : str or path-like
        A mesh file of a format :data:`MESH_EXTENSIONS` lists (``.obj``, ``.stl`` ascii or
        binary, ``.ply``, ``.off``, ``.glb``, ``.gltf``, ``.fbx``, ``.dae``, USD). Kept
        verbatim as each body's ``source``.
    merge : bool, optional
        Merge vertices at the same position (to 1e-8, per coordinate), also across UV and
        normal seams, and drop unreferenced vertices. On by default: topology checks
        (watertight, manifold) are only meaningful after it.

    Returns
    -------
    list of Body
        In file order (glTF: scene-graph order). Named after the file stem when the file holds
        one body, else ``<stem>/<object, solid or node name>``; a name several bodies share
        is told apart by the path of parent nodes (``<stem>/crate_01/mesh``,
        :mod:`meshcol.io.body_names`), or by ``#2``... in OBJ, STL, PLY and OFF. In glTF
        and FBX, a Godot hint ending a node name (``Floor-col``) is cut from it and sets the
        body's ``collider`` (:mod:`meshcol.io.collision_names`).
        ``vertices`` (n, 3) float64 are in the body's local frame with scale baked in;
        ``faces`` (m, 3) int64; ``pose`` (4, 4) is rigid, world from local.

    Raises
    ------
    InputFileError
        Missing, unreadable, a directory, or an unknown extension.
    InvalidMeshError
        Corrupt content, no faces, non-finite coordinates, face indices out of range.

    Notes
    -----
    A node matrix ``M`` with scale, shear or mirror is split by polar decomposition
    (Higham 1986; computed from the SVD ``A = W S V^T``): ``A = R B`` with ``R`` a rotation
    (det +1) and ``B`` symmetric. ``B`` is baked into the vertices and ``R`` with ``M``'s
    translation becomes the transform; when ``det B < 0`` (a mirror) the face winding is
    flipped so that outward normals stay outward.
    """
    source = os.fspath(path)
    fmt = check_file(source)
    file = Path(source)
    if fmt.scene is not None:
        scene = load_file_scene(source, merge=merge)
        if scene is not None:
            return list(scene.bodies)
    if fmt.read is None:
        return load_meshes([source], merge=merge)[0]
    nodes = fmt.read(file, source)
    if not nodes:
        raise InvalidMeshError("mesh has no faces", source)
    bodies = []
    names = node_body_names(file, nodes, fmt.godot_hints)
    for (full, hint), (_, matrix, vertices, faces, _) in zip(names, nodes):
        body = _node_body(full, matrix, vertices, faces, source, merge)
        if hint is not None and hint.collider is not None:
            body = dataclasses.replace(body, collider=hint.collider)
        bodies.append(body)
    return bodies


def node_body_names(
    file: Path, nodes: Sequence[MeshNode], godot_hints: bool
) -> list[tuple[str, GodotHint | None]]:
    """The name :func:`load_mesh` gives the body of each mesh node (its name and its
    ancestors', :data:`meshcol.io.mesh_formats.MeshNode`) of ``file``, by
    :func:`meshcol.io.body_names.file_body_names` (a Godot hint cut from the node's name when
    the format has them), with the node's hint (None: none)."""
    hints = [godot_hint(node[0]) if godot_hints else None for node in nodes]
    leaves = [node[0] if hint is None else hint.name for node, hint in zip(nodes, hints)]
    return list(zip(file_body_names(file.stem, leaves, [node[4] for node in nodes]), hints))


def load_file_scene(path: str | os.PathLike[str], *, merge: bool = True) -> Scene | None:
    """The scene a file declares of itself (its format's ``scene`` reader: USD, glTF with
    physics extensions), or None for a file that is only meshes (then :func:`load_mesh`
    has everything). ``merge``: as :func:`load_mesh`.

    Returns
    -------
    Scene or None
        One body per group the reader found, named as :func:`load_mesh` names bodies
        (``<stem>`` alone for one, else ``<stem>/<name>``, by the prim or node path where
        several share a name: :mod:`meshcol.io.body_names`); the
        reader's excluded pairs, units and warnings; ``source`` the path.
    """
    source = os.fspath(path)
    fmt = check_file(source)
    found = None if fmt.scene is None else fmt.scene(Path(source), source)
    if found is None:
        return None
    if not found.groups:
        raise InvalidMeshError("mesh has no faces", source)
    warnings = list(found.warnings)
    groups = found.groups
    named = file_body_names(
        Path(source).stem, [g.name for g in groups], [g.ancestors for g in groups]
    )
    names = {group.key: name for group, name in zip(groups, named)}
    bodies = [_group_body(names[g.key], source, g, warnings, merge) for g in groups]
    excluded = sorted(
        {(*sorted((names[a], names[b])), reason) for a, b, reason in found.excluded if a != b}
    )
    return Scene(
        bodies=tuple(bodies),
        units=found.units,
        source=source,
        excluded_pairs=tuple((a, b, reason) for a, b, reason in excluded),
        warnings=tuple(warnings),
    )


def _group_body(
    name: str, source: str, group: BodyGroup, warnings: list[str], merge: bool = True
) -> Body:
    """One body from a group of collision shapes (:mod:`meshcol.io.physics_bodies`): a lone
    primitive stays exact when its transform allows; anything else is a body of parts,
    every part merged; ``warnings`` gets a line when its parts ask for different colliders."""
    from meshcol.io.links import LinkElement, parts_body, primitive_body
    from meshcol.io.primitives import primitive_mesh

    pose, _ = split_rigid(group.world)
    inverse = np.linalg.inv(pose)
    elements = []
    exact_parts: list[PartPrimitive | None] = []  # the queries' shape of each part
    for element in group.elements:
        origin, exact = inverse @ element.world, None
        if element.primitive is not None:
            origin = origin @ axis_turn(element.axis)
            exact = scaled_primitive(element.primitive, origin)
            if exact is not None and len(group.elements) == 1:
                primitive, rigid = exact
                return primitive_body(name, source, primitive, pose @ rigid)
            vertices, faces = primitive_mesh(element.primitive)
        else:
            assert element.vertices is not None and element.faces is not None
            vertices, faces = element.vertices, element.faces
        # einsum, not matmul: a (n, 3) @ (3, 3) goes to BLAS, whose threads stall on a
        # loaded machine (seconds for a million points)
        vertices = np.einsum("ij,nj->ni", origin[:3, :3], vertices)
        vertices += origin[:3, 3]  # in place: a second array of a million points costs
        check_magnitude(vertices, "vertex", source)
        if np.linalg.det(origin[:3, :3]) < 0:
            faces = faces[:, ::-1]
        if merge:
            vertices, faces = merge_vertices(vertices, faces)
        elements.append(LinkElement(element.name, np.eye(4), None, vertices, faces))
        exact_parts.append(None if exact is None else PartPrimitive(*exact))
    body = parts_body(name, source, pose, elements, exact_parts)
    collider = choose_collider([e.collider for e in group.elements], warnings, name)
    return body if collider is None else dataclasses.replace(body, collider=collider)


def _node_body(name: str, matrix, vertices, faces, source: str, merge: bool) -> Body:
    """The body of one mesh node: checked, its scale, shear or mirror baked into its vertices
    (winding flipped for a mirror), merged."""
    vertices = np.asarray(vertices, dtype=np.float64)
    faces = np.asarray(faces, dtype=np.int64)
    if vertices.ndim != 2 or vertices.shape[1] != 3 or faces.ndim != 2 or faces.shape[1] != 3:
        raise InvalidMeshError("mesh is not made of triangles", source)
    if not np.isfinite(vertices).all():
        raise InvalidMeshError("mesh has non-finite vertex coordinates", source)
    check_magnitude(vertices, "vertex", source)
    if not np.isfinite(matrix).all():
        raise InvalidMeshError("scene graph has a non-finite transform", source)
    if faces.min() < 0 or faces.max() >= len(vertices):
        raise InvalidMeshError("face index out of range", source)
    try:
        transform, linear = split_rigid(matrix)
    except InvalidMeshError as error:
        raise InvalidMeshError(error.message, source) from None
    if linear is not None:
        vertices = vertices @ linear.T
        if np.linalg.det(linear) < 0:
            faces = faces[:, ::-1]
        if not np.isfinite(vertices).all():
            raise InvalidMeshError(
                "scene graph scale makes vertex coordinates overflow (non-finite)", source
            )
        check_magnitude(vertices, "vertex (after the scene graph's scale)", source)
    if merge:
        vertices, faces = merge_vertices(vertices, faces)
    return Body(
        name=name,
        source=source,
        vertices=np.ascontiguousarray(vertices),
        faces=np.ascontiguousarray(faces),
        pose=transform,
    )


_CORRUPT = 4  # the core's ReadStatus::Corrupt
_EYE = np.eye(4)  # copied per body: a third of the time of np.eye(4)


def load_meshes(
    paths: Sequence[str | os.PathLike[str]], *, merge: bool = True, threads: int = 0
) -> list[list[Body]]:
    """Load many mesh files at once: :func:`load_mesh` for each, with OBJ and STL files read
    and parsed by the native core in parallel (GIL released).

    Parameters
    ----------
    paths : list of str or path-like
    merge : bool, optional
        As :func:`load_mesh`.
    threads : int, optional
        Reader threads for the OBJ and STL files; 0 means all cores.

    Returns
    -------
    list of list of Body
        One list per path, in order, each as :func:`load_mesh` returns it.

    Raises
    ------
    InputFileError, InvalidMeshError
        As :func:`load_mesh`, for the first path (in order) that fails.

    Notes
    -----
    The native readers: OBJ ``v`` and ``f`` lines (any encoding; comments, ``vt``, ``vn``,
    materials and everything else skipped), polygons fan-triangulated, 1-based or negative
    (relative) indices, never 0 or out of range; ``o`` lines start bodies, or ``g`` lines when
    the file has none. STL: binary when the size is 84 + 50 x the triangle count, else ASCII
    (one body per ``solid``). Other formats go through trimesh, one file at a time.
    """
    return read_meshes(paths, merge=merge, threads=threads).per_file()


def read_meshes(
    paths: Sequence[str | os.PathLike[str]], *, merge: bool = True, threads: int = 0
) -> MeshFiles:
    """:func:`load_meshes` as a mapping from each path (``os.fspath``) to its bodies, whose
    Body objects are built only when asked for: a scene of files of one object each keeps the
    core's packed arrays (:func:`meshcol.io.mesh_read.lone_objects` reads them in bulk).
    Same arguments, same errors."""
    sources = [os.fspath(p) for p in paths]
    formats = _formats_of(sources)
    for source, fmt in zip(sources, formats):
        if fmt is None:
            _format_of(source)  # says what is wrong with the first such path
    known = [fmt for fmt in formats if fmt is not None]
    native = [i for i, fmt in enumerate(known) if fmt.native is not None]
    if len(native) == len(sources):
        return _read_native(sources, known, merge, threads)
    out: list[list[Body] | None] = [None] * len(sources)
    if native:
        read = _read_native(
            [sources[i] for i in native], [known[i] for i in native], merge, threads
        )
        for i, bodies in zip(native, read.per_file()):
            out[i] = bodies
    return MeshFiles(
        sources,
        [
            bodies if bodies is not None else load_mesh(source, merge=merge)
            for source, bodies in zip(sources, out)
        ],
    )


def file_identities(paths: Sequence[str]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Device and inode of each of ``paths`` (symbolic links followed, as :func:`os.stat`),
    stat'ed at once by the core's threads: (n,) uint64 each, and (n,) uint8 ``found``, 0
    where the path names nothing that can be stat'ed. What tells the output guard
    (:mod:`meshcol.io.outputs`) whether a report is one of 100,000 input files."""
    from meshcol._native import core

    # The core takes UTF-8 text without NUL; any other path (a file name of undecodable bytes,
    # kept as surrogates) is stat'ed here.
    joined = "".join(paths)  # the common case in two string scans: ASCII, no NUL
    plain = joined.isascii() and "\x00" not in joined
    apart = [] if plain else [i for i, p in enumerate(paths) if not _core_path(p)]
    usable = list(paths) if not apart else [p if _core_path(p) else "" for p in paths]
    device, inode, found = core.file_identities(usable)
    for i in apart:
        with contextlib.suppress(OSError, ValueError):
            info = os.stat(paths[i])
            device[i], inode[i], found[i] = info.st_dev, info.st_ino, 1
    return device, inode, found


def _core_path(path: str) -> bool:
    """Whether the core can take ``path`` as given: UTF-8 text without NUL."""
    if "\x00" in path:
        return False
    if path.isascii():
        return True
    try:
        path.encode("utf-8")
    except UnicodeEncodeError:
        return False
    return True


def _formats_of(sources: Sequence[str]) -> list[MeshFormat | None]:
    """The format of each of ``sources``, as :func:`mesh_format` finds it (None where it
    raises): each extension looked up once, and each extension found from
    the distinct ends of the paths (:func:`_extension_of_end`), not a ``splitext`` per path,
    for 100,000 files."""
    ends = list(map(_END, sources))
    by_end = {end: _extension_of_end(end) for end in set(ends)}
    if None in by_end.values():  # an end that cannot tell: splitext for those paths
        extensions = [
            os.path.splitext(source)[1] if by_end[end] is None else by_end[end]
            for source, end in zip(sources, ends)
        ]
    else:
        extensions = list(map(by_end.__getitem__, ends))
    found: dict[str | None, MeshFormat | None] = {}
    for extension in set(extensions):
        try:
            found[extension] = mesh_format(f"x{extension}")  # by its extension alone
        except InputFileError:
            found[extension] = None
    return list(map(found.__getitem__, extensions))


_END_LENGTH = 6  # a dot, up to four letters and the character before it
_END = itemgetter(slice(-_END_LENGTH, None))  # a path's last characters


def _extension_of_end(end: str) -> str | None:
    """``os.path.splitext``'s extension of every path that ends with ``end`` (its last
    :data:`_END_LENGTH` characters, or all of a shorter path), or None when the end alone
    cannot tell: its last dot, when no slash follows it and a character other than a dot or
    a slash comes just before it (the name then does not start with that dot)."""
    dot = end.rfind(".")
    if dot >= 1 and end.rfind("/") < dot and end[dot - 1] not in "./":
        return end[dot:]
    return None


def _format_of(source: str) -> MeshFormat:
    """The format of ``source``; for an unknown extension, a missing file or a directory
    says so first."""
    try:
        return mesh_format(source)
    except InputFileError:
        check_file(source)
        raise


@dataclass(frozen=True, eq=False)
class _NativeRead:
    """What the core's ``read_mesh_files`` returns: every object's vertices and faces (int32)
    packed, with offsets (k + 1 entries for k objects), the file of each object, its name, per
    file a status and an error text, and per object its largest |coordinate|."""

    vertices: np.ndarray
    faces: np.ndarray
    v_off: np.ndarray
    f_off: np.ndarray
    owner: np.ndarray
    names: list
    status: np.ndarray
    errors: list
    largest: np.ndarray

    def body(self, k: int, name: str, source: str) -> Body:
        """Object ``k`` as a body named ``name``."""
        return Body(
            name=name,
            source=source,
            vertices=self.vertices[self.v_off[k] : self.v_off[k + 1]],
            faces=self.faces[self.f_off[k] : self.f_off[k + 1]].astype(np.int64),
            pose=_EYE.copy(),
        )


def _read_native(
    sources: list[str], formats: list[MeshFormat], merge: bool, threads: int
) -> MeshFiles:
    """The bodies of files the core reads, read in parallel."""
    from meshcol._native import core

    codes = [fmt.native for fmt in formats if fmt.native is not None]
    assert len(codes) == len(formats), "every format read here has a native reader"
    read = _NativeRead(*core.read_mesh_files(sources, codes, merge=merge, threads=threads))
    # the objects with a coordinate beyond the limit (the core measured each object's largest)
    big = set((np.flatnonzero(read.largest > MAX_COORDINATE) + 1).tolist())
    one_each = len(read.owner) == len(sources) and bool(
        (read.owner == np.arange(len(sources))).all()
    )
    if not big and one_each and not read.status.any():
        # the common scene: every file read, one object each, no coordinate too big; each
        # body, when asked for, is what _checked_files builds (named by its file's stem)
        packed = PackedObjects(read.vertices, read.faces, read.v_off, read.f_off, read.largest)
        return MeshFiles(sources, [None] * len(sources), packed)
    return MeshFiles(sources, list(_checked_files(read, sources, formats, big)))


def _checked_files(
    read: _NativeRead, sources: list[str], formats: list[MeshFormat], big: set[int]
) -> list[list[Body]]:
    """Every file's bodies, the first file (in order) with a problem raising it."""
    names = [_text(n) for n in read.names]
    errors = [_text(e) for e in read.errors]
    per_file: list[list[int]] = [[] for _ in sources]
    for k, f in enumerate(read.owner.tolist()):
        per_file[f].append(k)
    out = []
    for j, (source, fmt) in enumerate(zip(sources, formats)):
        if read.status[j] == _CORRUPT:
            raise InvalidMeshError(f"cannot parse {fmt.name.upper()} file: {errors[j]}", source)
        if read.status[j] != 0:
            raise InputFileError(errors[j], source)
        objects = per_file[j]
        if not objects:
            raise InvalidMeshError("mesh has no faces", source)
        file_stem = _stem(source)
        leaves = [names[k] or (fmt.unnamed or file_stem) for k in objects]
        bodies = []
        for k, name in zip(objects, file_body_names(file_stem, leaves)):
            if k + 1 in big:
                check_magnitude(read.vertices[read.v_off[k] : read.v_off[k + 1]], "vertex", source)
            bodies.append(read.body(k, name, source))
        out.append(bodies)
    return out


def _text(data: bytes) -> str:
    """Bytes of a file as text: UTF-8, else Latin-1 (which maps every byte)."""
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        return data.decode("latin-1")


# --- many files read at once, kept packed ------------------------------------------------------


class PackedObjects:
    """One object per file, packed: file ``j``'s vertices are
    ``vertices[v_off[j]:v_off[j + 1]]`` ((V, 3) float64) and its faces
    ``faces[f_off[j]:f_off[j + 1]]`` ((F, 3) int32 as the core packs them, or int64, indexing
    its own vertices), in its frame (no transform); ``largest``, when given, each file's
    largest |coordinate| (as :meth:`largest` computes it).

    The faces are kept as given; :meth:`arrays` and :meth:`views` give them as int64, a
    body's type. The core's int32 halves a scene's largest array (100,000 files: 62 of
    125 MB), held for the bodies few checks ever make."""

    def __init__(
        self,
        vertices: np.ndarray,
        faces: np.ndarray,
        v_off: np.ndarray,
        f_off: np.ndarray,
        largest: np.ndarray | None = None,
    ) -> None:
        self.vertices, self.faces = vertices, faces
        self.v_off, self.f_off = v_off.tolist(), f_off.tolist()
        self._largest: np.ndarray | None = largest

    def arrays(self, j: int) -> tuple[np.ndarray, np.ndarray]:
        """(vertices, faces) of file ``j``, C-contiguous: a view of the vertices, the faces as
        int64 (a copy of int32 ones)."""
        vo, fo = self.v_off, self.f_off
        faces = self.faces[fo[j] : fo[j + 1]]
        return self.vertices[vo[j] : vo[j + 1]], faces.astype(np.int64, copy=False)

    def views(self, files: Sequence[int]) -> list[tuple[np.ndarray, np.ndarray]]:
        """:meth:`arrays` of each of ``files``, in one pass: the faces widened to int64 once,
        each file's a view of that."""
        vo, fo, vertices = self.v_off, self.f_off, self.vertices
        faces = self.faces.astype(np.int64, copy=False)
        return [(vertices[vo[j] : vo[j + 1]], faces[fo[j] : fo[j + 1]]) for j in files]

    def largest(self) -> np.ndarray:
        """The largest |coordinate| of each file's vertices (0 for none): one reduction over
        the flat coordinates."""
        if self._largest is None:
            starts = np.asarray(self.v_off, dtype=np.int64)
            sizes = np.diff(starts)
            largest = np.zeros(len(sizes))
            filled = sizes > 0
            if filled.any():
                magnitudes = np.abs(self.vertices.reshape(-1))
                largest[filled] = np.maximum.reduceat(magnitudes, starts[:-1][filled] * 3)
            self._largest = largest
        return self._largest


class MeshFiles(MutableMapping[str, list[Body]]):
    """The bodies of each file read, by its path as given (the first of repeated paths), in
    the order :func:`meshcol.io.mesh_read.load_mesh` gives them; files read later may be
    added (``files[path] = bodies``).

    ``sources[j]``'s bodies are ``bodies[j]`` when built already, else the one object
    ``packed`` holds for it, named after the file's stem, identity pose.
    """

    def __init__(
        self,
        sources: Sequence[str],
        bodies: list[list[Body] | None],
        packed: PackedObjects | None = None,
    ) -> None:
        self.sources = list(sources)
        self._bodies = bodies
        self.packed = packed
        self._index: dict[str, int] | None = None

    def index(self) -> dict[str, int]:
        """Position of each path (its first)."""
        if self._index is None:
            index: dict[str, int] = {}
            for j, source in enumerate(self.sources):
                index.setdefault(source, j)
            self._index = index
        return self._index

    def file(self, j: int) -> list[Body]:
        """The bodies of ``sources[j]``."""
        bodies = self._bodies[j]
        if bodies is None:
            assert self.packed is not None
            source = self.sources[j]
            vertices, faces = self.packed.arrays(j)
            bodies = [Body.plain(_stem(source), source, vertices, faces, _EYE.copy())]
            self._bodies[j] = bodies
        return bodies

    def packed_positions(self, keys: Sequence[str]) -> np.ndarray | None:
        """Each of ``keys``' object in ``packed``: None unless all are read, none built."""
        spots = list(map(self.index().get, keys))
        ok = self.packed is not None and self._bodies.count(None) == len(self._bodies)
        return np.asarray(spots, dtype=np.int64) if ok and None not in spots else None

    def per_file(self) -> list[list[Body]]:
        """The bodies of every path, in order (repeated paths included)."""
        return [self.file(j) for j in range(len(self.sources))]

    def __getitem__(self, key: str) -> list[Body]:
        return self.file(self.index()[key])

    def __setitem__(self, key: str, bodies: list[Body]) -> None:
        j = self.index().get(key)
        if j is None:
            self.index()[key] = len(self.sources)
            self.sources.append(key)
            self._bodies.append(bodies)
        else:
            self._bodies[j] = bodies

    def __delitem__(self, key: str) -> None:
        raise TypeError("mesh files read are never removed")

    def __iter__(self) -> Iterator[str]:
        return iter(self.index())

    def __len__(self) -> int:
        return len(self.index())


def lone_objects(
    files: Mapping[str, list[Body]], keys: Sequence[str]
) -> tuple[np.ndarray, np.ndarray, list[tuple[np.ndarray, np.ndarray] | None]]:
    """Of each of ``keys`` (paths of ``files``): whether its file is read and holds one object
    without a transform, the largest |coordinate| of that object (0 without vertices, inf
    when it is not such an object), and its (vertices, faces), C-contiguous (None when not).

    In one numpy pass for the files a :class:`MeshFiles` holds packed; from the bodies for
    the others.
    """
    n = len(keys)
    lone = np.zeros(n, dtype=bool)
    largest = np.full(n, np.inf)
    arrays: list[tuple[np.ndarray, np.ndarray] | None] = [None] * n
    others = list(range(n))
    if isinstance(files, MeshFiles) and files.packed is not None:
        index, built, packed = files.index(), files._bodies, files.packed
        spots = list(map(index.get, keys))  # None: not read
        if None not in spots and built.count(None) == len(built):
            packed_rows, others = others, []  # every key read, every file packed
        else:
            packed_rows = [k for k, j in enumerate(spots) if j is not None and built[j] is None]
            done = set(packed_rows)
            others = [k for k in others if k not in done]
        if packed_rows:
            positions = [spots[k] for k in packed_rows] if others else spots
            lone[packed_rows] = True
            largest[packed_rows] = packed.largest()[np.asarray(positions, dtype=np.int64)]
            views = packed.views(positions)  # type: ignore[arg-type]
            if others:
                for k, pair in zip(packed_rows, views):
                    arrays[k] = pair
            else:
                arrays = list(views)
    loaded = [files.get(keys[k]) for k in others]
    ones = [(k, f[0]) for k, f in zip(others, loaded) if f is not None and len(f) == 1]
    for k, body in ones:
        if (np.asarray(body.pose) == _EYE).all():
            lone[k] = True
            vertices = np.ascontiguousarray(body.vertices)
            largest[k] = float(np.abs(vertices).max()) if vertices.size else 0.0
            arrays[k] = (vertices, np.ascontiguousarray(body.faces))
    return lone, largest, arrays


def _stem(source: str) -> str:
    """``Path(source).stem`` without building a Path (a scene may name 100,000 files)."""
    name = os.path.basename(source.rstrip("/"))
    dot = name.rfind(".")
    return name[:dot] if 0 < dot < len(name) - 1 else name


def split_rigid(matrix: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """Split an affine 4x4 matrix into a rigid transform and a linear part to bake.

    Parameters
    ----------
    matrix : (4, 4) float
        Affine, world from local (row-major; last row ``0 0 0 1``).

    Returns
    -------
    rigid : (4, 4) float64
        Rotation (det +1) and the matrix's translation.
    linear : (3, 3) float64 or None
        Symmetric part ``B`` with ``matrix[:3, :3] == rigid[:3, :3] @ B``, to apply to local
        vertices; None when the matrix is already rigid (to 1e-12).

    Raises
    ------
    InvalidMeshError
        When the linear part is singular (a zero scale flattens the mesh).

    Notes
    -----
    Polar decomposition from the SVD ``A = W S V^T``: ``R = W V^T`` and ``B = V S V^T``
    (Higham 1986). If ``det R < 0`` the singular vector of the smallest singular value is
    negated, which moves the mirror into ``B`` (then ``det B < 0``) and keeps ``R`` proper.
    """
    matrix = np.asarray(matrix, dtype=np.float64)
    linear = matrix[:3, :3]
    rigid = np.eye(4)
    rigid[:3, 3] = matrix[:3, 3]
    largest = float(np.abs(linear).max())
    if not np.isfinite(largest) or largest > MAX_COORDINATE:  # before squaring it overflows
        raise InvalidMeshError(
            f"scene graph transform has scale {largest:.6g}, beyond the limit of {MAX_COORDINATE:g}"
        )
    if np.abs(linear.T @ linear - np.eye(3)).max() <= _RIGID_TOL and np.linalg.det(linear) > 0:
        rigid[:3, :3] = linear
        return rigid, None
    w, s, vt = np.linalg.svd(linear)
    if not np.isfinite(s).all() or s[0] > MAX_COORDINATE:
        raise InvalidMeshError(
            f"scene graph transform has scale {s[0]:.6g}, beyond the limit of {MAX_COORDINATE:g}"
        )
    if s[-1] == 0:
        raise InvalidMeshError("scene graph transform is singular (zero scale)")
    if s[-1] <= s[0] * 1e-12:
        raise InvalidMeshError(
            f"scene graph transform is degenerate (scales {s[0]:.6g} and {s[-1]:.6g} differ "
            "by more than 1e12)"
        )
    if np.linalg.det(w @ vt) < 0:
        w[:, -1] = -w[:, -1]
        s = s.copy()
        s[-1] = -s[-1]
    rigid[:3, :3] = w @ vt
    return rigid, (vt.T * s) @ vt


def merge_vertices(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Merge vertices at the same position and drop unreferenced ones.

    Parameters
    ----------
    vertices : (n, 3) float
    faces : (m, 3) int

    Returns
    -------
    vertices : (k, 3) float64
        Unique positions, in the input order of their first occurrence.
    faces : (m, 3) int64
        The same triangles (none removed, even if one becomes degenerate).

    Notes
    -----
    Positions are compared after rounding to 8 decimals, trimesh's merge tolerance, and
    only positions count: normals and UVs are ignored, so UV seams close.
    """
    from meshcol._native import core

    vertices = np.ascontiguousarray(vertices, dtype=np.float64).reshape(-1, 3)
    faces = np.ascontiguousarray(faces, dtype=np.int64).reshape(-1, 3)
    return core.merge_vertices(vertices, faces, _MERGE_DIGITS)
