"""The native boundary: the Python enums mirror the C++ ones, results cross as typed objects."""

from __future__ import annotations

import dataclasses
import enum
import re

import numpy as np
import pytest

from meshcol._native import core, defaults
from meshcol.collision.hull import FLAT_RELATIVE_TOLERANCE, MAX_ABS_COORDINATE, HullStatus
from meshcol.collision.narrowphase import DistanceBatch, IntersectsBatch
from meshcol.collision.shapes import ConvexSet, ShapeKind
from meshcol.types import Status, TimeOfImpactStatus


def members(e: type[enum.Enum]) -> dict[str, int]:
    return {m.name: int(m.value) for m in e}


@pytest.mark.parametrize(
    ("python_enum", "native_enum"),
    [
        (Status, core.Status),
        (TimeOfImpactStatus, core.TimeOfImpactStatus),
        (ShapeKind, core.ShapeKind),
        (HullStatus, core.HullStatus),
    ],
    ids=["Status", "TimeOfImpactStatus", "ShapeKind", "HullStatus"],
)
def test_python_enums_match_the_bound_cpp_enums(python_enum, native_enum) -> None:
    assert members(python_enum) == members(native_enum)
    assert len(python_enum) == len(native_enum)


def test_query_results_are_the_python_result_classes() -> None:
    """The core builds a batch's result object itself, each field an array of its own."""
    cs = ConvexSet.from_vertices([np.eye(3), np.eye(3) + 5.0])
    pairs = np.array([[0, 1]], dtype=np.int64)
    r = cs._core.query_object(0, None, pairs, 1, DistanceBatch)
    assert type(r) is DistanceBatch
    assert r.distance.shape == (1,) and r.normal.shape == (1, 3)
    assert r.iterations.dtype == np.int32 and r.status.dtype == np.int8
    assert len({id(getattr(r, f.name)) for f in dataclasses.fields(r)}) == 6
    with pytest.raises(dataclasses.FrozenInstanceError):
        r.distance = np.zeros(1)  # type: ignore[misc]
    hit = cs._core.query_object(2, None, pairs, 1, IntersectsBatch)
    assert hit.intersects.dtype == np.bool_ and hit.intersects.tolist() == [False]
    # anything not in the core's form is declined, for the caller to convert
    assert cs._core.query_object(0, None, pairs.astype(np.int32), 1, DistanceBatch) is None
    assert cs._core.query_object(0, np.eye(4), pairs, 1, DistanceBatch) is None
    with pytest.raises(ValueError, match=r"^layout must be 0\.\.3, got 4$"):
        cs._core.query_object(4, None, pairs, 1, DistanceBatch)


def test_time_of_impact_results_are_typed_objects() -> None:
    from meshcol.collision.time_of_impact import TimeOfImpactBatch

    cs = ConvexSet.from_vertices([np.eye(3), np.eye(3) + 5.0])
    poses = np.tile(np.eye(4), (2, 1, 1))
    pairs = np.array([[0, 1]], dtype=np.int64)

    def toi(*args):
        return core.time_of_impact_object(cs._core, *args, 1e-6, 100, 1, TimeOfImpactBatch)

    r = toi(poses, poses, pairs, None, None)
    assert type(r) is TimeOfImpactBatch
    assert r.status[0] == TimeOfImpactStatus.SEPARATED and np.isnan(r.time_of_impact[0])
    assert r.iterations.dtype == np.int32 and r.status.dtype == np.int8
    # anything not in the core's form is declined, for the caller to convert
    assert toi(None, poses, pairs, None, None) is None
    assert toi(poses, poses.astype(np.float32), pairs, None, None) is None
    assert toi(poses, poses, pairs, np.zeros((2, 3), dtype=np.float32), None) is None
    assert toi(poses, poses, pairs, None, np.zeros((3, 3))) is None
    assert toi(poses[:1], poses[:1], pairs, None, None) is None
    with pytest.raises(ValueError, match=r"^pairs: index 2 out of range for 2 shapes$"):
        toi(poses, poses, [(0, 2)], None, None)
    with pytest.raises(ValueError, match=r"^max_iterations must be >= 1, got 0$"):
        core.time_of_impact_object(
            cs._core, poses, poses, pairs, None, None, 1e-6, 0, 1, TimeOfImpactBatch
        )


def test_bounding_radii_match_the_shapes() -> None:
    from meshcol.collision.shapes import Box, Capsule, Cylinder, Sphere

    cs = ConvexSet.from_shapes(
        [
            np.array([[3.0, 4.0, 0.0], [0, 0, 0], [1, 0, 0], [0, 0, 1]]),
            Sphere(2.0),
            Box((2.0, 4.0, 4.0)),
            Capsule(1.0, 2.0),
            Cylinder(3.0, 8.0),
        ]
    )
    assert cs._core.bounding_radii() == pytest.approx([5.0, 2.0, 3.0, 2.0, 5.0], abs=1e-12)


def test_defaults_are_exposed_under_their_new_names() -> None:
    assert defaults.sort_and_sweep_max_cell_changes == 0.25
    assert not hasattr(defaults, "sweep_max_cell_changes")
    assert 0 < defaults.sat_parallel_edge_sine < 1e-6


def test_hull_constants_mirror_the_core_defaults() -> None:
    assert defaults.flat_relative_tolerance == FLAT_RELATIVE_TOLERANCE
    assert defaults.hull_max_abs_coordinate == MAX_ABS_COORDINATE


@pytest.mark.parametrize("scale", [1.0, 1e-300, 1e-310, 5e-322])
def test_exact_crossings_hold_at_denormal_coordinates(scale: float) -> None:
    # Two triangles crossing through each other, and a pair side by side, scaled together:
    # the verdict is scale-free. Below 2^-1022 the exact predicates' rescaling overflowed (a
    # factor 2^k past 2^1023) and returned one sign whatever the side.
    from meshcol.collision.self_intersection import face_pairs_cross

    vertices = (
        np.array(
            [
                [0, 0, 0],
                [4, 0, 0],
                [0, 4, 0],
                [1, 1, -1],
                [1, 1, 1],
                [3, 3, 1],
                [8, 0, 0],
                [9, 0, 0],
                [8, 1, 0],
            ],
            dtype=np.float64,
        )
        * scale
    )
    faces = np.array([[0, 1, 2], [3, 4, 5], [6, 7, 8]], dtype=np.int64)
    crossing = face_pairs_cross(vertices, faces, np.array([[0, 1], [0, 2], [1, 2]]))
    assert crossing.tolist() == [True, False, False]


def test_every_default_of_the_one_list_reaches_python() -> None:
    # cpp/include/meshcol/defaults.inc is the one list: each entry is a C++ constexpr and an
    # attribute of meshcol._core.defaults with the same value.
    from pathlib import Path

    import meshcol

    listing = Path(meshcol.__file__).resolve().parent.parent / "cpp/include/meshcol/defaults.inc"
    if not listing.is_file():
        pytest.skip("the C++ sources are not beside the package (an installed wheel)")
    entries = re.findall(r"^MESHCOL_DEFAULT\(([^,]+), (\w+), (.+)\)$", listing.read_text(), re.M)
    assert len(entries) > 50
    for type_name, name, value in entries:
        exposed = getattr(defaults, name)
        expected = int(value, 0) if "int" in type_name or "long" in type_name else float(value)
        assert exposed == expected and type(exposed) is type(expected), name
