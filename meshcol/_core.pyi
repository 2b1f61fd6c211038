"""meshcol native core (private: use the meshcol package API)"""

from collections.abc import Sequence
import enum
from typing import Annotated, TypeVar

import numpy
from numpy.typing import NDArray


class defaults:
    """Defaults and caps of the core (cpp/include/meshcol/defaults.inc)."""

    rigid_tolerance: float = 1e-06

    min_pairs_per_thread: int = 64

    min_shapes_per_thread: int = 256

    min_points_per_thread: int = 64

    triangle_min_pairs_per_thread: int = 4096

    self_intersection_max_work: int = 1000000000

    self_intersection_slow_cost: int = 3

    self_intersection_exact_cost: int = 12

    self_intersection_max_kept_pairs: int = 100000

    self_intersection_block_pairs: int = 65536

    hill_climbing_min_vertices: int = 32

    width_plateau_relative: float = 1e-12

    prefetch_max_vertices: int = 512

    climb_prefetch_min_vertices: int = 128

    gjk_max_iterations: int = 128

    support_warm_start_min_cosine: float = 0.5

    gjk_flat_tetrahedron_volume: float = 1e-14

    gjk_relative_tolerance: float = 1e-13

    contact_tolerance: float = 1e-14

    epa_max_iterations: int = 250

    epa_max_vertices: int = 256

    epa_blow_up_enough: float = 0.5

    epa_touching_supports: int = 6

    epa_touching_max_weight: float = 1e-08

    epa_deep_start_depth: float = 0.05

    epa_deep_start_spread: float = 0.65

    epa_relative_tolerance: float = 1e-12

    epa_absolute_tolerance_ratio: float = 0.01

    epa_min_squared_length: float = 1e-300

    epa_curved_relative_tolerance: float = 1e-07

    sat_max_work: int = 40000

    sat_edge_class_prefix: int = 8

    sat_parallel_edge_sine: float = 1e-09

    sat_arc_crossing_margin: float = 1e-09

    sat_arc_plane_tolerance: float = 1e-09

    sat_arc_pair_cost: int = 8

    sat_agreement_relative_depth: float = 1e-09

    sat_agreement_normal_cosine: float = 1e-09

    broadphase_min_boxes_per_thread: int = 20000

    sort_and_sweep_cell_extent_ratio: float = 2.0

    sort_and_sweep_max_cells_per_axis: int = 1024

    sort_and_sweep_min_boxes_per_cell: int = 16

    sort_and_sweep_max_entries_per_box: float = 3.0

    sort_and_sweep_min_candidates_for_grid: float = 16.0

    sort_and_sweep_max_shifts_per_box: int = 32

    sort_and_sweep_max_cell_changes: float = 0.25

    tree_bin_count: int = 32

    tree_max_height_imbalance: int = 2

    tree_max_objects: int = 1000000000

    toi_tolerance: float = 1e-06

    toi_max_iterations: int = 1000

    toi_min_pairs_per_thread: int = 8

    mesh_bvh_leaf_size: int = 4

    mesh_bvh_bins: int = 16

    mesh_min_pairs_per_thread: int = 4

    winding_number_inside: float = 0.5

    mesh_depth_max_work: int = 200000000

    mesh_depth_max_near_pairs: int = 24000000

    mesh_contacts_max_work: int = 200000000

    flat_relative_tolerance: float = 1e-09

    hull_relative_tolerance: float = 1e-14

    hull_max_abs_coordinate: float = 1e+100

    hull_max_reruns: int = 3

    hull_max_rerun_work: float = 50000000.0

    hull_min_shapes_per_thread: int = 16

    hull_min_filter_points_per_thread: int = 131072

    fit_containment_margin: float = 1e-09

    fit_box_normals: int = 200

    fit_ball_seed: int = 1835365224

    fit_ball_max_work_per_point: int = 4096

    fit_box_polish_step: float = 0.05

    fit_box_polish_iterations: int = 200

    fit_box_polish_smallest: float = 1e-07

    fit_box_polish_starts: int = 3

    fit_axis_polish_step: float = 0.05

    fit_axis_polish_iterations: int = 100

    fit_axis_polish_smallest: float = 1e-05

    fit_axis_polish_starts: int = 3

    fit_capsule_radius_grid: int = 33

    fit_capsule_golden_steps: int = 40

    fit_capsule_bound_pieces: int = 24

    fit_ellipsoid_tolerance: float = 1e-06

    fit_ellipsoid_max_iterations: int = 100000

    fit_min_sets_per_thread: int = 1

    max_mesh_file_bytes: int = 4294967296

    inscribed_ball_steps_per_plane: int = 8

    inscribed_ball_zero: float = 1e-12

    inscribed_ball_max_stages: int = 8

    inscribed_ball_min_planes_per_thread: int = 4096

def hardware_threads() -> int:
    """Number of hardware threads (at least 1)."""

class Status(enum.Enum):
    """Outcome of a pair query (status.hpp)."""

    CONVERGED = 0

    MAX_ITERATIONS = 1

    DEGENERATE = 2

    INVALID_INPUT = 3

    NOT_RUN = 4

    OUT_OF_RANGE = 5

class TimeOfImpactStatus(enum.Enum):
    """Outcome of a time-of-impact query (status.hpp)."""

    HIT = 0

    SEPARATED = 1

    OVERLAPPED_AT_START = 2

    FAILED = 3

    INVALID_INPUT = 4

