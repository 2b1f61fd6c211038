"""The configuration file: found as ruff finds its own, checked against its schema with the
key and line named, resolved per file with the origin of every setting."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from meshcol.io.config import (
    SCHEMA_PATH,
    ConfigError,
    find_config,
    glob_regex,
    line_of,
    load_config,
    parse_override,
    resolve,
    setting_keys,
)

ROOT = Path(__file__).resolve().parents[2]


def write(path: Path, text: str) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    return path


GOOD = """exclude = ["build/**"]
jobs = 2

[[assets]]
glob = "props/**/*.obj"
shape = "hull"
inspect = { fail-on = ["not-watertight"] }

[[assets]]
glob = ["props/hard/*.obj"]
target = "physx-gpu"

[assets.hull]
max-vertices = 32

[[scenes]]
path = "level.json"
check = { clearance = 0.01 }
ignore = [{ pair = "a:b", reason = "hinged" }]
"""


def test_closest_config_wins_and_meshcol_toml_before_pyproject(tmp_path):
    write(tmp_path / "pyproject.toml", "[tool.meshcol]\njobs = 3\n")
    write(tmp_path / "a" / "pyproject.toml", "[project]\nname = 'x'\n")  # no [tool.meshcol]
    write(tmp_path / "a" / "b" / "meshcol.toml", "jobs = 1\n")
    write(tmp_path / "a" / "b" / "pyproject.toml", "[tool.meshcol]\njobs = 4\n")
    (tmp_path / "a" / "b" / "c").mkdir()
    assert find_config(tmp_path / "a" / "b" / "c") == tmp_path / "a" / "b" / "meshcol.toml"
    assert find_config(tmp_path / "a") == tmp_path / "pyproject.toml"
    config = load_config(tmp_path / "pyproject.toml")
    assert config.get("jobs") == 3
    assert config.origin("jobs") == "pyproject.toml:2"


def test_resolution_later_section_wins_and_every_origin(tmp_path):
    config = load_config(write(tmp_path / "meshcol.toml", GOOD))
    [hard] = resolve(config, "props/hard/crate.obj", {"shape": ("mesh", "flag --shape")})
    assert hard.kind == "assets" and hard.commands == ("inspect", "hull")
    assert hard.values["shape"] == "mesh" and hard.origins["shape"] == "flag --shape"
    assert hard.values["target"] == "physx-gpu" and hard.origins["target"] == "meshcol.toml:11"
    assert hard.values["hull.max-vertices"] == 32
    assert hard.origins["hull.max-vertices"] == "meshcol.toml:14"
    assert hard.values["inspect.fail-on"] == ["not-watertight"]
    assert hard.origins["inspect.fail-on"] == "meshcol.toml:7"
    assert hard.values["inspect.volume-ratio"] == 2.0
    assert hard.origins["inspect.volume-ratio"] == "default"
    [soft] = resolve(config, "props/soft/x/y.obj")
    assert soft.commands == ("inspect",) and soft.values["target"] is None
    [scene] = resolve(config, "level.json")
    assert scene.kind == "scenes" and scene.commands == ("check",)
    assert scene.values["check.clearance"] == 0.01
    assert scene.values["check.fail-on"] == "penetration"  # the schema's default
    assert scene.origins["ignore"] == "meshcol.toml:19"
    assert resolve(config, "props/readme.txt") == []


@pytest.mark.parametrize(
    ("text", "line", "words"),
    [
        ("jobs = 0\n", 1, "jobs: must be >= 1, got 0"),
        ('[[assets]]\nglob = "*.obj"\nfail_on = ["x"]\n', 3, "assets[0].fail_on: unknown key"),
        (
            '[[assets]]\nglob = "*.obj"\n\n[[assets]]\nglob = "b/*.obj"\n'
            "inspect = { fail_on = [] }\n",
            6,
            "assets[1].inspect.fail_on: unknown key (did you mean 'fail-on'?)",
        ),
        ('[[scenes]]\npath = "l.json"\nshape = "cube"\n', 3, "scenes[0].shape: must be one of"),
        (
            '[[scenes]]\npath = "l.json"\nignore = [{ pair = "a:b" }]\n',
            3,
            "scenes[0].ignore[0]: missing the required key 'reason'",
        ),
        ('[[assets]]\nshape = "hull"\n', 1, "assets[0]: missing the required key 'glob'"),
        ('[[assets]]\nglob = "*"\n[assets.check]\ntolerance = "x"\n', 4, "must be a number"),
    ],
)
def test_a_bad_key_is_named_with_its_line(tmp_path, text, line, words):
    path = write(tmp_path / "meshcol.toml", text)
    with pytest.raises(ConfigError) as caught:
        load_config(path)
    assert str(caught.value).startswith(f"{path}:{line}: "), caught.value
    assert words in str(caught.value)


def test_not_toml_names_tomllib_line(tmp_path):
    path = write(tmp_path / "meshcol.toml", "jobs = \n")
    with pytest.raises(ConfigError, match=r"not TOML: .*line 1"):
        load_config(path)


def test_line_of_finds_keys_in_headers_inline_tables_and_dotted_names():
    text = '[tool.meshcol]\n[[tool.meshcol.assets]]\nglob = "a"\n[[tool.meshcol.assets]]\n'
    text += 'glob = "b"\ninspect.fail-on = []\n[tool.meshcol.assets.hull]\nmax-vertices = 4\n'
    assert line_of(text, ("tool", "meshcol", "assets", 1, "glob")) == 5
    assert line_of(text, ("tool", "meshcol", "assets", 1, "inspect", "fail-on")) == 6
    assert line_of(text, ("tool", "meshcol", "assets", 1, "hull", "max-vertices")) == 8
    assert line_of(text, ("tool", "meshcol", "assets", 0, "glob")) == 3


def test_globs():
    assert glob_regex("props/**/*.obj").fullmatch("props/a.obj")
    assert glob_regex("props/**/*.obj").fullmatch("props/x/y/a.obj")
    assert not glob_regex("props/*.obj").fullmatch("props/x/a.obj")
    assert glob_regex("a/[bc]?.stl").fullmatch("a/cx.stl")


def test_overrides_are_checked_against_the_schema():
    assert parse_override("shape=decomposed") == ("shape", "decomposed")
    assert parse_override('inspect.fail-on=["all"]') == ("inspect.fail-on", ["all"])
    assert parse_override("check.clearance=0.5") == ("check.clearance", 0.5)
    with pytest.raises(ValueError, match="KEY one of"):
        parse_override("colour=red")
    with pytest.raises(ValueError, match=r"^check.clearance: must be >= 0"):
        parse_override("check.clearance=-1")


def test_schema_is_valid_and_agrees_with_the_commands():
    jsonschema = pytest.importorskip("jsonschema", reason="the oracle needs jsonschema")
    import tomllib

    from meshcol.analysis.check_policy import FAIL_ON
    from meshcol.analysis.fit import DEFAULT_VOLUME_TOLERANCE, SHAPE_CHOICES
    from meshcol.analysis.physics import PhysicsOptions
    from meshcol.vocabulary import COLLIDER_KINDS

    schema = json.loads(SCHEMA_PATH.read_text())
    jsonschema.Draft202012Validator.check_schema(schema)
    jsonschema.validate(tomllib.loads(GOOD), schema)
    keys = setting_keys()
    assert tuple(keys["shape"]["enum"]) == COLLIDER_KINDS
    assert tuple(keys["fit.shape"]["enum"]) == SHAPE_CHOICES
    assert keys["fit.volume-tolerance"]["default"] == DEFAULT_VOLUME_TOLERANCE
    physics = PhysicsOptions()
    for key in ("volume-ratio", "com-offset", "inertia-ratio", "min-relative-volume", "min-volume"):
        assert keys[f"inspect.{key}"]["default"] == getattr(physics, key.replace("-", "_"))
    assert keys["check.fail-on"]["default"] in FAIL_ON


def test_every_key_is_documented():
    page = (ROOT / "docs" / "config.md").read_text()
    schema = json.loads(SCHEMA_PATH.read_text())
    documented = set(re.findall(r"^\| `([a-z.\-]+)` \|", page, re.M))
    top = set(schema["properties"])
    assert top | {"glob", "path"} | set(setting_keys()) <= documented


def test_resolve_all_gives_each_file_what_resolve_gives_it(tmp_path):
    """The plan's fast path (one pattern per section and one for them all, one resolution
    per set of sections) against ``resolve`` file by file, with overlapping sections, a
    section's own ``exclude``, files no section matches, a config-level exclude and odd
    spellings of a path."""
    from meshcol.io.config import resolve_all

    text = GOOD.replace(
        'glob = ["props/hard/*.obj"]',
        'glob = ["props/hard/*.obj", "extra/*.stl"]\nexclude = ["props/hard/skip*.obj"]',
    )
    config = load_config(write(tmp_path / "meshcol.toml", text))
    names = [
        "props/a.obj", "props/hard/b.obj", "props/hard/skip1.obj", "props/x/y/c.obj",
        "extra/d.stl", "extra/e.obj", "level.json", "readme.md", "build/props/f.obj",
        "./props/a.obj", "props//hard/b.obj",
    ]  # fmt: skip
    for name in names:
        write(tmp_path / name.replace("//", "/"), "x")
    overrides = {"shape": ("convex", "flag --shape")}
    fast = dict(resolve_all(config, names, overrides))
    for name in names:
        slow = resolve(config, name, overrides, shared=True)
        assert fast.get(name, []) == slow, name
        assert all(a is b for a, b in zip(fast.get(name, []), slow))  # the shared objects
    assert "readme.md" not in fast and "props/hard/skip1.obj" in fast
    assert [s.index for s in config.sections if s.matches("props/hard/skip1.obj")] == [0]
    listed = list(config.files())
    assert "build/props/f.obj" not in listed and "props/hard/b.obj" in listed
