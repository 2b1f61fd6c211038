"""Inspect on instanced meshes: each mesh measured once, each body reported as if alone."""

from __future__ import annotations

import json

import numpy as np
import pytest

from meshcol.analysis.health import HEALTH_IDS, health_findings, inspect_body
from meshcol.analysis.inspect import inspect
from meshcol.analysis.physics import PhysicsOptions, physics_readiness
from meshcol.io.report import dumps_json
from meshcol.io.scene import load_scene

CUBE = [(x, y, z) for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)]
# outward triangles of CUBE (vertex index = 4x + 2y + z)
CUBE_FACES = [
    (0, 1, 3),
    (0, 3, 2),
    (4, 6, 7),
    (4, 7, 5),
    (0, 4, 5),
    (0, 5, 1),
    (2, 3, 7),
    (2, 7, 6),
    (0, 2, 6),
    (0, 6, 4),
    (1, 5, 7),
    (1, 7, 3),
]
#: Width of a sliver through the cube's top face: above 1e-7 of the diagonal of the mesh's box
#: (sqrt 4.25) but not of that box turned 45 degrees about z (sqrt 6.25). Only turned
#: instances count it as degenerate, and a degenerate face is left out of the crossings.
SLIVER_WIDTH = 2.3e-7


def obj(vertices, faces) -> str:
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in vertices]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in faces]
    return "\n".join(lines) + "\n"


def write_meshes(folder) -> None:
    (folder / "cube.obj").write_text(obj(CUBE, CUBE_FACES))
    # the cube's vertices, two faces fewer: a key without the faces would take it for the cube
    (folder / "open.obj").write_text(obj(CUBE, CUBE_FACES[:-2]))
    (folder / "inverted.obj").write_text(obj(CUBE, [f[::-1] for f in CUBE_FACES]))
    sliver = [(0.1, -0.2, 0.0), (0.1, -0.2, 1.0), (0.1 + SLIVER_WIDTH, -0.2, 0.5)]
    (folder / "sliver.obj").write_text(obj(CUBE + sliver, CUBE_FACES + [(8, 9, 10)]))


ROTATIONS = [
    None,
    {"euler_deg": [0.0, 0.0, 45.0], "order": "xyz"},
    {"quaternion": [0.9, 0.1, -0.3, 0.2]},
    {"euler_deg": [12.0, -70.0, 33.0], "order": "zyx"},
    {"euler_deg": [0.0, 0.0, 90.0], "order": "xyz"},
]


