"""What start-up imports (issue 31 item 3: a repository re-checked after one file changed in
about a second). Each check runs in a fresh interpreter and reads ``sys.modules``, untimed:

- ``import meshcol`` imports no numpy, scipy, trimesh, jsonschema, Pillow, Ray, USD or the
  native core (the public API loads on first use);
- a warm ``meshcol ci`` (every job from the result cache) imports none of them, numpy
  included, whatever reports it writes: the index lookups and the reports need none;
- ``meshcol ci`` after one OBJ and one STL changed (the jobs run in the process) imports
  neither scipy nor trimesh: the core reads both formats and the health checks need neither
  (connected components by :mod:`meshcol.geometry.graph`).
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import UNIT_CUBE_OBJ

#: Never imported by ``import meshcol``.
HEAVY = (
    "numpy",
    "scipy",
    "trimesh",
    "jsonschema",
    "PIL",
    "ray",
    "pxr",
    "manifold3d",
    "lxml",
    "mujoco",
    "meshcol._core",
)
#: Never imported by a warm ``meshcol ci`` writing every report format (the native core may
#: be: it writes JSON).
HEAVY_WARM = tuple(name for name in HEAVY if name != "meshcol._core")
#: Never imported by ``meshcol ci`` inspecting an OBJ or STL that changed (what it freed).
FREED = ("scipy", "trimesh")

CONFIG = """[[assets]]
glob = "props/**/*"
inspect = { fail-on = ["not-watertight"] }
"""

BOX = "o box\n" + UNIT_CUBE_OBJ

TETRA_STL = """solid t
facet normal 0 0 -1
 outer loop
  vertex 0 0 0
  vertex 0 1 0
  vertex 1 0 0
 endloop
endfacet
facet normal 0 -1 0
 outer loop
  vertex 0 0 0
  vertex 1 0 0
  vertex 0 0 1
 endloop
endfacet
facet normal -1 0 0
 outer loop
  vertex 0 0 0
  vertex 0 0 1
  vertex 0 1 0
 endloop
endfacet
facet normal 1 1 1
 outer loop
  vertex 1 0 0
  vertex 0 1 0
  vertex 0 0 1
 endloop
endfacet
endsolid t
"""


def _modules(code: str, cwd: Path | None = None) -> tuple[set[str], str]:
    """The top-level and native modules loaded by ``code`` in a new interpreter (and the last
    line it printed before)."""
    probe = f"{code}\nimport json, sys\nprint(json.dumps(sorted(sys.modules)))\n"
    done = subprocess.run(
        [sys.executable, "-c", probe], capture_output=True, text=True, cwd=cwd, check=False
    )
    assert done.stdout, done.stderr
    *before, last = done.stdout.strip().splitlines()
    names = set(json.loads(last))
    return {n.split(".")[0] for n in names} | (names & {"meshcol._core"}), "\n".join(before)


def _ci(root: Path, cache: Path, *more: str) -> str:
    args = ["ci", "-j", "2", "--cache-dir", str(cache), *more]
    return (
        "from meshcol.cli import main\n"
        "try:\n"
        f"    main({args!r}, prog_name='meshcol')\n"
        "except SystemExit as exit:\n"
        "    print('EXIT', exit.code)\n"
    )


def test_import_meshcol_loads_nothing_heavy() -> None:
    loaded, _ = _modules("import meshcol\nmeshcol.__version__")
    assert loaded.isdisjoint(HEAVY), sorted(loaded & set(HEAVY))
    # the lazy API still answers, and then loads what it needs
    loaded, _ = _modules("import meshcol\nassert meshcol.Body.__module__ == 'meshcol.types'")
    assert "numpy" in loaded


@pytest.mark.slow  # 1-2 s: the fast lane (make test-fast) stays under 40 s
def test_warm_and_one_changed_ci_import_neither_scipy_nor_trimesh(tmp_path) -> None:
    root, cache = tmp_path / "repo", tmp_path / "cache"
    (root / "props").mkdir(parents=True)
    (root / "meshcol.toml").write_text(CONFIG)
    (root / "props" / "box.obj").write_text(BOX)
    (root / "props" / "open.obj").write_text(BOX.rsplit("f ", 1)[0])  # one face missing
    (root / "props" / "tetra.stl").write_text(TETRA_STL)
    # cold: the three jobs in a pool (whatever they import), every result cached
    _, printed = _modules(_ci(root, cache), cwd=root)
    assert printed.splitlines()[-1] == "EXIT 1"  # the open box fails not-watertight

    for outputs in ((), ("--outputs", str(tmp_path / "reports"))):
        loaded, printed = _modules(_ci(root, cache, *outputs), cwd=root)
        assert printed.splitlines()[-1] == "EXIT 1"
        assert loaded.isdisjoint(HEAVY_WARM), sorted(loaded & set(HEAVY_WARM))
    assert len(list((tmp_path / "reports").iterdir())) >= 5  # JSON, JUnit, SARIF, Markdown...

    for name, text in (("box.obj", BOX.replace("v 1 1 1", "v 2 2 2")), ("tetra.stl", None)):
        path = root / "props" / name
        path.write_text(text if text is not None else TETRA_STL.replace("1 0 0", "2 0 0"))
        loaded, printed = _modules(_ci(root, cache), cwd=root)
        assert printed.splitlines()[-1] == "EXIT 1"
        assert "meshcol._core" in loaded  # the job ran, here
        assert loaded.isdisjoint(FREED), (name, sorted(loaded & set(FREED)))
