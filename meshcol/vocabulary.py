"""The words every floor of meshcol shares, defined once.

Data only: this module imports nothing of meshcol's and may be imported from anywhere (like
``types`` and ``errors``). A list that two modules need lives here; the modules import it.
Adding a word (a collider kind, a limit key) starts here, and the recipes in ARCHITECTURE.md
say which one registry then maps it to its code. (Report formats are not here: their one list
is the registry that maps each to its writer, ``meshcol.io.formats.FORMATS``.)
"""

from __future__ import annotations

__all__ = [
    "COLLIDER_KINDS",
    "COUNT_LIMITS",
    "HALF_SPACE_COLLIDER",
    "INPUT_KINDS",
    "LIMITS",
    "LIMIT_KEYS",
    "MANIFEST_EXTENSIONS",
    "MATRIX_COLLIDERS",
    "PAIR_STATUSES",
    "ROBOT_EXTENSIONS",
    "SCENE_SHAPES",
    "SEVERITY_ORDER",
    "URDF_CAPSULES",
]

# -- colliders --------------------------------------------------------------------------------

#: Collider kinds a body can be checked as (``--shape``): builders in
#: :mod:`meshcol.analysis.colliders` (``box`` and ``sphere``: each part's enclosing oriented
#: box or minimum sphere, the simple colliders engines offer and USD's ``boundingCube`` and
#: ``boundingSphere`` approximations).
COLLIDER_KINDS = ("hull", "decomposed", "mesh", "fit", "box", "sphere")
#: The collider kind reported for the body of an MJCF plane (``<geom type="plane">``), the
#: half-space below it, measured exactly against every body (not a ``--shape`` choice).
HALF_SPACE_COLLIDER = "plane"
#: The collider kinds a scene manifest may name per body (``"shape"``).
SCENE_SHAPES = ("hull", "decomposed", "mesh")
#: The collider kinds of a robot's self-collision matrix (``mesh`` needs the exact mesh
#: queries, which are not batched over configurations).
MATRIX_COLLIDERS = ("hull", "decomposed", "fit")

#: How a URDF written (``--to urdf``) holds a capsule (``--urdf-capsules``): ``standard``, a
#: ``<cylinder>`` and two ``<sphere>`` elements, the same solid in elements every URDF reader
#: knows (urdfdom and so ROS, yourdfpy); ``extension``, one ``<capsule radius length>``, which
#: only pybullet and MuJoCo's importer read (:mod:`meshcol.io.urdf_write`).
URDF_CAPSULES = ("standard", "extension")

# -- engine targets ---------------------------------------------------------------------------

#: Every limit key of a target's ``[limits]``, in the order reports list them: its rule id and
#: rule name (stable forever; the rule's text is in ``meshcol.analysis.rules``) and its
#: column header in ``meshcol targets``.
LIMITS: dict[str, tuple[str, str, str]] = {
    "max_hull_vertices": ("MC101", "hull-vertices-over-limit", "vertices"),
    "max_hull_polygons": ("MC103", "hull-polygons-over-limit", "polygons"),
    "max_hull_triangles": ("MC104", "hull-triangles-over-limit", "triangles"),
    "max_faces_per_vertex": ("MC105", "faces-per-vertex-over-limit", "per vertex"),
    "max_hulls": ("MC106", "hull-count-over-limit", "hulls"),
    "max_oblong_ratio": ("MC102", "not-gpu-compatible-oblong", "oblong"),
    "min_thickness": ("MC107", "part-too-thin", "thickness m"),
    "min_volume": ("MC201", "volume-too-small", "volume m3"),
}
#: The limit keys alone, in that order.
LIMIT_KEYS = tuple(LIMITS)
#: Limits that count something (integers >= 1).
COUNT_LIMITS = (
    "max_hull_vertices",
    "max_hull_polygons",
    "max_hull_triangles",
    "max_faces_per_vertex",
    "max_hulls",
)

# -- inputs -----------------------------------------------------------------------------------

#: What a command's input path can be.
INPUT_KINDS = ("mesh", "manifest", "robot")
#: File extensions (lower case) of scene manifests.
MANIFEST_EXTENSIONS = (".json", ".toml")
#: File extensions (lower case) of robot descriptions (URDF, MJCF).
ROBOT_EXTENSIONS = (".urdf", ".mjcf", ".xml")

# -- results ----------------------------------------------------------------------------------

#: A checked pair's status, from the mildest to the worst. ``undecided``: the surfaces meet or
#: may nest, and neither the winding number nor ray parity decides inside from outside (a
#: non-orientable mesh), so the pair is at least in contact and at most ``depth_upper`` deep.
PAIR_STATUSES = ("separated", "clearance", "contact", "undecided", "penetrating", "contained")
#: The same, worst first (the order review pages and summaries list pairs in).
SEVERITY_ORDER = tuple(reversed(PAIR_STATUSES))
