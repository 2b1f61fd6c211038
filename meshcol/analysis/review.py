"""What each command's review page shows (``--html FILE``), computed here and drawn by
:mod:`meshcol.io.review`.

Each ``*_page`` function takes the command's report (and its inputs) and returns a
:class:`meshcol.io.review.ReviewPage`: the bodies' meshes at their poses, their colliders
translucent over them, and what the command found, as arrays and table rows. The inputs are
read again (a page is an extra view of a run, never part of its numbers); decompositions come
from the files the run wrote.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from typing import Any

import numpy as np

from meshcol.io.review import HIGHLIGHT, MESH_COLOR, PALETTE, ReviewPage
from meshcol.io.robot import RobotOptions
from meshcol.types import Body
from meshcol.vocabulary import SEVERITY_ORDER

__all__ = [
    "check_page",
    "decompose_page",
    "fit_page",
    "hull_page",
    "inspect_page",
    "sweep_page",
    "SEVERITY_ORDER",
]

#: Rows of a page's table at most (the report has every row).
MAX_ROWS = 2000
#: Samples along a moving body's path.
PATH_SAMPLES = 48
#: Share of the largest mesh-to-parts distance over which a face counts as far from the parts.
FAR_SHARE = 0.5

FINDING_COLORS = {
    "open edges": "#ff0000",
    "non-manifold edges": "#ff8c00",
    "self-intersecting faces": "#e000e0",
    "inverted regions": "#0050ff",
}


def _title(inputs: Sequence[Any]) -> str:
    names = [os.path.basename(os.fspath(p)) for p in inputs]
    return ", ".join(names[:3]) + (f" and {len(names) - 3} more" if len(names) > 3 else "")


def _units(units: str | None) -> str:
    return f" {units}" if units else ""


def _hull_mesh(vertices: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """Triangles of the exact hull of ``vertices`` (None when flat or degenerate)."""
    from meshcol.collision.hull import exact_hull
    from meshcol.errors import InvalidMeshError

    try:
        h = exact_hull(vertices)
    except (InvalidMeshError, ValueError):
        return None
    if h.dimension < 3 or not len(h.faces):
        return None
    return h.vertices, h.faces


def _add_bodies(page: ReviewPage, bodies: Sequence[Body], pose: str = "pose") -> list[int]:
    page.group("meshes", "meshes (input)", MESH_COLOR)
    ids = []
    for body in bodies:
        index = page.add_body(body.name)
        page.add_mesh(body.vertices, body.faces, getattr(body, pose), body=index, name=body.name)
        ids.append(index)
    return ids


def _add_colliders(page: ReviewPage, colliders: Any, ids: list[int]) -> None:
    """Each convex part of each body, translucent, a colour per part."""
    from meshcol.io.primitives import primitive_mesh

    shapes = colliders.shapes
    poses = colliders.part_poses()
    page.group("colliders", "colliders (convex parts, a colour each)", PALETTE[0])
    cache: dict[int, Any] = {}
    for k in range(len(colliders.part_body)):
        body = int(colliders.part_body[k])
        if colliders.kinds[body] == "mesh":
            continue  # the mesh is its own collider
        start, end = int(shapes.offsets[k]), int(shapes.offsets[k + 1])
        if end > start:
            key = start
            if key not in cache:
                cache[key] = _hull_mesh(shapes.vertices[start:end])
            mesh = cache[key]
        else:  # a primitive part: the body's own, or a ``fit`` part
            primitive = shapes.primitive(k)
            mesh = primitive_mesh(primitive) if primitive is not None else None
        if mesh is None:
            continue
        several = colliders.body_part_offsets[body + 1] - colliders.body_part_offsets[body] > 1
        color = PALETTE[int(colliders.part_index[k] if several else body) % len(PALETTE)]
        page.add_mesh(
            mesh[0], mesh[1], poses[k], group="colliders", color=color, opacity=0.35, body=ids[body]
        )


def check_page(
    report: Any,
    inputs: Sequence[Any],
    collider: str,
    decompose_options: dict,
    robot_options: RobotOptions | None = None,
) -> ReviewPage:
    """The page of ``meshcol check``: bodies, colliders, and the pairs sorted by severity
    (violations first); choosing a pair frames both bodies, marks the witness points, draws
    the normal and labels the depth or gap."""
    from meshcol.analysis.check import with_half_spaces
    from meshcol.analysis.colliders import build_colliders
    from meshcol.io.scene import load_inputs

    scene = load_inputs(list(inputs), robot_options=with_half_spaces(robot_options))
    colliders = build_colliders(
        scene.bodies, collider, mesh_parts="hull", decompose_options=decompose_options
    )
    page = ReviewPage("check", _title(inputs), report.units)
    ids = _add_bodies(page, colliders.bodies)
    _add_colliders(page, colliders, ids)
    index = {name: i for i, name in enumerate(page.bodies)}
    s = report.summary
    u = _units(report.units)
    page.info += [
        ("bodies", str(s["bodies"])),
        ("candidate pairs", str(s["candidate_pairs"])),
        ("violations", f"{s['violations']} (--fail-on {report.settings['fail_on']})"),
        ("tolerance", f"{report.settings['tolerance']:g}{u}"),
        ("clearance", f"{report.settings['clearance']:g}{u}"),
        ("collider", report.settings["collider"]),
    ]
    rank = {name: k for k, name in enumerate(SEVERITY_ORDER)}

    def order(p: dict) -> tuple:
        sd = p["signed_distance"]
        return (not p["violation"], rank.get(p["status"], 99), np.inf if sd is None else sd)

    pairs = sorted(report.pairs, key=order)
    if len(pairs) > MAX_ROWS:
        page.notes.append(f"the table shows the {MAX_ROWS} worst of {len(pairs)} pairs")
    page.table(
        "Pairs (violations first, then by severity)",
        ["status", "signed distance" + u, "depth at most" + u, "body a", "body b"],
    )
    for p in pairs[:MAX_ROWS]:
        a = p["body_a"] if p["part_a"] is None else f"{p['body_a']}/{p['part_a']}"
        b = p["body_b"] if p["part_b"] is None else f"{p['body_b']}/{p['part_b']}"
        points = [q for q in (p["point_a"], p["point_b"]) if q is not None]
        if p["status"] in ("contained", "undecided"):
            label = p["status"]
        elif (p["depth"] or 0) > 0:
            label = f"depth {p['depth']:.4g}{u}"
        elif p["distance"] is not None:
            label = f"gap {p['distance']:.4g}{u}"
        else:
            label = p["status"]
        page.add_row(
            [p["status"], p["signed_distance"], p["depth_upper"], a, b],
            bodies=tuple(index[n] for n in (p["body_a"], p["body_b"]) if n in index),
            points=points or None,
            normal=p["normal"],
            label=label,
            severity="violation" if p["violation"] else "",
        )
    return page


def sweep_page(report: Any) -> ReviewPage:
    """The page of ``meshcol sweep``: each moving body's path, its start and end poses, and
    per hit the two bodies at the time of impact and the contact point."""
    bodies = report.bodies
    source = report.scene.source
    page = ReviewPage(
        "sweep", _title((source and [source]) or [b.name for b in bodies[:3]]), report.scene.units
    )
    _add_bodies(page, bodies)
    _add_motions(page, report)
    u = _units(report.scene.units)
    page.info += [
        ("bodies", str(len(bodies))),
        ("moving", str(sum(_moving(report)))),
        ("hits", str(len(report.hits))),
        ("collider", report.collider),
        ("tolerance", f"{report.tolerance:g}{u}"),
    ]
    _add_hits(page, report)
    return page


def _moving(report: Any) -> Sequence[bool]:
    return report.moving or tuple(False for _ in report.bodies)


def _add_motions(page: ReviewPage, report: Any) -> None:
    """Each moving body at its end pose, translucent, and the path of its centre."""
    from meshcol.analysis.sweep import _turns
    from meshcol.collision.time_of_impact import interpolate_pose

    bodies = report.bodies
    page.group("end", "end poses", "#4363d8")
    page.group("paths", "paths (body origins)", "#000000")
    start = np.stack([b.pose for b in bodies]) if bodies else np.zeros((0, 4, 4))
    end = (
        np.stack([b.end_pose if b.end_pose is not None else b.pose for b in bodies])
        if bodies
        else start
    )
    rotations, pivots = _turns(tuple(bodies), start, end) if bodies else (None, None)
    t = np.linspace(0.0, 1.0, PATH_SAMPLES)
    for k, (body, moving) in enumerate(zip(bodies, _moving(report))):
        if not moving:
            continue
        page.add_mesh(body.vertices, body.faces, end[k], group="end", color="#4363d8", opacity=0.3)
        turn: dict[str, Any] = {}
        if rotations is not None and pivots is not None:
            turn = {
                "rotation": np.repeat(rotations[k][None], len(t), 0),
                "pivot": np.repeat(pivots[k][None], len(t), 0),
            }
        poses = interpolate_pose(
            np.repeat(start[k][None], len(t), 0), np.repeat(end[k][None], len(t), 0), t, **turn
        )
        centre = 0.5 * (body.vertices.min(axis=0) + body.vertices.max(axis=0))
        path = poses[:, :3, :3] @ centre + poses[:, :3, 3]
        page.add_lines(np.stack([path[:-1], path[1:]], axis=1), group="paths", color="#000000")


def _if_finite(value: Any) -> Any:
    """``value`` when it is there and every entry of it is finite, else None."""
    return value if value is not None and np.all(np.isfinite(value)) else None


def _add_hits(page: ReviewPage, report: Any) -> None:
    """The table of hits, earliest first: choosing one shows both bodies at the time of
    impact (a group of its own, hidden otherwise) and the contact point and normal."""
    index = {name: i for i, name in enumerate(page.bodies)}
    by_name = {b.name: b for b in report.bodies}
    page.table(
        "Hits (earliest first)", ["body a", "body b", "toi (fraction)", "time (s)", "status"]
    )
    hits = sorted(report.hits, key=lambda h: h.time_of_impact)[:MAX_ROWS]
    for k, h in enumerate(hits):
        group = f"impact{k}"
        page.group(group, f"time-of-impact poses of hit {k}", HIGHLIGHT, visible=False)
        for name, pose in ((h.body_a, h.pose_a), (h.body_b, h.pose_b)):
            body = by_name.get(name)
            if body is not None and _if_finite(pose) is not None:
                page.add_mesh(
                    body.vertices, body.faces, pose, group=group, color=HIGHLIGHT, opacity=0.6
                )
        point = _if_finite(h.point)
        when = f"toi {h.time_of_impact:.4g}" + ("" if h.time is None else f", t = {h.time:.4g} s")
        page.add_row(
            [h.body_a, h.body_b, h.time_of_impact, h.time, h.status.name.lower()],
            bodies=tuple(index[n] for n in (h.body_a, h.body_b) if n in index),
            points=None if point is None else [point],
            normal=_if_finite(h.normal),
            label=f"contact at {when}",
            severity="violation" if report.exit_code else "",
            group=group,
        )
    # the impact groups are declared for the rows; the legend keeps only the scene's toggles
    for k in range(len(hits)):
        page.groups.pop(f"impact{k}", None)


def _distance_to_parts(
    points: np.ndarray, planes: list[np.ndarray]
) -> tuple[np.ndarray, np.ndarray]:
    """Per point, its distance outside the nearest convex part (0 inside one; from the part's
    face planes, exact on a face's region, a lower bound near edges) and that part's index."""
    best = np.full(len(points), np.inf)
    nearest = np.full(len(points), -1, dtype=np.int64)
    for k, eq in enumerate(planes):
        d = np.maximum((points @ eq[:, :3].T + eq[:, 3]).max(axis=1), 0.0)
        closer = d < best
        best[closer] = d[closer]
        nearest[closer] = k
    return best, nearest


def decompose_page(
    report: Any,
    out_dir: str,
    inputs: Sequence[Any] | None = None,
    robot_options: RobotOptions | None = None,
) -> ReviewPage:
    """The page of ``meshcol decompose``: each body's mesh with its parts in distinct colours,
    the fidelity numbers per part, and the mesh faces farthest from the parts highlighted.

    ``inputs`` are the command's inputs (mesh files or a manifest; default: the report's
    files); their bodies are read as the run read them, each part of a body on its own and
    at its pose (``robot_options``: as the run read a robot), and the parts from the files
    the run wrote in ``out_dir`` (world frame)."""
    from meshcol.io.scene import iter_inputs

    page = ReviewPage("decompose", _title([f["path"] for f in report.files]), report.units)
    page.group("meshes", "meshes (input)", MESH_COLOR)
    page.group("parts", "parts (a colour each)", PALETTE[0])
    page.group(
        "far", f"mesh faces far from the parts (over {FAR_SHARE:.0%} of the largest gap)", "#ff0000"
    )
    page.table("Parts", ["body", "part", "vertices", "volume", "covers", "farthest"])
    paths = list(inputs or [f["path"] for f in report.files])
    bodies_by_source = {
        source: {part.name: part for whole in bodies for part in whole.part_bodies()}
        for source, bodies in iter_inputs(paths, robot_options=robot_options)
    }
    for entry in report.files:
        if entry["status"] != "ok":
            message = f"{os.path.basename(entry['path'])}: {entry['status']}: "
            page.notes.append((message + (entry.get("message") or "")).strip())
            continue
        meshes = bodies_by_source.get(entry["path"]) or {}
        for row in entry["bodies"]:
            body = meshes.get(row["name"])
            if body is not None:
                _add_decomposed_body(page, body, row, out_dir, _units(report.units))
    return page


def _add_decomposed_body(page: ReviewPage, body: Body, row: dict, out_dir: str, u: str) -> None:
    """One body of a decomposition: its mesh, its faces far from the parts, its numbers, and
    each part (drawn and a row of the table)."""
    from meshcol.collision.hull import exact_hull

    index = page.add_body(body.name)
    page.add_mesh(body.vertices, body.faces, body.pose, body=index, name=body.name)
    hulls = [exact_hull(points) for points in _part_points(row["outputs"], out_dir)]
    world = body.vertices @ body.pose[:3, :3].T + body.pose[:3, 3]
    metrics = row.get("metrics") or {}
    far, nearest, flagged = _far_faces(world[body.faces].mean(axis=1), hulls, metrics)
    if flagged.any():
        page.add_mesh(world, body.faces[flagged], group="far", color="#ff0000", body=index)
    page.info.append(
        (
            body.name,
            f"{len(hulls)} parts, Hausdorff mesh->parts "
            f"{metrics.get('hausdorff_mesh_to_parts', float('nan')):.4g}{u}, parts->mesh "
            f"{metrics.get('hausdorff_parts_to_mesh', float('nan')):.4g}{u}, volume ratio "
            f"{metrics.get('volume_ratio') or float('nan'):.4g}",
        )
    )
    _add_parts(page, body.name, index, hulls, far, nearest)


def _part_points(outputs: Sequence[str], out_dir: str) -> list[np.ndarray]:
    """The vertices (world frame) of every part of the files a body's decomposition wrote."""
    from meshcol.io.mesh_read import load_mesh
    from meshcol.io.staging import written_path

    parts: list[np.ndarray] = []
    for output in outputs:
        # the run's outputs may still wait to be put in place (meshcol.io.staging)
        for part_body in load_mesh(written_path(os.path.join(out_dir, output)), merge=False):
            for _name, v, _f in part_body.part_meshes():
                parts.append(v @ part_body.pose[:3, :3].T + part_body.pose[:3, 3])
    return parts


