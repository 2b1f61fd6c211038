"""Reports: one envelope for every command, a schema per report, golden reports on the samples.

Every JSON file in tests/golden/ is validated against the schema its ``command`` names; the
hull, inspect and decompose goldens are written here (check's and sweep's by their own test
files), with machine-dependent values normalised.
"""

from __future__ import annotations

import copy
import json
import shutil
from pathlib import Path

import jsonschema
import pytest
from click.testing import CliRunner
from conftest import FAST_DECOMPOSE

from meshcol.cli import COMMANDS, main
from meshcol.io.report import ENVELOPE_KEYS, SCHEMA_VERSION, envelope

#: The commands that write a run's report (``meshcol targets`` lists the packaged engine
#: profiles: data, not a run, so no envelope).
REPORT_COMMANDS = sorted(set(COMMANDS) - {"targets", "rules", "config"})  # listings, not runs

SCHEMAS = Path(__file__).resolve().parents[2] / "meshcol" / "schemas"
GOLDEN = Path(__file__).resolve().parents[1] / "golden"
GOLDEN_FILES = sorted(GOLDEN.glob("*.json"))
FAST = FAST_DECOMPOSE


def schema_for(report: dict) -> dict:
    path = SCHEMAS / f"{report['command']}_report.schema.json"
    assert path.is_file(), f"no schema for command {report['command']!r}: {path}"
    return json.loads(path.read_text())


def validate(report: dict) -> None:
    schema = schema_for(report)
    jsonschema.Draft202012Validator.check_schema(schema)
    jsonschema.Draft202012Validator(schema).validate(report)


#: Below this a float of a golden report's mass properties (its ``physics`` rows) is rounding
#: noise (the centre of mass or a product of inertia of a symmetric sample, about 1e-17) and is
#: written as 0: its digits depend on the order numpy sums in, which its SIMD code picks per
#: CPU, so they differ from machine to machine. Elsewhere small values are settings and
#: limits (``min_volume`` 1e-15) and are kept.
NOISE = 1e-12


def normalised(data: dict) -> str:
    """Golden text: tool version out, floats to 9 significant digits (mass properties below
    ``NOISE`` as 0), sorted keys."""
    data = copy.deepcopy(data)
    data["tool"]["version"] = "<version>"
    return json.dumps(_round_floats(data), sort_keys=True, indent=2) + "\n"


def _round_floats(obj, noisy: bool = False):
    if isinstance(obj, dict):
        return {k: _round_floats(v, noisy or k == "physics") for k, v in obj.items()}
    if isinstance(obj, list):
        return [_round_floats(v, noisy) for v in obj]
    if isinstance(obj, float):
        return 0.0 if noisy and abs(obj) < NOISE else float(f"{obj:.9g}") + 0.0
    return obj


def run(*args: str) -> dict:
    result = CliRunner().invoke(main, list(args))
    assert result.exit_code == 0, result.output
    return json.loads(result.stdout)


# ---------------------------------------------------------------------------------------------
# Golden reports on the samples (run from the repository root: relative paths)