class ShapeKind(enum.Enum):
    """Kind of a packed convex shape (shapes.hpp)."""

    POLYTOPE = 0

    SPHERE = 1

    BOX = 2

    CAPSULE = 3

    CYLINDER = 4

    ELLIPSOID = 5

    HALFSPACE = 6

def shape_pair_object(layout: int, kind_a: int, a: object, kind_b: int, b: object, pose_a: object | None, pose_b: object | None, result_type: object | None, statuses: object) -> object:
    """
    One pair of shapes (primitives, or (n, 3) points by their hull; kind_a, kind_b their ShapeKind) as its single-pair result (layout as query_object; for intersects a bool); None when a shape or pose is not in the core's form, or for an invalid intersects pair.
    """

class PackSeal:
    """
    pack_polytopes' word for its own index arrays (PackedConvexSet skips reading them again when handed them in its layout).
    """

class PackedConvexSet:
    """
    Packed convex shapes (the arrays of meshcol.collision.shapes.ConvexSet).
    """

    def __init__(self, vertices: Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C', device='cpu', writable=False)], offsets: Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C', device='cpu', writable=False)], kinds: Annotated[NDArray[numpy.int8], dict(shape=(None,), order='C', device='cpu', writable=False)], params: Annotated[NDArray[numpy.float64], dict(shape=(None, 4), order='C', device='cpu', writable=False)], adjacency_offsets: Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C', device='cpu', writable=False)] | None, adjacency: Annotated[NDArray[numpy.int32], dict(shape=(None,), order='C', device='cpu', writable=False)] | None, face_offsets: Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C', device='cpu', writable=False)] | None, face_normals: Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C', device='cpu', writable=False)] | None, edge_pair_offsets: Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C', device='cpu', writable=False)] | None, edge_pairs: Annotated[NDArray[numpy.int32], dict(shape=(None, 2), order='C', device='cpu', writable=False)] | None, seal: PackSeal | None = None, climb_list_offsets: Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C', device='cpu', writable=False)] | None = None, climb_lists: Annotated[NDArray[numpy.uint8], dict(shape=(None, 16), order='C', device='cpu', writable=False)] | None = None) -> None: ...

    def __len__(self) -> int: ...

    @property
    def sealed(self) -> bool:
        """Whether the seal vouched for the index arrays (not read again)."""

    def query_object(self, layout: int, poses: object | None, pairs: object | None, threads: int, result_type: object) -> object:
        """
        One batch as result_type (layout 0 distance, 1 penetration, 2 intersects, 3 signed distance); None when poses or pairs are not in the core's form.
        """

    def climb_arrays(self) -> tuple[object, object]:
        """
        The climb lists the core makes from the set's adjacency, as new arrays (not the set's): offsets (H + 1,) int64 and (M, 16) uint8 rows (count, then 15 neighbour slots).
        """

    def aabbs(self, poses: Annotated[NDArray[numpy.float64], dict(shape=(None, 4, 4), order='C', device='cpu', writable=False)] | None, threads: int = 0) -> tuple[Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C')], Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C')]]:
        """World AABBs (H, 3), (H, 3) under poses (None: identity)."""

    def edge_classes(self, threads: int = 0) -> tuple[Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C')], Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C')]]:
        """
        Every shape's edge-direction classes, each computed at most once in the set's life (SAT shares them): offsets (H + 1,) int64 and unit directions (E, 3).
        """

    def bounding_radii(self, threads: int = 0) -> Annotated[NDArray[numpy.float64], dict(shape=(None,), order='C')]:
        """
        Radius (H,) of a ball about each shape's local origin holding the whole shape; NaN for an invalid shape.
        """

def sort_and_sweep(aabb_min: Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C', device='cpu', writable=False)], aabb_max: Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C', device='cpu', writable=False)], axis: int = -1, threads: int = 0, groups: Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C', device='cpu', writable=False)] | None = None, max_pairs: int = -1) -> Annotated[NDArray[numpy.int64], dict(shape=(None, 2), order='C')] | None:
    """
    Overlapping pairs (K, 2) int64, i < j, sorted; axis -1 chooses by variance; boxes of one group (groups: (N,) int64) never pair; None when there are more than max_pairs (>= 0) pairs, found without holding them all.
    """

def choose_sweep_axis(aabb_min: Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C', device='cpu', writable=False)], aabb_max: Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C', device='cpu', writable=False)]) -> int:
    """The axis of largest variance of the box centres."""

class SortAndSweep:
    """Incremental sort and sweep."""

    def __init__(self, aabb_min: Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C', device='cpu', writable=False)], aabb_max: Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C', device='cpu', writable=False)], axis: int = -1, threads: int = 0) -> None: ...

    def pairs(self) -> Annotated[NDArray[numpy.int64], dict(shape=(None, 2), order='C', writable=False)]: ...

    def update(self, aabb_min: Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C', device='cpu', writable=False)], aabb_max: Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C', device='cpu', writable=False)]) -> Annotated[NDArray[numpy.int64], dict(shape=(None, 2), order='C', writable=False)]: ...

    @property
    def axis(self) -> int: ...

    @property
    def last_shifts(self) -> int: ...

    def __len__(self) -> int: ...

