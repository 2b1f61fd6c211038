"""--snapshots in sweep, hull, fit and ci (meshcol.analysis.snapshots, ci_snapshots): one
PNG per violation, tested by its pixels, linked from the Markdown, written with the report."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from conftest import SAMPLES

from meshcol.cli import main
from meshcol.io.snapshots import COLLIDER_COLOR, PAIR_COLORS, SUBJECT_COLOR, WITNESS_COLOR

Image = pytest.importorskip("PIL.Image", reason="Pillow (meshcol[snapshots]) is not installed")
from snapshot_pixels import exact_mask, hue_mask, pixels  # noqa: E402 - after the skip

trimesh = pytest.importorskip("trimesh", reason="the test meshes are made with trimesh")


def run(*args: str) -> tuple[int, str, str]:
    result = CliRunner().invoke(main, list(args))
    return result.exit_code, result.stdout, result.stderr


def gap(a: np.ndarray, b: np.ndarray) -> float:
    """Smallest pixel distance between two masks (by their pixels' coordinates)."""
    pa, pb = np.argwhere(a)[::7], np.argwhere(b)[::7]
    return float(np.sqrt(((pa[:, None, :] - pb[None, :, :]) ** 2).sum(axis=2)).min())


def test_sweep_pictures_the_pair_at_the_time_of_impact(tmp_path):
    scene = str(SAMPLES / "bullet" / "scene.json")
    code, _, err = run("sweep", scene, "--format", "markdown", "--report",
                       str(tmp_path / "sweep.md"), "--snapshots", str(tmp_path / "shots"))  # fmt: skip
    assert code == 1, err
    (picture,) = sorted((tmp_path / "shots").iterdir())  # the one hit: the bullet, the wall
    assert "bullet" in picture.name and "wall" in picture.name
    markdown = (tmp_path / "sweep.md").read_text(encoding="utf-8")
    assert f"(shots/{picture.name})" in markdown and "| HIT | 1 |" in markdown
    image = pixels(picture)
    wall, bullet = (hue_mask(image, color) for color in PAIR_COLORS)
    assert wall.sum() > 300 and bullet.sum() > 3000
    # seen from the bullet's side (the wall would hide it): the bullet whole in the view
    ys, xs = np.nonzero(bullet)
    assert xs.min() > 0 and ys.min() > 0 and xs.max() < 799 and ys.max() < 599
    # at the time of impact the contact point is on the bullet (at its start pose the
    # bullet is 1 m, twice its length, from that point) and the wall meets it there
    witness = exact_mask(image, WITNESS_COLOR)
    assert witness.sum() > 20
    assert gap(witness, bullet) < 12 and gap(witness, wall) < 12
    # with --fail-on none nothing fails: no pictures, no folder left behind
    code, _, _ = run("sweep", scene, "--fail-on", "none", "--snapshots", str(tmp_path / "none"))
    assert code == 0 and list((tmp_path / "none").iterdir()) == []


def test_hull_pictures_the_collider_that_breaks_the_target(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    trimesh.creation.icosphere(3, 0.5).export("ball.obj")
    trimesh.creation.box(extents=(1, 1, 1)).export("cube.obj")
    Path("tiny.toml").write_text(
        'title = "Tiny"\n[limits]\nmax_hull_vertices = 4\nmax_oblong_ratio = 2\n'
    )
    code, _, err = run("hull", "ball.obj", "--target", "tiny.toml", "--format", "markdown",
                       "--report", "hull.md", "--snapshots", "shots")  # fmt: skip
    assert code == 1, err
    (picture,) = sorted(Path("shots").iterdir())
    markdown = Path("hull.md").read_text(encoding="utf-8")
    assert f"(shots/{picture.name})" in markdown and "MC102" in markdown
    image = pixels(picture)
    mesh, collider = hue_mask(image, SUBJECT_COLOR), exact_mask(image, COLLIDER_COLOR)
    assert mesh.sum() > 300 and collider.sum() > 300  # the mesh, the hull's edges
    ys, xs = np.nonzero(collider)
    assert xs.max() - xs.min() > 200 and ys.max() - ys.min() > 150  # framed, hull whole
    assert xs.min() > 0 and ys.min() > 0 and xs.max() < 799 and ys.max() < 599
    my, mx = np.nonzero(mesh)  # the ball inside its hull's outline
    assert xs.min() < mx.min() and mx.max() < xs.max() and ys.min() < my.min()
    # within its budget, a hull passes: no picture
    code, _, err = run("hull", "cube.obj", "--max-vertices", "8", "--snapshots", "none")
    assert code == 0, err
    assert list(Path("none").iterdir()) == []


def test_fit_pictures_a_primitive_past_the_volume_tolerance(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    trimesh.creation.box(extents=(3.0, 0.3, 0.3)).export("rod.obj")
    trimesh.creation.icosphere(2, 0.5).export("ball.obj")
    code, _, err = run("fit", "rod.obj", "ball.obj", "--shape", "sphere", "--format", "markdown",
                       "--report", "fit.md", "--snapshots", "shots")  # fmt: skip
    assert code == 0, err  # fit has no policy: a loose fit warns
    (picture,) = sorted(Path("shots").iterdir())  # the rod in a sphere; the ball fits
    assert "rod" in picture.name
    markdown = Path("fit.md").read_text(encoding="utf-8")
    assert f"(shots/{picture.name})" in markdown and "volume-tolerance" in markdown
    image = pixels(picture)
    mesh, collider = hue_mask(image, SUBJECT_COLOR), exact_mask(image, COLLIDER_COLOR)
    assert mesh.sum() > 500 and collider.sum() > 300
    # the sphere's outline reaches past the rod's ends and sides
    ys, xs = np.nonzero(mesh)
    cys, cxs = np.nonzero(collider)
    assert cxs.min() <= xs.min() and cxs.max() >= xs.max()
    assert cys.max() - cys.min() > 2 * (ys.max() - ys.min())


@pytest.mark.slow  # 1-2 s: the fast lane (make test-fast) stays under 40 s
def test_ci_snapshots_every_failing_job_linked_from_the_markdown(tmp_path, monkeypatch):
    pytest.importorskip("yourdfpy", reason="the test repository's robot needs yourdfpy")
    import sys

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "cli"))
    from ci_repo import box_obj, make_repo

    root = make_repo(tmp_path / "repo")
    monkeypatch.chdir(root)
    cache = str(tmp_path / "cache")
    assert run("ci", "--cache-dir", cache, "--report", "cold.json")[0] == 1
    cold = json.loads(Path("cold.json").read_text())
    Path("pr").mkdir()
    args = ["ci", "--cache-dir", cache, "--output", "markdown=pr/comment.md",
            "--snapshots", "pr/shots", "--report", "pr/ci.json"]  # fmt: skip
    code, _, err = run(*args)  # every job from the cache: the pictures still come
    assert code == 1, err
    pictures = sorted(Path("pr/shots").iterdir())
    markdown = Path("pr/comment.md").read_text(encoding="utf-8")
    for picture in pictures:
        assert f"(shots/{picture.name})" in markdown
    failing = [
        (r["command"], r["input"]) for r in cold["runs"] if r["exit_code"] == 1
    ]  # the open props (inspect) and the level (check)
    assert ("check", "levels/level/scene.json") in failing
    level = next(r for r in cold["runs"] if r["command"] == "check")["report"]
    violations = sum(p["violation"] for p in level["pairs"])
    inspected = [f for f in failing if f[0] == "inspect"]
    assert len(pictures) == violations + len(inspected)
    assert sum("levels-level-scene.json" in p.name for p in pictures) == violations
    for picture in pictures:
        image = pixels(picture)
        if "scene.json" in picture.name:
            assert all(hue_mask(image, c).sum() > 200 for c in PAIR_COLORS), picture.name
        else:
            assert hue_mask(image, SUBJECT_COLOR).sum() > 1000, picture.name
    # the report with the pictures is the report without them, but for its links
    report = json.loads(Path("pr/ci.json").read_text())
    assert report["summary"] == cold["summary"]
    # a run that cannot write its report leaves no pictures
    import meshcol.io.formats

    def broken(*args: object, **kwargs: object) -> None:
        raise OSError(28, "No space left on device", str(root / "pr2.json"))

    monkeypatch.setattr(meshcol.io.formats, "write_report", broken)
    (root / "props" / "soft" / "open.obj").write_text(box_obj(1.0, True, name="open2"))
    code, _, err = run("ci", "--cache-dir", cache, "--snapshots", "pics", "--report", "pr2.json")
    assert code != 0 and "No space left on device" in err
    assert not Path("pics").exists()


def test_ci_snapshots_draw_from_the_cached_jobs_without_running_them(tmp_path, monkeypatch):
    """A failing job keeps what its pictures need (the part of its review page they draw)
    with its result: pictures of cached jobs come without running them again, the same
    bytes; a job cached by a run without --snapshots runs once more, and only such a job."""
    pytest.importorskip("yourdfpy", reason="the test repository's robot needs yourdfpy")
    import sys

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "cli"))
    from ci_repo import make_repo

    import meshcol.analysis.ci as ci

    root = make_repo(tmp_path / "repo")
    monkeypatch.chdir(root)
    executed: list[str] = []
    execute = ci._execute

    def counted(job, folder, pair_cache=None):
        executed.append(job.label)
        return execute(job, folder, pair_cache)

    monkeypatch.setattr(ci, "_execute", counted)
    cache = str(tmp_path / "cache")
    assert run("ci", "--cache-dir", cache)[0] == 1  # cached without pictures
    total = len(executed)
    assert run("ci", "--cache-dir", cache, "--snapshots", "one")[0] == 1
    failing = executed[total:]  # the failing jobs only, once each
    assert sorted(failing) == ["check levels/level/scene.json", "inspect props/hard/open.obj"]
    del executed[:]
    assert run("ci", "--cache-dir", cache, "--snapshots", "two")[0] == 1
    assert executed == []  # drawn from the cache
    one, two = sorted(Path("one").iterdir()), sorted(Path("two").iterdir())
    assert [p.name for p in one] == [p.name for p in two] and len(one) >= 2
    assert all(a.read_bytes() == b.read_bytes() for a, b in zip(one, two))


def test_a_shot_page_draws_what_the_review_page_draws(tmp_path):
    """The part of a page the shots need, through JSON, gives the page's pictures pixel for
    pixel, and keeps fewer meshes than the page when a picture shows part of a scene."""
    from meshcol.analysis.check import check
    from meshcol.analysis.review import check_page
    from meshcol.analysis.snapshots import shots_of
    from meshcol.io.snapshots import ShotPage, render_shots, shot_page

    scene = str(SAMPLES / "level" / "scene.json")
    report = check([scene], fail_on="contact")
    page = check_page(report, [scene], "hull", {})
    shots = [shot for _, shot in shots_of(report)][:2]
    assert len(shots) == 2
    kept = ShotPage.from_data(json.loads(json.dumps(shot_page(page, shots).to_data())))
    assert len(kept.meshes()) < len(page.meshes())
    (tmp_path / "page").mkdir()
    (tmp_path / "kept").mkdir()
    whole = render_shots(page, shots, str(tmp_path / "page"))
    part = render_shots(kept, shots, str(tmp_path / "kept"))
    assert list(whole) == list(part) == [shot.name for shot in shots]
    for name in whole:
        assert Path(whole[name]).read_bytes() == Path(part[name]).read_bytes(), name
