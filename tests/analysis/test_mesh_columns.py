"""A manifest of static mesh bodies kept as columns (issue 32, item 5): the core reads the
manifest and its one-object files into arrays, and no Body is made from the manifest to the
report; the bodies, colliders and reports are those of the Python reader's bodies built one
by one, to the bit, with instances (files named by several bodies), a file named twice by two
spellings, an identical copy of a file under another name, quaternions and Euler angles and
collider shapes."""

from __future__ import annotations

import dataclasses
import json
import re
from pathlib import Path

import numpy as np
import pytest
from manifest_readers import python_reader
from test_scene_columns import describe

import meshcol.io.scene_validate as scene_validate
from meshcol.analysis.bulk_colliders import bulk_colliders
from meshcol.analysis.check import CheckOptions, check_scene
from meshcol.analysis.colliders import build_colliders
from meshcol.collision.shapes import ConvexSet
from meshcol.io import scene_parse
from meshcol.io.column_bodies import MeshBodies, body_names, body_sources, vertex_counts
from meshcol.io.scene import load_scene

#: An octahedron, a cube of 1 m and a thin tetrahedron: hulls whose pairs in the document
#: below are apart, touching and overlapping.
OCTAHEDRON = "v 0.5 0 0\nv -0.5 0 0\nv 0 0.5 0\nv 0 -0.5 0\nv 0 0 0.5\nv 0 0 -0.5\n" + "".join(
    f"f {a} {b} {c}\n"
    for a, b, c in (
        (1, 3, 5),
        (3, 2, 5),
        (2, 4, 5),
        (4, 1, 5),
        (3, 1, 6),
        (2, 3, 6),
        (4, 2, 6),
        (1, 4, 6),
    )
)
CUBE = (
    "v -0.5 -0.5 -0.5\nv 0.5 -0.5 -0.5\nv 0.5 0.5 -0.5\nv -0.5 0.5 -0.5\n"
    "v -0.5 -0.5 0.5\nv 0.5 -0.5 0.5\nv 0.5 0.5 0.5\nv -0.5 0.5 0.5\n"
    "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\n"
    "f 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n"
)
TET = "v 0 0 0\nv 0.9 0 0\nv 0 0.4 0\nv 0 0 0.3\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
FILES = {"octahedron.obj": OCTAHEDRON, "cube.obj": CUBE, "tet.obj": TET, "copy.obj": CUBE}
#: Each body's mesh, in turn: "./cube.obj" is cube.obj spelt another way, copy.obj the same
#: vertices as cube.obj in another file.
MESHES = ["cube.obj", "octahedron.obj", "tet.obj", "./cube.obj", "copy.obj", "cube.obj"]
CLOCKS = re.compile(r'("generated_at"|"seconds"|"load_seconds"): [^,\n]*')


def document(n: int = 60, seed: int = 11) -> dict:
    rng = np.random.default_rng(seed)
    bodies = []
    for i in range(n):
        body: dict = {
            "name": f"prop{i:03d}",
            "mesh": MESHES[i % len(MESHES)],
            "position": [0.9 * (i % 6), 0.9 * (i // 6 % 5), 0.9 * (i // 30)],
        }
        if i % 3 == 0:
            body["rotation"] = {"quaternion": rng.normal(size=4).tolist()}
        elif i % 3 == 1:
            body["rotation"] = {"euler_deg": rng.uniform(-200, 200, 3).tolist(), "order": "zxz"}
        if i % 7 == 0:
            body["shape"] = "hull"
        elif i % 11 == 0:
            body["shape"] = "mesh"
        bodies.append(body)
    return {"units": "m", "bodies": bodies}


def forget() -> None:
    scene_parse.forget_documents()
    scene_validate._LAST[:] = [object(), None, None]


def load_both(folder: Path, doc: dict) -> tuple:
    """The scene of ``doc`` over :data:`FILES` as the native reader loads it (columns) and
    as the Python reader does (bodies built in bulk, one object each)."""
    for name, text in FILES.items():
        (folder / name).write_text(text)
    path = folder / "scene.json"
    path.write_text(json.dumps(doc))
    forget()
    columns = load_scene(path)
    forget()
    with python_reader():
        objects = load_scene(path)
    forget()
    return columns, objects


@pytest.fixture
def both(tmp_path):
    return load_both(tmp_path, document())


def report_text(scene, options: CheckOptions) -> str:
    return CLOCKS.sub(r"\1: 0", check_scene(scene, options).to_json())


def test_the_mesh_columns_are_the_python_readers_bodies_to_the_bit(both):
    columns, objects = both
    assert isinstance(columns.bodies, MeshBodies)
    assert isinstance(objects.bodies, tuple)
    assert body_names(columns.bodies) == [b.name for b in objects.bodies]
    assert body_sources(columns.bodies) == [b.source for b in objects.bodies]
    assert vertex_counts(columns.bodies).tolist() == [len(b.vertices) for b in objects.bodies]
    assert not columns.bodies._made  # the readers above made no body
    assert describe(columns) == describe(objects)
    assert len(columns.bodies._made) == len(objects.bodies)


def test_a_check_of_mesh_columns_makes_no_body_and_writes_the_same_bytes(both):
    columns, objects = both
    for options in (
        CheckOptions(),
        CheckOptions(clearance=0.2, tolerance=1e-3, ignore=("prop001:*",)),
    ):
        for excluded in ((), (("prop000", "prop001", "adjacent"),)):
            a = dataclasses.replace(columns, excluded_pairs=excluded)
            b = dataclasses.replace(objects, excluded_pairs=excluded)
            text = report_text(a, options)
            assert text == report_text(b, options)
            statuses = {p["status"] for p in json.loads(text)["pairs"]}
            assert {"penetrating", "separated"} <= statuses, statuses
    # a body is made only for the triangles of a pair that needs them (a "mesh" body, a box
    # inside another's: the mesh phase), as it would be read from the body
    made = set(columns.bodies._made)
    assert made and len(made) < len(columns.bodies)


def test_a_check_of_hulls_in_columns_makes_no_body(tmp_path):
    doc = document()
    for body in doc["bodies"]:
        body["mesh"] = "cube.obj" if body["mesh"] != "octahedron.obj" else body["mesh"]
        body.pop("shape", None)
    columns, objects = load_both(tmp_path, doc)
    assert isinstance(columns.bodies, MeshBodies)
    assert report_text(columns, CheckOptions()) == report_text(objects, CheckOptions())
    assert not columns.bodies._made


def test_the_colliders_of_mesh_columns_are_the_body_loops_array_for_array(both):
    columns, objects = both
    fast, slow = build_colliders(columns.bodies), build_colliders(objects.bodies)
    assert isinstance(fast.bodies, MeshBodies) and not columns.bodies._made
    assert fast.kinds == slow.kinds
    for name in (*ConvexSet._FIELDS, "hull_status"):
        x, y = getattr(fast.shapes, name), getattr(slow.shapes, name)
        assert x.dtype == y.dtype and x.shape == y.shape and x.tobytes() == y.tobytes(), name
    for name in ("part_body", "part_index", "body_part_offsets", "part_label"):
        assert np.array_equal(getattr(fast, name), getattr(slow, name)), name
    assert fast.part_poses().tobytes() == slow.part_poses().tobytes()
    # cube.obj, ./cube.obj and copy.obj are one shape; octahedron and tet one each
    found = bulk_colliders(columns.bodies, "hull", "hull")
    assert found is not None and len(found[1].kinds) == 3 and not columns.bodies._made
