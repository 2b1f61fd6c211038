"""Workers import the installed meshcol, whatever folder the run starts from (issue #29, item
16): the fork server runs ``python -c``, which put the working folder first on ``sys.path``,
so a run from a folder holding a ``meshcol/`` directory (the repository's root) had its
workers import that one.

The project's own venv is an editable install whose import finder hides the problem, so the
run here is of a regular install: the package copied into a folder of its own (with its
built extension), the venv's site-packages on ``PYTHONPATH`` without its ``.pth`` files
(``-S``: no editable finder), and the command started from a script outside the working
folder, as the ``meshcol`` console script is.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest

import meshcol
from meshcol import _native

TETRA_OBJ = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"


def _regular_install(folder: Path) -> Path:
    """A copy of the package (sources and the built extension) in ``folder/site``."""
    site = folder / "site"
    shutil.copytree(
        Path(meshcol.__file__).parent,
        site / "meshcol",
        ignore=shutil.ignore_patterns("__pycache__"),
    )
    core = Path(_native.core.__file__)
    if not (site / "meshcol" / core.name).exists():
        shutil.copy2(core, site / "meshcol" / core.name)
    return site


@pytest.mark.skipif(sys.version_info < (3, 11), reason="PYTHONSAFEPATH needs Python 3.11")
@pytest.mark.skipif(
    "forkserver" not in __import__("multiprocessing").get_all_start_methods(),
    reason="the fork server is where the working folder leads sys.path",
)
def test_workers_never_import_a_meshcol_folder_of_the_working_folder(tmp_path) -> None:
    site = _regular_install(tmp_path / "install")
    # the repository's root: the package's sources, without the built extension
    work = tmp_path / "repo"
    shutil.copytree(
        Path(meshcol.__file__).parent,
        work / "meshcol",
        ignore=shutil.ignore_patterns("__pycache__", "*.so", "*.pyd"),
    )
    for name in ("a.obj", "b.obj"):
        (work / name).write_text(TETRA_OBJ)
    script = tmp_path / "bin" / "meshcol_cli.py"
    script.parent.mkdir()
    script.write_text('from meshcol.cli import main\n\nif __name__ == "__main__":\n    main()\n')
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(site), sysconfig.get_paths()["purelib"]]),
    }
    env.pop("PYTHONSAFEPATH", None)
    done = subprocess.run(
        [sys.executable, "-S", str(script), "inspect", "a.obj", "b.obj", "--jobs", "2"],
        cwd=work,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    assert "_core" not in done.stderr
    assert done.stderr.splitlines()[-1] == "meshcol: inspect: PASS: 2 bodies, 0 with findings"
