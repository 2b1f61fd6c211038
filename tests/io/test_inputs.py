"""meshcol.io.inputs: the one answer to "what kind of input is this"."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest
from package_source import sources, tree

from meshcol.io.inputs import input_kind, is_manifest, is_robot_file, is_whole_scene, root_tag
from meshcol.vocabulary import INPUT_KINDS


def write(folder: Path, name: str, text: str) -> Path:
    path = folder / name
    path.write_text(text)
    return path


@pytest.mark.parametrize(
    ("name", "text", "kind"),
    [
        ("scene.json", "{}", "manifest"),
        ("scene.JSON", "{}", "manifest"),
        ("scene.toml", "", "manifest"),
        ("arm.urdf", "", "robot"),
        ("arm.MJCF", "", "robot"),
        ("arm.xml", "<?xml version='1.0'?>\n<!-- x -->\n<mujoco model='a'/>", "robot"),
        ("arm.xml", "<!DOCTYPE robot>\n<robot name='x'/>", "robot"),
        ("other.xml", "<scene/>", "mesh"),
        ("cube.obj", "", "mesh"),
        ("cube.stl", "", "mesh"),
        ("noextension", "", "mesh"),
    ],
)
def test_input_kind_by_extension_and_root(tmp_path, name, text, kind):
    path = write(tmp_path, name, text)
    assert input_kind(path) == kind
    assert input_kind(str(path)) == kind
    assert kind in INPUT_KINDS
    assert is_manifest(path) == (kind == "manifest")
    assert is_robot_file(path) == (kind == "robot")


def test_missing_files_are_judged_by_extension(tmp_path):
    assert input_kind(tmp_path / "missing.json") == "manifest"
    assert input_kind(tmp_path / "missing.urdf") == "robot"
    assert input_kind(tmp_path / "missing.xml") == "mesh"  # no root element to read
    assert root_tag(tmp_path / "missing.xml") is None


def test_a_whole_scene_is_one_manifest_or_one_robot(tmp_path):
    assert is_whole_scene([tmp_path / "s.json"])
    assert is_whole_scene([tmp_path / "r.urdf"])
    assert not is_whole_scene([tmp_path / "a.obj"])
    assert not is_whole_scene([tmp_path / "s.json", tmp_path / "a.obj"])
    assert not is_whole_scene([])


def test_the_robot_loader_asks_the_same_function(tmp_path):
    from meshcol.io import robot

    xml = write(tmp_path, "c.xml", "<scene/>")
    assert robot.is_robot_file(xml) is False
    assert robot.is_robot_file(write(tmp_path, "m.xml", "<mujoco/>")) is True


def test_no_module_tests_manifest_extensions_itself():
    # Every "is this a manifest / a robot" question goes through meshcol.io.inputs.
    for path in sources():
        if path.name in ("vocabulary.py", "inputs.py"):
            continue
        nodes = list(ast.walk(tree(path)))
        names = {node.id for node in nodes if isinstance(node, ast.Name)}
        names |= {node.attr for node in nodes if isinstance(node, ast.Attribute)}
        assert "MANIFEST_EXTENSIONS" not in names, path
