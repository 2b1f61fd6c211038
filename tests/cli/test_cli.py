"""The command group: version, help on every command, error mapping, light start-up."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

import meshcol
from meshcol.cli import COMMANDS, main


def test_version() -> None:
    result = CliRunner().invoke(main, ["--version"])
    assert result.exit_code == 0
    assert result.output == f"meshcol, version {meshcol.__version__}\n"


def test_short_help_flag_lists_every_command() -> None:
    result = CliRunner().invoke(main, ["-h"])
    assert result.exit_code == 0
    for name in COMMANDS:
        assert name in result.output


@pytest.mark.parametrize("name", sorted(COMMANDS))
def test_every_command_has_help_with_examples(name: str) -> None:
    result = CliRunner().invoke(main, [name, "-h"])
    assert result.exit_code == 0, result.output
    assert f"meshcol {name}" in result.output
    assert "Examples" in result.output


def test_unknown_command_is_a_usage_error() -> None:
    result = CliRunner().invoke(main, ["frobnicate"])
    assert result.exit_code == 2
    assert result.output == "meshcol: error: no such command 'frobnicate' (see 'meshcol -h')\n"


def test_help_does_not_import_heavy_modules() -> None:
    code = (
        "import sys\n"
        "from meshcol.cli import main\n"
        "try:\n"
        "    main(['--help'], standalone_mode=False)\n"
        "except SystemExit:\n"
        "    pass\n"
        "heavy = [m for m in ('trimesh', 'coacd', 'scipy', 'manifold3d', 'meshcol._core') if m in sys.modules]\n"
        "print('HEAVY=' + ','.join(heavy))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip().splitlines()[-1] == "HEAVY="


def test_python_dash_m_runs() -> None:
    out = subprocess.run(
        [sys.executable, "-m", "meshcol", "--version"], capture_output=True, text=True
    )
    assert out.returncode == 0
    assert out.stdout.strip() == f"meshcol, version {meshcol.__version__}"


def test_native_core_loads() -> None:
    from meshcol._native import core as _core

    assert _core.hardware_threads() >= 1
    assert 0 < _core.defaults.rigid_tolerance < 1e-3


def test_output_files_get_the_usual_permissions(tmp_path) -> None:
    import os
    import stat

    from meshcol.io.report import atomic_write

    target = tmp_path / "out.json"
    atomic_write(target, "{}\n")
    mask = os.umask(0)
    os.umask(mask)
    assert stat.S_IMODE(target.stat().st_mode) == 0o666 & ~mask
    assert [p.name for p in tmp_path.iterdir()] == ["out.json"]


def test_same_named_functions_stay_callable() -> None:
    """`meshcol.check`, `meshcol.sweep` and `meshcol.decompose` are the functions whatever was
    imported first: no module shares their names."""
    code = (
        "import meshcol.analysis.check, meshcol.analysis.sweep, meshcol.decomposition, meshcol\n"
        "from meshcol.cli import check as _c, sweep as _s\n"
        "print(callable(meshcol.check), callable(meshcol.sweep), meshcol.check.__module__, meshcol.sweep.__module__)\n"
        "import sys\n"
        "print('HEAVY=' + ','.join(m for m in ('trimesh', 'scipy', 'meshcol._core') if m in sys.modules))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    first, heavy = out.stdout.strip().splitlines()
    assert first == "True True meshcol.analysis.check meshcol.analysis.sweep"
    assert heavy == "HEAVY="


def test_a_run_collects_garbage_less_often_then_restores_the_rate() -> None:
    import gc

    import meshcol.cli as cli

    before = gc.get_threshold()
    with cli._collect_less_often():
        assert gc.get_threshold() == (cli.GC_THRESHOLD, *before[1:])
    assert gc.get_threshold() == before
    with pytest.raises(RuntimeError), cli._collect_less_often():
        raise RuntimeError  # a failing command restores it too
    assert gc.get_threshold() == before
    assert CliRunner().invoke(main, ["--version"]).exit_code == 0
    assert gc.get_threshold() == before


SAMPLES = Path(__file__).resolve().parents[2] / "samples"


@pytest.mark.parametrize(
    ("inputs", "flags", "named"),
    [
        (["level/props/crate.obj", "level/props/barrel.obj"], ["--srdf", "x.srdf"], "--srdf"),
        (["level/scene.json"], ["--joint", "elbow=1", "--include-adjacent"], "--joint/--joints"),
        (["robot/arm.urdf"], ["--joint", "elbow=1"], None),
        (["level/props/crate.obj"], [], None),
    ],
)
def test_robot_flags_without_a_robot_are_said_to_be_ignored(
    inputs: list[str], flags: list[str], named: str | None
) -> None:
    if any(path.endswith(".urdf") for path in inputs):
        pytest.importorskip("yourdfpy")
    paths = [str(SAMPLES / path) for path in inputs]
    result = CliRunner().invoke(main, ["check", *paths, *flags, "--format", "json"])
    assert result.exit_code in (0, 1), result.stderr  # 1: the samples' props overlap
    warned = [line for line in result.stderr.splitlines() if "no input is one" in line]
    if named is None:
        assert not warned
    else:
        assert len(warned) == 1 and named in warned[0], result.stderr
        assert all(flag in warned[0] for flag in flags if flag.startswith("--"))