def _far_faces(
    centroids: np.ndarray, hulls: Sequence[Any], metrics: dict
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per mesh face (its centroid): its distance outside the parts, its nearest part (-1:
    none), and whether it is far (over :data:`FAR_SHARE` of the largest distance and over
    the run's tolerance)."""
    planes = [h.equations for h in hulls if h.dimension == 3]
    solid = [k for k, h in enumerate(hulls) if h.dimension == 3]
    far = np.zeros(len(centroids))
    nearest = np.full(len(centroids), -1)
    if planes:
        far, near_solid = _distance_to_parts(centroids, planes)
        nearest = np.asarray(solid)[near_solid]
    largest = float(far.max()) if len(far) else 0.0
    tolerance = float(metrics.get("tolerance") or 0.0)
    if largest > 0:
        flagged = (far > FAR_SHARE * largest) & (far > tolerance)
    else:
        flagged = np.zeros(len(far), bool)
    return far, nearest, flagged


def _add_parts(
    page: ReviewPage,
    name: str,
    index: int,
    hulls: Sequence[Any],
    far: np.ndarray,
    nearest: np.ndarray,
) -> None:
    """Each part, a colour each, and its row: vertices, volume, the share of the mesh's faces
    it is nearest to, and their largest distance outside it."""
    from meshcol.geometry.topology import closed_volume

    for k, h in enumerate(hulls):
        color = PALETTE[k % len(PALETTE)]
        if h.dimension == 3:
            page.add_mesh(h.vertices, h.faces, group="parts", color=color, opacity=0.45, body=index)
        mine = nearest == k
        share = float(mine.mean()) if len(mine) else 0.0
        page.add_row(
            [
                name,
                k,
                len(h.vertices),
                closed_volume(h.vertices, h.faces) if h.dimension == 3 else 0.0,
                f"{share:.1%}",
                float(far[mine].max()) if mine.any() else 0.0,
            ],
            bodies=(index,),
            label=f"{name} part {k}",
        )


def _findings(page: ReviewPage, body: Body, index: int) -> dict[str, int]:
    """Open edges, non-manifold edges, self-intersecting faces and inverted regions of a
    body, drawn on its mesh; returns their counts. The self-intersecting faces are those of
    the crossing pairs :func:`~meshcol.collision.self_intersection.self_intersecting_pairs`
    returns: at most ``MAX_KEPT_PAIRS`` pairs, found within its work budget."""
    from meshcol.collision.self_intersection import self_intersecting_pairs
    from meshcol.geometry.topology import edge_table, oriented_volume

    world = body.vertices @ body.pose[:3, :3].T + body.pose[:3, 3]
    faces = body.faces
    counts = dict.fromkeys(FINDING_COLORS, 0)
    if not len(faces):
        return counts
    edges, face_counts, _ = edge_table(faces)
    for name, mask in (("open edges", face_counts == 1), ("non-manifold edges", face_counts > 2)):
        if mask.any():
            page.add_lines(
                world[edges[mask]], group="findings", color=FINDING_COLORS[name], body=index
            )
            counts[name] = int(mask.sum())
    crossing = self_intersecting_pairs(body.vertices, faces)
    if len(crossing):
        bad = np.unique(crossing)
        page.add_mesh(
            world,
            faces[bad],
            group="findings",
            color=FINDING_COLORS["self-intersecting faces"],
            body=index,
        )
        counts["self-intersecting faces"] = len(bad)
    volume = oriented_volume(body.vertices, faces)
    if volume is not None and volume[0] < 0:
        page.add_mesh(
            world,
            faces,
            group="findings",
            color=FINDING_COLORS["inverted regions"],
            opacity=0.5,
            body=index,
        )
        counts["inverted regions"] = len(faces)
    return counts


def _shape_page(
    command: str,
    inputs: Sequence[Any],
    units: str | None,
    hulls: dict[str, tuple],
    robot_options: RobotOptions | None = None,
) -> ReviewPage:
    from meshcol.io.scene import load_inputs

    scene = load_inputs(list(inputs), robot_options=robot_options)
    page = ReviewPage(command, _title(inputs), units if units is not None else scene.units)
    ids = _add_bodies(page, scene.bodies)
    page.group("hulls", "convex hulls", PALETTE[0])
    page.group(
        "findings",
        "findings: open edges red, non-manifold orange, self-intersecting magenta, inverted blue",
        "#ff0000",
    )
    page.table("Bodies", ["body", "hull volume", "added", *FINDING_COLORS])
    for k, body in enumerate(scene.bodies):
        hull = hulls.get(body.name)
        if hull is None:
            world = body.vertices @ body.pose[:3, :3].T + body.pose[:3, 3]
            mesh = _hull_mesh(world)
            hull = (None, None) if mesh is None else (mesh[0], mesh[1])
        if hull[0] is not None:
            page.add_mesh(
                hull[0],
                hull[1],
                group="hulls",
                color=PALETTE[k % len(PALETTE)],
                opacity=0.35,
                body=ids[k],
            )
        counts = _findings(page, body, ids[k])
        volume, added = _hull_numbers(hull)
        page.add_row(
            [body.name, volume, added, *counts.values()],
            bodies=(ids[k],),
            label=body.name,
            severity="violation" if any(counts.values()) else "",
        )
    return page


def _hull_numbers(hull: tuple) -> tuple[float | None, float | None]:
    if len(hull) > 2:
        return hull[2], hull[3]
    if hull[0] is None:
        return None, None
    from meshcol.geometry.topology import closed_volume

    return closed_volume(hull[0], hull[1]), None


def hull_page(
    report: Any, inputs: Sequence[Any], robot_options: RobotOptions | None = None
) -> ReviewPage:
    """The page of ``meshcol hull``: each hull over its mesh, the volume it adds, and the
    mesh's findings."""
    hulls = {
        row["name"]: (h.vertices, h.faces, h.volume, h.added_volume if h.max_vertices else None)
        for row, h in zip(report.bodies, report.hulls)
    }
    page = _shape_page("hull", inputs, report.units, hulls, robot_options)
    if report.target is not None:  # the target's limits shaped every hull
        limits = ", ".join(f"{k} {v:g}" for k, v in sorted(report.target.limits.items()))
        page.info.append(("target", f"{report.target.name} ({limits})"))
    if report.max_vertices or report.target is None:
        page.info.append(("max vertices", str(report.max_vertices or "exact hull")))
    return page


def fit_page(
    report: Any, inputs: Sequence[Any], robot_options: RobotOptions | None = None
) -> ReviewPage:
    """The page of ``meshcol fit``: each body's fitted primitive (or the hull it kept) over
    its mesh, and the mesh's findings. Fits in a link's frame (a robot rebuilt) are shown
    as the bodies' hulls."""
    from meshcol.analysis.fit import _fit_mesh

    fits: dict[str, tuple] = {}
    if report.frame == "world":
        for row, result in zip(report.bodies, report.fits):
            _, vertices, faces = _fit_mesh(str(row["name"]), result)
            fits[str(row["name"])] = (vertices, faces)
    page = _shape_page("fit", inputs, report.units, fits, robot_options)
    page.info.append(("shape", f"{report.shape} (volume tolerance {report.volume_tolerance:g})"))
    return page


def inspect_page(
    report: Any, inputs: Sequence[Any], robot_options: RobotOptions | None = None
) -> ReviewPage:
    """The page of ``meshcol inspect``: each mesh with its findings drawn on it (open edges,
    non-manifold edges, self-intersecting faces, inverted regions) and its hull over it."""
    page = _shape_page("inspect", inputs, report.units, {}, robot_options)
    page.info.append(("bodies", str(len(report.inspections))))
    return page
