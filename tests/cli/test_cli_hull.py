"""``meshcol hull``: outputs, reports, flat input and every kind of bad input."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from conftest import UNIT_CUBE_OBJ

from meshcol.cli import main


def run(*args: str):
    return CliRunner().invoke(main, [str(a) for a in args])


def write(folder: Path, name: str, text: str) -> Path:
    path = folder / name
    path.write_text(text)
    return path


def outside_distance(points: np.ndarray, hull_vertices: np.ndarray) -> float:
    from scipy.spatial import ConvexHull

    hull = ConvexHull(hull_vertices)
    return float((points @ hull.equations[:, :3].T + hull.equations[:, 3]).max())


def test_report_on_stdout_without_mesh_output(tmp_path: Path) -> None:
    cube = write(tmp_path, "cube.obj", UNIT_CUBE_OBJ)
    result = run("hull", cube)
    assert result.exit_code == 0, result.output
    assert result.stderr == "meshcol: hull: PASS: 1 hull, 8 vertices\n"
    report = json.loads(result.stdout)
    assert report["schema_version"] == 1 and report["command"] == "hull"
    assert report["tool"]["name"] == "meshcol"
    assert report["settings"] == {
        "frame": "world",
        "max_vertices": None,
        "out_dir": None,
        "output": None,
    }
    (body,) = report["bodies"]
    assert body["name"] == "cube" and body["source"] == str(cube)
    assert (body["input_vertices"], body["input_faces"]) == (8, 12)
    assert (body["hull_vertices"], body["hull_faces"]) == (8, 12)
    assert body["hull_volume"] == pytest.approx(1.0)
    assert body["mesh_volume"] == pytest.approx(1.0)
    assert body["volume_ratio"] == pytest.approx(1.0)
    assert body["flat"] is False
    assert body["added_volume"] is None and body["max_distance"] is None


def test_budget_writes_an_enclosing_mesh(corpus, tmp_path: Path) -> None:
    from meshcol.io.mesh_read import load_mesh

    source = corpus / "trimesh-models" / "unit_sphere.STL"
    out = tmp_path / "hull.obj"
    result = run("hull", source, "--max-vertices", "64", "-o", out, "--report", tmp_path / "r.json")
    assert result.exit_code == 0, result.output
    assert result.stdout == ""
    (body,) = load_mesh(source)
    (hull,) = load_mesh(out)
    assert len(hull.vertices) <= 64
    assert outside_distance(body.world_vertices(), hull.world_vertices()) <= 1e-9 * 2 * np.sqrt(3)
    (row,) = json.loads((tmp_path / "r.json").read_text())["bodies"]
    assert row["hull_vertices"] == len(hull.vertices)
    assert row["added_volume"] == pytest.approx(row["hull_volume"] - row["exact_hull_volume"])
    assert row["added_volume_fraction"] == pytest.approx(
        row["added_volume"] / row["exact_hull_volume"]
    )
    assert 0 < row["max_distance"] < 0.2
    assert row["output"] == str(out)


def test_output_is_in_the_world_frame(corpus, tmp_path: Path) -> None:
    """nested.glb bodies carry node transforms: the hulls sit over the world vertices."""
    from meshcol.io.mesh_read import load_mesh

    source = corpus / "trimesh-models" / "nested.glb"
    out = tmp_path / "hulls.glb"
    result = run("hull", source, "-o", out)
    assert result.exit_code == 0, result.output
    import trimesh

    written = trimesh.load(out, force="scene")
    bodies = load_mesh(source)
    assert len(written.geometry) == len(bodies)
    assert any(not np.allclose(b.pose, np.eye(4)) for b in bodies)  # else this proves nothing
    for body in bodies:
        world = body.world_vertices()
        hull = written.geometry[body.name]
        # GLB stores float32
        assert np.allclose(hull.bounds, [world.min(axis=0), world.max(axis=0)], atol=1e-6)


def test_several_bodies_in_one_obj(corpus, tmp_path: Path) -> None:
    out = tmp_path / "both.obj"
    result = run("hull", corpus / "trimesh-models" / "multibody.stl", "-o", out)
    assert result.exit_code == 0, result.output
    objects = [
        line.split(" ", 1)[1] for line in out.read_text().splitlines() if line.startswith("o ")
    ]
    assert sorted(objects) == ["multibody/bodyA", "multibody/bodyB"]


def test_out_dir_writes_one_file_per_body(corpus, tmp_path: Path) -> None:
    out = tmp_path / "hulls"
    result = run(
        "hull",
        corpus / "trimesh-models" / "multibody.stl",
        "--out-dir",
        out,
        "--report",
        tmp_path / "r.csv",
    )
    assert result.exit_code == 0, result.output
    assert sorted(p.name for p in out.iterdir()) == ["multibody_bodyA.obj", "multibody_bodyB.obj"]
    lines = (tmp_path / "r.csv").read_text().splitlines()
    assert lines[0].startswith("name,source,input_vertices,input_faces,hull_vertices")
    assert len(lines) == 3


def test_csv_report_on_stdout(tmp_path: Path) -> None:
    cube = write(tmp_path, "cube.obj", UNIT_CUBE_OBJ)
    result = run("hull", cube, "--format", "csv", "--max-vertices", "4")
    assert result.exit_code == 0, result.output
    header, row = result.stdout.splitlines()
    cells = dict(zip(header.split(","), row.split(",")))
    assert (
        cells["name"] == "cube" and cells["hull_vertices"] == "4" and cells["max_vertices"] == "4"
    )
    assert float(cells["added_volume"]) > 0


def test_flat_mesh_warns_and_reports_flat(tmp_path: Path) -> None:
    flat = write(tmp_path, "flat.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n")
    result = run("hull", flat)
    assert result.exit_code == 0
    assert (
        result.stderr
        == f"meshcol: warning: {flat}: body 'flat' is flat: the hull is a 2-D polygon\n"
        "meshcol: hull: PASS: 1 hull, 4 vertices, 1 flat\n"
    )
    (body,) = json.loads(result.stdout)["bodies"]
    assert body["flat"] is True and body["hull_volume"] == 0.0
    assert body["hull_area"] == pytest.approx(1.0)
    assert body["note"] == "coplanar input: the hull is a 2-D polygon (volume 0)"


def test_inside_out_mesh_gets_the_outward_hull_and_a_warning(tmp_path: Path) -> None:
    flipped = "".join(
        "f " + " ".join(reversed(line.split()[1:])) + "\n" if line.startswith("f ") else line + "\n"
        for line in UNIT_CUBE_OBJ.splitlines()
    )
    cube = write(tmp_path, "inside_out.obj", flipped)
    result = run("hull", cube)
    assert result.exit_code == 0, result.output
    assert result.stderr.splitlines()[0] == (
        f"meshcol: warning: {cube}: body 'inside_out' is inside out: its faces point inward "
        "(negative mesh_volume); the hull does not depend on winding and is unaffected"
    )
    (body,) = json.loads(result.stdout)["bodies"]
    assert body["mesh_volume"] == pytest.approx(-1.0)
    assert body["hull_volume"] == pytest.approx(1.0) and body["volume_ratio"] == pytest.approx(1.0)
    assert (body["hull_vertices"], body["hull_faces"]) == (8, 12)
    assert body["note"].startswith("inside-out mesh: its faces point inward")
    outward = json.loads(run("hull", write(tmp_path, "cube.obj", UNIT_CUBE_OBJ)).stdout)["bodies"][
        0
    ]
    assert outward["note"] is None and outward["hull_volume"] == body["hull_volume"]


def test_single_triangle_is_flat(corpus) -> None:
    source = corpus / "trimesh-models" / "notenoughindices.obj"
    result = run("hull", source)
    assert result.exit_code == 0
    assert result.stderr == (
        f"meshcol: warning: {source}: body 'notenoughindices' is flat: the hull is a 2-D polygon\n"
        "meshcol: hull: PASS: 1 hull, 3 vertices, 1 flat\n"
    )
    assert json.loads(result.stdout)["bodies"][0]["hull_faces"] == 1


def test_soup_hull_uses_its_points(corpus) -> None:
    result = run("hull", corpus / "trimesh-models" / "soup.stl")
    assert result.exit_code == 0, result.output
    (body,) = json.loads(result.stdout)["bodies"]
    assert body["mesh_volume"] is None and body["volume_ratio"] is None
    assert body["hull_volume"] > 0


# ---------------------------------------------------------------------------------------
# usage errors


def test_output_and_out_dir_together_is_a_usage_error(tmp_path: Path) -> None:
    cube = write(tmp_path, "cube.obj", UNIT_CUBE_OBJ)
    result = run("hull", cube, "-o", tmp_path / "a.obj", "--out-dir", tmp_path / "d")
    assert result.exit_code == 2
    assert result.stderr == (
        "meshcol: error: give either -o/--output or --out-dir, not both (see 'meshcol hull -h')\n"
    )


def test_unknown_output_extension(tmp_path: Path) -> None:
    cube = write(tmp_path, "cube.obj", UNIT_CUBE_OBJ)
    result = run("hull", cube, "-o", "hull.xyz")
    assert result.exit_code == 2
    assert result.stderr == (
        "meshcol: error: invalid value for '-o' / '--output': unknown mesh extension '.xyz' in "
        "'hull.xyz' (expected .obj, .stl, .ply, .off, .glb) (see 'meshcol hull -h')\n"
    )


def test_several_bodies_into_stl_is_refused(corpus, tmp_path: Path) -> None:
    out = tmp_path / "out"
    out.mkdir()
    result = run("hull", corpus / "trimesh-models" / "multibody.stl", "-o", out / "h.stl")
    assert result.exit_code == 2
    assert result.stderr == (
        f"meshcol: error: -o {out / 'h.stl'}: 2 bodies need a file that holds several meshes "
        "(.obj, .glb) or --out-dir (see 'meshcol hull -h')\n"
    )
    assert list(out.iterdir()) == []


def test_budget_below_four_is_a_usage_error(tmp_path: Path) -> None:
    cube = write(tmp_path, "cube.obj", UNIT_CUBE_OBJ)
    result = run("hull", cube, "--max-vertices", "3")
    assert result.exit_code == 2
    assert result.stderr == (
        "meshcol: error: invalid value for '--max-vertices': 3 is not in the range x>=4 "
        "(see 'meshcol hull -h')\n"
    )


def test_no_input_is_a_usage_error() -> None:
    result = run("hull")
    assert result.exit_code == 2
    assert result.stderr == "meshcol: error: missing argument 'INPUT...' (see 'meshcol hull -h')\n"


# ---------------------------------------------------------------------------------------
# bad input: exit 2, one line naming the file, no traceback, no output left behind

BAD_MESHES = {
    "nan.obj": (
        "v 0 0 0\nv 1 nan 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\n",
        "cannot parse OBJ file: line 2: non-finite vertex coordinate",
    ),
    "inf.obj": (
        "v 0 0 0\nv 1 inf 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\n",
        "cannot parse OBJ file: line 2: non-finite vertex coordinate",
    ),
    "line.obj": (
        "v 0 0 0\nv 1 1 1\nv 2 2 2\nf 1 2 3\n",
        "body 'line': all vertices are collinear: there is no meaningful hull",
    ),
    "point.obj": (
        "v 1 1 1\nv 1 1 1\nv 1 1 1\nf 1 2 3\n",
        "body 'point': all vertices coincide: there is no meaningful hull",
    ),
    "unknown.xyz": (
        "x\n",
        "unknown mesh file extension '.xyz' "
        "(expected .obj, .stl, .ply, .off, .glb, .gltf, .fbx, .dae, .usd, .usda, .usdc, .usdz)",
    ),
}


def assert_clean_failure(result, path, message: str, out_dir: Path) -> None:
    assert result.exit_code == 2, result.output
    assert result.stdout == ""
    assert result.stderr == f"meshcol: error: {path}: {message}\n"
    assert "Traceback" not in result.output
    assert list(out_dir.iterdir()) == []


@pytest.mark.parametrize("name", sorted(BAD_MESHES))
def test_bad_mesh(tmp_path: Path, name: str) -> None:
    text, message = BAD_MESHES[name]
    source = write(tmp_path, name, text)
    out = tmp_path / "out"
    out.mkdir()
    result = run("hull", source, "-o", out / "hull.obj", "--report", out / "r.json")
    assert_clean_failure(result, source, message, out)


def test_missing_file(tmp_path: Path) -> None:
    out = tmp_path / "out"
    out.mkdir()
    result = run("hull", tmp_path / "nope.obj", "-o", out / "hull.obj")
    assert_clean_failure(result, tmp_path / "nope.obj", "file not found", out)


def test_unreadable_inputs(tmp_path: Path) -> None:
    """Running as root, chmod 000 stays readable: test a directory and corrupt bytes instead."""
    out = tmp_path / "out"
    out.mkdir()
    folder = tmp_path / "folder.obj"
    folder.mkdir()
    result = run("hull", folder, "-o", out / "hull.obj")
    assert_clean_failure(result, folder, "is a directory, not a mesh file", out)
    corrupt = tmp_path / "corrupt.stl"
    corrupt.write_bytes(bytes(range(256)) * 2)
    result = run("hull", corrupt, "-o", out / "hull.obj")
    assert_clean_failure(
        result,
        corrupt,
        "cannot parse STL file: neither binary STL (size does not match the triangle count) nor ASCII text",
        out,
    )


@pytest.mark.parametrize("name", ["empty.obj", "empty.stl"])
def test_empty_corpus_meshes(corpus, tmp_path: Path, name: str) -> None:
    source = corpus / "trimesh-models" / name
    result = run("hull", source, "--out-dir", tmp_path)
    assert_clean_failure(result, source, "mesh has no faces", tmp_path)


MANIFESTS = {
    "bad_json.json": '{"bodies": [\n',
    "unknown_field.json": '{"bodies": [{"name": "a", "mesh": "cube.obj", "colour": 1}]}',
    "missing_mesh.json": '{"bodies": [{"name": "a", "mesh": "nope.obj"}]}',
    "wrong_type.json": '{"bodies": [{"name": "a", "mesh": "cube.obj", "position": "up"}]}',
}


@pytest.mark.parametrize("name", sorted(MANIFESTS))
def test_broken_manifest_maps_the_scene_error(tmp_path: Path, name: str) -> None:
    from meshcol.errors import SceneError
    from meshcol.io.scene import load_inputs

    write(tmp_path, "cube.obj", UNIT_CUBE_OBJ)
    manifest = write(tmp_path, name, MANIFESTS[name])
    with pytest.raises(SceneError) as info:
        load_inputs([str(manifest)])
    out = tmp_path / "out"
    out.mkdir()
    result = run("hull", manifest, "-o", out / "hull.glb")
    assert_clean_failure(result, manifest, info.value.message, out)


@pytest.mark.slow
def test_debug_shows_a_traceback(tmp_path: Path) -> None:
    missing = tmp_path / "nope.obj"
    quiet = subprocess.run(
        [sys.executable, "-m", "meshcol", "hull", str(missing)], capture_output=True, text=True
    )
    assert quiet.returncode == 2
    assert quiet.stderr == f"meshcol: error: {missing}: file not found\n"
    loud = subprocess.run(
        [sys.executable, "-m", "meshcol", "--debug", "hull", str(missing)],
        capture_output=True,
        text=True,
    )
    assert loud.returncode != 0
    assert "Traceback (most recent call last)" in loud.stderr
    assert "InputFileError" in loud.stderr


def test_library_hull_returns_the_report_and_writes_meshes(tmp_path: Path) -> None:
    from meshcol.analysis.hull import HullReport, OutputDestinationError, hull, out_dir_paths

    cube = write(tmp_path, "cube.obj", UNIT_CUBE_OBJ)
    report = hull([cube], out_dir=tmp_path / "hulls")
    assert isinstance(report, HullReport) and report.exit_code == 0
    assert report.summary == {"bodies": 1, "flat": 0, "hull_vertices": 8, "files_written": 1}
    assert report.to_dict()["command"] == "hull"
    assert [p.name for p in (tmp_path / "hulls").iterdir()] == ["cube.obj"]
    assert out_dir_paths("d", ["a/b", "A/B", "é"]) == [
        os.path.join("d", "a_b.obj"),
        os.path.join("d", "A_B-2.obj"),
        os.path.join("d", "body.obj"),
    ]
    with pytest.raises(ValueError, match="either output or out_dir"):
        hull([cube], output=tmp_path / "a.obj", out_dir=tmp_path / "d")
    two = write(tmp_path, "two.obj", UNIT_CUBE_OBJ)
    with pytest.raises(OutputDestinationError):
        hull([cube, two], output=tmp_path / "both.stl")
