"""Engine target profiles: the package's files, their citations, and user profiles validated."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from meshcol.cli import main
from meshcol.errors import TargetError
from meshcol.io.targets import (
    LIMIT_KEYS,
    TARGETS_DIR,
    list_targets,
    load_target,
    target_names,
    targets_markdown,
)

#: Every profile of the package: the files of meshcol/targets/ (adding one is adding a file).
PROFILES = tuple(target_names())
#: The engines issue 8 asked for (each must keep its profile).
ISSUE_ENGINES = ("physx", "physx-gpu", "unity", "unreal", "godot", "mujoco", "bullet", "isaac")
DOCS = Path(__file__).resolve().parents[2] / "docs" / "targets.md"


def run(*args: str):
    return CliRunner().invoke(main, [str(a) for a in args])


def test_every_engine_of_the_issue_has_a_profile() -> None:
    assert set(ISSUE_ENGINES) <= set(PROFILES)


def test_the_profiles_are_the_files_of_the_folder_named_as_their_files() -> None:
    files = sorted(path.stem for path in TARGETS_DIR.glob("*.toml"))
    assert tuple(files) == PROFILES
    assert sorted(t.name for t in list_targets()) == files
    assert all(load_target(name).name == name for name in files)


def test_the_docs_page_is_generated_from_the_profiles() -> None:
    assert DOCS.read_text(encoding="utf-8") == targets_markdown(), (
        'docs/targets.md is stale: python -c "from meshcol.io.targets import '
        "targets_markdown; print(targets_markdown(), end='')\" > docs/targets.md"
    )
    for name in PROFILES:
        assert f"| `{name}` |" in targets_markdown()


def test_the_jolt_profile_is_jolts_documented_hull_limit() -> None:
    jolt = load_target("jolt")
    assert jolt.limits == {"max_hull_vertices": 256}  # ConvexHullShape::cMaxPointsInHull
    assert jolt.units == "m"
    assert {s.kind for s in jolt.sources} == {"documented"}


@pytest.mark.parametrize("name", PROFILES)
def test_every_limit_cites_a_document_and_a_sentence(name: str) -> None:
    target = load_target(name)
    assert target.limits, f"{name} sets no limit"
    cited = {s.limit for s in target.sources}
    assert set(target.limits) <= cited, f"{name}: uncited limits {set(target.limits) - cited}"
    for source in target.sources:
        assert source.url.startswith("https://")
        assert len(source.quote) > 20
        assert source.kind in ("documented", "convention")
        # a convention says why the number was chosen
        assert source.kind == "documented" or source.note


def test_the_documented_numbers_are_the_documents() -> None:
    physx, gpu, unity = load_target("physx"), load_target("physx-gpu"), load_target("unity")
    assert physx.limits == {"max_hull_vertices": 255, "max_hull_polygons": 255}
    assert gpu.limits["max_hull_vertices"] == 64
    assert gpu.limits["max_hull_polygons"] == 64
    assert gpu.limits["max_faces_per_vertex"] == 32
    assert gpu.limits["max_oblong_ratio"] == 100
    assert unity.limits["max_hull_triangles"] == 255
    quote = next(s.quote for s in gpu.sources if s.limit == "max_faces_per_vertex")
    assert "limited to 64" in quote and "limited to 32" in quote
    unreal = load_target("unreal")
    assert unreal.units == "cm" and unreal.naming["convex_prefix"] == "UCX_"
    assert {"UBX_", "UCP_", "USP_"} <= set(unreal.naming.values())


def test_unreal_lengths_convert_to_centimetres() -> None:
    unreal, bullet = load_target("unreal"), load_target("bullet")
    assert unreal.length_scale() == pytest.approx(100.0)
    assert unreal.length_scale("m") == pytest.approx(1.0)  # a scene that says metres
    assert bullet.length_scale("mm") == pytest.approx(1000.0)
    assert bullet.length_scale("furlongs") == pytest.approx(1.0)  # unknown: the profile's


def test_a_user_profile_loads_like_a_package_one(tmp_path: Path) -> None:
    path = tmp_path / "my_engine.toml"
    path.write_text(
        'title = "Mine"\nunits = "mm"\n[limits]\nmax_hull_vertices = 24\nmin_thickness = 0.002\n'
    )
    target = load_target(str(path))
    assert target.name == "my_engine" and target.units == "mm"
    assert target.limits == {"max_hull_vertices": 24, "min_thickness": 0.002}
    assert target.limit("max_hulls") is None


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("colour = 1\n", "colour: unknown key"),
        ("[limits]\nmax_vertices = 12\n", "limits.max_vertices: unknown limit"),
        (
            "[limits]\nmax_hull_vertices = 12.5\n",
            "limits.max_hull_vertices: must be an integer, got 12.5",
        ),
        (
            '[limits]\nmax_hull_vertices = "64"\n',
            "limits.max_hull_vertices: must be an integer, got '64'",
        ),
        (
            "[limits]\nmax_hull_vertices = true\n",
            "limits.max_hull_vertices: must be an integer, got True",
        ),
        ("[limits]\nmax_hull_vertices = 3\n", "limits.max_hull_vertices: must be at least 4"),
        ("[limits]\nmax_hulls = -2\n", "limits.max_hulls: must be at least 1, got -2"),
        ("[limits]\nmin_thickness = -0.1\n", "limits.min_thickness: must be a finite number >= 0"),
        ("[limits]\nmin_volume = nan\n", "limits.min_volume: must be a finite number >= 0"),
        ("[limits]\nmax_oblong_ratio = 0.5\n", "limits.max_oblong_ratio: must be at least 1"),
        ('units = "parsec"\n', "units: unknown unit 'parsec'"),
        ("limits = 3\n", "limits: must be a table"),
        ('[naming]\nprefix = "X_"\n', "naming.prefix: unknown key"),
        (
            '[[sources]]\nlimit = "max_hulls"\nurl = "https://x"\nquote = "q"\n',
            "sources[0].kind: is required",
        ),
        (
            '[[sources]]\nlimit = "max_hulls"\nurl = "https://x"\nquote = "q"\nkind = "rumour"\n',
            "sources[0].kind: must be one of documented, convention",
        ),
        ("[limits\n", "invalid TOML"),
    ],
)
def test_a_bad_profile_names_the_file_and_the_key(tmp_path: Path, text: str, message: str) -> None:
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(TargetError) as error:
        load_target(str(path))
    assert str(error.value).startswith(f"{path}: {message}")


def test_an_unknown_name_lists_the_profiles() -> None:
    with pytest.raises(TargetError, match="unknown target 'havok': choose one of bullet, godot"):
        load_target("havok")


def test_targets_lists_every_profile_with_its_limits_as_json() -> None:
    result = run("targets", "--format", "json")
    assert result.exit_code == 0, result.output
    listed = {t["name"]: t for t in json.loads(result.output)["targets"]}
    assert set(listed) == set(PROFILES)
    assert listed["physx-gpu"]["limits"]["max_faces_per_vertex"] == 32
    assert all(set(t["limits"]) <= set(LIMIT_KEYS) for t in listed.values())
    assert all(t["sources"] for t in listed.values())


def test_targets_table_shows_limits_and_conventions() -> None:
    result = run("targets", "--format", "table", "physx-gpu", "unreal")
    assert result.exit_code == 0, result.output
    lines = result.output.splitlines()
    assert lines[0].split()[:3] == ["name", "units", "vertices"]
    gpu = next(line for line in lines if line.startswith("physx-gpu"))
    assert gpu.split()[:5] == ["physx-gpu", "m", "64", "64", "-"]
    assert "max_oblong_ratio" in gpu  # a convention, said so
    assert next(line for line in lines if line.startswith("unreal")).split()[1] == "cm"


def test_targets_and_rules_both_print_a_table_unless_asked_for_json() -> None:
    # One behaviour for the two listings (issue 29 item 18): a table on stdout, piped or not
    # (the CliRunner's stdout is not a terminal), and JSON only with --format json.
    for command in ("targets", "rules"):
        result = run(command)
        assert result.exit_code == 0, result.output
        assert result.output.split()[0] in ("name", "id"), (command, result.output[:80])
        listed = run(command, "--format", "json")
        assert listed.exit_code == 0 and isinstance(json.loads(listed.output), dict)


def test_rules_help_lists_only_the_formats_it_writes() -> None:
    from meshcol.analysis.rules import rules_report
    from meshcol.cli.rules import RULES_FORMATS
    from meshcol.io.formats import formats_for

    assert formats_for(type(rules_report(()))) == RULES_FORMATS
    help_text = " ".join(run("rules", "-h").output.split())
    assert "[json|csv]" in help_text
    for refused in ("junit", "github", "tap"):
        assert refused not in help_text
        assert run("rules", "--format", refused).exit_code == 2


def test_targets_with_a_bad_profile_exits_2_naming_file_and_key(tmp_path: Path) -> None:
    path = tmp_path / "engine.toml"
    path.write_text("[limits]\nmax_hulls = -1\n")
    result = run("targets", path)
    assert result.exit_code == 2
    assert (
        result.output == f"meshcol: error: {path}: limits.max_hulls: must be at least 1, got -1\n"
    )
