"""The rule registry and every rule in it: each rule has a case that fires and a near miss
that does not (a rule registered without a case here fails ``test_every_rule_has_a_case``),
ids are stable and unique, and every id the package can emit is registered."""

from __future__ import annotations

import json
import re
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
import trimesh
from click.testing import CliRunner

from meshcol.analysis.check import check
from meshcol.analysis.check_policy import PAIR_RULES
from meshcol.analysis.health import HEALTH_IDS
from meshcol.analysis.inspect import PhysicsOptions, inspect
from meshcol.analysis.rules import (
    RULES,
    TARGET_RULES,
    UnknownRuleError,
    command_rules,
    get_rule,
    select_rules,
)
from meshcol.cli import main
from meshcol.collision import limits
from meshcol.collision.limits import measure_parts
from meshcol.io.targets import load_target

PACKAGE = Path(__file__).resolve().parents[2] / "meshcol"


def run(*args: object):
    return CliRunner().invoke(main, [str(a) for a in args])


# -- meshes ---------------------------------------------------------------------------------


def box(size=(1.0, 1.0, 1.0), at=(0.0, 0.0, 0.0)) -> tuple[np.ndarray, np.ndarray]:
    mesh = trimesh.creation.box(extents=size)
    mesh.apply_translation(at)
    return np.asarray(mesh.vertices), np.asarray(mesh.faces)


