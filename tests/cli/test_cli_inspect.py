"""``meshcol inspect``: reports, --fail-on, bad input; both commands over the whole corpus."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from conftest import UNIT_CUBE_OBJ as CUBE_OBJ
from test_cli_hull import MANIFESTS, assert_clean_failure, outside_distance, write

from meshcol.analysis.rules import command_rules
from meshcol.cli import main


def run(*args: str):
    return CliRunner().invoke(main, [str(a) for a in args])


def test_report_on_stdout(tmp_path: Path) -> None:
    cube = write(tmp_path, "cube.obj", CUBE_OBJ)
    result = run("inspect", cube)
    assert result.exit_code == 0, result.output
    assert result.stderr.splitlines()[-1] == "meshcol: inspect: PASS: 1 body, 0 with findings"
    report = json.loads(result.stdout)
    assert report["schema_version"] == 1 and report["command"] == "inspect"
    settings = report["settings"]
    assert settings["bounds_frame"] == "world" and settings["shape"] == "hull"
    assert settings["fail_on"] == [] and settings["fail_on_rules"] == []
    assert report["failed"] is False
    (body,) = report["bodies"]
    assert body["name"] == "cube" and body["source"] == str(cube)
    assert body["watertight"] is True and body["winding_consistent"] is True
    assert body["volume"] == pytest.approx(1.0)
    assert body["size"] == [1.0, 1.0, 1.0]
    assert body["findings"] == [] and body["failed_rules"] == []


def test_inside_out_mesh_is_inverted_and_can_fail_the_run(tmp_path: Path) -> None:
    lines = CUBE_OBJ.splitlines()
    flipped = [
        "f " + " ".join(reversed(line.split()[1:])) if line.startswith("f ") else line
        for line in lines
    ]
    cube = write(tmp_path, "inside_out.obj", "\n".join(flipped) + "\n")
    result = run("inspect", cube, "--fail-on", "inverted")
    assert result.exit_code == 1, result.output
    assert (
        f"meshcol: fail: {cube}: body 'inside_out': MC404 inverted: inside out: volume -1"
        in result.stderr.splitlines()
    )
    report = json.loads(result.stdout)
    (body,) = report["bodies"]
    assert body["volume"] == pytest.approx(-1.0)
    assert body["findings"] == ["inverted"] and body["failed_rules"] == ["inverted"]
    assert report["summary"]["findings"]["inverted"] == 1


def test_report_file_prints_a_table(corpus, tmp_path: Path) -> None:
    teapot = corpus / "trimesh-models" / "teapot.stl"
    result = run("inspect", teapot, "--report", tmp_path / "r.csv")
    assert result.exit_code == 0
    assert result.stdout == ""
    table = result.stderr.splitlines()
    assert table[0].split() == ["body", "faces", "closed", "volume", "size", "units", "findings"]
    assert table[1].startswith("teapot") and "not-watertight" in table[1]
    header, row = (tmp_path / "r.csv").read_text().splitlines()
    cells = dict(zip(header.split(","), row.split(",")))
    assert cells["watertight"] == "False" and cells["volume"] == ""


def test_fail_on_exits_one_after_writing_the_report(corpus, tmp_path: Path) -> None:
    teapot = corpus / "trimesh-models" / "teapot.stl"
    cube = corpus / "trimesh-models" / "unit_cube.STL"
    result = run(
        "inspect",
        cube,
        teapot,
        "--fail-on",
        "not-watertight,duplicate-faces",
        "--report",
        tmp_path / "r.json",
    )
    assert result.exit_code == 1
    assert result.stderr.splitlines()[-2:] == [
        f"meshcol: fail: {teapot}: body 'teapot': MC401 not-watertight: open: 64 boundary "
        "and 0 non-manifold edges",
        "meshcol: inspect: FAIL: 2 bodies, 1 with findings, 1 failing --fail-on MC401,MC407",
    ]
    report = json.loads((tmp_path / "r.json").read_text())
    assert report["failed"] is True
    assert [b["failed_rules"] for b in report["bodies"]] == [[], ["not-watertight"]]
    # the same mesh passes a policy it does not break
    assert run("inspect", cube, "--fail-on", "all").exit_code == 0
    assert run("inspect", teapot, "--fail-on", "non-manifold,degenerate-faces").exit_code == 0


def test_fail_on_all_lists_every_rule(tmp_path: Path) -> None:
    cube = write(tmp_path, "cube.obj", CUBE_OBJ)
    report = json.loads(run("inspect", cube, "--fail-on", "all").stdout)
    assert report["settings"]["fail_on"] == [rule.name for rule in command_rules("inspect")]
    assert report["settings"]["fail_on_rules"] == [rule.id for rule in command_rules("inspect")]


def test_unknown_rule_is_a_usage_error(tmp_path: Path) -> None:
    cube = write(tmp_path, "cube.obj", CUBE_OBJ)
    result = run("inspect", cube, "--fail-on", "not-watertight,leaky")
    assert result.exit_code == 2
    valid = ", ".join(f"{rule.id} {rule.name}" for rule in command_rules("inspect"))
    assert result.stderr == (
        "meshcol: error: invalid value for '--fail-on': unknown rule 'leaky' for inspect "
        f"(valid: all, {valid}) (see 'meshcol inspect -h')\n"
    )


def test_single_triangle_and_soup_are_reported(corpus) -> None:
    result = run(
        "inspect",
        corpus / "trimesh-models" / "notenoughindices.obj",
        corpus / "trimesh-models" / "soup.stl",
        "--fail-on",
        "not-watertight",
    )
    assert result.exit_code == 1
    triangle, soup = json.loads(result.stdout)["bodies"]
    assert triangle["faces"] == 1 and triangle["boundary_edges"] == 3
    assert soup["components"] == 100 and not soup["watertight"]


def test_manifest_units_are_reported(tmp_path: Path) -> None:
    chair = "".join(
        line.replace(" 1", " 400") if line.startswith("v ") else line
        for line in CUBE_OBJ.splitlines(keepends=True)
    )
    write(tmp_path, "cube.obj", chair)
    manifest = write(
        tmp_path, "scene.json", '{"units": "mm", "bodies": [{"name": "a", "mesh": "cube.obj"}]}'
    )
    report = json.loads(run("inspect", manifest, "--fail-on", "suspect-units").stdout)
    assert report["units"] == "mm"
    (body,) = report["bodies"]
    assert body["units_guess"] == "mm" and body["declared_units"] == "mm"
    assert "suspect-units" not in body["findings"]


@pytest.mark.parametrize("name", sorted(MANIFESTS))
def test_broken_manifest(tmp_path: Path, name: str) -> None:
    from meshcol.errors import SceneError
    from meshcol.io.scene import load_inputs

    write(tmp_path, "cube.obj", CUBE_OBJ)
    manifest = write(tmp_path, name, MANIFESTS[name])
    with pytest.raises(SceneError) as info:
        load_inputs([str(manifest)])
    out = tmp_path / "out"
    out.mkdir()
    result = run("inspect", manifest, "--report", out / "r.json")
    assert_clean_failure(result, manifest, info.value.message, out)


@pytest.mark.parametrize(
    ("name", "text", "message"),
    [
        (
            "nan.obj",
            "v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n",
            "cannot parse OBJ file: line 2: non-finite vertex coordinate",
        ),
        (
            "inf.obj",
            "v 0 0 0\nv 1 -inf 0\nv 0 1 0\nf 1 2 3\n",
            "cannot parse OBJ file: line 2: non-finite vertex coordinate",
        ),
        (
            "mesh.3ds",
            "<xml/>\n",
            "unknown mesh file extension '.3ds' "
            "(expected .obj, .stl, .ply, .off, .glb, .gltf, .fbx, .dae, .usd, .usda, .usdc, .usdz)",
        ),
    ],
)
def test_bad_mesh(tmp_path: Path, name: str, text: str, message: str) -> None:
    source = write(tmp_path, name, text)
    out = tmp_path / "out"
    out.mkdir()
    result = run("inspect", source, "--report", out / "r.json")
    assert_clean_failure(result, source, message, out)


@pytest.mark.parametrize("name", ["empty.obj", "empty.stl"])
def test_empty_and_missing(corpus, tmp_path: Path, name: str) -> None:
    source = corpus / "trimesh-models" / name
    assert_clean_failure(
        run("inspect", source, "--report", tmp_path / "r.json"),
        source,
        "mesh has no faces",
        tmp_path,
    )
    missing = tmp_path / "missing.obj"
    assert_clean_failure(run("inspect", missing), missing, "file not found", tmp_path)


# ---------------------------------------------------------------------------------------
# the whole corpus, once per session: every loadable mesh through both commands

CLOSED = [
    "fandisk.obj",
    "featuretype.STL",
    "torus.STL",
    "octagonal_pocket.stl",
    "plate_holes.STL",
    "1002_tray_bottom.STL",
    "idler_riser.STL",
    "angle_block.STL",
    "busted.STL",
    "round.stl",
    "ballA.off",
    "ballB.off",
    "unit_cube.STL",
    "unit_sphere.STL",
    "cylinder.stl",
    "tet.ply",
    "7_8ths_cube.stl",
    "counter.unitsmm.STL",
    "Octocat-v2.obj",
    "SnowFlake.obj",
]


@pytest.fixture(scope="module")
def corpus_run(tmp_path_factory):
    from conftest import CORPUS

    from meshcol.errors import MeshcolError
    from meshcol.io.mesh_read import MESH_EXTENSIONS, load_mesh

    if not CORPUS.is_dir():
        pytest.skip("shared corpus not present (../shared/corpus)")
    from meshcol.io.scene import load_inputs

    files, rejected = [], []
    for path in sorted(CORPUS.rglob("*")):
        if path.suffix.lower() not in MESH_EXTENSIONS:
            continue
        try:
            load_mesh(path)
        except MeshcolError:
            rejected.append(path.name)
            continue
        files.append(str(path))
    # Names as the commands give them (a clash between files gets a '#2' suffix).
    bodies = list(load_inputs(files).bodies)
    out = tmp_path_factory.mktemp("corpus")
    inspect = run("inspect", *files, "--report", out / "inspect.json")
    hull = run(
        "hull",
        *files,
        "--max-vertices",
        "64",
        "--out-dir",
        out / "hulls",
        "--report",
        out / "hull.json",
    )
    return {
        "rejected": rejected,
        "bodies": bodies,
        "inspect": inspect,
        "hull": hull,
        "inspect_report": json.loads((out / "inspect.json").read_text()),
        "hull_report": json.loads((out / "hull.json").read_text()),
    }


def by_file(report: dict, name: str) -> list[dict]:
    return [b for b in report["bodies"] if Path(b["source"]).name == name]


def test_corpus_rejects_only_the_empty_files(corpus_run) -> None:
    assert sorted(corpus_run["rejected"]) == ["empty.obj", "empty.stl"]


def test_corpus_inspect(corpus_run) -> None:
    assert corpus_run["inspect"].exit_code == 0, corpus_run["inspect"].output
    report = corpus_run["inspect_report"]
    assert len(report["bodies"]) == len(corpus_run["bodies"])
    (cube,) = by_file(report, "unit_cube.STL")
    assert cube["volume"] == pytest.approx(1.0, abs=1e-6) and cube["findings"] == []
    for name in CLOSED:
        for body in by_file(report, name):
            assert body["watertight"], name
            assert body["winding_consistent"], name
            assert body["volume"] > 0, name
    (counter,) = by_file(report, "counter.unitsmm.STL")
    assert counter["units_guess"] == "mm"
    assert "suspect-units" in counter["findings"]
    # its five knobs are separate shells sunk into the base: crossing, but each one clean
    assert counter["components"] == 6 and counter["self_intersecting"]
    (soup,) = by_file(report, "soup.stl")
    assert not soup["watertight"] and soup["components"] == 100
    (shared,) = by_file(report, "shared.STL")
    assert shared["non_manifold_edges"] > 0 and "non-manifold" in shared["findings"]
    (bottle,) = by_file(report, "Bottle.obj")
    assert not bottle["watertight"]
    for name in ("unit_sphere.STL", "torus.STL", "Octocat-v2.obj", "SnowFlake.obj", "fandisk.obj"):
        (body,) = by_file(report, name)
        assert not body["self_intersecting"], name
        assert body["units_guess"] == "m", name


def test_corpus_hull_within_64_vertices_encloses(corpus_run) -> None:
    assert corpus_run["hull"].exit_code == 0, corpus_run["hull"].output
    from meshcol.io.mesh_read import load_mesh

    report = corpus_run["hull_report"]
    bodies = {b.name: b for b in corpus_run["bodies"]}
    assert [row["name"] for row in report["bodies"]] == list(bodies)
    for row in report["bodies"]:
        body = bodies[row["name"]]
        assert row["hull_vertices"] <= 64, row["name"]
        assert row["added_volume"] >= 0 and row["max_distance"] >= 0
        (written,) = load_mesh(row["output"], merge=False)
        assert len(written.vertices) == row["hull_vertices"]
        world = body.world_vertices()
        if row["flat"]:
            assert row["hull_volume"] == 0.0
            continue
        scale = float(np.linalg.norm(np.ptp(world, axis=0)))
        assert outside_distance(world, written.world_vertices()) <= 1e-9 * scale, row["name"]
    (cube,) = by_file(report, "unit_cube.STL")
    assert cube["hull_volume"] == pytest.approx(1.0) and cube["max_distance"] == 0.0
    (triangle,) = by_file(report, "notenoughindices.obj")
    assert triangle["flat"] is True


# ------------------------------------------------------------------------------ work budget


def crossing_pairs_obj(count: int) -> str:
    """``count`` pairs of triangles, each pair crossing like an X, spaced apart in a row: the
    sweep's grid splits them into many blocks, so a budget can stop between them."""
    lines = []
    for i in range(count):
        x = 3.0 * i
        for p in ((x, -1, 0), (x + 1, -1, 0), (x, 1, 0), (x, 0, -1), (x + 1, 0, -1), (x, 0, 1)):
            lines.append("v {} {} {}".format(*p))
    lines += [f"f {6 * i + 1} {6 * i + 2} {6 * i + 3}" for i in range(count)]
    lines += [f"f {6 * i + 4} {6 * i + 5} {6 * i + 6}" for i in range(count)]
    return "\n".join(lines) + "\n"


