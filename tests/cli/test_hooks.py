"""Hooks where users put them: the real pre-commit running this repository's
.pre-commit-hooks.yaml (``pre-commit try-repo``, offline) on staged assets of a test
repository, the GitLab CI example's script lines, and the GitHub composite action."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

yaml = pytest.importorskip("yaml", reason="PyYAML (with pre-commit) is not installed")

REPO = Path(__file__).resolve().parents[2]
BIN = Path(sys.executable).parent  # the meshcol of this environment, on PATH

# A unit cube (12 triangles, outward), and the same without its x = 0 side (open).
CUBE = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]
FACES = [(1, 3, 2), (1, 4, 3), (5, 6, 7), (5, 7, 8), (1, 2, 6), (1, 6, 5), (2, 3, 7), (2, 7, 6),
         (3, 4, 8), (3, 8, 7), (4, 1, 5), (4, 5, 8)]  # fmt: skip


def obj(faces: list[tuple[int, int, int]]) -> str:
    text = "".join(f"v {x} {y} {z}\n" for x, y, z in CUBE)
    return text + "".join(f"f {a} {b} {c}\n" for a, b, c in faces)


def level(offset: float) -> str:
    """Two cubes, the second ``offset`` along x from the first (below 1: penetrating)."""
    bodies = [
        {"name": "crate_a", "mesh": "props/crate.obj", "position": [0.0, 0.0, 0.0]},
        {"name": "crate_b", "mesh": "props/crate.obj", "position": [offset, 0.0, 0.0]},
    ]
    return json.dumps({"units": "m", "bodies": bodies})


def git(repo: Path, *args: str) -> None:
    subprocess.run(["git", "-C", str(repo), *args], check=True, capture_output=True)


def environment(tmp: Path) -> dict[str, str]:
    env = dict(os.environ)
    env["PATH"] = f"{BIN}{os.pathsep}{env.get('PATH', '')}"
    env["PRE_COMMIT_HOME"] = str(tmp / "pre-commit-home")  # never the user's cache
    env["GIT_AUTHOR_NAME"] = env["GIT_COMMITTER_NAME"] = "test"
    env["GIT_AUTHOR_EMAIL"] = env["GIT_COMMITTER_EMAIL"] = "test@example.invalid"
    for key in ("GITHUB_STEP_SUMMARY", "GITHUB_WORKSPACE", "PRE_COMMIT"):
        env.pop(key, None)
    return env


@pytest.fixture
def assets(tmp_path: Path) -> Path:
    """A test repository: good props and a level that rests, staged."""
    if shutil.which("git") is None:
        pytest.skip("git is not installed")
    repo = tmp_path / "assets"
    (repo / "props").mkdir(parents=True)
    (repo / "props" / "crate.obj").write_text(obj(FACES))
    (repo / "level_01.json").write_text(level(2.0))
    git(repo, "init", "-q")
    git(repo, "add", "-A")
    return repo


@pytest.fixture(scope="module")
def hooks_repo(tmp_path_factory) -> Path:
    """This repository's .pre-commit-hooks.yaml, committed alone in a git repository:
    try-repo clones what it is given, and a clone of the whole source is slow."""
    if shutil.which("git") is None:
        pytest.skip("git is not installed")
    repo = tmp_path_factory.mktemp("hooks")
    shutil.copy(REPO / ".pre-commit-hooks.yaml", repo / ".pre-commit-hooks.yaml")
    git(repo, "init", "-q")
    git(repo, "add", "-A")
    env = environment(repo)
    subprocess.run(["git", "-C", str(repo), "commit", "-q", "-m", "hooks"], env=env, check=True)
    return repo


def try_repo(hooks: Path, repo: Path, hook: str, tmp: Path) -> subprocess.CompletedProcess:
    pre_commit = shutil.which("pre-commit", path=str(BIN)) or shutil.which("pre-commit")
    if pre_commit is None:
        pytest.skip("pre-commit is not installed (pip install pre-commit)")
    command = [pre_commit, "try-repo", str(hooks), hook, "--color", "never"]
    return subprocess.run(
        command, cwd=repo, env=environment(tmp), capture_output=True, text=True, timeout=300
    )


@pytest.mark.slow
def test_pre_commit_inspect_passes_good_meshes_and_fails_an_open_one(hooks_repo, assets, tmp_path):
    good = try_repo(hooks_repo, assets, "meshcol-inspect", tmp_path)
    assert good.returncode == 0, good.stdout + good.stderr
    assert "meshcol inspect (mesh health)" in good.stdout and "Passed" in good.stdout
    (assets / "props" / "open.obj").write_text(obj(FACES[:-2]))
    git(assets, "add", "props/open.obj")
    bad = try_repo(hooks_repo, assets, "meshcol-inspect", tmp_path)
    assert bad.returncode == 1, bad.stdout + bad.stderr
    assert "Failed" in bad.stdout and "exit code: 1" in bad.stdout
    assert "| fails | MC401 not-watertight | props/open.obj::" in bad.stdout  # the Markdown
    assert "crate.obj::crate" not in bad.stdout.split("| --- |")[-1]  # only the open one fails


@pytest.mark.slow
def test_pre_commit_check_fails_a_level_whose_crates_interpenetrate(hooks_repo, assets, tmp_path):
    good = try_repo(hooks_repo, assets, "meshcol-check", tmp_path)
    assert good.returncode == 0, good.stdout + good.stderr
    assert "meshcol check (interpenetration)" in good.stdout and "Passed" in good.stdout
    (assets / "level_01.json").write_text(level(0.75))  # a quarter metre into each other
    git(assets, "add", "level_01.json")
    bad = try_repo(hooks_repo, assets, "meshcol-check", tmp_path)
    assert bad.returncode == 1, bad.stdout + bad.stderr
    row = "| fails | MC501 penetrating | crate\\_a \\<-\\> crate\\_b | level\\_01.json |"
    assert f"{row} depth 0.25 m |" in bad.stdout


def test_the_hooks_file_matches_mesh_extensions_and_scenes():
    import re

    from meshcol.io.mesh_formats import MESH_EXTENSIONS

    hooks = {h["id"]: h for h in yaml.safe_load((REPO / ".pre-commit-hooks.yaml").read_text())}
    assert {"meshcol-inspect", "meshcol-check", "meshcol-ci"} <= set(hooks)
    inspect = re.compile(hooks["meshcol-inspect"]["files"])
    for extension in MESH_EXTENSIONS:
        assert inspect.search(f"props/chair{extension.upper()}"), extension
    assert not inspect.search("props/chair.json")
    check = re.compile(hooks["meshcol-check"]["files"])
    assert check.search("levels/level_01.json") and check.search("robots/arm.urdf")
    assert not check.search("props/material.json")
    assert hooks["meshcol-ci"]["pass_filenames"] is False


def gitlab_script(job: str) -> str:
    """The job's script lines as GitLab's shell runs them (one shell, stop at a failing
    line), without those that need the runner (``pip install``: its network)."""
    config = yaml.safe_load((REPO / "docs" / "gitlab-ci.yml").read_text())
    lines = [*config[".meshcol"]["before_script"], *config[job]["script"]]
    kept = [line for line in lines if "pip install" not in line]
    assert len(kept) == len(lines) - 1
    return "set -eo pipefail\n" + "\n".join(kept) + "\n"


def run_bash(script: str, cwd: Path, tmp: Path) -> subprocess.CompletedProcess:
    bash = shutil.which("bash")
    if bash is None:
        pytest.skip("bash is not installed")
    return subprocess.run(
        [bash, "-c", script], cwd=cwd, env=environment(tmp), capture_output=True, text=True,
        timeout=300,
    )  # fmt: skip


@pytest.mark.slow
def test_gitlab_example_script_fails_bad_assets_with_every_report(assets, tmp_path):
    """A PR-like change (the crates of a level moved into each other): the job fails after
    writing JUnit, SARIF, the Markdown summary and its picture. (Good assets pass the same
    commands in the pre-commit tests above.)"""
    (assets / "level_01.json").write_text(level(0.75))
    git(assets, "add", "-A")
    bad = run_bash(gitlab_script("meshcol-assets"), assets, tmp_path)
    assert bad.returncode == 1, bad.stdout + bad.stderr
    reports = assets / "reports"
    assert {p.name for p in reports.iterdir()} >= {
        "inspect.xml", "inspect.sarif", "check-level_01.xml", "check-level_01.md", "snapshots"
    }  # fmt: skip
    assert json.loads((reports / "inspect.sarif").read_text())["runs"][0]["results"] == []
    assert "### ❌ meshcol check: FAIL" in bad.stdout  # the summary in the job log
    (picture,) = (reports / "snapshots" / "level_01").iterdir()
    assert f"(snapshots/level_01/{picture.name})" in (reports / "check-level_01.md").read_text()


@pytest.mark.slow
def test_gitlab_example_ci_job_runs_meshcol_ci(assets, tmp_path):
    probe = subprocess.run([str(BIN / "meshcol"), "ci", "--help"], capture_output=True)
    if probe.returncode != 0:
        pytest.skip("meshcol ci is not available in this build")
    (assets / "meshcol.toml").write_text(
        '[[assets]]\nglob = "props/*.obj"\ninspect = { fail-on = ["not-watertight"] }\n\n'
        '[[scenes]]\npath = "level_01.json"\ncheck = { fail-on = "penetration" }\n'
    )
    git(assets, "add", "-A")
    result = run_bash(gitlab_script("meshcol-ci"), assets, tmp_path)
    assert result.returncode == 0, result.stdout + result.stderr  # good assets pass
    sarif = json.loads((assets / "reports" / "meshcol.sarif").read_text())
    assert sarif["version"] == "2.1.0"
    assert "meshcol" in (assets / "reports" / "meshcol.md").read_text()


def test_github_action_is_composite_and_uploads_sarif_and_the_summary(tmp_path):
    action = yaml.safe_load((REPO / "action.yml").read_text())
    assert action["runs"]["using"] == "composite"
    steps = action["runs"]["steps"]
    uses = [step.get("uses", "") for step in steps]
    assert any(u.startswith("actions/setup-python@") for u in uses)
    assert any(u.startswith("github/codeql-action/upload-sarif@") for u in uses)
    runs = {step.get("name"): step.get("run", "") for step in steps}
    assert "pip install" in runs["Install meshcol"]
    assert "meshcol ci" in runs["meshcol ci"] and "sarif=" in runs["meshcol ci"]
    for step in steps:
        if "run" in step:
            assert step["shell"] == "bash"  # composite steps must name their shell
            assert "${{" not in step["run"]  # inputs reach scripts through env, not inlined
    # the summary step, run as the runner would: the Markdown lands in the job summary
    reports = tmp_path / "meshcol-reports"
    reports.mkdir()
    (reports / "meshcol.md").write_text("### ❌ meshcol check: FAIL\n")
    summary = tmp_path / "summary.md"
    env = {**environment(tmp_path), "GITHUB_STEP_SUMMARY": str(summary),
           "MESHCOL_REPORTS": str(reports)}  # fmt: skip
    done = subprocess.run(["bash", "-c", runs["Job summary"]], env=env, cwd=tmp_path)
    assert done.returncode == 0
    assert summary.read_text() == "### ❌ meshcol check: FAIL\n"