class AabbTree:
    """Dynamic AABB tree (Box2D v3 style)."""

    def __init__(self, margin: float = 0.0) -> None: ...

    def insert(self, aabb_min: Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C', device='cpu', writable=False)], aabb_max: Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C', device='cpu', writable=False)]) -> Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C')]: ...

    def remove(self, ids: Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C', device='cpu', writable=False)]) -> None: ...

    def move(self, ids: Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C', device='cpu', writable=False)], aabb_min: Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C', device='cpu', writable=False)], aabb_max: Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C', device='cpu', writable=False)]) -> Annotated[NDArray[numpy.bool_], dict(shape=(None,), order='C')]: ...

    def clear(self) -> None: ...

    def build(self, aabb_min: Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C', device='cpu', writable=False)], aabb_max: Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C', device='cpu', writable=False)], threads: int = 0) -> None: ...

    def rebuild(self, threads: int = 0) -> None: ...

    def query(self, aabb_min: Annotated[NDArray[numpy.float64], dict(shape=(3), order='C', device='cpu', writable=False)], aabb_max: Annotated[NDArray[numpy.float64], dict(shape=(3), order='C', device='cpu', writable=False)]) -> Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C')]: ...

    def query_pairs(self, threads: int = 0) -> Annotated[NDArray[numpy.int64], dict(shape=(None, 2), order='C')]: ...

    def query_pairs_with(self, other: AabbTree, threads: int = 0) -> Annotated[NDArray[numpy.int64], dict(shape=(None, 2), order='C')]: ...

    def ray_cast(self, origin: Annotated[NDArray[numpy.float64], dict(shape=(3), order='C', device='cpu', writable=False)], direction: Annotated[NDArray[numpy.float64], dict(shape=(3), order='C', device='cpu', writable=False)], max_fraction: float = 1.0) -> tuple[Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C')], Annotated[NDArray[numpy.float64], dict(shape=(None,), order='C')]]: ...

    def validate(self) -> None: ...

    @property
    def height(self) -> int: ...

    @property
    def margin(self) -> float: ...

    @property
    def area_ratio(self) -> float: ...

    def __len__(self) -> int: ...

def shape_pair_toi_object(kind_a: int, a: object, kind_b: int, b: object, start_pose_a: object | None, end_pose_a: object | None, start_pose_b: object | None, end_pose_b: object | None, tolerance: float, max_iterations: int, result_type: object, statuses: object) -> object:
    """
    Time of impact of one pair of shapes (primitives, or (n, 3) points by their hull; each turning the shortest way about its origin) as result_type; None when a shape or pose is not in the core's form.
    """

def time_of_impact_object(shapes: PackedConvexSet, start_poses: object | None, end_poses: object | None, pairs: object | None, rotations: object | None, pivots: object | None, tolerance: float, max_iterations: int, threads: int, result_type: object) -> object:
    """
    Time of impact of the (P, 2) pairs of a PackedConvexSet's shapes moving from start_poses to end_poses ((H, 4, 4) each), turning by the world rotation vectors rotations (H, 3; None: the shortest rotation) about the world points pivots (H, 3; None: the local origins), as result_type; None when an argument is not in the core's form.
    """

def interpolate_poses(start_poses: Annotated[NDArray[numpy.float64], dict(shape=(None, 4, 4), order='C', device='cpu', writable=False)], end_poses: Annotated[NDArray[numpy.float64], dict(shape=(None, 4, 4), order='C', device='cpu', writable=False)], t: Annotated[NDArray[numpy.float64], dict(shape=(None,), order='C', device='cpu', writable=False)], rotations: Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C', device='cpu', writable=False)] | None = None, pivots: Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C', device='cpu', writable=False)] | None = None) -> Annotated[NDArray[numpy.float64], dict(shape=(None, 4, 4), order='C')]:
    """
    Poses (N, 4, 4) at times t (N,) of the motions start -> end (the pivot moves linearly, the body turns about it by the rotation vector, any angle).
    """

def shortest_rotations(start_poses: Annotated[NDArray[numpy.float64], dict(shape=(None, 4, 4), order='C', device='cpu', writable=False)], end_poses: Annotated[NDArray[numpy.float64], dict(shape=(None, 4, 4), order='C', device='cpu', writable=False)]) -> Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C')]:
    """
    World rotation vectors (N, 3), angle in [0, pi], of the shortest rotations taking each start pose's rotation to its end pose's.
    """

ResultT = TypeVar("ResultT")

