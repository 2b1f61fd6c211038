"""--snapshots (meshcol.io.snapshots, meshcol.io.raster): one PNG per violation, drawn
offscreen, tested by its pixels; written with the report or not at all."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from conftest import SAMPLES

from meshcol.cli import main
from meshcol.io.raster import Camera, Raster
from meshcol.io.snapshots import NORMAL_COLOR, PAIR_COLORS, SUBJECT_COLOR, WITNESS_COLOR

Image = pytest.importorskip("PIL.Image", reason="Pillow (meshcol[snapshots]) is not installed")
from snapshot_pixels import exact_mask, hue_mask, pixels  # noqa: E402 - after the skip


def run(*args: str) -> tuple[int, str, str]:
    result = CliRunner().invoke(main, list(args))
    return result.exit_code, result.stdout, result.stderr


def test_rasterizer_fills_a_triangle_and_keeps_the_nearest():
    camera = Camera(np.array([-1.0, -1.0, -1.0]), np.array([1.0, 1.0, 1.0]), 200, 150)
    raster = Raster(camera)
    right, up, back = camera.axes
    far = np.array([-0.8 * right - 0.8 * up, 0.8 * right - 0.8 * up, 0.8 * up]) - 0.5 * back
    near = far + 1.0 * back  # the same triangle, nearer the viewer
    raster.triangles(near[None], (0, 0, 255))
    raster.triangles(far[None], (255, 0, 0))  # drawn later, but behind: hidden
    image = raster.pixels
    blue = (image[..., 2] > 0) & (image[..., 0] == 0)
    (a, b, c) = camera.project(near)[:, :2]
    area = 0.5 * abs((b - a)[0] * (c - a)[1] - (b - a)[1] * (c - a)[0])
    perimeter = sum(np.linalg.norm(p - q) for p, q in ((a, b), (b, c), (c, a)))
    assert abs(blue.sum() - area) <= perimeter  # filled, to the pixel along its edges
    assert (image[~blue] == 255).all()  # the rest is background: the far one is hidden
    corner = camera.project(np.zeros(3))
    assert blue[int(corner[1]), int(corner[0])]  # the centre is inside


@pytest.fixture(scope="module")
def level_run(tmp_path_factory):
    samples = SAMPLES
    out = tmp_path_factory.mktemp("snapshots")
    args = ["check", str(samples / "level" / "scene.json"), "--fail-on", "contact"]
    report = json.loads(run(*args)[1])
    code, _, err = run(*args, "--format", "markdown", "--report", str(out / "check.md"),
                       "--snapshots", str(out / "pictures"))  # fmt: skip
    return out, report, code, err


def test_one_picture_per_violation_linked_from_the_markdown(level_run):
    out, report, code, err = level_run
    assert code == 1
    violating = [p for p in report["pairs"] if p["violation"]]
    pictures = sorted((out / "pictures").iterdir())
    assert len(pictures) == len(violating) > 0
    assert all(p.suffix == ".png" for p in pictures)
    markdown = (out / "check.md").read_text(encoding="utf-8")
    for picture in pictures:
        assert f"(pictures/{picture.name})" in markdown  # relative to the report's folder
    assert f"meshcol: snapshots: {len(pictures)} in " in err


def test_pictures_show_the_pair_framed_with_witnesses_and_normal(level_run):
    out, report, _, _ = level_run
    for picture in sorted((out / "pictures").iterdir()):
        image = pixels(picture)
        masks = [hue_mask(image, color) for color in PAIR_COLORS]
        for color, mask in zip(PAIR_COLORS, masks):  # each body of the pair, in its colour
            assert mask.sum() > 400, (picture.name, color)
        assert exact_mask(image, WITNESS_COLOR).sum() > 20, picture.name  # a witness disc
        ys, xs = np.nonzero(masks[0] | masks[1])
        width, height = xs.max() - xs.min(), ys.max() - ys.min()
        assert width > 0.25 * 800 or height > 0.25 * 600  # framed: the pair fills the view
        # the smaller body (a barrel on a floor) is wholly in the picture
        small = min(masks, key=lambda m: m.sum())
        ys, xs = np.nonzero(small)
        assert xs.min() > 0 and ys.min() > 0 and xs.max() < 799 and ys.max() < 599
    penetrating = next(p for p in report["pairs"] if p["status"] == "penetrating")
    name = f"{penetrating['body_a']} <-> {penetrating['body_b']}"
    picture = next(p for p in (out / "pictures").iterdir() if penetrating["body_a"] in p.name)
    assert hue_mask(pixels(picture), NORMAL_COLOR).sum() > 30, name  # the normal's arrow


def test_a_picture_poses_only_the_meshes_near_its_frame(tmp_path, monkeypatch):
    """A scene of many bodies and a few violations: each picture poses the triangles of the
    meshes whose box meets its frame, not every mesh of the scene (pictures x bodies)."""
    from meshcol.io import snapshots

    crate = str(SAMPLES / "level" / "props" / "crate.obj")
    bodies = [
        {"name": f"far_{k}", "mesh": crate, "position": [4.0 * k, 50.0, 0.0]} for k in range(60)
    ]
    bodies += [
        {"name": f"hit_{k}", "mesh": crate, "position": [10.0 * (k // 2) + 0.5 * (k % 2), 0.0, 0.0]}
        for k in range(6)
    ]
    scene = tmp_path / "scene.json"
    scene.write_text(json.dumps({"units": "m", "bodies": bodies}))
    posed = []
    world = snapshots._world
    monkeypatch.setattr(snapshots, "_world", lambda mesh: posed.append(mesh["body"]) or world(mesh))
    code, _, err = run("check", str(scene), "--fail-on", "contact", "--report",
                       str(tmp_path / "r.json"), "--snapshots", str(tmp_path / "shots"))  # fmt: skip
    assert code == 1, err
    pictures = sorted((tmp_path / "shots").iterdir())
    assert len(pictures) == 3  # hit_0 with hit_1, hit_2 with hit_3, hit_4 with hit_5
    assert 0 < len(posed) <= 10 * len(pictures)  # the pair and its few neighbours, not 66 a picture


def test_inspect_pictures_one_per_failing_asset(samples, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    cube = (samples / "bowl" / "bowl.obj").read_text()
    corners = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1)]
    open_box = "".join(f"v {x} {y} {z}\n" for x, y, z in corners)
    open_box += "v 0 1 1\nf 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\n"
    open_box += "f 2 7 6\nf 3 4 8\nf 3 8 7\n"  # the x = 0 side missing: open
    Path("open.obj").write_text(open_box)
    Path("bowl.obj").write_text(cube)
    code, _, _ = run("inspect", "bowl.obj", "open.obj", "--fail-on", "not-watertight",
                     "--report", "inspect.md", "--snapshots", "shots")  # fmt: skip
    assert code == 1
    (picture,) = sorted(Path("shots").iterdir())
    assert "open" in picture.name
    image = pixels(picture)
    assert hue_mask(image, SUBJECT_COLOR).sum() > 2000  # the mesh
    assert exact_mask(image, "#ff0000").sum() > 50  # its open edges, red
    assert f"(shots/{picture.name})" in Path("inspect.md").read_text(encoding="utf-8")


def test_pictures_and_report_are_written_together_or_not_at_all(samples, tmp_path, monkeypatch):
    import meshcol.io.formats

    def broken(*args: object, **kwargs: object) -> None:
        raise OSError(28, "No space left on device", str(tmp_path / "check.md"))

    monkeypatch.setattr(meshcol.io.formats, "write_report", broken)
    code, _, err = run("check", str(samples / "level" / "scene.json"), "--fail-on", "contact",
                       "--report", str(tmp_path / "check.md"),
                       "--snapshots", str(tmp_path / "pictures" / "check"))  # fmt: skip
    assert code != 0 and "No space left on device" in err
    assert not (tmp_path / "pictures").exists()  # nothing half-written, no folder made


def test_snapshots_without_pillow_is_one_line_and_exit_2(samples, tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "PIL", None)
    code, out, err = run("check", str(samples / "level" / "scene.json"),
                         "--snapshots", str(tmp_path / "pictures"))  # fmt: skip
    assert code == 2 and out == ""
    assert err == ("meshcol: error: --snapshots needs Pillow: pip install 'meshcol[snapshots]'\n")
    assert not (tmp_path / "pictures").exists()


def test_snapshots_folder_that_is_a_file_is_refused_before_the_work(samples, tmp_path):
    (tmp_path / "taken").write_text("x")
    code, _, err = run("check", str(samples / "level" / "scene.json"),
                       "--snapshots", str(tmp_path / "taken"))  # fmt: skip
    assert code == 2 and "invalid value for '--snapshots'" in err and "is a file" in err
