"""``meshcol decompose --run-manifest/--resume``: every file's state as the run goes; resume
skips what finished (from the cache) and retries what failed; Ctrl-C loses nothing."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import trimesh
from click.testing import CliRunner
from conftest import FAST_DECOMPOSE

from meshcol.cli import main
from meshcol.decomposition.batch import decompose_files
from meshcol.decomposition.manifest import RunManifest
from meshcol.errors import MeshcolError


@pytest.fixture(scope="module")
def meshes(tmp_path_factory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("manifest-inputs")
    shapes = {
        "torus": trimesh.creation.torus(1.0, 0.3, major_sections=24, minor_sections=12),
        "box": trimesh.creation.box(extents=(2, 1, 1)),
        "capsule": trimesh.creation.capsule(height=1.0, radius=0.3, count=[12, 12]),
    }
    paths = {}
    for name, mesh in shapes.items():
        paths[name] = folder / f"{name}.obj"
        mesh.export(paths[name])
    return paths


SCHEMA = Path(__file__).resolve().parents[2] / "meshcol" / "schemas"


def read(path: Path) -> dict:
    """The manifest, checked against its schema."""
    import jsonschema

    data = json.loads(path.read_text())
    schema = json.loads((SCHEMA / "run_manifest.schema.json").read_text())
    jsonschema.Draft202012Validator(schema).validate(data)
    return data


def states(path: Path) -> dict[str, str]:
    return {Path(f["path"]).name: f["state"] for f in read(path)["files"]}


def run(args: list[str]):
    return CliRunner().invoke(main, ["decompose", *args])


@pytest.mark.slow
def test_failed_file_is_recorded_and_retried_on_resume(meshes, tmp_path) -> None:
    manifest, cache = tmp_path / "run.json", tmp_path / "cache"
    inputs = [meshes["box"], meshes["torus"]]  # the torus takes seconds with CoACD's defaults
    # The box is in the cache already (a hit never times out, however loaded the machine).
    decompose_files([meshes["box"]], tmp_path / "o0", cache_dir=cache)
    messages: list[str] = []
    first = decompose_files(
        inputs,
        tmp_path / "o1",
        cache_dir=cache,
        timeout=0.3,
        run_manifest=manifest,
        progress=messages.append,
    )
    assert [f["status"] for f in first.files] == ["ok", "timeout"]
    data = read(manifest)
    assert data["counts"] == {"done": 1, "failed": 1, "pending": 0}
    torus = next(f for f in data["files"] if f["path"] == str(meshes["torus"]))
    assert torus["state"] == "failed" and torus["status"] == "timeout"
    assert torus["reason"] == "timed out after 0.3 s"
    assert messages[-1] == "decompose: 2/2 files, 1 failed"

    second = decompose_files(
        inputs, tmp_path / "o2", cache_dir=cache, run_manifest=manifest, resume=True
    )
    assert [f["status"] for f in second.files] == ["ok", "ok"]
    assert [f["bodies"][0]["from_cache"] for f in second.files] == [True, False]
    assert states(manifest) == {"box.obj": "done", "torus.obj": "done"}
    assert read(manifest)["counts"] == {"done": 2, "failed": 0, "pending": 0}


def test_resume_with_other_options_or_no_manifest_is_an_error(meshes, tmp_path) -> None:
    manifest = tmp_path / "run.json"
    args = [str(meshes["box"]), "--cache-dir", str(tmp_path / "c"), *FAST_DECOMPOSE]
    missing = run([*args, "-o", str(tmp_path / "o"), "--run-manifest", str(manifest), "--resume"])
    assert missing.exit_code == 2
    assert "no run manifest to resume" in missing.stderr
    first = run([*args, "-o", str(tmp_path / "o"), "--run-manifest", str(manifest)])
    assert first.exit_code == 0, first.stderr
    assert states(manifest) == {"box.obj": "done"}
    other = run(
        [
            *args,
            "-o",
            str(tmp_path / "o"),
            "--run-manifest",
            str(manifest),
            "--resume",
            "--seed",
            "1",
        ]
    )
    assert other.exit_code == 2
    assert "written by a run with another engine" in other.stderr
    manifest.write_text("{not json")
    broken = run([*args, "-o", str(tmp_path / "o"), "--run-manifest", str(manifest), "--resume"])
    assert broken.exit_code == 2 and "unreadable run manifest" in broken.stderr


def test_resume_and_manifest_usage_errors(meshes, tmp_path) -> None:
    base = [str(meshes["box"]), "-o", str(tmp_path / "o")]
    assert "--resume needs --run-manifest" in run([*base, "--resume"]).stderr
    no_cache = run([*base, "--run-manifest", str(tmp_path / "m.json"), "--no-cache"])
    assert no_cache.exit_code == 2 and "--run-manifest needs the cache" in no_cache.stderr


@pytest.mark.slow
def test_manifest_rewrites_are_throttled_but_never_lost(tmp_path) -> None:
    now = [0.0]
    path = tmp_path / "m.json"
    m = RunManifest(path, {"engine": "coacd"}, clock=lambda: now[0])
    for name in "abc":
        m.pending(name)
    m.finished("a", "ok")
    assert states(path) == {"a": "done", "b": "pending", "c": "pending"}
    m.finished("b", "failed", "ValueError: bad")
    assert states(path)["b"] == "pending"  # within the interval: the timer writes it
    deadline = time.monotonic() + 30  # a bound, not a speed
    while states(path)["b"] != "failed" and time.monotonic() < deadline:
        time.sleep(0.05)
    assert states(path)["b"] == "failed"
    m.finished("c", "timeout", "timed out after 1 s")
    m.write()  # the end of a run writes at once
    assert states(path) == {"a": "done", "b": "failed", "c": "failed"}
    with pytest.raises(MeshcolError, match="another engine"):
        RunManifest(path, {"engine": "vhacd"}, resume=True)
    resumed = RunManifest(path, {"engine": "coacd"}, resume=True)
    assert resumed.was_done("a") and not resumed.was_done("b")


@pytest.mark.slow
def test_resume_after_sigint_skips_the_files_that_finished(meshes, corpus, tmp_path) -> None:
    slow = corpus / "coacd-examples" / "Octocat-v2.obj"  # minutes with CoACD's defaults
    manifest, cache, out = tmp_path / "run.json", tmp_path / "cache", tmp_path / "out"
    inputs = [str(meshes["box"]), str(meshes["capsule"]), str(meshes["torus"]), str(slow)]
    command = [sys.executable, "-m", "meshcol", "decompose", *inputs, "-o", str(out)]
    command += ["--cache-dir", str(cache), "--run-manifest", str(manifest), "--preprocess", "off"]
    command += ["--report", "-"]
    command += FAST_DECOMPOSE
    proc = subprocess.Popen(
        [*command, "--timeout", "600"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        start_new_session=True,
    )
    try:
        deadline = time.monotonic() + 240  # three CoACD runs, on a loaded machine too
        while time.monotonic() < deadline:
            if manifest.exists() and read(manifest)["counts"]["done"] == 3:
                break
            time.sleep(0.1)
        assert states(manifest) == {
            "box.obj": "done",
            "capsule.obj": "done",
            "torus.obj": "done",
            "Octocat-v2.obj": "pending",
        }
        os.killpg(proc.pid, signal.SIGINT)  # Ctrl-C reaches the whole process group
        _, stderr = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    assert proc.returncode == 130, stderr
    assert states(manifest)["Octocat-v2.obj"] == "pending"
    assert not out.exists() or [p for p in out.rglob("*") if p.is_file()] == []

    resumed = subprocess.run(
        [*command, "--resume", "--timeout", "1"], capture_output=True, text=True, timeout=120
    )
    assert resumed.returncode == 1, resumed.stderr  # the slow file times out this time
    report = json.loads(resumed.stdout)
    assert [f["status"] for f in report["files"]] == ["ok", "ok", "ok", "timeout"]
    assert all(f["bodies"][0]["from_cache"] for f in report["files"][:3])
    assert states(manifest)["Octocat-v2.obj"] == "failed"
    assert sorted(p.name for p in out.iterdir() if p.name.startswith("box_")) == ["box_00.obj"]