class MeshBvhSet:
    """
    Bounding volume hierarchies of M triangle meshes, built once (mesh_bvh.hpp).
    """

    def __init__(self, vertices: Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C', device='cpu', writable=False)], faces: Annotated[NDArray[numpy.int64], dict(shape=(None, 3), order='C', device='cpu', writable=False)], vertex_offsets: Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C', device='cpu', writable=False)], face_offsets: Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C', device='cpu', writable=False)], threads: int = 0) -> None:
        """
        Builds every mesh's hierarchy. vertices (V, 3) local frames; faces (F, 3) indices local to each mesh's vertex block; offsets (M + 1,).
        """

    def __len__(self) -> int: ...

    def valid(self, i: int) -> bool:
        """Whether mesh i has finite vertices and at least one face."""

    def closed(self, i: int) -> bool:
        """
        Whether mesh i is a closed, consistently wound surface (MeshBvh::closed).
        """

    def node_count(self, i: int) -> int: ...

    def distinct_count(self) -> int:
        """
        Hierarchies built: one per distinct mesh (meshes of the same vertex and face bytes share one).
        """

    def validate(self) -> bool:
        """Checks every hierarchy's invariants (for tests)."""

    def winding_number(self, i: int, points: Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C', device='cpu', writable=False)]) -> Annotated[NDArray[numpy.float64], dict(shape=(None,), order='C')]:
        """Generalized winding numbers of points (mesh i's local frame)."""

    def fast_winding_number(self, i: int, points: Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C', device='cpu', writable=False)], max_error: float) -> tuple[Annotated[NDArray[numpy.float64], dict(shape=(None,), order='C')], Annotated[NDArray[numpy.float64], dict(shape=(None,), order='C')], Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C')]]:
        """
        Fast winding numbers of points (mesh i's local frame) with their error bounds and work.
        """

    def winding_number_inside(self, i: int, points: Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C', device='cpu', writable=False)]) -> tuple[Annotated[NDArray[numpy.bool_], dict(shape=(None,), order='C')], Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C')]]:
        """
        Whether |winding number| >= winding_number_inside for points (mesh i's local frame), by the refined fast winding number, with the nodes and triangles visited.
        """

    def closest_points(self, i: int, points: Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C', device='cpu', writable=False)], threads: int = 0) -> tuple[Annotated[NDArray[numpy.float64], dict(shape=(None,), order='C')], Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C')], Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C')]]:
        """
        Exact distances (N,), closest surface points (N, 3) and faces (N,) of points (N, 3) to mesh i (its local frame); NaN and -1 for a non-finite point or an invalid mesh.
        """

    def largest_distance_batch(self, meshes: Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C', device='cpu', writable=False)], points: Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C', device='cpu', writable=False)], point_offsets: Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C', device='cpu', writable=False)], threads: int = 0) -> dict:
        """
        Item k: the largest distance from points[point_offsets[k]:point_offsets[k + 1]] (mesh meshes[k]'s local frame) to that mesh's surface, the maximum of closest_points' distances bit for bit, by a search pruned at the largest found: {distance, point (index in the item's block), status}; items on threads.
        """

    def largest_distance_to_patches_batch(self, meshes: Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C', device='cpu', writable=False)], patch_map: Annotated[NDArray[numpy.int8], dict(shape=(None,), order='C', device='cpu', writable=False)], patch_nodes: Annotated[NDArray[numpy.int64], dict(shape=(None, 2), order='C', device='cpu', writable=False)], patch_numbers: Annotated[NDArray[numpy.float64], dict(shape=(None, 13), order='C', device='cpu', writable=False)], patch_offsets: Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C', device='cpu', writable=False)], threads: int = 0) -> dict:
        """
        Item k: the largest distance from the grid nodes of patches [patch_offsets[k], patch_offsets[k + 1]) (SurfacePatch: map (P,) int8, nodes (P, 2) n_u, n_v, numbers (P, 13) g[9], v0, v1, lu, lv) to mesh meshes[k], the maximum over every node by a search that skips the blocks that cannot raise it: {distance, point (the node, counted patch after patch), status}; items on threads.
        """

    def set_poses(self, poses: Annotated[NDArray[numpy.float64], dict(shape=(None, 4, 4), order='C', device='cpu', writable=False)]) -> None:
        """
        Sets the default poses (M, 4, 4) that queries with poses=None use (read and checked for rigidity once).
        """

    def intersects_pair(self, i: int, j: int, pose_i: object | None = None, pose_j: object | None = None) -> bool:
        """
        Whether meshes i and j intersect, at the default poses or the given (4, 4) ones (read in place when C-contiguous float64, else converted); ValueError when a pose is not (4, 4) or the pair has no verdict (invalid mesh or pose, out of range).
        """

    def distance_batch(self, poses: object | None, pairs: object, threads: int, max_distance: float, result_type: type[ResultT]) -> ResultT | None:
        """
        Mesh-pair distances as result_type(distance, point_a, point_b, intersecting, a_inside_b, b_inside_a, triangle_a, triangle_b, status); None when poses or pairs are not in the form intersects_batch reads in place (convert them and call again).
        """

    def depth_batch(self, poses: Annotated[NDArray[numpy.float64], dict(shape=(None, 4, 4), order='C', device='cpu', writable=False)] | None, pairs: Annotated[NDArray[numpy.int64], dict(shape=(None, 2), order='C', device='cpu', writable=False)], threads: int = 0) -> dict:
        """
        Mesh-pair penetration depths (lower bounds of the minimum translation distance): {depth, point_a, point_b, normal, deepest_mesh, points_tested, status}.
        """

    def contacts_batch(self, poses: Annotated[NDArray[numpy.float64], dict(shape=(None, 4, 4), order='C', device='cpu', writable=False)] | None, pairs: Annotated[NDArray[numpy.int64], dict(shape=(None, 2), order='C', device='cpu', writable=False)], threads: int = 0, max_contacts: int = 0, max_work: int = 200000000) -> dict:
        """
        Mesh-pair contacts (every crossing triangle pair, its own penetration): {count, depth, normal, point, face_depth, triangle_a, triangle_b, status} of the deepest, and up to max_contacts listed contacts a pair: {contact_offsets, contact_depth, contact_normal, contact_point, contact_face_depth, contact_triangle_a, contact_triangle_b}.
        """

    def ray_cast_batch(self, meshes: Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C', device='cpu', writable=False)], origins: Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C', device='cpu', writable=False)], directions: Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C', device='cpu', writable=False)], poses: Annotated[NDArray[numpy.float64], dict(shape=(None, 4, 4), order='C', device='cpu', writable=False)] | None, max_distance: float = float('inf'), threads: int = 0) -> dict:
        """
        First hits of rays (world frame) on meshes[k]: {hit, distance, point, normal, triangle, status}.
        """

    def intersects_batch(self, poses: object | None, pairs: object, threads: int, result_type: type[ResultT]) -> ResultT | None:
        """
        Mesh-pair surface intersection tests as result_type(intersecting, status); None when poses is not None or a C-contiguous (M, 4, 4) float64 array, or pairs not a C-contiguous (P, 2) int64 array or a non-empty list of (i, j) Python ints (convert them and call again).
        """