def test_hull_golden(samples: Path, golden, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(samples.parent)
    report = run("hull", "samples/bowl/bowl.obj", "--max-vertices", "64")
    (body,) = report["bodies"]
    assert body["hull_vertices"] <= 64 and body["output"] is None
    golden("hull_bowl.json", normalised(report))


def test_fit_golden(samples: Path, golden, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(samples.parent)
    report = run("fit", "samples/level/props/barrel.obj", "samples/level/props/ramp.obj")
    assert [b["shape"] for b in report["bodies"]] == ["cylinder", "hull"]
    for body in report["bodies"]:  # sampled gaps: round off float noise
        if body["max_gap"] is not None:
            body["max_gap"] = round(body["max_gap"], 6)
    golden("fit_props.json", normalised(report))


def test_inspect_golden(samples: Path, golden, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(samples.parent)
    report = run("inspect", "samples/bowl/scene.json", "--fail-on", "not-watertight")
    assert report["units"] == "m" and report["failed"] is False
    golden("inspect_bowl.json", normalised(report))


def test_decompose_golden(
    samples: Path, golden, monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    monkeypatch.chdir(samples.parent)
    report = run(
        "decompose",
        "samples/bullet/wall.obj",
        "samples/bullet/bullet.obj",
        "-o",
        str(tmp_path / "parts"),
        "--no-cache",
        "--report",
        "-",
        *FAST,
    )
    assert report["settings"]["out_dir"] == str(tmp_path / "parts")
    assert report["summary"]["ok"] == 2
    # The settings state the values used (issue 29 item 18), which every body's params repeat
    # but for the preprocessing CoACD's auto mode decides per mesh.
    used = report["settings"]["engine_parameters"]
    assert used["threshold"] == 0.2 and used["mcts_nodes"] == 8 and used["max_ch_vertex"] == 256
    for entry in report["files"]:
        for body in entry["bodies"]:
            assert {**used, "preprocess_mode": body["params"]["preprocess_mode"]} == body["params"]
    report["settings"]["out_dir"] = "<out_dir>"
    for entry in report["files"]:
        entry["seconds"] = 0.0
        for body in entry["bodies"]:
            body["cache_key"] = "<cache_key>"  # hashes the engine version too
            body["engine_version"] = "<engine_version>"
            # Sampled distances and boolean volumes: round off float noise (1e-10 here,
            # 0 elsewhere) at 1e-6 mesh units, far below what the metrics are read for.
            body["metrics"] = {
                k: round(v, 6) if isinstance(v, float) else v for k, v in body["metrics"].items()
            }
    golden("decompose_bullet.json", normalised(report))


# ---------------------------------------------------------------------------------------------
# Schemas


def test_every_command_has_a_schema_and_a_golden_report() -> None:
    commands = {json.loads(p.read_text())["command"] for p in GOLDEN_FILES}
    assert commands == set(REPORT_COMMANDS)
    for name in REPORT_COMMANDS:
        assert (SCHEMAS / f"{name}_report.schema.json").is_file(), name


@pytest.mark.parametrize("path", GOLDEN_FILES, ids=[p.name for p in GOLDEN_FILES])
def test_golden_report_matches_its_schema(path: Path) -> None:
    validate(json.loads(path.read_text()))


def _mutations(report: dict):
    """Reports that must fail validation: one wrong thing each."""
    extra = copy.deepcopy(report)
    extra["unexpected"] = 1
    yield "unknown top-level field", extra
    for key in ENVELOPE_KEYS:
        missing = copy.deepcopy(report)
        del missing[key]
        missing.setdefault("command", report["command"])  # still picks the schema
        if key != "command":
            yield f"no {key}", missing
    version = copy.deepcopy(report)
    version["schema_version"] = SCHEMA_VERSION + 1
    yield "other schema version", version
    tool = copy.deepcopy(report)
    tool["tool"]["name"] = "othertool"
    yield "other tool", tool
    setting = copy.deepcopy(report)
    setting["settings"]["unexpected"] = 1
    yield "unknown setting", setting
    summary = copy.deepcopy(report)
    summary["summary"] = "none"
    yield "summary of the wrong type", summary
    for key, rows in report.items():
        if isinstance(rows, list) and rows and isinstance(rows[0], dict):
            row = copy.deepcopy(report)
            del row[key][0][sorted(rows[0])[0]]
            yield f"{key}[0] without a field", row


@pytest.mark.slow
@pytest.mark.parametrize("path", GOLDEN_FILES, ids=[p.name for p in GOLDEN_FILES])
def test_schema_rejects_broken_reports(path: Path) -> None:
    report = json.loads(path.read_text())
    count = 0
    for what, broken in _mutations(report):
        with pytest.raises(jsonschema.ValidationError):
            validate(broken)
            pytest.fail(f"{path.name}: {what} was accepted")
        count += 1
    assert count >= 9, what


def _properties(node, where: str):
    if isinstance(node, dict):
        for name, sub in node.get("properties", {}).items():
            yield f"{where}.{name}", sub
        for key, sub in node.items():
            yield from _properties(sub, f"{where}/{key}")
    elif isinstance(node, list):
        for i, sub in enumerate(node):
            yield from _properties(sub, f"{where}[{i}]")


@pytest.mark.parametrize("name", REPORT_COMMANDS)
def test_every_schema_field_is_described(name: str) -> None:
    schema = json.loads((SCHEMAS / f"{name}_report.schema.json").read_text())
    assert schema["$schema"] == "https://json-schema.org/draft/2020-12/schema"
    assert schema.get("description")
    undescribed = [where for where, sub in _properties(schema, name) if not sub.get("description")]
    assert undescribed == []


# ---------------------------------------------------------------------------------------------
# The envelope


def _envelope_shape(report: dict) -> dict:
    return {
        "first_keys": list(report)[: len(ENVELOPE_KEYS)],
        "schema_version": report["schema_version"],
        "tool": sorted(report["tool"]),
        "tool_name": report["tool"]["name"],
        "tool_version": type(report["tool"]["version"]).__name__,
        "command": type(report["command"]).__name__,
        "settings": type(report["settings"]).__name__,
        "units": report["units"] is None or isinstance(report["units"], str),
    }


def test_envelope_function() -> None:
    import meshcol

    head = envelope("hull", {"frame": "world"}, "m")
    assert list(head) == list(ENVELOPE_KEYS)
    assert head == {
        "schema_version": SCHEMA_VERSION,
        "tool": {"name": "meshcol", "version": meshcol.__version__},
        "command": "hull",
        "settings": {"frame": "world"},
        "units": "m",
    }


def _ci_report(samples: Path, tmp_path: Path):
    """``meshcol ci``'s report on one asset (inspected)."""
    from meshcol.analysis.ci import run_ci
    from meshcol.io.config import load_config

    (tmp_path / "repo").mkdir()
    shutil.copy(samples / "bullet" / "wall.obj", tmp_path / "repo" / "wall.obj")
    (tmp_path / "repo" / "meshcol.toml").write_text('[[assets]]\nglob = "*.obj"\n')
    return run_ci(load_config(tmp_path / "repo" / "meshcol.toml"), use_cache=False)


def test_envelope_is_the_same_in_every_command_report(samples: Path, tmp_path: Path) -> None:
    """Each library report object starts from the one envelope, in the same shape."""
    from meshcol.analysis.check import check
    from meshcol.analysis.collision_matrix import collision_matrix
    from meshcol.analysis.fit import fit
    from meshcol.analysis.hull import hull
    from meshcol.analysis.inspect import inspect
    from meshcol.analysis.sweep import sweep
    from meshcol.decomposition.batch import decompose_files

    wall = samples / "bullet" / "wall.obj"
    robot = tmp_path / "two.urdf"
    robot.write_text(
        '<robot name="two"><link name="a"><collision><geometry><sphere radius="1"/></geometry>'
        '</collision></link><link name="b"><collision><geometry><box size="1 1 1"/></geometry>'
        '</collision></link><joint name="j" type="fixed"><parent link="a"/><child link="b"/>'
        "</joint></robot>"
    )
    reports = {
        "check": check([samples / "bowl" / "scene.json"]),
        "sweep": sweep(samples / "bullet" / "scene.json"),
        "hull": hull([wall]),
        "fit": fit([wall]),
        "inspect": inspect([wall]),
        "decompose": decompose_files(
            [wall],
            tmp_path / "parts",
            use_cache=False,
            threshold=0.2,
            resolution=500,
            engine_options={"mcts_iterations": "20", "mcts_nodes": "8", "mcts_max_depth": "2"},
        ),
        "collision-matrix": collision_matrix(robot, samples=10),
        "ci": _ci_report(samples, tmp_path),
    }
    assert set(reports) == set(REPORT_COMMANDS)
    shapes = {}
    for name, report in reports.items():
        data = report.to_dict()
        assert data["command"] == name
        assert json.loads(report.to_json())["command"] == name
        assert report.exit_code in (0, 1)
        assert isinstance(report.summary, dict)
        assert report.to_csv().count("\n") >= 1
        shape = _envelope_shape(data)
        shape.pop("command")
        shapes[name] = shape
    first = next(iter(shapes.values()))
    assert first["first_keys"] == list(ENVELOPE_KEYS)
    assert all(shape == first for shape in shapes.values()), shapes


def test_envelope_is_the_same_in_every_golden_report_and_schema() -> None:
    shapes = {}
    envelopes = {}
    for path in GOLDEN_FILES:
        report = json.loads(path.read_text())
        shape = _envelope_shape(report)
        shape.pop("first_keys")  # golden files are written with sorted keys
        shapes[path.name] = shape
        schema = schema_for(report)
        props = copy.deepcopy({k: schema["properties"][k] for k in ENVELOPE_KEYS})
        assert props["command"]["const"] == report["command"]
        for key in ("command", "settings"):
            props.pop(key)
        envelopes[report["command"]] = props
        assert set(ENVELOPE_KEYS) <= set(schema["required"])
    assert len({json.dumps(s, sort_keys=True) for s in shapes.values()}) == 1, shapes
    assert len({json.dumps(e, sort_keys=True) for e in envelopes.values()}) == 1
