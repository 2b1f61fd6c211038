"""Untrusted pull requests: every path a file names (a manifest's meshes, a URDF's meshes, a
glTF's buffers, an MJCF's includes) resolves inside the root, symlinks followed, or the run
exits 2 naming the file and the path; under ``meshcol ci`` and with ``meshcol --root``."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest
from ci_repo import box_obj
from click.testing import CliRunner

from meshcol.cli import main
from meshcol.io.paths import OutsideRootError, confine, confined_to, recording_reads


def run(*args: str, env: dict | None = None) -> tuple[int, str, str]:
    result = CliRunner().invoke(main, list(args), env=env)
    return result.exit_code, result.stdout, result.stderr


@pytest.fixture
def repo(tmp_path, monkeypatch):
    """``tmp/repo`` (the root) and ``tmp/secret/x.obj`` beside it, outside."""
    (tmp_path / "secret").mkdir()
    (tmp_path / "secret" / "x.obj").write_text(box_obj(1.0, name="x"))
    (tmp_path / "secret" / "x.bin").write_bytes(b"\0" * 36)
    root = tmp_path / "repo"
    (root / "meshes").mkdir(parents=True)
    (root / "meshes" / "ok.obj").write_text(box_obj(1.0, name="ok"))
    os.symlink(tmp_path / "secret" / "x.obj", root / "meshes" / "link.obj")
    os.symlink(tmp_path / "secret" / "x.bin", root / "meshes" / "link.bin")
    monkeypatch.chdir(root)
    return root


def escapes(repo: Path) -> list[tuple[str, str]]:
    """``(relative, absolute, symlinked)`` references to the secret file."""
    return [
        ("../secret/x.obj", "../secret/x.obj"),
        (str(repo.parent / "secret" / "x.obj"), str(repo.parent / "secret" / "x.obj")),
        ("meshes/link.obj", "meshes/link.obj"),
    ]


def manifest(mesh: str) -> str:
    bodies = [{"name": "ok", "mesh": "meshes/ok.obj"}, {"name": "bad", "mesh": mesh}]
    return json.dumps({"bodies": bodies})


def urdf(mesh: str) -> str:
    link = (
        '<link name="{0}"><collision><geometry><mesh filename="{1}"/></geometry></collision></link>'
    )
    return (
        f'<robot name="r">{link.format("a", "meshes/ok.obj")}{link.format("b", mesh)}'
        '<joint name="j" type="fixed"><parent link="a"/><child link="b"/></joint></robot>'
    )


def gltf(uri: str) -> str:
    document = {
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"}],
        "bufferViews": [{"buffer": 0, "byteLength": 36}],
        "buffers": [{"byteLength": 36, "uri": uri}],
    }
    return json.dumps(document)


KINDS = {
    "manifest": ("scene.json", manifest, '[[scenes]]\npath = "scene.json"\n'),
    "urdf": ("robot.urdf", urdf, '[[scenes]]\npath = "robot.urdf"\n'),
    "gltf": ("level.gltf", gltf, '[[assets]]\nglob = "*.gltf"\n'),
}


@pytest.mark.parametrize("kind", sorted(KINDS))
@pytest.mark.parametrize("how", ["relative", "absolute", "symlink"])
def test_meshcol_ci_refuses_paths_outside_the_root(repo, kind, how):
    if kind == "urdf":
        pytest.importorskip("yourdfpy", reason="URDF reading needs yourdfpy")
    name, make, section = KINDS[kind]
    reference = dict(zip(("relative", "absolute", "symlink"), escapes(repo)))[how][0]
    if kind == "gltf":
        reference = reference.replace("x.obj", "x.bin").replace("link.obj", "link.bin")
    (repo / name).write_text(make(reference))
    (repo / "meshcol.toml").write_text(section)
    code, out, err = run("ci", "--no-cache", "--root", str(repo), "--report", "-")
    assert code == 2, err
    lines = [line for line in err.splitlines() if line.startswith("meshcol: error: ")]
    assert len(lines) == 1 and "Traceback" not in err, err
    assert lines[0].startswith(f"meshcol: error: {name}: "), lines[0]
    assert f"{reference!r} resolves outside the root" in lines[0], lines[0]
    report = json.loads(out)
    assert report["summary"]["errors"] == 1
    # nothing of the file outside was read into the report
    assert "secret" not in json.dumps([r["report"] for r in report["runs"]])


def test_inside_the_root_and_without_a_root_it_is_read(repo):
    (repo / "scene.json").write_text(manifest("meshes/ok.obj").replace('"bad"', '"twin"'))
    (repo / "meshcol.toml").write_text(KINDS["manifest"][2])
    code, _, err = run("ci", "--no-cache", "--root", str(repo))
    assert code == 1, err  # the twins penetrate: a finding, not an escape
    (repo / "scene.json").write_text(manifest("../secret/x.obj"))
    assert run("check", "scene.json")[0] == 1  # no root: read as before
    code, _, err = run("--root", ".", "check", "scene.json")
    assert code == 2 and "'../secret/x.obj' resolves outside the root" in err, err
    code, _, err = run("check", "scene.json", env={"MESHCOL_ROOT": str(repo)})
    assert code == 2 and "resolves outside the root" in err, err


def test_mjcf_include_outside_the_root(repo):
    pytest.importorskip("mujoco", reason="MJCF needs MuJoCo")
    (repo.parent / "secret" / "inc.xml").write_text("<mujoco><worldbody/></mujoco>")
    (repo / "model.xml").write_text(
        '<mujoco><include file="../secret/inc.xml"/>'
        '<worldbody><body><geom type="sphere" size="0.1"/></body></worldbody></mujoco>'
    )
    code, _, err = run("--root", ".", "check", "model.xml")
    assert code == 2 and "'../secret/inc.xml' resolves outside the root" in err, err


def test_confine_records_reads_and_resolves_symlinks(repo):
    with confined_to(repo), recording_reads() as reads:
        assert confine("meshes/ok.obj", "scene.json") == "meshes/ok.obj"
        with pytest.raises(OutsideRootError, match=r"to .*secret/x\.obj"):
            confine("meshes/link.obj", "scene.json")
    assert os.path.realpath("meshes/ok.obj") in reads
    assert confine(None, "scene.json") is None


def test_files_the_configuration_names_stay_inside_the_root(repo):
    (repo / "scene.json").write_text(manifest("meshes/ok.obj").replace('"bad"', '"twin"'))
    (repo.parent / "secret" / "base.json").write_text("{}")
    (repo / "meshcol.toml").write_text(
        '[[scenes]]\npath = "scene.json"\ncheck = { baseline = "../secret/base.json" }\n'
    )
    code, _, err = run("ci", "--no-cache", "--root", str(repo))
    assert code == 2, err
    assert "the configuration: path '../secret/base.json' resolves outside the root" in err


@pytest.mark.parametrize("env", [None, "root"])
def test_a_nul_byte_in_a_mesh_path_is_one_line_with_or_without_a_root(repo, env):
    """A path with a NUL byte names no file: "not found", exit 2, never a traceback (the
    root's check used to raise realpath's ValueError)."""
    (repo / "scene.json").write_text(manifest("meshes/ok\u0000.obj"))
    code, out, err = run(
        "check", "scene.json", env=None if env is None else {"MESHCOL_ROOT": str(repo)}
    )
    assert code == 2 and out == "", err
    assert "not found" in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