def patch_points(patch_map: Annotated[NDArray[numpy.int8], dict(shape=(None,), order='C', device='cpu', writable=False)], patch_nodes: Annotated[NDArray[numpy.int64], dict(shape=(None, 2), order='C', device='cpu', writable=False)], patch_numbers: Annotated[NDArray[numpy.float64], dict(shape=(None, 13), order='C', device='cpu', writable=False)]) -> Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C')]:
    """
    The grid nodes (P, 3) of surface patches (as largest_distance_to_patches_batch takes them), patch after patch, row by row (i, then j).
    """

def triangle_distance_batch(a: Annotated[NDArray[numpy.float64], dict(shape=(None, 3, 3), order='C', device='cpu', writable=False)], b: Annotated[NDArray[numpy.float64], dict(shape=(None, 3, 3), order='C', device='cpu', writable=False)]) -> tuple[Annotated[NDArray[numpy.float64], dict(shape=(None,), order='C')], Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C')], Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C')], Annotated[NDArray[numpy.bool_], dict(shape=(None,), order='C')]]:
    """
    Exact distances of triangle pairs a[k], b[k] (n, 3, 3): (distance, point_a, point_b, intersecting).
    """

def read_mesh_files(paths: Sequence[str], formats: Sequence[int], merge: bool = True, threads: int = 0) -> tuple[Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C')], Annotated[NDArray[numpy.int32], dict(shape=(None, 3), order='C')], Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C')], Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C')], Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C')], list, Annotated[NDArray[numpy.int8], dict(shape=(None,), order='C')], list, Annotated[NDArray[numpy.float64], dict(shape=(None,), order='C')]]:
    """
    Reads OBJ (format 0) and STL (format 1) files in parallel. Returns (vertices (V, 3), faces (F, 3) int32 local to each object, vertex_offsets (O + 1,), face_offsets (O + 1,), object_file (O,), object names (bytes), status (N,) int8 per file (0 read, 1 not found, 2 a directory, 3 unreadable, 4 corrupt), one message per file ('' when read), the largest |coordinate| of each object (O,), 0 without vertices).
    """

def file_identities(paths: Sequence[str], threads: int = 0) -> tuple[Annotated[NDArray[numpy.uint64], dict(shape=(None,), order='C')], Annotated[NDArray[numpy.uint64], dict(shape=(None,), order='C')], Annotated[NDArray[numpy.uint8], dict(shape=(None,), order='C')]]:
    """
    Device and inode of each path, symbolic links followed, stat'ed in parallel. Returns (device (N,) uint64, inode (N,) uint64, found (N,) uint8: 0 where stat fails).
    """

def point_set_fingerprints(points: Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C', device='cpu', writable=False)], offsets: Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C', device='cpu', writable=False)], threads: int = 0) -> Annotated[NDArray[numpy.uint64], dict(shape=(None,), order='C')]:
    """
    The fingerprint (uint64) of each point set packed in points (V, 3), set s being rows offsets[s]:offsets[s + 1]: see meshcol/point_sets.hpp (bulk colliders find repeats with it, then compare the bits).
    """

def merge_vertices(vertices: Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C', device='cpu', writable=False)], faces: Annotated[NDArray[numpy.int64], dict(shape=(None, 3), order='C', device='cpu', writable=False)], digits: int = 8) -> tuple[Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C')], Annotated[NDArray[numpy.int64], dict(shape=(None, 3), order='C')]]:
    """
    Merges vertices equal after rounding to `digits` decimals (trimesh's rule), drops unused ones, renumbers faces. Returns (vertices, faces).
    """

def self_intersecting_pairs(vertices: Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C', device='cpu', writable=False)], faces: Annotated[NDArray[numpy.int64], dict(shape=(None, 3), order='C', device='cpu', writable=False)], max_work: int = 1000000000, slow_cost: int = 3, exact_cost: int = 12, max_kept_pairs: int = 100000, block_pairs: int = 65536, threads: int = 0) -> tuple[Annotated[NDArray[numpy.int64], dict(shape=(None, 2), order='C')], int, int, int, bool]:
    """
    Crossing face pairs of a mesh, streamed from the sweep of the face boxes into the exact test: (pairs (K, 2) int64 i < j sorted, at most max_kept_pairs (< 0: all); crossing count; candidate pairs decided; work units spent; complete). At most max_work (< 0: no budget) units are spent (one per candidate, slow_cost per orientation past its filter, exact_cost more per exact one): past it complete is False and the count a lower bound.
    """

def mesh_topology_batch(faces: Annotated[NDArray[numpy.int64], dict(shape=(None, 3), order='C', device='cpu', writable=False)], face_offsets: Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C', device='cpu', writable=False)], vertex_offsets: Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C', device='cpu', writable=False)], threads: int = 0) -> tuple[Annotated[NDArray[numpy.int64], dict(shape=(None, 5), order='C')], Annotated[NDArray[numpy.bool_], dict(shape=(None,), order='C')], Annotated[NDArray[numpy.bool_], dict(shape=(None,), order='C')], Annotated[NDArray[numpy.bool_], dict(shape=(None,), order='C')], Annotated[NDArray[numpy.int8], dict(shape=(None,), order='C')]]:
    """
    Topology of each mesh of a batch (mesh i: faces[face_offsets[i]:face_offsets[i + 1]], indices into its own vertices, vertex_offsets[i + 1] - vertex_offsets[i] of them): (counts (n, 5) int64: boundary, non-manifold and inconsistently wound edges, duplicate faces, connected pieces; closed (n,) bool; balanced (n,) bool, of the faces without a repeated corner; used (V,) bool per vertex; status (n,) int8, 1 when a face index is out of its mesh's range and nothing was counted).
    """

