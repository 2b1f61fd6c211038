"""``Body.plain``, the loader's fast constructor of the common body, against the frozen
constructor it stands for (issue 32: a manifest of 1,000,000 bodies)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from meshcol.types import Body, Box, Sphere


def same(a: Body, b: Body) -> None:
    for f in dataclasses.fields(Body):
        x, y = a.__dict__[f.name], b.__dict__[f.name]
        if isinstance(x, np.ndarray) or isinstance(y, np.ndarray):
            assert x is y, f.name
        else:
            assert x == y, f.name


def test_a_plain_mesh_body_is_the_constructors() -> None:
    vertices, faces = np.eye(3), np.array([[0, 1, 2]])
    pose = np.eye(4)
    made = Body.plain("a", "a.obj", vertices, faces, pose, None, "hull")
    same(made, Body("a", "a.obj", vertices, faces, pose, collider="hull"))
    assert made.vertex_count == 3
    with pytest.raises(dataclasses.FrozenInstanceError):
        made.name = "b"  # type: ignore[misc]


@pytest.mark.parametrize("primitive", [Sphere(0.5), Box((1.0, 2.0, 3.0)), Sphere(1e-4)])
def test_a_plain_primitive_body_is_of_primitives(primitive) -> None:
    pose = np.eye(4)
    made = Body.plain("p", "scene.json", None, None, pose, primitive)
    reference = Body.of_primitive("p", "scene.json", primitive, pose=pose)
    same(made, reference)
    assert made.vertex_count == reference.vertex_count == len(reference.vertices)
    assert np.array_equal(made.faces, reference.faces)
