"""`--html FILE` review pages: written offline and atomically, within their limits, and drawn
by a real browser (headless Chromium; those tests skip when /usr/bin/chromium is absent)."""

from __future__ import annotations

import html.parser
import os
import re
import shutil
import subprocess
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
import trimesh
from click.testing import CliRunner

from meshcol.cli import main
from meshcol.io import review
from meshcol.io.review import PALETTE, ReviewPage, ReviewTooLargeError, write_review

pytest.importorskip("meshcat", reason="the review pages need meshcol[review] (meshcat)")

CHROMIUM = shutil.which("chromium") or (
    "/usr/bin/chromium" if os.path.exists("/usr/bin/chromium") else None
)
browser = pytest.mark.skipif(CHROMIUM is None, reason="no headless browser (/usr/bin/chromium)")

#: Flags of a headless, offline, software-WebGL Chromium (swiftshader: no GPU needed).
FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--use-angle=swiftshader",
    "--enable-unsafe-swiftshader",
    "--virtual-time-budget=1500",
    "--window-size=1200,800",
]
#: Left edge of the 3D view (the side panel is 460 px wide).
PANE_LEFT = 470


def run(args: list[str]):
    return CliRunner().invoke(main, args, catch_exceptions=False)


def chromium(
    page: Path, tmp_path: Path, hash_: str = "", shot: bool = True, dom: bool = True
) -> tuple[np.ndarray | None, str]:
    """Screenshot (H, W, 3) uint8 and DOM after load of ``page`` (``#pair=N`` in hash_), of
    one browser run (about 3 s; the DOM on stdout, the PNG to a file: the same bytes as a run
    for each), so either can be left out."""
    from PIL import Image

    url = page.resolve().as_uri() + hash_
    path = tmp_path / f"{page.stem}{hash_.replace('#', '_').replace('=', '')}.png"
    command = [CHROMIUM, *FLAGS, f"--user-data-dir={tmp_path / 'profile'}"]
    command += [f"--screenshot={path}"] * shot + ["--dump-dom"] * dom
    done = subprocess.run([*command, url], capture_output=True, timeout=120, text=True)
    pixels = np.asarray(Image.open(path).convert("RGB")) if shot else None
    return pixels, done.stdout if dom else ""


def assert_drew(pixels: np.ndarray | None, dom: str | None) -> np.ndarray:
    """The page ran without a JavaScript error (``dom``; None: not read) and its 3D view is
    not blank."""
    assert pixels is not None
    if dom is not None:
        assert_no_error(dom)
    view = pixels[:, PANE_LEFT:]
    background = np.median(view.reshape(-1, 3), axis=0)
    drawn = np.abs(view.astype(int) - background).sum(axis=2) > 40
    assert drawn.mean() > 0.01, "the 3D view is blank"
    return view


def assert_no_error(dom: str) -> None:
    root = re.search(r"<html[^>]*>", dom).group(0)  # the page's markers sit on <html>
    title = re.search(r"<title>(.*?)</title>", dom, re.S).group(1)
    assert "data-error" not in root and not title.startswith("meshcol-error"), root + title
    assert "data-console-error" not in root, root
    assert 'data-meshcol-ready="' in root, "the page script did not finish"


def hue_present(view: np.ndarray, color: str, share: float = 1e-4) -> bool:
    """Pixels of ``color``'s hue (shaded: any brightness), saturated, cover ``share``."""
    import colorsys

    target = colorsys.rgb_to_hsv(*(int(color[i : i + 2], 16) / 255 for i in (1, 3, 5)))[0]
    rgb = view.reshape(-1, 3).astype(float) / 255
    hi, lo = rgb.max(axis=1), rgb.min(axis=1)
    sat = np.where(hi > 0, (hi - lo) / np.maximum(hi, 1e-9), 0)
    r, g, b = rgb.T
    delta = np.maximum(hi - lo, 1e-9)
    hue = (
        np.select(
            [hi == r, hi == g], [((g - b) / delta) % 6, (b - r) / delta + 2], (r - g) / delta + 4
        )
        / 6
    )
    close = np.minimum(abs(hue - target), 1 - abs(hue - target)) < 0.03
    # translucent over a grey mesh: the colour is blended, so saturation is moderate
    return bool(((sat > 0.2) & (hi > 0.25) & close).mean() > share)


def magenta(view: np.ndarray) -> float:
    v = view.astype(int)
    return float(((v[..., 0] > 150) & (v[..., 2] > 150) & (v[..., 1] < 90)).mean())