def face_heights(vertices: Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C', device='cpu', writable=False)], faces: Annotated[NDArray[numpy.int64], dict(shape=(None, 3), order='C', device='cpu', writable=False)], threads: int = 0) -> tuple[Annotated[NDArray[numpy.float64], dict(shape=(None,), order='C')], Annotated[NDArray[numpy.bool_], dict(shape=(None,), order='C')]]:
    """
    Per face: (height on its longest edge (F,) float64, 0 when that edge has length 0; names a vertex twice (F,) bool), the bits of numpy's face_heights.
    """

def face_pairs_cross(vertices: Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C', device='cpu', writable=False)], faces: Annotated[NDArray[numpy.int64], dict(shape=(None, 3), order='C', device='cpu', writable=False)], pairs: Annotated[NDArray[numpy.int64], dict(shape=(None, 2), order='C', device='cpu', writable=False)], threads: int = 0) -> Annotated[NDArray[numpy.bool_], dict(shape=(None,), order='C')]:
    """Per face pair (K,) bool: the open triangles share a point (exact)."""

class HullStatus(enum.Enum):
    """What a point set's hull is (hull.hpp)."""

    OK = 0

    FLAT = 1

    COLLINEAR = 2

    SINGLE_POINT = 3

    EMPTY = 4

    NON_FINITE = 5

    OVERFLOW = 6

    FAILED = 7

def exact_hull(points: Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C', device='cpu', writable=False)]) -> tuple[int, int, Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C')], Annotated[NDArray[numpy.int64], dict(shape=(None, 3), order='C')], Annotated[NDArray[numpy.float64], dict(shape=(None, 4), order='C')], Annotated[NDArray[numpy.float64], dict(shape=(3), order='C')], float, float, float]:
    """
    Exact convex hull of (n, 3) points: (status, dimension, vertex indices (k,), faces (m, 3) into the vertices, equations (m, 4), normal (3,), volume, area, diagonal).
    """

def pack_polytopes(points: Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C', device='cpu', writable=False)], offsets: Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C', device='cpu', writable=False)], threads: int = 0) -> tuple[Annotated[NDArray[numpy.int8], dict(shape=(None,), order='C')], Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C')], Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C')], Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C')], Annotated[NDArray[numpy.int32], dict(shape=(None,), order='C')], Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C')], Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C')], Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C')], Annotated[NDArray[numpy.int32], dict(shape=(None, 2), order='C')], Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C')], Annotated[NDArray[numpy.uint8], dict(shape=(None, 16), order='C')], object]:
    """
    Hulls of H point sets (shape h owns points[offsets[h]:offsets[h + 1]]) packed for a ConvexSet: (status (H,), vertices, offsets, adjacency_offsets, adjacency, face_offsets, face_normals, edge_pair_offsets, edge_pairs, climb_list_offsets, climb_lists, seal); the seal, passed to PackedConvexSet with these arrays, spares it reading their indices again.
    """

def inscribed_balls(planes: Annotated[NDArray[numpy.float64], dict(shape=(None, 4), order='C', device='cpu', writable=False)], offsets: Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C', device='cpu', writable=False)], threads: int = 0) -> tuple[Annotated[NDArray[numpy.int8], dict(shape=(None,), order='C')], Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C')], Annotated[NDArray[numpy.float64], dict(shape=(None,), order='C')]]:
    """
    In-sphere of H polytopes {x : n . x + d <= 0}, polytope h owning the unit-normal planes (n_x, n_y, n_z, d) planes[offsets[h]:offsets[h + 1]] (P, 4): (status (H,) int8 Status codes, centres (H, 3), radii (H,)); the Chebyshev centre's linear programme by an active-set simplex (inscribed_ball.hpp).
    """

def hull_widths(vertices: Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C', device='cpu', writable=False)], faces: Annotated[NDArray[numpy.int64], dict(shape=(None, 3), order='C', device='cpu', writable=False)], directions: Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C', device='cpu', writable=False)]) -> Annotated[NDArray[numpy.float64], dict(shape=(None,), order='C')]:
    """
    Width of a 3-D polytope (vertices (k, 3), triangles faces (m, 3)) across each of the directions (n, 3): the largest minus the smallest vertex projection fma(d.z, p.z, fma(d.y, p.y, d.x * p.x)), by support climbs; (n,) float64.
    """

def distances_to_facets(points: Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C', device='cpu', writable=False)], facets: Annotated[NDArray[numpy.float64], dict(shape=(None, 3, 3), order='C', device='cpu', writable=False)], in_front: Annotated[NDArray[numpy.bool_], dict(shape=(None, None), order='C', device='cpu', writable=False)]) -> tuple[Annotated[NDArray[numpy.float64], dict(shape=(None,), order='C')], Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C')]]:
    """
    Distance (q,) and closest point (q, 3) from each point (q, 3) to a convex polytope, searching the facets (m, 3, 3) in_front (q, m) marks for it (none: 0 and the point itself); numpy's arithmetic of closest_points_on_triangles, step for step.
    """

