"""The exact even-odd inside test (issue 29): against an oracle in rational arithmetic, on
shuffled, flipped, nested, non-orientable, open meshes and on points whose +x ray grazes
edges, vertices and faces (axis-aligned boxes queried on their own coordinates)."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import trimesh
from dirty_meshes import blob, moebius, shuffled

from meshcol.collision.ray_parity import ray_parity

#: Ray directions of the oracle (integers, no two parallel): it takes the first along which
#: every crossing is a proper one (no edge, no vertex, no face's plane).
ORACLE_DIRECTIONS = [(7, 3, 11), (-5, 13, 2), (3, -17, 8), (19, 6, -7), (-11, -4, 13)]


def _sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _on_triangle(p, a, b, c) -> bool:
    """p in the closed triangle abc (rational, exact)."""
    n = _cross(_sub(b, a), _sub(c, a))
    if _dot(n, _sub(p, a)) != 0:
        return False
    if n == (0, 0, 0):  # collinear corners: p on one of the three segments
        return any(_on_segment(p, u, w) for u, w in ((a, b), (b, c), (c, a)))
    k = max(range(3), key=lambda i: abs(n[i]))  # drop the largest normal component
    i, j = [x for x in range(3) if x != k]

    def side(u, w):
        return (w[i] - u[i]) * (p[j] - u[j]) - (w[j] - u[j]) * (p[i] - u[i])

    s = [side(a, b), side(b, c), side(c, a)]
    return all(x >= 0 for x in s) or all(x <= 0 for x in s)


def _on_segment(p, u, w) -> bool:
    if _cross(_sub(w, u), _sub(p, u)) != (0, 0, 0):
        return False
    return all(min(u[k], w[k]) <= p[k] <= max(u[k], w[k]) for k in range(3))


def _crossings(p, d, triangles) -> int | None:
    """Proper crossings of the ray p + t d (t > 0) with the triangles; None if the ray meets
    one improperly (an edge, a vertex, or along its plane)."""
    count = 0
    for a, b, c in triangles:
        e1, e2 = _sub(b, a), _sub(c, a)
        n = _cross(e1, e2)
        if n == (0, 0, 0):
            # a collinear triangle: the ray may only graze it
            if any(_ray_meets_segment(p, d, u, w) for u, w in ((a, b), (b, c), (c, a))):
                return None
            continue
        det = _dot(n, d)
        offset = _dot(n, _sub(a, p))
        if det == 0:
            if offset == 0:
                return None  # the ray in the face's plane: try another
            continue
        t = offset / det
        if t <= 0:
            continue
        hit = tuple(p[k] + t * d[k] for k in range(3))
        # barycentric coordinates of the hit
        h = _sub(hit, a)
        nn = _dot(n, n)
        v = _dot(_cross(h, e2), n) / nn
        w = _dot(_cross(e1, h), n) / nn
        u = 1 - v - w
        if u > 0 and v > 0 and w > 0:
            count += 1
        elif u >= 0 and v >= 0 and w >= 0:
            return None
    return count


def _ray_meets_segment(p, d, u, w) -> bool:
    # coplanar and the 2D segments meet: conservatively any coplanarity counts as grazing
    return _dot(_cross(d, _sub(w, u)), _sub(u, p)) == 0


def oracle(points: np.ndarray, vertices: np.ndarray, faces: np.ndarray) -> list[int | None]:
    """Per point: 1 inside, 0 outside (odd or even proper crossings), None on the surface;
    in rationals, from the floats as given. (Floats only skip triangles far from the point or
    the ray, with a wide margin.)"""
    rational = [tuple(Fraction(float(x)) for x in v) for v in vertices]
    triangles = [(rational[i], rational[j], rational[k]) for i, j, k in faces.tolist()]
    corners = np.asarray(vertices, dtype=np.float64)[faces]
    lower, upper = corners.min(axis=1), corners.max(axis=1)
    centre = corners.mean(axis=1)
    radius = np.linalg.norm(corners - centre[:, None], axis=2).max(axis=1) * 1.001 + 1e-9
    out: list[int | None] = []
    for point in points:
        p = tuple(Fraction(float(x)) for x in point)
        near = np.flatnonzero(((lower <= point) & (point <= upper)).all(axis=1))
        if any(_on_triangle(p, *triangles[i]) for i in near.tolist()):
            out.append(None)
            continue
        for d in ORACLE_DIRECTIONS:
            unit = np.asarray(d, dtype=np.float64) / np.linalg.norm(d)
            off_line = np.linalg.norm(np.cross(centre - point, unit), axis=1)
            ahead = (centre - point) @ unit > -radius
            reached = np.flatnonzero((off_line <= radius) & ahead)
            count = _crossings(p, tuple(Fraction(x) for x in d), [triangles[i] for i in reached])
            if count is not None:
                out.append(count % 2)
                break
        else:
            raise AssertionError(f"every oracle direction grazes at {point}")
    return out


def _verdicts(points, vertices, faces) -> list[int | None]:
    inside, decided = ray_parity(points, vertices, faces)
    return [int(i) if d else None for i, d in zip(inside.tolist(), decided.tolist())]


def _boxes() -> tuple[np.ndarray, np.ndarray]:
    """A unit box with a cubic cavity (0.25 to 0.75) and a separate box beside it, faces
    shuffled: axis-aligned, so rays along +x run along faces and through edges."""
    outer = trimesh.creation.box(bounds=[(0, 0, 0), (1, 1, 1)])
    cavity = trimesh.creation.box(bounds=[(0.25, 0.25, 0.25), (0.75, 0.75, 0.75)])
    beside = trimesh.creation.box(bounds=[(1.5, 0, 0), (2, 1, 1)])
    parts = [outer, cavity, beside]
    offsets = np.cumsum([0] + [len(m.vertices) for m in parts[:-1]])
    v = np.concatenate([m.vertices for m in parts])
    f = np.concatenate([m.faces + o for m, o in zip(parts, offsets)])
    return v, shuffled(f, 4)


def test_grazing_rays_on_axis_aligned_boxes_match_the_rational_oracle() -> None:
    v, f = _boxes()
    grid = np.array([-0.5, 0.0, 0.125, 0.25, 0.5, 0.75, 0.875, 1.0, 1.25, 1.5, 1.75, 2.0])
    points = np.stack(np.meshgrid(grid, grid[:8], grid[:8], indexing="ij"), -1).reshape(-1, 3)
    expected = oracle(points, v, f)
    assert _verdicts(points, v, f) == expected
    # the grid holds every kind: inside the wall, in the cavity, outside, on faces/edges/corners
    assert {0, 1, None} <= set(expected)
    assert expected.count(None) > 50 and expected.count(1) > 20
    # the wall between the box and its cavity: inside; the cavity's centre: outside
    assert _verdicts(np.array([[0.1, 0.5, 0.5], [0.5, 0.5, 0.5]]), v, f) == [1, 0]
    # winding does not matter: every face flipped, the same answers
    assert _verdicts(points, v, f[:, ::-1]) == expected


def test_shuffled_blob_and_random_points_match_the_oracle() -> None:
    v, f = blob()
    rng = np.random.default_rng(29)
    points = rng.uniform(-0.7, 0.7, size=(40, 3))
    points[:5] = v[rng.choice(len(v), 5)]  # on the surface: vertices
    points[5:8] = v[f[:3]].mean(axis=1)  # near or on faces (the mean rounds)
    points[8:12, 1:] = v[rng.choice(len(v), 4)][:, 1:]  # +x rays through vertices
    expected = oracle(points, v, shuffled(f, 7))
    assert _verdicts(points, v, shuffled(f, 7)) == expected
    assert expected[:5] == [None] * 5 and 1 in expected and 0 in expected


def klein_bottle(sections: int = 24, rings: int = 12, r: float = 2.0):
    """The figure-8 immersion of the Klein bottle: closed, non-orientable, crossing itself
    along a circle; its faces close up modulo 2 (every edge twice)."""
    u = np.linspace(0, 2 * np.pi, sections, endpoint=False)[:, None]
    w = np.linspace(0, 2 * np.pi, rings, endpoint=False)[None, :]
    radius = r + np.cos(u / 2) * np.sin(w) - np.sin(u / 2) * np.sin(2 * w)
    points = np.stack(
        [
            radius * np.cos(u),
            radius * np.sin(u),
            np.sin(u / 2) * np.sin(w) + np.cos(u / 2) * np.sin(2 * w),
        ],
        -1,
    ).reshape(-1, 3)

    def index(i: int, j: int) -> int:
        if i == sections:  # u + 2 pi is u at -w
            i, j = 0, -j
        return i * rings + j % rings

    faces = []
    for i in range(sections):
        for j in range(rings):
            a, b = index(i, j), index(i + 1, j)
            c, d = index(i, j + 1), index(i + 1, j + 1)
            faces += [[a, b, d], [a, d, c]]
    return points, np.array(faces)


def test_a_klein_bottle_is_decided_exactly() -> None:
    from meshcol.collision.orientation import orient_consistently

    v, f = klein_bottle()
    assert not orient_consistently(v, f).orientable  # no winding number decides it
    rng = np.random.default_rng(3)
    points = rng.uniform(-3.2, 3.2, size=(30, 3)) * [1, 1, 0.4]
    points[:3] = v[:3]
    expected = oracle(points, v, f)
    assert _verdicts(points, v, f) == expected
    assert expected[:3] == [None] * 3 and 1 in expected and 0 in expected


def test_open_surfaces_have_no_inside() -> None:
    v, f = moebius()
    assert _verdicts(np.array([[1.0, 0, 0], [0, 0, 0]]), v, f) == [None, None]
    box = trimesh.creation.box()
    points = np.array([[0.0, 0, 0], [2.0, 0, 0]])
    assert _verdicts(points, box.vertices, box.faces[:-1]) == [None, None]
    # the same box unwelded (a soup, each face its own corners) closes up by coordinates
    soup = box.vertices[box.faces].reshape(-1, 3)
    assert _verdicts(points, soup, np.arange(len(soup)).reshape(-1, 3)) == [1, 0]
    # a face counted twice (a duplicate) cancels: even-odd sees the box whole
    faces = np.concatenate([box.faces, box.faces[:1], box.faces[:1]])
    assert _verdicts(points, box.vertices, faces) == [1, 0]


def test_non_finite_points_and_vertices_are_undecided() -> None:
    box = trimesh.creation.box()
    points = np.array([[np.nan, 0, 0], [0.0, 0, 0]])
    assert _verdicts(points, box.vertices, box.faces) == [None, 1]
    v = np.array(box.vertices)
    v[0, 0] = np.inf
    assert _verdicts(points, v, box.faces) == [None, None]
