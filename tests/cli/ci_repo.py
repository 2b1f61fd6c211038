"""A small asset repository for the ``meshcol ci`` tests: a level (a manifest whose bodies
penetrate), props in two folders with different rules (one open mesh in each), a robot (a
URDF whose links are mesh files), and the ``meshcol.toml`` that says so."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

SAMPLES = Path(__file__).resolve().parents[2] / "samples"

BOX_FACES = [
    (1, 3, 2), (1, 4, 3), (5, 6, 7), (5, 7, 8), (1, 2, 6), (1, 6, 5),
    (2, 3, 7), (2, 7, 6), (3, 4, 8), (3, 8, 7), (4, 1, 5), (4, 5, 8),
]  # fmt: skip


def box_obj(size: float = 1.0, open_top: bool = False, name: str = "box") -> str:
    """An axis-aligned box (closed, outward), or without its top face (open: MC401)."""
    h = size / 2
    corners = [(-h, -h, 0), (h, -h, 0), (h, h, 0), (-h, h, 0)]
    corners += [(x, y, size) for x, y, _ in corners]
    faces = [f for f in BOX_FACES if not (open_top and f in ((5, 6, 7), (5, 7, 8)))]
    lines = [f"o {name}"] + [f"v {x} {y} {z}" for x, y, z in corners]
    lines += [f"f {a} {b} {c}" for a, b, c in faces]
    return "\n".join(lines) + "\n"


ROBOT = """<?xml version="1.0"?>
<robot name="arm">
  <link name="base"><collision><geometry><mesh filename="meshes/base.obj"/></geometry></collision></link>
  <link name="upper"><collision><geometry><mesh filename="meshes/upper.obj"/></geometry></collision></link>
  <link name="tool"><collision><origin xyz="0 0 0.3"/><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="upper"/>
    <origin xyz="0 0 0.5"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="j2" type="fixed"><parent link="upper"/><child link="tool"/><origin xyz="0 0 0.5"/></joint>
</robot>
"""

CONFIG = """# the test repository's policy
exclude = ["baselines/**"]

[[assets]]
glob = "props/**/*.obj"
shape = "hull"
inspect = { volume-ratio = 2.0 }
hull = { max-vertices = 16 }

[[assets]]
glob = "props/hard/*.obj"
inspect = { fail-on = ["not-watertight", "MC402"] }
ignore = [{ rule = "MC402", reason = "crossing faces are authored on purpose here" }]

[[scenes]]
path = "levels/*/scene.json"
check = { fail-on = "penetration", tolerance = 1e-6 }
ignore = [{ pair = "crate_06:crate_07", reason = "stacked on purpose" }]

[[scenes]]
path = "robots/arm/arm.urdf"
check = { fail-on = "contact" }
robot = { joints = { j1 = 0.5 } }
"""


def make_repo(root: Path, git: bool = False) -> Path:
    """Write the repository under ``root`` (and commit it with ``git``); returns ``root``."""
    shutil.copytree(SAMPLES / "level", root / "levels" / "level")
    (root / "levels" / "level" / "expected.json").unlink()
    for folder in ("hard", "soft"):
        (root / "props" / folder).mkdir(parents=True)
        (root / "props" / folder / "closed.obj").write_text(box_obj(1.0, name="closed"))
        (root / "props" / folder / "open.obj").write_text(box_obj(1.0, True, name="open"))
    meshes = root / "robots" / "arm" / "meshes"
    meshes.mkdir(parents=True)
    (meshes / "base.obj").write_text(box_obj(0.4, name="base"))
    (meshes / "upper.obj").write_text(box_obj(0.2, name="upper"))
    (root / "robots" / "arm" / "arm.urdf").write_text(ROBOT)
    (root / "meshcol.toml").write_text(CONFIG)
    if git:
        commit(root, "assets", init=True)
    return root


def commit(root: Path, message: str, init: bool = False) -> None:
    """``git add -A && git commit`` in ``root`` (``init`` first), offline and quiet."""
    env = ["-c", "user.name=t", "-c", "user.email=t@example.com", "-c", "commit.gpgsign=false"]
    if init:
        subprocess.run(["git", "init", "-q", "-b", "main", str(root)], check=True)
    subprocess.run(["git", "-C", str(root), "add", "-A"], check=True)
    subprocess.run(["git", "-C", str(root), *env, "commit", "-q", "-m", message], check=True)