def test_budget_run_out_with_no_crossing_is_undecided(tmp_path: Path, monkeypatch) -> None:
    import meshcol.collision.self_intersection as crossing_module

    monkeypatch.setattr(crossing_module, "MAX_WORK", 0)
    cube = write(tmp_path, "cube.obj", CUBE_OBJ)
    result = run("inspect", cube)
    assert result.exit_code == 0, result.output  # a warning unless --fail-on lists it
    report = json.loads(result.stdout)
    jsonschema = pytest.importorskip("jsonschema")
    schema = Path(crossing_module.__file__).parents[1] / "schemas" / "inspect_report.schema.json"
    jsonschema.Draft202012Validator(json.loads(schema.read_text())).validate(report)
    (body,) = report["bodies"]
    assert body["self_intersecting"] is None and body["self_intersecting_pairs"] == 0
    assert body["findings"] == ["undecided"]
    assert "cube  12     yes     1       1 x 1 x 1  m      undecided" in result.stderr
    failing = run("inspect", cube, "--fail-on", "undecided")
    assert failing.exit_code == 1
    assert (
        f"meshcol: fail: {cube}: body 'cube': MC505 undecided: the self-intersection test "
        "stopped at its work budget (0 units) with no crossing found: undecided"
    ) in failing.stderr.splitlines()
    csv = run("inspect", cube, "--format", "csv").stdout.splitlines()
    row = dict(zip(csv[0].split(","), csv[1].split(",")))
    assert row["self_intersecting"] == "" and row["findings"] == "undecided"