# -- pages without a browser ---------------------------------------------------------------


def test_check_page_is_offline_small_and_atomic(samples, tmp_path):
    page = tmp_path / "level.html"
    result = run(
        [
            "check",
            str(samples / "level" / "scene.json"),
            "--report",
            str(tmp_path / "r.json"),
            "--html",
            str(page),
        ]
    )
    assert result.exit_code == 1  # the level's four designed penetrations
    assert "review page: " in result.stderr
    text = page.read_text()
    assert len(text.encode()) < 5_000_000
    # self-contained: no script, stylesheet or image fetched from anywhere
    assert not re.search(r"<(script|link|img)[^>]+(src|href)=", text)
    assert "MeshCat.Viewer" in text and "crate_long_01" in text
    assert sorted(os.listdir(tmp_path)) == ["level.html", "r.json"]  # no temporary file left


def test_without_meshcat_html_exits_2_with_the_hint(samples, tmp_path, monkeypatch):
    monkeypatch.setattr(review.importlib.util, "find_spec", lambda name: None)
    page = tmp_path / "x.html"
    result = run(["inspect", str(samples / "bowl" / "bowl.obj"), "--html", str(page)])
    assert result.exit_code == 2
    assert result.stderr.strip().splitlines() == [
        "meshcol: error: --html needs the meshcat viewer: pip install 'meshcol[review]'"
    ]
    assert not page.exists()


def test_html_never_replaces_an_input(samples, tmp_path):
    mesh = tmp_path / "bowl.obj"
    shutil.copy(samples / "bowl" / "bowl.obj", mesh)
    before = mesh.read_bytes()
    result = run(["inspect", str(mesh), "--html", str(mesh)])
    assert result.exit_code == 2
    assert mesh.read_bytes() == before


@pytest.mark.parametrize("command", ["inspect", "check"])
def test_too_many_bodies_is_refused_in_one_line(samples, tmp_path, monkeypatch, command):
    """A page over its limits is refused before anything is written: no page, no report."""
    monkeypatch.setattr(review, "MAX_REVIEW_BODIES", 10)
    page = tmp_path / "x.html"
    report = tmp_path / "report.json"
    scene = str(samples / "level" / "scene.json")
    result = run([command, scene, "--html", str(page), "--report", str(report)])
    assert result.exit_code == 2
    assert not report.exists()
    last = result.stderr.strip().splitlines()[-1]
    assert last == (
        "meshcol: error: review page: 25 bodies is over the limit of 10 a browser can show; "
        "review a part of the scene"
    )
    assert not page.exists()


def test_hundred_thousand_bodies_refused_before_any_drawing():
    page = ReviewPage("check", "many")
    for k in range(100_000):
        page.add_body(f"b{k}")
    with pytest.raises(ReviewTooLargeError, match="100,000 bodies is over the limit of 2,000"):
        page.to_html()


def test_zero_bodies_page_is_written(tmp_path):
    size = write_review(tmp_path / "empty.html", ReviewPage("check", "nothing", "m"))
    assert 0 < size < 2_000_000


def test_huge_coordinates_are_shifted_before_float32(tmp_path):
    box = trimesh.creation.box((1.0, 1.0, 1.0))
    page = ReviewPage("inspect", "far away", "m")
    pose = np.eye(4)
    pose[:3, 3] = [1e12, -3e11, 5e9]
    page.add_mesh(box.vertices, box.faces, pose, body=page.add_body("far"))
    text = page.to_html()
    data = re.search(r'id="meshcol-data" type="application/json">(.*?)</script>', text, re.S)
    import json

    payload = json.loads(data.group(1))
    assert np.allclose(payload["centre"], [1e12, -3e11, 5e9])
    # the drawn pose is within the box's size of the page origin: float32 keeps the detail
    assert np.abs(np.asarray(payload["objects"][0]["m"][12:15])).max() < 1.0


def test_large_meshes_are_simplified_for_display_only(tmp_path, monkeypatch):
    pytest.importorskip("fast_simplification")
    monkeypatch.setattr(review, "DISPLAY_TRIANGLES", 2000)
    sphere = trimesh.creation.icosphere(6)  # 81,920 faces
    page = ReviewPage("inspect", "sphere")
    page.add_mesh(sphere.vertices, sphere.faces, body=page.add_body("sphere"))
    small = page.to_html()
    assert "shown simplified (fast-simplification)" in small
    full = ReviewPage("inspect", "sphere")
    monkeypatch.setattr(review, "DISPLAY_TRIANGLES", 10**7)
    full.add_mesh(sphere.vertices, sphere.faces, body=full.add_body("sphere"))
    empty = len(ReviewPage("inspect", "sphere").to_html())  # the viewer alone
    assert len(small) - empty < (len(full.to_html()) - empty) / 5