def joined(*meshes: tuple[np.ndarray, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    vertices, faces, base = [], [], 0
    for v, f in meshes:
        vertices.append(v)
        faces.append(f + base)
        base += len(v)
    return np.vstack(vertices), np.vstack(faces)


def write_obj(path: Path, objects: dict[str, tuple[np.ndarray, np.ndarray]]) -> Path:
    """An OBJ file of named objects (each ``o NAME`` is a body)."""
    lines, base = [], 1
    for name, (v, f) in objects.items():
        lines.append(f"o {name}")
        lines += [f"v {float(x)!r} {float(y)!r} {float(z)!r}" for x, y, z in v]
        lines += ["f " + " ".join(str(base + int(i)) for i in face) for face in f]
        base += len(v)
    path.write_text("\n".join(lines) + "\n")
    return path


def fired(path: Path, **physics: object) -> set[str]:
    """Rule ids of inspect's findings on one file."""
    report = inspect([path], physics=PhysicsOptions(**physics))  # type: ignore[arg-type]
    return {f.rule for f in report.findings}


def physics_row(path: Path, **physics: object) -> dict:
    report = inspect([path], physics=PhysicsOptions(**physics))  # type: ignore[arg-type]
    (row,) = report.physics
    return row


def profile(tmp_path: Path, limits_: dict[str, float], name: str = "edge") -> object:
    """A user target profile of just these limits."""
    body = "\n".join(f"{key} = {value!r}" for key, value in limits_.items())
    path = tmp_path / f"{name}.toml"
    path.write_text(f'name = "{name}"\nunits = "m"\n\n[limits]\n{body}\n')
    return load_target(path)


# -- the registry ---------------------------------------------------------------------------


def test_ids_and_names_are_unique_and_well_formed() -> None:
    ids = [rule.id for rule in RULES]
    names = [rule.name for rule in RULES]
    assert len(set(ids)) == len(ids) and len(set(names)) == len(names)
    assert ids == sorted(ids)
    for rule in RULES:
        assert re.fullmatch(r"MC[1-5]\d\d", rule.id), rule.id
        assert re.fullmatch(r"[a-z]+(-[a-z]+)*", rule.name), rule.name
        assert rule.severity in ("error", "warning", "info")
        assert rule.summary and rule.measured and rule.fix and rule.commands
        assert get_rule(rule.id) is rule and get_rule(rule.name) is rule


def test_the_limits_module_uses_the_registry_ids() -> None:
    """collision/limits names its rules; they are the registry's, limit key for limit key."""
    keyed = {rule.limit_key: (rule.id, rule.name) for rule in RULES if rule.limit_key}
    assert keyed == limits.RULES
    assert tuple(rule_id for rule_id, _ in limits.RULES.values()) == TARGET_RULES


def test_pair_statuses_and_health_findings_are_registered() -> None:
    for rule_id in (*PAIR_RULES.values(), *HEALTH_IDS.values()):
        get_rule(rule_id)
    assert {get_rule(i).name for i in HEALTH_IDS.values()} == set(HEALTH_IDS)


def test_every_id_in_the_package_is_registered() -> None:
    """A scan of the source: any ``MCnnn`` literal names a registered rule."""
    registered = {rule.id for rule in RULES}
    found: dict[str, str] = {}
    for path in PACKAGE.rglob("*.py"):
        for match in re.finditer(r"[\"']MC(\d{3})[\"']", path.read_text()):
            found.setdefault(f"MC{match.group(1)}", str(path))
    assert found, "the scan found nothing: the pattern is wrong"
    unknown = {rule: where for rule, where in found.items() if rule not in registered}
    assert not unknown


def test_select_rules_takes_ids_names_and_all() -> None:
    assert select_rules("MC401,not-watertight, MC404", "inspect") == ("MC401", "MC404")
    assert select_rules("all", "check") == tuple(r.id for r in command_rules("check"))
    with pytest.raises(UnknownRuleError, match="unknown rule 'MC999'"):
        select_rules("MC999", "inspect")
    with pytest.raises(UnknownRuleError, match="for inspect"):
        select_rules("MC504", "inspect")  # a rule of check only


# -- one case that fires and one near miss per rule -------------------------------------------

#: rule id -> (tmp_path -> (fires, misses)): whether the rule fired on its case and on its
#: near miss.
CASES: dict[str, Callable[[Path], tuple[bool, bool]]] = {}


def case(*rule_ids: str):
    def register(func):
        for rule_id in rule_ids:
            CASES[rule_id] = lambda tmp_path, rule_id=rule_id: func(tmp_path, rule_id)
        return func

    return register


_LIMIT_MEASURE = {
    "max_hull_vertices": "vertices",
    "max_hull_polygons": "polygons",
    "max_hull_triangles": "triangles",
    "max_faces_per_vertex": "max_faces_per_vertex",
    "max_oblong_ratio": "oblong_ratio",
    "min_thickness": "thickness",
    "min_volume": "volume",
}


@case(*(rule.id for rule in RULES if rule.limit_key and rule.limit_key != "max_hulls"))
def _part_limit(tmp_path: Path, rule_id: str) -> tuple[bool, bool]:
    """A limit set just past the measured value fires; set at the value, it does not."""
    key = get_rule(rule_id).limit_key
    assert key is not None
    cone = trimesh.creation.cone(radius=0.3, height=2.0, sections=12)  # 12 faces at its apex
    path = write_obj(tmp_path / "part.obj", {"part": (cone.vertices, cone.faces)})
    measured = float(getattr(measure_parts([(cone.vertices, cone.faces)]), _LIMIT_MEASURE[key])[0])
    at: float | int = measured
    if key.startswith("min_"):
        past: float | int = measured * 1.01
    elif key == "max_oblong_ratio":
        past = measured * 0.99
    else:  # counts
        at, past = int(measured), int(measured) - 1
    fires = rule_id in fired(path, target=profile(tmp_path, {key: past}, "past"))
    misses = rule_id in fired(path, target=profile(tmp_path, {key: at}, "at"))
    return fires, misses


@case("MC106")
def _hull_count(tmp_path: Path, rule_id: str) -> tuple[bool, bool]:
    """Two UCX_ parts for one body (its decomposed collider): over max_hulls 1, within 2."""
    path = write_obj(
        tmp_path / "two.obj",
        {
            "crate": box((2, 1, 1)),
            "UCX_crate_01": box((1, 1, 1), (-0.5, 0, 0)),
            "UCX_crate_02": box((1, 1, 1), (0.5, 0, 0)),
        },
    )
    one, two = (profile(tmp_path, {"max_hulls": n}, f"n{n}") for n in (1, 2))
    fires = rule_id in fired(path, shape="decomposed", target=one)
    misses = rule_id in fired(path, shape="decomposed", target=two)
    return fires, misses


@case("MC202")
def _flat(tmp_path: Path, rule_id: str) -> tuple[bool, bool]:
    flat = write_obj(tmp_path / "flat.obj", {"sheet": box((1, 1, 1e-9))})
    thin = write_obj(tmp_path / "thin.obj", {"slab": box((1, 1, 0.01))})
    return rule_id in fired(flat), rule_id in fired(thin)


@case("MC203")
def _tiny(tmp_path: Path, rule_id: str) -> tuple[bool, bool]:
    path = write_obj(tmp_path / "grain.obj", {"grain": box((1e-5, 1e-5, 1e-5))})
    volume = physics_row(path)["collider_mass"]["volume"]  # 1e-15
    return (
        rule_id in fired(path, min_volume=volume * 1.01),
        rule_id in fired(path, min_volume=volume * 0.99),
    )


@case("MC204")
def _inverted_collider(tmp_path: Path, rule_id: str) -> tuple[bool, bool]:
    v, f = box()
    inside_out = write_obj(tmp_path / "in.obj", {"crate": (v, f[:, ::-1])})
    outward = write_obj(tmp_path / "out.obj", {"crate": (v, f)})
    return rule_id in fired(inside_out, shape="mesh"), rule_id in fired(outward, shape="mesh")


#: Two cubes of different sizes apart, one mesh: its hull is much more than the mesh, and
#: its centre of mass and moments differ.
def _dumbbell(tmp_path: Path) -> Path:
    return write_obj(
        tmp_path / "dumbbell.obj", {"dumbbell": joined(box(), box((0.5,) * 3, (4, 0, 0)))}
    )


@case("MC205", "MC206", "MC207")
def _collider_against_visual(tmp_path: Path, rule_id: str) -> tuple[bool, bool]:
    """Each tolerance just under the measured value fires, just over it does not."""
    path = _dumbbell(tmp_path)
    row = physics_row(path)
    option, measured = {
        "MC205": ("volume_ratio", row["volume_ratio"]),
        "MC206": ("com_offset", row["center_of_mass_offset"]),
        "MC207": ("inertia_ratio", row["inertia_ratio"]),
    }[rule_id]
    assert measured is not None and measured > 1.0 if option != "com_offset" else measured > 0
    return (
        rule_id in fired(path, **{option: measured * 0.99}),
        rule_id in fired(path, **{option: measured * 1.01}),
    )


@case("MC301")
def _missing_collider(tmp_path: Path, rule_id: str) -> tuple[bool, bool]:
    """In a file with UCX_ colliders, a body without one; the near miss gives it one."""
    crate = {"crate": box(), "UCX_crate_01": box((1.01,) * 3)}
    barrel = {"barrel": box(at=(3, 0, 0))}
    without = write_obj(tmp_path / "without.obj", crate | barrel)
    with_ = write_obj(
        tmp_path / "with.obj", crate | barrel | {"UCX_barrel_01": box((1.01,) * 3, (3, 0, 0))}
    )
    return rule_id in fired(without), rule_id in fired(with_)


@case("MC302")
def _orphan_ucx(tmp_path: Path, rule_id: str) -> tuple[bool, bool]:
    orphan = write_obj(tmp_path / "orphan.obj", {"crate": box(), "UCX_ghost_01": box((1.01,) * 3)})
    owned = write_obj(tmp_path / "owned.obj", {"crate": box(), "UCX_crate_01": box((1.01,) * 3)})
    return rule_id in fired(orphan), rule_id in fired(owned)


@case("MC303")
def _non_convex_ucx(tmp_path: Path, rule_id: str) -> tuple[bool, bool]:
    two = joined(box((1, 1, 1), (-1, 0, 0)), box((1, 1, 1), (1, 0, 0)))
    concave = write_obj(tmp_path / "concave.obj", {"crate": box((3, 1, 1)), "UCX_crate_01": two})
    convex = write_obj(
        tmp_path / "convex.obj", {"crate": box((3, 1, 1)), "UCX_crate_01": box((3, 1, 1))}
    )
    return rule_id in fired(concave), rule_id in fired(convex)


def _health(broken: Callable[[], tuple[np.ndarray, np.ndarray]]):
    def check_rule(tmp_path: Path, rule_id: str) -> tuple[bool, bool]:
        bad = write_obj(tmp_path / "bad.obj", {"mesh": broken()})
        good = write_obj(tmp_path / "good.obj", {"mesh": box()})
        return rule_id in fired(bad), rule_id in fired(good)

    return check_rule


def _open() -> tuple[np.ndarray, np.ndarray]:
    v, f = box()
    return v, f[:-1]


def _one_face_flipped() -> tuple[np.ndarray, np.ndarray]:
    v, f = box()
    f = f.copy()
    f[0] = f[0, ::-1]
    return v, f


def _degenerate() -> tuple[np.ndarray, np.ndarray]:
    v, f = box()
    return v, np.vstack([f, [[0, 0, 1]]])


def _non_manifold() -> tuple[np.ndarray, np.ndarray]:
    v, f = box()
    fin = np.vstack([v, [[0.0, 0.0, 3.0]]])
    return fin, np.vstack([f, [list(f[0][:2]) + [len(v)]]])


def _duplicate() -> tuple[np.ndarray, np.ndarray]:
    v, f = box()
    return v, np.vstack([f, f[:1]])


HEALTH_CASES = {
    "MC401": _open,
    "MC402": lambda: joined(box(), box(at=(0.5, 0.5, 0.5))),
    "MC403": _one_face_flipped,
    "MC404": lambda: (box()[0], box()[1][:, ::-1]),
    "MC405": _degenerate,
    "MC406": _non_manifold,
    "MC407": _duplicate,
    "MC408": lambda: joined(box(), box(at=(3, 0, 0))),
    "MC409": lambda: box((900.0, 800.0, 700.0)),  # a crate in millimetres
}
for _rule, _make in HEALTH_CASES.items():
    CASES[_rule] = lambda tmp_path, rule_id=_rule, make=_make: _health(make)(tmp_path, rule_id)


def _pair(rule_id: str, tmp_path: Path, other_at: tuple, other_size: tuple, **options) -> bool:
    """Whether a pair of boxes fails a check that fails on ``rule_id`` alone."""
    a = write_obj(tmp_path / "a.obj", {"a": box((1, 1, 1))})
    b = write_obj(tmp_path / "b.obj", {"b": box(other_size, other_at)})
    report = check([a, b], fail_on=rule_id, **options)
    return report.exit_code == 1


@case("MC505")
def _undecided(tmp_path: Path, rule_id: str) -> tuple[bool, bool]:
    """A box across a Moebius strip under ``--shape mesh`` is undecided (neither contact nor
    penetration is claimed); the same box clear of the strip's hull is not."""
    from dirty_meshes import moebius

    strip = write_obj(tmp_path / "strip.obj", {"strip": moebius()})

    def fails(at: tuple) -> bool:
        b = write_obj(tmp_path / "b.obj", {"b": box((0.2, 0.2, 0.2), at)})
        return check([strip, b], fail_on=rule_id, collider="mesh", clearance=0.5).exit_code == 1

    return fails((1.0, 0.0, 0.0)), fails((1.6, 0.0, 0.0))


@case("MC506")
def _no_collision_geometry(tmp_path: Path, rule_id: str) -> tuple[bool, bool]:
    """A robot whose one link has a visual box and no collision element fails a check that
    fails on MC506 (zero pairs); the same link with a collision box does not."""
    shape = "<geometry><box size='1 1 1'/></geometry>"

    def fails(element: str) -> bool:
        robot = tmp_path / f"{element}.urdf"
        robot.write_text(
            f"<robot name='r'><link name='a'><{element}>{shape}</{element}></link></robot>"
        )
        return check(robot, fail_on=rule_id).exit_code == 1

    return fails("visual"), fails("collision")


@case("MC501", "MC502", "MC503", "MC504")
def _pairs(tmp_path: Path, rule_id: str) -> tuple[bool, bool]:
    """Each pair status fails the run when its rule is listed; the next status does not."""
    unit = (1.0, 1.0, 1.0)
    cases = {
        "MC501": (((0.5, 0, 0), unit), ((1.0, 0, 0), unit)),  # penetrating, then contact
        "MC502": (((0, 0, 0), (0.2,) * 3), ((0.5, 0, 0), unit)),  # contained, penetrating
        "MC503": (((1.0, 0, 0), unit), ((1.05, 0, 0), unit)),  # contact, then clearance
        "MC504": (((1.05, 0, 0), unit), ((1.2, 0, 0), unit)),  # clearance, then separated
    }
    (at, size), (near_at, near_size) = cases[rule_id]
    return (
        _pair(rule_id, tmp_path, at, size, clearance=0.1),
        _pair(rule_id, tmp_path, near_at, near_size, clearance=0.1),
    )


def test_every_rule_has_a_case() -> None:
    assert set(CASES) == {rule.id for rule in RULES}


@pytest.mark.parametrize("rule_id", sorted(CASES))
def test_rule_fires_on_its_case_and_not_on_the_near_miss(tmp_path: Path, rule_id: str) -> None:
    fires, misses = CASES[rule_id](tmp_path)
    assert fires, f"{rule_id} did not fire on its case"
    assert not misses, f"{rule_id} fired on its near miss"


# -- findings in reports and on the command line ---------------------------------------------


def test_inspect_finding_names_body_part_rule_measured_and_limit(tmp_path: Path) -> None:
    path = _dumbbell(tmp_path)
    result = run("inspect", path, "--fail-on", "MC205")
    assert result.exit_code == 1
    report = json.loads(result.stdout)
    (found,) = [f for f in report["findings"] if f["rule"] == "MC205"]
    assert found["body"] == "dumbbell" and found["part"] is None
    assert found["name"] == "collider-volume-mismatch" and found["failed"] is True
    assert found["measured"] > found["limit"] == 2.0
    assert f"{path}: body 'dumbbell': MC205 collider-volume-mismatch:" in result.stderr


def test_inspect_target_fails_the_run_by_default(tmp_path: Path) -> None:
    sphere = trimesh.creation.icosphere(subdivisions=3)
    path = write_obj(tmp_path / "ball.obj", {"ball": (sphere.vertices, sphere.faces)})
    result = run("inspect", path, "--target", "physx-gpu")
    assert result.exit_code == 1, result.output
    report = json.loads(result.stdout)
    assert report["settings"]["target"] == "physx-gpu"
    (found,) = [f for f in report["findings"] if f["rule"] == "MC101"]
    assert found["measured"] == 642 and found["limit"] == 64 and found["failed"]
    # --fail-on other rules: reported, not failing
    assert run("inspect", path, "--target", "physx-gpu", "--fail-on", "MC401").exit_code == 0


def test_check_target_findings_and_fail_on_levels(tmp_path: Path) -> None:
    sphere = trimesh.creation.uv_sphere(count=[10, 10])
    ball = write_obj(tmp_path / "ball.obj", {"ball": (sphere.vertices, sphere.faces)})
    crate = write_obj(tmp_path / "crate.obj", {"crate": box(at=(5, 0, 0))})
    result = run("check", ball, crate, "--target", "physx-gpu")
    assert result.exit_code == 1
    report = json.loads(result.stdout)
    # past both of physx-gpu's 64 vertices and polygons, within physx's 255
    assert [(f["body"], f["rule"]) for f in report["findings"]] == [
        ("ball", "MC101"),
        ("ball", "MC103"),
    ]
    assert report["summary"]["failed_findings"] == 2 and report["summary"]["passed"] is False
    assert "meshcol: fail: body 'ball': MC101 hull-vertices-over-limit" in result.stderr
    assert run("check", ball, crate, "--target", "physx-gpu", "--fail-on", "none").exit_code == 0
    assert run("check", ball, crate, "--target", "physx").exit_code == 0  # 255 vertices


def test_check_fail_on_unknown_rule_lists_levels_and_rules(tmp_path: Path) -> None:
    crate = write_obj(tmp_path / "crate.obj", {"crate": box()})
    result = run("check", crate, "--fail-on", "MC401")
    assert result.exit_code == 2
    assert "unknown rule 'MC401'" in result.stderr and "penetration" in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1


def test_unknown_or_malformed_target_exits_2_in_one_line(tmp_path: Path) -> None:
    crate = write_obj(tmp_path / "crate.obj", {"crate": box()})
    for command in ("inspect", "check"):
        result = run(command, crate, "--target", "physx-cpu")
        assert result.exit_code == 2 and len(result.stderr.strip().splitlines()) == 1
        assert "physx-cpu" in result.stderr
    bad = tmp_path / "bad.toml"
    bad.write_text('name = "bad"\n[limits]\nmax_hull_vertices = "many"\n')
    result = run("inspect", crate, "--target", bad)
    assert result.exit_code == 2 and "bad.toml" in result.stderr


def test_rules_command_lists_and_shows_one() -> None:
    listing = run("rules")
    assert listing.exit_code == 0
    for rule in RULES:
        assert rule.id in listing.output and rule.name in listing.output
    one = run("rules", "MC101")
    assert one.exit_code == 0 and "hull-vertices-over-limit" in one.output
    assert "MC102" not in one.output
    data = json.loads(run("rules", "--format", "json").output)
    assert [r["id"] for r in data["rules"]] == [rule.id for rule in RULES]
    unknown = run("rules", "MC999")
    assert unknown.exit_code == 2 and "MC999" in unknown.stderr
    rows = run("rules", "--format", "csv").output.splitlines()
    assert rows[0].startswith("id,") and len(rows) == len(RULES) + 1
    # The registry has no findings for CI annotations: refused, never JSON in their place.
    for fmt in ("junit", "github"):
        refused = run("rules", "--format", fmt)
        assert refused.exit_code == 2 and "is not one of 'json', 'csv'" in refused.stderr


@pytest.mark.parametrize("name", ["7_8ths_cube.stl", "angle_block.STL", "featuretype.STL"])
def test_physics_rows_on_the_corpus_match_independent_oracles(corpus: Path, name: str) -> None:
    """The hull collider's mass properties are scipy's hull volume and trimesh's centre of mass
    of that hull; the visual mesh's are trimesh's; the hull holds the mesh (ratio >= 1)."""
    from scipy.spatial import ConvexHull

    path = corpus / "trimesh-models" / name
    mesh = trimesh.load(path, force="mesh")
    row = physics_row(path)
    hull = ConvexHull(mesh.vertices)
    hull_mesh = trimesh.Trimesh(mesh.vertices, hull.simplices).convex_hull
    collider, visual = row["collider_mass"], row["visual_mass"]
    assert collider["volume"] == pytest.approx(hull.volume, rel=1e-9)
    np.testing.assert_allclose(collider["center_of_mass"], hull_mesh.center_mass, atol=1e-9)
    assert visual["volume"] == pytest.approx(mesh.volume, rel=1e-9)
    np.testing.assert_allclose(visual["center_of_mass"], mesh.center_mass, atol=1e-9)
    np.testing.assert_allclose(
        visual["inertia"], mesh.moment_inertia, rtol=1e-7, atol=1e-9 * abs(mesh.volume)
    )
    assert row["comparison"] == "solid" and row["volume_ratio"] >= 1.0
    assert row["volume_ratio"] == pytest.approx(hull.volume / mesh.volume, rel=1e-9)


def test_docs_rules_page_is_current() -> None:
    """docs/rules.md is generated from the registry: regenerate it when a rule changes."""
    from meshcol.analysis.rules import rules_report

    page = PACKAGE.parent / "docs" / "rules.md"
    assert page.read_text() == rules_report().to_markdown(), (
        'docs/rules.md is stale: python -c "from meshcol.analysis.rules import rules_report; '
        "open('docs/rules.md', 'w').write(rules_report().to_markdown())\""
    )