def budget_hull_planes(hull_vertices: Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C', device='cpu', writable=False)], vertex_offsets: Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C', device='cpu', writable=False)], facets: Annotated[NDArray[numpy.float64], dict(shape=(None, 3, 3), order='C', device='cpu', writable=False)], equations: Annotated[NDArray[numpy.float64], dict(shape=(None, 4), order='C', device='cpu', writable=False)], facet_offsets: Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C', device='cpu', writable=False)], starts: Annotated[NDArray[numpy.float64], dict(shape=(None, 4), order='C', device='cpu', writable=False)], budgets: Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C', device='cpu', writable=False)], max_planes: Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C', device='cpu', writable=False)], converged_distances: Annotated[NDArray[numpy.float64], dict(shape=(None,), order='C', device='cpu', writable=False)], merge_distances: Annotated[NDArray[numpy.float64], dict(shape=(None,), order='C', device='cpu', writable=False)], candidates: int, threads: int = 0) -> tuple[Annotated[NDArray[numpy.float64], dict(shape=(None, 4), order='C')], Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C')], Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C')], Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C')], Annotated[NDArray[numpy.int8], dict(shape=(None,), order='C')]]:
    """
    The budgeted hull's cut loop for B bodies (body i: exact hull vertices hull_vertices[vertex_offsets[i]:vertex_offsets[i + 1]], facets (m, 3, 3) and their outward planes (m, 4) by facet_offsets, start tetrahedron starts[4i:4i + 4] as (n, offset), budgets, max_planes (-1: none), tolerances): (planes (P, 4) as (n, offset), plane_offsets (B + 1,), the final polytopes' vertices (V, 3) and polytope_offsets (B + 1,), status (B,): 0 ok, 1 a degenerate start).
    """

def clip_planes(planes: Annotated[NDArray[numpy.float64], dict(shape=(None, 4), order='C', device='cpu', writable=False)], merge_distance: float) -> tuple[bool, Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C')]]:
    """
    The polytope {x : n . x <= offset} of planes (P, 4) as (n, offset): the tetrahedron of the first four, clipped by each further plane in turn (near-duplicate vertices merged within merge_distance): (ok, vertices (V, 3)); ok False when a clip left nothing or the first four bound no tetrahedron.
    """

class FitStatus(enum.Enum):
    """Outcome of one enclosing fit (fit.hpp)."""

    OK = 0

    MAX_ITERATIONS = 1

    INVALID_INPUT = 2

    FAILED = 3

def minimum_ball(points: Annotated[NDArray[numpy.float64], dict(shape=(None, None), order='C', device='cpu', writable=False)]) -> tuple[Annotated[NDArray[numpy.float64], dict(shape=(None,), order='C')], float, bool]:
    """
    Smallest ball of (n, d) points, d <= 3 (Welzl): (centre (d,), radius, converged).
    """

def fit_primitives(points: Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C', device='cpu', writable=False)], offsets: Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C', device='cpu', writable=False)], shapes: Annotated[NDArray[numpy.int8], dict(shape=(None,), order='C', device='cpu', writable=False)], threads: int = 0) -> tuple[Annotated[NDArray[numpy.int8], dict(shape=(None,), order='C')], Annotated[NDArray[numpy.int8], dict(shape=(None,), order='C')], Annotated[NDArray[numpy.float64], dict(shape=(None,), order='C')], Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C')], Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C')], Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C')], Annotated[NDArray[numpy.int64], dict(shape=(None, 3), order='C')], Annotated[NDArray[numpy.int8], dict(shape=(None, None), order='C')], Annotated[NDArray[numpy.float64], dict(shape=(None, None, 3), order='C')], Annotated[NDArray[numpy.float64], dict(shape=(None, None, 4, 4), order='C')], Annotated[NDArray[numpy.float64], dict(shape=(None, None), order='C')], Annotated[NDArray[numpy.float64], dict(shape=(None, None), order='C')]]:
    """
    Enclosing primitives of H point sets (set h owns points[offsets[h]:offsets[h + 1]]), shapes (K,) codes (0 sphere, 1 capsule, 2 box, 3 cylinder, 4 ellipsoid): (hull_status (H,), dimension (H,), hull_volume (H,), hull_vertex_offsets (H + 1,), hull_vertices (V,) indices into each set, hull_face_offsets (H + 1,), hull_faces (F, 3) into each set's hull vertices, status (H, K), params (H, K, 3), poses (H, K, 4, 4), volume (H, K), excess (H, K)).
    """

def dumps_indented(document: object | None, builtin: object) -> str | None:
    """
    json.dumps(document, sort_keys=True, indent=2) + newline, NaN and infinities as null; builtin(o) turns any other object into one of those; None when the document is one to leave to Python's json (a key that is not a string, an int beyond 64 bits, a dict subclass, a string that is not UTF-8, nesting past 400, or builtin raising).
    """

def dumps_rows(columns: list, count: int, start: int, stop: int, level: int) -> str:
    """
    The rows start..stop of a list of `count` dicts of one set of keys, as dumps_indented writes them inside a list at nesting `level`: each row ',' (but the first of the list), a newline, the dict. columns: (key, kind, array[, table]) in key order; kind number (n,) float64, vector (n, 3) and box (n, 6) float64 (a non-finite row null), numbers3 (n, 3) float64 (a list of 3) and matrix4 (n, 16) float64 (a 4x4 list of lists, row-major), each non-finite entry null, integer (n,) int64, index (n,) int64 (negative null), boolean (n,) bool, string and raw (n,) int64 codes into a list of str (negative null; raw: JSON text as given).
    """