def test_check_rows_violations_first(samples):
    from meshcol.analysis.check import check
    from meshcol.analysis.review import check_page

    inputs = [str(samples / "level" / "scene.json")]
    report = check(inputs, clearance=0.0)
    page = check_page(report, inputs, "hull", {})
    rows = page._rows
    severities = [r["severity"] for r in rows]
    assert severities == sorted(severities, key=lambda s: s != "violation")
    assert rows[0]["label"].startswith("depth ") and rows[0]["label"].endswith(" m")
    assert rows[0]["points"].shape == (2, 3) and rows[0]["normal"] is not None


def test_check_page_draws_fitted_primitives(tmp_path):
    """``--collider fit`` parts are primitives packed without vertices: each is drawn, at its
    fitted pose, and the drawing holds the body's mesh."""
    from meshcol.analysis.check import check
    from meshcol.analysis.review import check_page

    sphere = trimesh.creation.icosphere(subdivisions=2, radius=0.5)
    sphere.export(tmp_path / "ball.obj")
    slab = trimesh.creation.box((2.0, 0.4, 0.3))
    slab.apply_transform(trimesh.transformations.rotation_matrix(0.3, (0, 0, 1)))
    slab.apply_translation((3.0, 0.0, 0.0))
    slab.export(tmp_path / "slab.obj")
    inputs = [str(tmp_path / "ball.obj"), str(tmp_path / "slab.obj")]
    report = check(inputs, collider="fit")
    page = check_page(report, inputs, "fit", {})
    drawn = [o for o in page._objects if o["group"] == "colliders"]
    assert len(drawn) == 2
    for o, mesh in zip(drawn, (sphere, slab)):
        v = page._geometries[o["g"]].vertices @ o["pose"][:3, :3].T + o["pose"][:3, 3]
        hull = trimesh.Trimesh(v, page._geometries[o["g"]].faces).convex_hull
        # the drawn polytope is inscribed in the primitive: it holds the mesh up to its facets
        assert np.all(hull.bounds[0] <= mesh.bounds[0] + 0.03)
        assert np.all(hull.bounds[1] >= mesh.bounds[1] - 0.03)


def _two_part_decomposition(tmp_path: Path) -> SimpleNamespace:
    """A 2x1x1 block 'decomposed' into two cubes (written as the run writes parts)."""
    block = trimesh.creation.box((2.0, 1.0, 1.0))
    block.export(tmp_path / "block.obj")
    out = tmp_path / "parts"
    out.mkdir()
    for k, x in enumerate((-0.5, 0.5)):
        part = trimesh.creation.box((1.0, 1.0, 1.0))
        part.apply_translation((x, 0, 0))
        part.export(out / f"block_{k:02d}.obj")
    metrics = {
        "tolerance": 0.01,
        "hausdorff_mesh_to_parts": 0.0,
        "hausdorff_parts_to_mesh": 0.0,
        "volume_ratio": 1.0,
    }
    body = {"name": "block", "outputs": ["block_00.obj", "block_01.obj"], "metrics": metrics}
    files = [{"path": str(tmp_path / "block.obj"), "status": "ok", "bodies": [body]}]
    return SimpleNamespace(files=files, units=None, out_dir=str(out))


def test_decompose_page_rows_per_part(tmp_path):
    from meshcol.analysis.review import decompose_page

    report = _two_part_decomposition(tmp_path)
    page = decompose_page(report, report.out_dir)
    assert [r["cells"][1] for r in page._rows] == [0, 1]
    assert [r["cells"][3] for r in page._rows] == [1.0, 1.0]  # each part's volume
    assert [r["cells"][4] for r in page._rows] == ["50.0%", "50.0%"]  # surface each covers


# -- the page's own files: package data, parsed ------------------------------------------

#: Slots of the page's skeleton, each filled once.
SLOTS = ["TITLE", "STYLE", "ERRORS", "VIEWER", "DATA", "APP"]
#: sha256 of _small_page(): ee068ea's page (when it was strings in review.py) but for issue
#: 29 item 19's changes (a chosen body alone on single-body pages, cut cells with titles):
#: the page must not change by a byte unless on purpose (change it only with the page).
SMALL_PAGE_SHA256 = "74a1fa00c96cb0629199d65c6f6bafd02218aa674c6f1ba03cf113fbe3f729aa"