def test_budget_run_out_after_crossings_is_at_least_k(tmp_path: Path, monkeypatch) -> None:
    import meshcol.collision.self_intersection as crossing_module

    source = write(tmp_path, "crossing.obj", crossing_pairs_obj(400))
    full = run("inspect", source)
    (body,) = json.loads(full.stdout)["bodies"]
    assert body["self_intersecting"] is True and body["self_intersecting_pairs"] == 400
    assert "undecided" not in body["findings"]
    from meshcol.io.mesh_read import load_mesh

    (mesh,) = load_mesh(source)
    work = crossing_module.self_intersections(mesh.vertices, mesh.faces).work
    monkeypatch.setattr(crossing_module, "MAX_WORK", work // 2)
    result = run("inspect", source, "--fail-on", "self-intersecting,undecided")
    assert result.exit_code == 1
    report = json.loads(result.stdout)
    (body,) = report["bodies"]
    k = body["self_intersecting_pairs"]
    assert body["self_intersecting"] is True and 0 < k < 400
    assert {"self-intersecting", "undecided"} <= set(body["findings"])
    messages = {f["rule"]: f["message"] for f in report["findings"]}
    assert messages["MC402"] == f"at least {k} pairs of faces cross"
    assert messages["MC505"] == (
        f"the self-intersection test stopped at its work budget ({work // 2:,} units): "
        f"at least {k} pairs of faces cross"
    )
    assert report["summary"]["findings"]["undecided"] == 1
    # the same K on every run and thread count
    assert json.loads(run("inspect", source).stdout)["bodies"][0]["self_intersecting_pairs"] == k
    sarif = json.loads(run("inspect", source, "--format", "sarif").stdout)
    (sarif_run,) = sarif["runs"]
    assert {"MC402", "MC505"} <= {rule["id"] for rule in sarif_run["tool"]["driver"]["rules"]}
    github = run("inspect", source, "--format", "github").stdout
    assert f"self-intersecting (at least {k} crossing face pairs)" in github
    assert f"undecided (self-intersection test stopped at its budget, at least {k}" in github