def write_level(folder, count: int, meshes: list[str], scales: bool = True) -> str:
    """A manifest of ``count`` instances of ``meshes``: moved (near and far from the origin),
    turned, some scaled; ``inverted.obj`` bodies are ``mesh`` colliders."""
    bodies = []
    for i in range(count):
        mesh = meshes[i % len(meshes)]
        spec: dict = {
            "name": f"{mesh.split('.')[0]}_{i}",
            "mesh": mesh,
            "position": [3.0 * i + (1e4 if i % 6 == 5 else 0.0), 0.25 * (i % 5), 0.1 * i],
        }
        rotation = ROTATIONS[(i // len(meshes)) % len(ROTATIONS)]
        if rotation is not None:
            spec["rotation"] = rotation
        if scales and i % 7 == 3:
            spec["scale"] = 2.0
        elif scales and i % 11 == 6:
            spec["scale"] = [1.0, 3.0, 0.5]
        if mesh == "inverted.obj":
            spec["shape"] = "mesh"
        bodies.append(spec)
    path = folder / "level.json"
    path.write_text(json.dumps({"units": "m", "bodies": bodies}))
    return str(path)


def by_body(findings) -> dict[str, list[dict]]:
    """Findings grouped by body, in their order: a body's own findings keep their order
    whether it is inspected alone or in a scene (where MC204 of every body comes first)."""
    out: dict[str, list[dict]] = {}
    for f in findings:
        out.setdefault(f.body, []).append(f.to_dict())
    return out


def test_instances_are_reported_as_each_body_alone(tmp_path) -> None:
    write_meshes(tmp_path)
    meshes = ["cube.obj", "open.obj", "inverted.obj", "sliver.obj"]
    path = write_level(tmp_path, 80, meshes)
    report = inspect(path)
    scene = load_scene(path)

    # the oracle: every body inspected on its own, nothing shared with another
    alone = [inspect_body(body, declared_units="m") for body in scene.bodies]
    assert dumps_json([r.to_dict() for r in report.inspections]) == dumps_json(
        [r.to_dict() for r in alone]
    )
    rows = []
    findings = [f for r in alone for f in health_findings(r, r.name, None)]
    for body in scene.bodies:
        body_rows, body_findings = physics_readiness([body], PhysicsOptions(), units="m")
        rows += body_rows
        findings += body_findings
    assert dumps_json(list(report.physics)) == dumps_json(rows)
    assert by_body(report.findings) == by_body(findings)

    # the cases the sharing could get wrong did occur
    kinds = {
        name: [r for r in report.inspections if r.name.startswith(name)]
        for name in ("cube", "open", "inverted", "sliver")
    }
    assert all(r.watertight for r in kinds["cube"]) and not any(r.watertight for r in kinds["open"])
    # pose-dependent: the sliver is degenerate, and so not crossing, in some instances only
    assert {(r.degenerate_faces, r.self_intersecting_pairs) for r in kinds["sliver"]} == {
        (0, 1),
        (1, 0),
    }
    assert len({tuple(r.size) for r in kinds["cube"]}) > 1
    assert {row["collider"] for row in report.physics} == {"hull", "mesh"}


def test_inspect_measures_each_unique_mesh_once(tmp_path, monkeypatch) -> None:
    import meshcol.analysis.geometry_cache as geometry_module
    import meshcol.collision.hull as hull_module
    import meshcol.collision.mesh_topology as topology_module
    import meshcol.collision.self_intersection as crossing_module
    import meshcol.geometry.mass as mass_module

    calls: dict[str, int] = {}

    def counted(module, name: str, batch: bool = False) -> None:
        original = getattr(module, name)

        def count(*args, **kwargs):
            # a batch counts the meshes it is given
            calls[name] = calls.get(name, 0) + (len(args[0]) if batch else 1)
            return original(*args, **kwargs)

        monkeypatch.setattr(module, name, count)

    counted(crossing_module, "self_intersections")
    counted(geometry_module, "_manifold_status")
    counted(topology_module, "mesh_topology_batch", batch=True)
    counted(mass_module, "mass_properties_batch", batch=True)
    counted(hull_module, "exact_hull")

    write_meshes(tmp_path)
    meshes = ["cube.obj", "open.obj", "inverted.obj"]  # no sliver: one mask per mesh
    report = inspect(write_level(tmp_path, 60, meshes, scales=False))
    assert len(report.inspections) == 60
    unique = len(meshes)
    assert calls["self_intersections"] == unique
    assert calls["_manifold_status"] == unique
    assert calls["mesh_topology_batch"] == unique
    # the visual meshes' and the hulls' (the open box's hull is the cube's)
    assert calls["mass_properties_batch"] <= 2 * unique
    assert calls["exact_hull"] <= unique


def test_each_degenerate_mask_is_crossed_once(tmp_path, monkeypatch) -> None:
    import meshcol.collision.self_intersection as crossing_module

    seen: list[bytes] = []
    original = crossing_module.self_intersections

    def count(vertices, faces, skip=None):
        seen.append(np.asarray(skip).tobytes())
        return original(vertices, faces, skip=skip)

    monkeypatch.setattr(crossing_module, "self_intersections", count)
    write_meshes(tmp_path)
    report = inspect(write_level(tmp_path, 30, ["sliver.obj"], scales=False))
    assert {r.degenerate_faces for r in report.inspections} == {0, 1}
    assert len(seen) == len(set(seen)) == 2


@pytest.mark.parametrize("shape", ["mesh", "fit"])
def test_instances_with_other_colliders_match_each_body_alone(tmp_path, shape) -> None:
    write_meshes(tmp_path)
    path = write_level(tmp_path, 24, ["cube.obj", "open.obj", "inverted.obj"])
    options = PhysicsOptions(shape=shape)
    report = inspect(path, physics=options)
    rows, findings = [], []
    for body in load_scene(path).bodies:
        body_rows, body_findings = physics_readiness([body], options, units="m")
        rows += body_rows
        findings += body_findings
    assert dumps_json(list(report.physics)) == dumps_json(rows)
    physics = [f for f in report.findings if f.rule not in HEALTH_IDS.values()]
    assert by_body(physics) == by_body(findings)
    if shape == "mesh":  # authored triangles: each inside-out instance named (MC204)
        inside_out = {f.body for f in report.findings if f.rule == "MC204"}
        assert inside_out == {r.name for r in report.inspections if r.name.startswith("inv")}