def _small_page(monkeypatch) -> str:
    """A page with every kind of content (notes, groups, meshes, lines, points, rows, markup
    in names), the viewer stubbed."""
    monkeypatch.setattr(review, "viewer_script", lambda: "/* viewer </script> */")
    p = ReviewPage("check", "a <b> & c", "m")
    p.notes.append("a note")
    p.info.append(("bodies", "2"))
    p.group("meshes", "meshes", "#b8b8b8")
    p.group("hits", "hits", "#ff00ff", visible=False)
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    f = np.array([[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]])
    a, b = p.add_body("a</script>"), p.add_body("b")
    pose = np.eye(4)
    pose[:3, 3] = [2.0, 0.5, -1.0]
    p.add_mesh(v, f, body=a, name="a")
    p.add_mesh(v, f, pose, body=b, name="b", opacity=0.5, wireframe=True)
    p.add_lines([[[0, 0, 0], [1, 1, 1]]], group="paths", color="#000000")
    p.add_points([[0.5, 0.5, 0.5], [np.nan, 0, 0]], group="hits", color="#00c000", labels=["x"])
    p.table("Pairs", ["status", "distance", "a", "b", "flag"])
    p.add_row(
        ["penetrating", -0.25, "a", "b", True],
        bodies=(a, b),
        points=[[0, 0, 0], [1, 0, 0]],
        normal=[1, 0, 0],
        label="depth 0.25 m",
        severity="violation",
        group="hits",
    )
    p.add_row(["separated", float("nan"), "a", None, np.int64(3)], bodies=(a,))
    return p.to_html()


def test_the_page_from_its_files_is_byte_identical_to_the_page_in_strings(monkeypatch):
    import hashlib

    text = _small_page(monkeypatch)
    assert hashlib.sha256(text.encode("utf-8")).hexdigest() == SMALL_PAGE_SHA256


def test_the_page_files_are_package_data_read_once():
    """Found the way an installed package finds them (importlib.resources, not a path from
    the source tree), and read once."""
    import importlib.resources

    folder = importlib.resources.files("meshcol.io") / "review_assets"
    assert sorted(p.name for p in folder.iterdir() if p.is_file()) == sorted(review.ASSETS.values())
    assert review.review_assets() is review.review_assets()
    page = review.review_assets()["page"]
    assert re.findall(r"@([A-Z]+)@", page) == SLOTS
    assert "</script" not in review.review_assets()["app"] + review.review_assets()["errors"]
    assert "</style" not in review.review_assets()["style"]


def test_the_page_files_ship_in_the_wheel():
    """scikit-build-core puts every file of ``wheel.packages`` in the wheel (a wheel built from
    this tree holds meshcol/io/review_assets/*, and a page from it installed is this page);
    nothing in pyproject.toml leaves them out."""
    import fnmatch

    try:
        import tomllib
    except ImportError:  # Python 3.10
        import tomli as tomllib

    root = Path(review.__file__).resolve().parents[2]
    config = tomllib.loads((root / "pyproject.toml").read_text())["tool"]["scikit-build"]
    assert "meshcol" in config["wheel"]["packages"]
    excluded = config["wheel"].get("exclude", []) + config.get("sdist", {}).get("exclude", [])
    for name in review.ASSETS.values():
        path = f"meshcol/io/review_assets/{name}"
        assert (root / path).is_file()
        assert not any(fnmatch.fnmatch(path, pattern) for pattern in excluded)


def test_a_name_holding_a_slot_stays_as_it_is(monkeypatch):
    monkeypatch.setattr(review, "viewer_script", lambda: "")
    text = ReviewPage("check", "@DATA@ @APP@").to_html()
    assert "<title>meshcol check: @DATA@ @APP@</title>" in text


class _Tags(html.parser.HTMLParser):
    """Open elements, closed in order; void elements never open."""

    VOID = frozenset(
        {"meta", "link", "br", "hr", "img", "input", "col", "area", "base", "source", "wbr"}
    )

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.stack: list[str] = []
        self.errors: list[str] = []

    def handle_starttag(self, tag, attrs) -> None:
        if tag not in self.VOID:
            self.stack.append(tag)

    def handle_endtag(self, tag) -> None:
        if not self.stack or self.stack[-1] != tag:
            self.errors.append(f"</{tag}> at {self.getpos()} closes {self.stack[-1:]}")
        else:
            self.stack.pop()


