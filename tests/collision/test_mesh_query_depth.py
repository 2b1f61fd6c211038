"""The mesh penetration depth's region classification and branch and bound (issue 14).

For a closed other mesh the core decides inside-ness by regions (vertices joined by edges of
triangles that stay clear of the other surface share a side; one exact test decides each) and
finds the largest distance by branch and bound over the hierarchies, instead of a test and a
distance per sampled point. The answer must stay the maximum, over the same sampled points, of
the same distances. Checked here against a brute-force oracle (every sample decided by the
O(F) generalized winding number, distances over every triangle), against the per-point
winding-number path (the same pair made open by a stray far triangle), and on the layouts a
wrong region would get wrong: several components on either side, a thin wall crossed by edges
whose ends are outside, nested meshes, touching pairs, open and non-manifold meshes.
"""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st
from oracles import quaternion_rotation

from meshcol.collision.mesh_query import MeshSet, mesh_penetration_depth_batch
from meshcol.types import Status

# -- brute-force oracle ----------------------------------------------------------------------


def _winding_numbers(points: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Generalized winding number of each point w.r.t. triangles (n, 3, 3): the O(F) sum of
    signed solid angles (van Oosterom and Strackee), over 4 pi."""
    a = tri[None, :, 0, :] - points[:, None, :]
    b = tri[None, :, 1, :] - points[:, None, :]
    c = tri[None, :, 2, :] - points[:, None, :]
    la, lb, lc = (np.linalg.norm(x, axis=2) for x in (a, b, c))
    det = np.einsum("pfk,pfk->pf", a, np.cross(b, c))
    den = (
        la * lb * lc
        + np.einsum("pfk,pfk->pf", a, b) * lc
        + np.einsum("pfk,pfk->pf", b, c) * la
        + np.einsum("pfk,pfk->pf", c, a) * lb
    )
    return (2.0 * np.arctan2(det, den)).sum(axis=1) / (4.0 * np.pi)


def _closest_on_triangles(p: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Distance from each point to each triangle (p, f): Ericson 5.1.5, vectorised."""
    a, b, c = tri[None, :, 0], tri[None, :, 1], tri[None, :, 2]
    p = p[:, None, :]
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = (ab * ap).sum(-1), (ac * ap).sum(-1)
    bp = p - b
    d3, d4 = (ab * bp).sum(-1), (ac * bp).sum(-1)
    cp = p - c
    d5, d6 = (ab * cp).sum(-1), (ac * cp).sum(-1)
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    with np.errstate(divide="ignore", invalid="ignore"):
        denom = 1.0 / (va + vb + vc)
        v, w = vb * denom, vc * denom
        q = a + ab * v[..., None] + ac * w[..., None]
        cases = [
            (d1 <= 0) & (d2 <= 0),
            (d3 >= 0) & (d4 <= d3),
            (d6 >= 0) & (d5 <= d6),
            (vc <= 0) & (d1 >= 0) & (d3 <= 0),
            (vb <= 0) & (d2 >= 0) & (d6 <= 0),
            (va <= 0) & ((d4 - d3) >= 0) & ((d5 - d6) >= 0),
        ]
        points = [
            np.broadcast_to(a, q.shape),
            np.broadcast_to(b, q.shape),
            np.broadcast_to(c, q.shape),
            a + ab * (d1 / (d1 - d3))[..., None],
            a + ac * (d2 / (d2 - d6))[..., None],
            b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)))[..., None],
        ]
    for case, point in zip(reversed(cases), reversed(points), strict=True):
        q = np.where(case[..., None], point, q)
    return np.linalg.norm(q - p, axis=-1)


