"""Wrong statuses and depths out of their interval on dirty hosts (issue 29, items 1-3).

Hosts of our own making (a concave airplane, a torus, a lumpy blob), each as wound
consistently, shuffled (half the faces reversed at random, three seeds), turned inside out,
and opened (5% of the faces removed); a 2 cm cube 4 mm above the top, pushed 1e-7 into it,
and (closed hosts) deep inside. Oracles independent of meshcol's inside test: python-fcl's
distance for the cube above; a point deep inside by the consistently wound copy's winding number
for the cube inside; contact for the cube pushed 1e-7 in (its minimum translation distance is
at most 1e-7). Counted: statuses other than the oracle's, depths above the known minimum
translation distance, depths above ``depth_upper`` (when the report has it). Then the parts ->
mesh Hausdorff distance of slab hulls of Octocat-v2 against a 1,000,000-point sampling.

Run with any meshcol on the path (``python benchmarks/mesh_truth.py``; main's venv for the
"before" figures).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import trimesh

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import itertools

from dirty_meshes import HOSTS, cube, inner, on_top, shuffled

from meshcol.analysis.check import CheckOptions, check_scene
from meshcol.types import Body, Scene


def _check(host, box, pose, collider):
    scene = Scene((Body("host", None, host[0], host[1]), Body("cube", None, box[0], box[1], pose)))
    (pair,) = check_scene(scene, CheckOptions(collider=collider, clearance=0.01)).pairs
    return pair


def _fcl_distance(host, pose, edge):
    import fcl

    model = fcl.BVHModel()
    model.beginModel(len(host[0]), len(host[1]))
    model.addSubModel(host[0], host[1])
    model.endModel()
    body = fcl.CollisionObject(model, fcl.Transform())
    placed = fcl.CollisionObject(
        fcl.Box(edge, edge, edge), fcl.Transform(pose[:3, :3], pose[:3, 3])
    )
    return fcl.distance(body, placed, fcl.DistanceRequest(), fcl.DistanceResult())


def _variants(v, f):
    yield "consistent", f, True
    for seed in range(3):
        yield f"shuffled{seed}", shuffled(f, seed), True
    yield "inside-out", f[:, ::-1], True
    keep = np.random.default_rng(7).random(len(f)) >= 0.05
    yield "open", f[keep], False
    yield "open-shuffled", shuffled(f[keep], 4), False


def main() -> None:
    box = cube(0.005)
    total = wrong = too_deep = outside = 0
    for name, make in HOSTS.items():
        v, f = make()
        above, pushed = on_top((v, f), 0.004, 0.005), on_top((v, f), -1e-7, 0.005)
        deep = np.eye(4)
        deep[:3, 3] = inner((v, f))
        gap = _fcl_distance((v, f), above, 0.005)
        for variant, faces, closed in _variants(v, f):
            for collider in ("mesh", "hull"):
                cases = [("above", above), ("pushed", pushed)] + (
                    [("inside", deep)] if closed else []
                )
                for case, pose in cases:
                    pair = _check((v, faces), box, pose, collider)
                    total += 1
                    if case == "above":  # fcl: apart by 4 mm; the hull may reach over it
                        expected = (
                            {"clearance"}
                            if collider == "mesh"
                            else {"clearance", "contact", "penetrating"}
                        )
                        true = 0.0 if collider == "mesh" else None
                    elif case == "pushed":  # minimum translation distance 1e-7
                        expected = {"contact"} if collider == "mesh" else {"contact", "penetrating"}
                        true = 1e-7 if collider == "mesh" else None
                    else:
                        expected, true = {"contained"}, None
                    bad = pair["status"] not in expected
                    if case == "above" and collider == "mesh":
                        bad |= abs(pair["distance"] - gap) > 1e-9
                    over = true is not None and pair["depth"] > true * (1 + 1e-6) + 1e-12
                    upper = pair.get("depth_upper")
                    # the true value outside [depth, depth_upper] (or depth above depth_upper)
                    out = upper is not None and (
                        pair["depth"] > upper or (true is not None and upper < true * (1 - 1e-6))
                    )
                    wrong += bad
                    too_deep += over
                    outside += out
                    if bad or over or out:
                        print(
                            f"  {name:9s} {variant:14s} {collider:5s} {case:7s}: {pair['status']}"
                            f" depth {pair['depth']:.3g} upper {upper}"
                        )
    print(
        f"pairs {total}: wrong statuses {wrong}, depth above the true {too_deep}, true outside [depth, depth_upper] {outside}"
    )
    _hausdorff()


CORPUS = Path(__file__).resolve().parents[2] / "shared" / "corpus" / "coacd-examples"


def _slab_hulls(mesh, k):
    v = np.asarray(mesh.vertices)
    axis = int(np.argmax(np.ptp(v, axis=0)))
    edges = np.quantile(v[:, axis], np.linspace(0, 1, k + 1))
    parts = []
    for lo, hi in itertools.pairwise(edges):
        hull = trimesh.convex.convex_hull(v[(v[:, axis] >= lo) & (v[:, axis] <= hi)])
        parts.append((np.asarray(hull.vertices), np.asarray(hull.faces)))
    return tuple(parts)


def _dense(mesh, parts, count=1_000_000, seed=1):
    """Largest distance to the mesh's solid of ``count`` points of the parts' surfaces on the
    boundary of their union (closest points and the winding number, point by point)."""
    from meshcol.collision.mesh_query import MeshSet
    from meshcol.decomposition.fidelity import SHARED_FACE_FRACTION, points_to_parts
    from meshcol.geometry.triangles import sample_surface

    rng = np.random.default_rng(seed)
    areas = np.array([trimesh.Trimesh(v, f).area for v, f in parts])
    counts = np.maximum(1, np.round(count * areas / areas.sum()).astype(int))
    points = np.concatenate([sample_surface(v, f, int(c), rng) for (v, f), c in zip(parts, counts)])
    owner = np.repeat(np.arange(len(parts)), counts)
    diagonal = float(np.linalg.norm(np.ptp(mesh.vertices, axis=0)))
    if len(parts) > 1:
        points = points[points_to_parts(points, parts, owner) > SHARED_FACE_FRACTION * diagonal]
    meshes = MeshSet.from_arrays([(mesh.vertices, mesh.faces)])
    distances, _ = meshes.closest_points(0, points)
    outside = ~meshes.contains(0, points)
    return float(distances[outside].max(initial=0.0))


def _hausdorff() -> None:
    from meshcol.decomposition.fidelity import fidelity

    mesh = trimesh.load(CORPUS / "Octocat-v2.obj", force="mesh", process=True)
    for k in (1, 4, 8):
        parts = _slab_hulls(mesh, k)
        reported = fidelity(mesh.vertices, mesh.faces, parts).hausdorff_parts_to_mesh
        dense = _dense(mesh, parts)
        print(
            f"octocat, {k} slab hulls: reported {reported:.6g}, dense (1e6) {dense:.6g}, ratio {reported / dense:.4f}"
        )


if __name__ == "__main__":
    trimesh.util.log.setLevel("ERROR")
    main()