def test_the_page_skeleton_is_well_formed_html():
    parser = _Tags()
    parser.feed(review.review_assets()["page"])
    parser.close()
    assert parser.errors == []
    assert parser.stack == [], f"unclosed: {parser.stack}"
    assert review.review_assets()["page"].startswith("<!DOCTYPE html>\n")


def test_the_style_sheet_balances_its_braces():
    css = re.sub(r"/\*.*?\*/", "", review.review_assets()["style"], flags=re.S)
    depth = 0
    for ch in css:
        depth += {"{": 1, "}": -1}.get(ch, 0)
        assert depth in (0, 1)
    assert depth == 0


NODE = shutil.which("node")


@pytest.mark.skipif(NODE is None, reason="no node to parse the page's scripts (node --check)")
@pytest.mark.parametrize("name", ["errors.js", "app.js"])
def test_the_page_scripts_parse(name, tmp_path):
    """``node --check``: a real JavaScript parser (V8's), offline; the scripts run in the page
    as classic scripts, as node checks a .js file outside a package."""
    script = tmp_path / name
    script.write_text(review.review_assets()[name.replace(".js", "")], encoding="utf-8")
    done = subprocess.run([NODE, "--check", str(script)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr


# -- pages in a real browser ---------------------------------------------------------------


@browser
@pytest.mark.slow
def test_browser_check_pair_is_highlighted(samples, tmp_path):
    page = tmp_path / "check.html"
    run(
        [
            "check",
            str(samples / "level" / "scene.json"),
            "--report",
            str(tmp_path / "r.json"),
            "--html",
            str(page),
        ]
    )
    plain, _ = chromium(page, tmp_path, dom=False)
    view = assert_drew(plain, None)
    assert magenta(view) < 1e-4  # nothing chosen: no highlight
    chosen, dom = chromium(page, tmp_path, "#pair=0")
    view = assert_drew(chosen, dom)
    assert magenta(view) > 0.01, "the chosen pair's highlight colour is not drawn"
    assert 'class="chosen violation"' in dom or 'class="violation chosen"' in dom
    assert "depth 0.25 m" in dom


@browser
@pytest.mark.slow
def test_browser_decomposition_part_colours(tmp_path):
    from meshcol.analysis.review import decompose_page

    report = _two_part_decomposition(tmp_path)
    page = tmp_path / "decompose.html"
    write_review(page, decompose_page(report, report.out_dir))
    pixels, dom = chromium(page, tmp_path)
    view = assert_drew(pixels, dom)
    assert hue_present(view, PALETTE[0]) and hue_present(view, PALETTE[1]), "part colours missing"


@browser
@pytest.mark.slow
def test_browser_sweep_hit(samples, tmp_path):
    page = tmp_path / "sweep.html"
    run(
        [
            "sweep",
            str(samples / "bullet" / "scene.json"),
            "--report",
            str(tmp_path / "s.json"),
            "--html",
            str(page),
        ]
    )
    pixels, dom = chromium(page, tmp_path, "#pair=0")
    view = assert_drew(pixels, dom)
    assert magenta(view) > 0.01
    assert "contact at toi 0.475, t = 0.00475 s" in dom


@browser
@pytest.mark.slow
def test_browser_inspect_findings_and_hull(tmp_path):
    box = trimesh.creation.box((1.0, 1.0, 1.0))
    open_box = trimesh.Trimesh(box.vertices, box.faces[2:], process=False)
    open_box.export(tmp_path / "open.obj")
    page = tmp_path / "inspect.html"
    result = run(["inspect", str(tmp_path / "open.obj"), "--html", str(page)])
    assert result.exit_code == 0
    pixels, dom = chromium(page, tmp_path)
    assert_drew(pixels, dom)
    cells = re.findall(r"<td[^>]*>([^<]*)</td>", dom)
    assert "open" in cells and "4" in cells  # 4 open edges listed for the body


@browser
@pytest.mark.slow
def test_browser_hull_page(samples, tmp_path):
    page = tmp_path / "hull.html"
    result = run(
        [
            "hull",
            str(samples / "bowl" / "bowl.obj"),
            "--max-vertices",
            "32",
            "--report",
            str(tmp_path / "h.json"),
            "--html",
            str(page),
        ]
    )
    assert result.exit_code == 0
    pixels, dom = chromium(page, tmp_path)
    view = assert_drew(pixels, dom)
    assert hue_present(view, PALETTE[0])  # the hull, translucent over the mesh


@browser
@pytest.mark.slow
def test_browser_zero_bodies_and_huge_coordinates(tmp_path):
    empty = tmp_path / "empty.html"
    write_review(empty, ReviewPage("check", "nothing", "m"))
    _, dom = chromium(empty, tmp_path, shot=False)
    assert re.search(r'<html[^>]*data-meshcol-ready="0"', dom) and "data-error=" not in dom
    box = trimesh.creation.box((1.0, 1.0, 1.0))
    far = ReviewPage("inspect", "far away", "m")
    pose = np.eye(4)
    pose[:3, 3] = [1e12, -3e11, 5e9]
    far.add_mesh(box.vertices, box.faces, pose, body=far.add_body("far"))
    path = tmp_path / "far.html"
    write_review(path, far)
    pixels, dom = chromium(path, tmp_path)
    assert_drew(pixels, dom)


@browser
@pytest.mark.slow
def test_browser_error_marker_catches_a_script_error(tmp_path):
    """The no-error check can fail: a page whose script throws is caught by it."""
    page = tmp_path / "broken.html"
    write_review(page, ReviewPage("check", "broken"))
    text = page.read_text().replace("</body>", '<script>throw new Error("boom")</script></body>')
    page.write_text(text)
    _, dom = chromium(page, tmp_path, shot=False)
    with pytest.raises(AssertionError, match="boom"):
        assert_no_error(dom)


@pytest.mark.slow
def test_decompose_command_writes_its_page(tmp_path):
    trimesh.creation.box((2.0, 1.0, 1.0)).export(tmp_path / "block.obj")
    page = tmp_path / "block.html"
    result = run(
        [
            "decompose",
            str(tmp_path / "block.obj"),
            "--out-dir",
            str(tmp_path / "parts"),
            "--no-cache",
            "--report",
            str(tmp_path / "d.json"),
            "--html",
            str(page),
        ]
    )
    assert result.exit_code == 0, result.output
    text = page.read_text()
    assert '"title":"block.obj"' in text and '"columns":["body","part","vertices"' in text
    assert "block.html" not in os.listdir(tmp_path / "parts")


@pytest.mark.slow  # 1-2 s: the fast lane (make test-fast) stays under 40 s
def test_hull_page_under_a_target_names_it_not_an_exact_hull(samples):
    # Issue 29 item 19: the page said "max vertices: exact hull" for hulls a target shaped.
    from meshcol.analysis.hull import hull
    from meshcol.analysis.review import hull_page
    from meshcol.io.targets import load_target

    bowl = str(samples / "bowl" / "bowl.obj")
    info = dict(hull_page(hull([bowl], target=load_target("physx-gpu")), [bowl]).info)
    assert info["target"].startswith("physx-gpu (") and "max_hull_vertices 64" in info["target"]
    assert "max vertices" not in info
    assert dict(hull_page(hull([bowl]), [bowl]).info)["max vertices"] == "exact hull"
    assert dict(hull_page(hull([bowl], max_vertices=32), [bowl]).info)["max vertices"] == "32"


@browser
@pytest.mark.slow
def test_browser_inspect_shows_a_chosen_body_alone(tmp_path):
    # Issue 29 item 19: choosing a body on the inspect page left the others drawn, so a body
    # inside another stayed hidden behind it.
    trimesh.creation.box((4.0, 4.0, 4.0)).export(tmp_path / "outer.obj")
    trimesh.creation.box((1.0, 1.0, 1.0)).export(tmp_path / "inner.obj")
    page = tmp_path / "inspect.html"
    inputs = [str(tmp_path / "outer.obj"), str(tmp_path / "inner.obj")]
    assert run(["inspect", *inputs, "--html", str(page)]).exit_code == 0
    chosen, dom = chromium(page, tmp_path, "#pair=1")
    view = assert_drew(chosen, dom)
    assert magenta(view) > 0.005, "the chosen inner body is hidden by the outer one"
    assert 'title="inner"' in dom  # every cell whole in its title, cut or not


def test_long_names_are_cut_with_an_ellipsis_not_the_table():
    # Issue 29 item 19: long link names pushed the check page's numbers out of view.
    style = (Path(review.__file__).parent / "review_assets" / "page.css").read_text()
    rule = re.search(r"#rows td \{([^}]*)\}", style)
    assert rule and "text-overflow: ellipsis" in rule[1] and "max-width" in rule[1]