def write_rows(fd: int, columns: list, count: int, level: int) -> None:
    """
    dumps_rows's text of all `count` rows as a list ('[', the rows, a newline and ']'; '[]' when empty) written to the open file descriptor `fd` at its offset, formatted on the core's threads and written in blocks of a few megabytes, never whole in memory. OSError (errno set) when a write fails: the file then holds part of the text.
    """

def round_significant(values: Annotated[NDArray[numpy.float64], dict(shape=(None,), order='C', device='cpu', writable=False)], digits: int) -> Annotated[NDArray[numpy.float64], dict(shape=(None,), order='C')]:
    """
    float(f'{x:.{digits}g}') + 0.0 of each value (digits 1..17): correctly rounded to `digits` significant digits, negative zero made 0.0, non-finite values as they are.
    """

def float_reprs(values: Annotated[NDArray[numpy.float64], dict(shape=(None,), order='C', device='cpu', writable=False)]) -> list[str]:
    """repr(float(x)) of each value, by the core's formatter (for tests)."""

def ray_parity(vertices: Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C', device='cpu', writable=False)], faces: Annotated[NDArray[numpy.int64], dict(shape=(None, 3), order='C', device='cpu', writable=False)], points: Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C', device='cpu', writable=False)]) -> Annotated[NDArray[numpy.int8], dict(shape=(None,), order='C')]:
    """
    Per point (N,) int8: 1 inside, 0 outside by the even-odd rule (exact), -1 undecided (on the surface, or the faces are not closed modulo 2).
    """

def orient_faces(vertices: Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C', device='cpu', writable=False)], faces: Annotated[NDArray[numpy.int64], dict(shape=(None, 3), order='C', device='cpu', writable=False)], nesting_max_components: int, flat_volume: float) -> tuple[Annotated[NDArray[numpy.bool_], dict(shape=(None,), order='C')], bool, bool]:
    """
    (flipped (M,) bool, orientable, balanced): each component wound consistently, closed ones outward (inward for a cavity's wall).
    """

def triangulate_polygons(vertices: Annotated[NDArray[numpy.float64], dict(shape=(None, 3), order='C', device='cpu', writable=False)], counts: Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C', device='cpu', writable=False)], indices: Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C', device='cpu', writable=False)], holes: Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C', device='cpu', writable=False)], reverse: bool = False, max_triangles: int = -1) -> Annotated[NDArray[numpy.int64], dict(shape=(None, 3), order='C')]:
    """
    Splits polygon faces (counts (F,) corners each, indices (sum(counts),) into vertices (V, 3)) into triangles (T, 3) int64 in face order: convex faces fanned from their first corner, others ear clipped in the plane of their Newell normal. Faces of fewer than 3 corners and the faces in holes give none; reverse flips each triangle's winding. Raises ValueError on a negative count, counts not adding up to len(indices), an index out of range, or more than max_triangles (>= 0) triangles.
    """

def read_plain_manifest(data: bytes, types: Sequence[str], type_fields: Sequence[int], orders: Sequence[str], shapes: Sequence[str]) -> dict | None:
    """
    Reads a plain JSON manifest of static mesh and primitive bodies into columns; None for any other document (Python's reader decides). Returns a dict: names (list of str), meshes (list of str, None for a primitive body; None when no body has a mesh), units and duration (str as written, or None), kinds (int8: index into types, -1 for a mesh body), rotation and shapes (int8 codes, shapes indexing shapes with -1 where absent), lengths (zeros for a mesh body) and positions (N, 3), position_count, quaternions (NQ, 4), euler (NE, 3) and orders (NE,) of the bodies so rotated, in order. type_fields: per type, its fields besides type (bits: 1 radius, 2 length, 4 size, 8 semi_axes).
    """

def raster_fill_triangles(depth: Annotated[NDArray[numpy.float64], dict(shape=(None, None), order='C', device='cpu')], pixels: Annotated[NDArray[numpy.uint8], dict(shape=(None, None, 3), order='C', device='cpu')], corners: Annotated[NDArray[numpy.float64], dict(shape=(None, 3, 3), order='C', device='cpu', writable=False)], colors: Annotated[NDArray[numpy.uint8], dict(shape=(None, 3), order='C', device='cpu', writable=False)], lo: Annotated[NDArray[numpy.int64], dict(shape=(None, 2), order='C', device='cpu', writable=False)], hi: Annotated[NDArray[numpy.int64], dict(shape=(None, 2), order='C', device='cpu', writable=False)], order: Annotated[NDArray[numpy.int64], dict(shape=(None,), order='C', device='cpu', writable=False)]) -> None:
    """
    Fills screen triangles corners (N, 3, 3) (pixel x, pixel y down, depth), colours (N, 3) uint8, pixel boxes lo and hi (N, 2) int64 (floor and ceil of the corners' x and y), in place into depth (H, W) float64 and pixels (H, W, 3) uint8, triangle order[0], order[1], ...: a pixel whose centre the triangle covers takes its colour and depth when nearer (a larger depth) than the buffer's. Raises ValueError on mismatched shapes or an index of order out of range.
    """