def _segment_hits(p: np.ndarray, q: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Parameter s in [0, 1] where segment k meets triangle f (Moller-Trumbore), NaN when it
    misses: (k, f)."""
    d = (q - p)[:, None, :]
    e1, e2 = tri[None, :, 1] - tri[None, :, 0], tri[None, :, 2] - tri[None, :, 0]
    h = np.cross(d, e2)
    det = (e1 * h).sum(-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / det
        s_vec = p[:, None, :] - tri[None, :, 0]
        u = (s_vec * h).sum(-1) * inv
        qv = np.cross(s_vec, e1)
        v = (d * qv).sum(-1) * inv
        t = (e2 * qv).sum(-1) * inv
    with np.errstate(invalid="ignore"):
        hit = (np.abs(det) > 1e-300) & (u >= 0) & (v >= 0) & (u + v <= 1) & (t >= 0) & (t <= 1)
    return np.where(hit, t, np.nan)


def _posed(mesh: trimesh.Trimesh, pose: np.ndarray) -> np.ndarray:
    v = np.asarray(mesh.vertices, dtype=float) @ pose[:3, :3].T + pose[:3, 3]
    return v[np.asarray(mesh.faces)]


def oracle_depth(ta: np.ndarray, tb: np.ndarray) -> tuple[float, np.ndarray]:
    """Largest distance to the other surface of a sampled point inside the other mesh, by brute
    force: vertices, the pieces of the edges of crossing triangles, and the points stepped in
    from the centroids of crossing triangle pairs (the core's samples but for the ones stepped
    in from a witness point of a pair, which depend on its triangle test). Returns the depth
    and the samples (world), for the core's deepest point to be found among them."""
    best, samples = 0.0, []
    sides = ((ta, tb), (tb, ta))
    hits = [None, None]
    for k, (own, other) in enumerate(sides):
        starts = own.reshape(-1, 3)
        ends = own[:, [1, 2, 0]].reshape(-1, 3)
        hits[k] = _segment_hits(starts, ends, other).reshape(len(own), 3, len(other))
    # triangle i of a meets triangle j of b when an edge of one meets the other
    meets = np.isfinite(hits[0]).any(axis=1) | np.isfinite(hits[1]).any(axis=1).T
    crossing = (meets.any(axis=1), meets.any(axis=0))
    for k, (own, other) in enumerate(sides):
        points = [np.unique(own.reshape(-1, 3), axis=0)]
        for i in np.flatnonzero(crossing[k]):
            for e in range(3):
                p, q = own[i, e], own[i, (e + 1) % 3]
                cuts = np.sort(np.r_[0.0, 1.0, hits[k][i, e][np.isfinite(hits[k][i, e])]])
                mids = 0.5 * (cuts[:-1] + cuts[1:])[np.diff(cuts) > 0]
                points.append(p + (q - p) * mids[:, None])
        pts = np.vstack(points)
        inside = np.abs(_winding_numbers(pts, other)) >= 0.5
        if inside.any():
            best = max(best, float(_closest_on_triangles(pts[inside], other).min(axis=1).max()))
        samples.append(pts)
    wedge = []
    for i, j in zip(*np.nonzero(meets), strict=True):
        h = min(np.linalg.norm(ta[i] - ta[i][[1, 2, 0]], axis=1).max(),
                np.linalg.norm(tb[j] - tb[j][[1, 2, 0]], axis=1).max())  # fmt: skip
        for t in (ta[i], tb[j]):
            n = np.cross(t[1] - t[0], t[2] - t[0])
            n = n / np.linalg.norm(n)
            for step in (0.5 * h, 0.125 * h, 0.03125 * h):
                wedge.append(t.mean(axis=0) - n * step)
    if wedge:
        pts = np.array(wedge)
        inside = (np.abs(_winding_numbers(pts, ta)) >= 0.5) & (
            np.abs(_winding_numbers(pts, tb)) >= 0.5
        )
        if inside.any():
            da = _closest_on_triangles(pts[inside], ta).min(axis=1)
            db = _closest_on_triangles(pts[inside], tb).min(axis=1)
            best = max(best, float(np.maximum(da, db).max()))
        samples.append(pts)
    return best, np.vstack(samples)


# -- helpers ---------------------------------------------------------------------------------


def _pose(rotation=None, translation=(0.0, 0.0, 0.0)) -> np.ndarray:
    m = np.eye(4)
    if rotation is not None:
        m[:3, :3] = rotation
    m[:3, 3] = translation
    return m


def _depth(meshes, poses, pairs=((0, 1), (1, 0))):
    s = MeshSet.from_arrays(list(meshes), np.stack(poses))
    return mesh_penetration_depth_batch(s, None, np.array(pairs), threads=1)


def _open_copy(mesh: trimesh.Trimesh) -> tuple[np.ndarray, np.ndarray]:
    """The mesh plus a tiny stray triangle far away: not closed, so the core decides each
    sample by the generalized winding number, deepest first (the per-point path)."""
    v = np.asarray(mesh.vertices)
    far = v.max(axis=0) + 10.0
    stray = np.array([far, far + [1e-3, 0, 0], far + [0, 1e-3, 0]])
    return np.vstack([v, stray]), np.vstack([np.asarray(mesh.faces), len(v) + np.arange(3)[None]])


def _witness_consistent(r, k: int) -> None:
    if r.depth[k] > 0:
        gap = r.point_b[k] - r.point_a[k]
        assert gap == pytest.approx(-r.depth[k] * r.normal[k], abs=1e-12 * max(1.0, r.depth[k]))


def _check_against_oracle(r, k: int, ta: np.ndarray, tb: np.ndarray) -> None:
    """Pair k of `r` (a = ta, b = tb, world triangles) against the oracle: the same depth to
    1e-12, or a deeper point that the oracle does not sample (one stepped in from a witness
    point), checked by brute force: inside both meshes, at exactly the depth."""
    expected, samples = oracle_depth(ta, tb)
    depth = float(r.depth[k])
    assert depth >= expected * (1 - 1e-12) - 1e-15  # the core samples at least these points
    if depth <= expected * (1 + 1e-12) + 1e-15:
        return
    deep = r.point_a[k] if r.deepest_mesh[k] == 0 else r.point_b[k]
    assert np.linalg.norm(samples - deep, axis=1).min() > 1e-9  # not one of the oracle's
    wa, wb = _winding_numbers(deep[None], ta)[0], _winding_numbers(deep[None], tb)[0]
    assert abs(wa) >= 0.5 and abs(wb) >= 0.5
    da = _closest_on_triangles(deep[None], ta).min()
    db = _closest_on_triangles(deep[None], tb).min()
    assert max(da, db) == pytest.approx(depth, rel=1e-12)


SHAPES = {
    "icosphere": trimesh.creation.icosphere(1, radius=0.5),
    "box": trimesh.creation.box(extents=[0.9, 0.6, 0.4]),
    "torus": trimesh.creation.torus(0.5, 0.18, 12, 8),
    "slab": trimesh.creation.box(extents=[1.6, 1.6, 0.08]),
}

quaternion = st.tuples(*[st.floats(-1, 1) for _ in range(4)]).filter(
    lambda q: sum(x * x for x in q) > 0.01
)
offset = st.tuples(*[st.floats(-0.7, 0.7) for _ in range(3)])


# Poses nudged off exact alignments: the oracle's floating-point crossing tests (unlike the
# core's exact predicates) cannot decide flush or touching faces, which simple rotations such
# as a quarter turn produce.
NUDGE_Q = np.array([2.0**0.5, 3.0**0.5, 5.0**0.5, 7.0**0.5]) * 1e-3
NUDGE_T = np.array([11.0**0.5, 13.0**0.5, 17.0**0.5]) * 1e-4


@pytest.mark.slow
@settings(max_examples=60, deadline=None)
@given(st.sampled_from(sorted(SHAPES)), st.sampled_from(sorted(SHAPES)), quaternion, offset)
def test_depth_matches_a_brute_force_oracle(name_a: str, name_b: str, q, t) -> None:
    """Small posed pairs of closed meshes in general position, in both orders: the core's depth
    is the oracle's (all samples decided by the O(F) winding number, distances over every
    triangle) to 1e-12, unless its deepest point is one the oracle leaves out (stepped in from
    a pair's witness point); that point is then checked by brute force: inside both meshes, at
    exactly the depth."""
    a, b = SHAPES[name_a], SHAPES[name_b]
    pose_b = _pose(quaternion_rotation(np.asarray(q) + NUDGE_Q), np.asarray(t) + NUDGE_T)
    r = _depth([a, b], [np.eye(4), pose_b])
    assert (r.status == Status.CONVERGED).all()
    ta, tb = _posed(a, np.eye(4)), _posed(b, pose_b)
    for k, (first, second) in enumerate(((ta, tb), (tb, ta))):
        _witness_consistent(r, k)
        _check_against_oracle(r, k, first, second)


@settings(max_examples=25, deadline=None)
@given(st.sampled_from(sorted(SHAPES)), st.sampled_from(sorted(SHAPES)), quaternion, offset)
def test_regions_agree_with_the_per_point_winding_number(name_a: str, name_b: str, q, t) -> None:
    """The same pair with both meshes made open (a stray far triangle each) goes the per-point
    way: every sample decided by the generalized winding number, deepest first. The samples and
    distances are the same, so the depths are too."""
    a, b = SHAPES[name_a], SHAPES[name_b]
    poses = [np.eye(4), _pose(quaternion_rotation(q), t)]
    closed = _depth([a, b], poses)
    opened = _depth([_open_copy(a), _open_copy(b)], poses)
    assert closed.depth == pytest.approx(opened.depth, rel=1e-12, abs=1e-15)
    assert (closed.status == Status.CONVERGED).all()


def _balls(centres, radius=0.3) -> trimesh.Trimesh:
    return trimesh.util.concatenate(
        [trimesh.creation.icosphere(2, radius=radius).apply_translation(c) for c in centres]
    )


def test_components_inside_and_outside_are_told_apart() -> None:
    """One mesh of two disjoint balls, one inside a box and one beside it: each region is
    decided on its own, the inner one giving the depth of its deepest vertex (the box's faces
    are 1 from its centre), the outer one nothing, also when a second part of the box's mesh
    stretches the box's bounding box over the outer ball (so that an exact test decides it)."""
    box = trimesh.creation.box(extents=[2.0, 2.0, 2.0])
    balls = _balls([(0.0, 0.0, 0.0), (3.0, 0.0, 0.0)])
    r = _depth([balls, box], [np.eye(4), np.eye(4)])
    # the deepest vertex of the inner ball: 1 - (its distance from the centre) from the faces
    verts = np.asarray(trimesh.creation.icosphere(2, radius=0.3).vertices)
    expected = float((1.0 - np.abs(verts).max(axis=1)).max())
    assert r.depth[0] == pytest.approx(expected, rel=1e-12)
    assert r.depth[1] == pytest.approx(expected, rel=1e-12)
    assert r.deepest_mesh[0] == 0 and r.deepest_mesh[1] == 1
    # the outer ball alone gives nothing
    outer = _depth([_balls([(3.0, 0.0, 0.0)]), box], [np.eye(4), np.eye(4)])
    assert (outer.depth == 0.0).all()
    # an outer ball inside the box's root box (a box with a notch would do; a second box
    # beside the first, in one mesh, makes the root box span the outer ball)
    two_boxes = trimesh.util.concatenate(
        [box, trimesh.creation.box(extents=[0.2, 0.2, 0.2]).apply_translation([3.5, 0, 0])]
    )
    r2 = _depth([balls, two_boxes], [np.eye(4), np.eye(4)])
    assert r2.depth == pytest.approx([expected, expected], rel=1e-12)


def test_a_component_with_a_vertex_outside_the_box_is_not_inside() -> None:
    """A row of balls in one mesh: three inside a box, one through its face, one outside. The
    regions of the inner balls are inside, the outer ball's outside, and the ball through the
    face is decided near its crossing; with the box moved away, nothing."""
    box = trimesh.creation.box(extents=[2.0, 2.0, 2.0])
    centres = [(x, 0.0, 0.0) for x in (-0.6, 0.0, 0.6, 1.0, 2.6)]
    balls = _balls(centres, 0.25)
    r = _depth([balls, box], [np.eye(4), np.eye(4)])
    verts = np.asarray(balls.vertices)
    inside = (np.abs(verts) < 1.0).all(axis=1)
    expected = float((1.0 - np.abs(verts[inside]).max(axis=1)).max())
    assert r.depth[0] == pytest.approx(expected, rel=1e-12)
    apart = _depth([balls, box], [np.eye(4), _pose(translation=(0, 10, 0))])
    assert (apart.depth == 0.0).all()


def test_thin_wall_crossed_by_edges_with_both_ends_outside() -> None:
    """A long bar through a thin wall: every vertex of the bar is outside the wall and every
    vertex of the wall outside the bar, so no region is inside; only the pieces of the bar's
    edges between the wall's faces are. The depth is their distance to the wall's faces, at
    most its half thickness, and equal to the per-point search's."""
    wall = trimesh.creation.box(extents=[2.0, 2.0, 0.1])
    bar = trimesh.creation.box(extents=[0.1, 0.1, 1.0])
    tilt = _pose(quaternion_rotation([np.cos(0.2), np.sin(0.2), 0, 0]))
    r = _depth([wall, bar], [np.eye(4), tilt])
    assert (r.depth > 0.0).all() and (r.depth <= 0.05 + 1e-12).all()
    opened = _depth([_open_copy(wall), _open_copy(bar)], [np.eye(4), tilt])
    assert r.depth == pytest.approx(opened.depth, rel=1e-12)
    expected, _ = oracle_depth(_posed(wall, np.eye(4)), _posed(bar, tilt))
    assert expected > 0.0 and r.depth[0] >= expected * (1 - 1e-12)
    for k in range(2):
        _witness_consistent(r, k)


def test_nested_meshes_without_crossing() -> None:
    """A ball inside a torus's tube and a box inside a ball: no triangle crosses, one region
    per mesh, and the depth is the deepest vertex's distance."""
    big = trimesh.creation.icosphere(3, radius=2.0)
    small = trimesh.creation.box(extents=[0.4, 0.6, 0.8])
    r = _depth([small, big], [_pose(translation=(0.3, -0.2, 0.1)), np.eye(4)])
    expected, _ = oracle_depth(
        _posed(small, _pose(translation=(0.3, -0.2, 0.1))), _posed(big, np.eye(4))
    )
    assert r.depth == pytest.approx([expected, expected], rel=1e-12)
    assert r.deepest_mesh[0] == 0 and r.deepest_mesh[1] == 1
    # one exact test: the small box's one region (the ball's vertices are outside its box)
    assert (r.points_tested == 1).all()
    # the other way round: the big ball's vertices are all outside the small box
    tube = trimesh.creation.torus(1.0, 0.4, 32, 16)
    ball = trimesh.creation.icosphere(2, radius=0.15)
    r = _depth([ball, tube], [_pose(translation=(1.0, 0.0, 0.0)), np.eye(4)])
    expected, _ = oracle_depth(
        _posed(ball, _pose(translation=(1.0, 0, 0))), _posed(tube, np.eye(4))
    )
    assert r.depth == pytest.approx([expected, expected], rel=1e-12)
    assert 0.2 < r.depth[0] < 0.4


@pytest.mark.parametrize("gap", [0.0, 1e-12, 1e-9])
def test_touching_pairs_have_no_depth(gap: float) -> None:
    """Boxes face to face, a box on a subdivided floor, a ball on a box: touching (or a hair
    apart) is depth 0, whichever order the pair is in."""
    floor = trimesh.creation.box(bounds=[[-2, -2, -1], [2, 2, 0]]).subdivide().subdivide()
    cube = trimesh.creation.box(bounds=[[-0.5, -0.5, gap], [0.5, 0.5, 1 + gap]])
    ball = trimesh.creation.icosphere(2, radius=0.5)
    ball_pose = _pose(translation=(0.3, 0.2, gap - float(ball.vertices[:, 2].min())))
    for meshes, poses in (
        ([floor, cube], [np.eye(4), np.eye(4)]),
        ([cube, floor], [np.eye(4), np.eye(4)]),
        ([floor, ball], [np.eye(4), ball_pose]),
    ):
        r = _depth(meshes, poses)
        assert (r.status == Status.CONVERGED).all()
        assert (r.depth == 0.0).all(), r.depth
        assert (r.deepest_mesh == -1).all()


def test_a_depth_below_the_pose_rounding_still_has_a_unit_normal() -> None:
    """Resting pairs moved together by a rigid motion far from the origin: a depth of a few
    ulps (the rounding of the shared motion) maps the deepest point and its surface point to
    one world point, yet the normal is a unit vector whenever the depth is not 0 (its
    direction known in the local frame); it was NaN. Depths stay at rounding level."""
    rng = np.random.default_rng(0)
    shapes = [
        trimesh.creation.box(),
        trimesh.creation.icosphere(2),
        trimesh.creation.cylinder(0.5, 1.0, sections=24),
    ]
    coincident = 0
    for trial in range(240):
        a, b = shapes[trial % 3], shapes[(trial // 3) % 3]
        motion = _pose(quaternion_rotation(rng.normal(size=4)), rng.normal(size=3) * 100.0)
        on_top = _pose(translation=(rng.uniform(-0.3, 0.3), 0.0, a.bounds[1, 2] - b.bounds[0, 2]))
        r = _depth([a, b], [motion, motion @ on_top])
        assert (r.status == Status.CONVERGED).all()
        assert (r.depth < 1e-9).all(), r.depth
        deep = r.depth > 0.0
        coincident += int((deep & (r.point_a == r.point_b).all(axis=1)).sum())
        assert np.isfinite(r.normal[deep]).all(), (trial, r.depth, r.normal)
        assert np.linalg.norm(r.normal[deep], axis=1) == pytest.approx(1.0, abs=1e-12)
        assert np.isnan(r.normal[~deep]).all()
    assert coincident > 0  # the case this test is about did occur


def test_open_and_non_manifold_meshes_take_the_winding_number_path() -> None:
    """An open box (one face removed) and a non-manifold one (two boxes sharing an edge) are
    not closed: the samples inside them are decided by the generalized winding number, point
    by point, as before; a closed partner still takes the region path. Depths agree with the
    oracle."""
    box = trimesh.creation.box(extents=[1.0, 1.0, 1.0])
    ball = trimesh.creation.icosphere(2, radius=0.3)
    open_box = (np.asarray(box.vertices), np.asarray(box.faces)[:-1])
    twin = trimesh.creation.box(extents=[1.0, 1.0, 1.0]).apply_translation([1.0, 1.0, 0.0])
    shared_edge = trimesh.util.concatenate([box, twin])
    shared_edge.merge_vertices()
    s = MeshSet.from_arrays([open_box, shared_edge, ball])
    assert not s._handle.closed(0) and not s._handle.closed(1) and s._handle.closed(2)
    hosts = (np.asarray(box.vertices)[open_box[1]], _posed(shared_edge, np.eye(4)))
    for k, host in enumerate(hosts):
        for t in ((0.1, 0.0, 0.0), (0.45, 0.1, 0.0)):
            poses = np.stack([np.eye(4), np.eye(4), _pose(translation=t)])
            r = mesh_penetration_depth_batch(s, poses, [[2, k], [k, 2]], threads=1)
            assert (r.status == Status.CONVERGED).all()
            assert r.depth[1] == pytest.approx(r.depth[0], rel=1e-12)
            _check_against_oracle(r, 0, _posed(ball, _pose(translation=t)), host)
