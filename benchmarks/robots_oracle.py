"""Robots from the wild measured twice: by ``meshcol check`` and by engines that share none of
its code, pair by pair (issue 32 item 4; the sweeps of RESULTS.md, "Session 37").

For every robot of the collections ``bench_robots_wild.py`` finds (example-robot-data,
gymnasium, dm_control, the Menagerie wheels, the samples), check reports every pair of links it
measures (``--clearance 1e6``), and the oracle gives each pair's least distance over the two
links' collision elements at the same configuration (check's default: zero, or the middle of
limits that exclude zero):

- MJCF: MuJoCo itself (``mj_geomDistance`` at the model's own kinematics: ``tests/mujoco_oracle.py``).
  MuJoCo's mesh distances can stop early on large meshes, and its penetration depths are its
  contact solver's, not the translation that separates the pair: penetrating pairs are compared
  by sign only.
- URDF: yourdfpy's forward kinematics, trimesh's reading of each mesh (its URDF scale; an OBJ
  file's ``o`` and ``g`` blocks read here, one hull each, as pybullet and meshcol take them)
  and coal (its hull of each, GJK at a 1e-12 tolerance; its own primitives).

Columns: the pairs compared, the separated ones' largest difference (m), the pairs whose sign
differs, and the pairs left out (those the oracle fails on: coal's EPA on touching
cylinders). Each robot runs in a process of its own (an oracle's crash is that robot's row).

Run:  .venv/bin/python benchmarks/robots_oracle.py [--only COLLECTION] [--limit N]
      [--match NAME] [--json F]   (make robots-wild / robots-menagerie install the collections)
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent / "tests"))

from bench_robots_wild import COLLECTIONS


def check_pairs(robot: Path) -> list[dict] | str:
    """check's pairs of the robot, or why there are none."""
    with tempfile.TemporaryDirectory() as work:
        report = Path(work) / "r.json"
        command = [sys.executable, "-m", "meshcol", "check", str(robot), "--clearance", "1e6"]
        done = subprocess.run(
            [*command, "--fail-on", "none", "--report", str(report)],
            capture_output=True,
            text=True,
            timeout=600,
        )
        if done.returncode != 0:
            lines = done.stderr.strip().splitlines()
            last = lines[-1].rpartition(": ")[2] if lines else ""  # the reason, past the path
            return f"check exit {done.returncode}: {last[:90]}"
        return json.loads(report.read_text())["pairs"]


def mjcf_oracle(robot: Path) -> tuple[dict, set]:
    """MuJoCo's least distance of each body pair (ellipsoids included: exact on both sides
    since session 37), and no body to leave out."""
    import mujoco
    from mujoco_oracle import check_qpos, collision_geoms, least_distance

    model = mujoco.MjModel.from_xml_path(str(robot))
    data = mujoco.MjData(model)
    data.qpos[:] = check_qpos(robot)
    mujoco.mj_forward(model, data)
    geoms = collision_geoms(mujoco, model)

    def distance(a: str, b: str) -> float:
        return least_distance(mujoco, model, data, geoms[a], geoms[b], 1e6)

    return _Lazy(distance, geoms), set()


class _Lazy(dict):
    """Pair -> distance, computed when asked (only for the pairs check reports)."""

    def __init__(self, distance, links) -> None:
        super().__init__()
        self.distance, self.links = distance, links

    def __missing__(self, pair: tuple[str, str]) -> float | None:
        a, b = pair
        value = self.distance(a, b) if a in self.links and b in self.links else None
        self[pair] = value
        return value


def urdf_oracle(robot: Path) -> tuple[dict, set]:
    """coal's least distance of each link pair, on yourdfpy's poses and trimesh's meshes."""
    import coal
    import trimesh
    import yourdfpy

    model = yourdfpy.URDF.load(str(robot), build_scene_graph=True, load_meshes=False)
    configuration = {}
    for name, joint in model.joint_map.items():
        if joint.type in ("revolute", "prismatic") and joint.mimic is None and joint.limit:
            lower, upper = joint.limit.lower, joint.limit.upper
            if lower is not None and upper is not None and not lower <= 0.0 <= upper:
                configuration[name] = 0.5 * (lower + upper)
    model.update_cfg(configuration)
    shapes: dict[str, list] = {}
    for link in model.robot.links:
        pose = model.get_transform(link.name, model.base_link)
        for element in link.collisions:
            world = pose @ (np.eye(4) if element.origin is None else element.origin)
            for shape, at in _coal_shapes(coal, trimesh, model, element.geometry, world):
                shapes.setdefault(link.name, []).append((shape, at))
    request = coal.DistanceRequest()
    request.gjk_tolerance = request.epa_tolerance = 1e-12

    def distance(a: str, b: str) -> float:
        return min(
            coal.distance(sa, ta, sb, tb, request, coal.DistanceResult())
            for sa, ta in shapes[a]
            for sb, tb in shapes[b]
        )

    return _Lazy(distance, shapes), set()


def _coal_shapes(coal, trimesh, model, geometry, world: np.ndarray):
    """The coal shapes of one URDF collision element at its world pose."""
    at = coal.Transform3s(world[:3, :3], world[:3, 3])
    if geometry.box is not None:
        return [(coal.Box(*geometry.box.size), at)]
    if geometry.sphere is not None:
        return [(coal.Sphere(geometry.sphere.radius), at)]
    if geometry.cylinder is not None:
        return [(coal.Cylinder(geometry.cylinder.radius, geometry.cylinder.length), at)]
    if getattr(geometry, "capsule", None) is not None:
        return [(coal.Capsule(geometry.capsule.radius, geometry.capsule.length), at)]
    if geometry.mesh is None:
        return []
    file = model._filename_handler(geometry.mesh.filename)
    if str(file).lower().endswith(".obj"):
        pieces = _obj_pieces(Path(file))
    else:
        pieces = [np.asarray(m.vertices) for m in trimesh.load(file, force="scene").dump()]
    given = 1.0 if geometry.mesh.scale is None else geometry.mesh.scale
    scale = np.broadcast_to(np.asarray(given, dtype=np.float64), (3,))
    out = []
    for vertices in pieces:
        points = (np.asarray(vertices, dtype=np.float64) * scale) @ world[:3, :3].T
        points = _thickened(points + world[:3, 3])
        vec = coal.StdVec_Vec3s()
        for point in points:
            vec.append(point)
        out.append((coal.ConvexBase.convexHull(vec, False, ""), coal.Transform3s()))
    return out


def _thickened(points: np.ndarray) -> np.ndarray:
    """A flat point set moved 1e-7 of its size to each side of its plane (coal cannot hull a
    flat set; meshcol's part is its convex polygon, the distances then agree to that)."""
    centred = points - points.mean(axis=0)
    _, sizes, axes = np.linalg.svd(centred, full_matrices=False)
    if len(points) >= 4 and sizes[-1] > 1e-9 * max(sizes[0], 1e-300):
        return points
    shift = axes[-1] * 1e-7 * max(float(np.ptp(points, axis=0).max()), 1e-300)
    return np.concatenate([points + shift, points - shift])


def _obj_pieces(path: Path) -> list[np.ndarray]:
    """The vertices each ``o`` or ``g`` block of an OBJ file's faces uses: the pieces pybullet
    hulls one by one (a VHACD file's convex parts) and meshcol makes parts of. trimesh
    groups them otherwise (by material; laikago's 48 ``o`` blocks as one)."""
    vertices: list[list[float]] = []
    pieces: list[set[int]] = [set()]
    for line in path.read_text(errors="replace").splitlines():
        head, _, rest = line.strip().partition(" ")
        if head == "v":
            vertices.append([float(x) for x in rest.split()[:3]])
        elif head in ("o", "g") and pieces[-1]:
            pieces.append(set())
        elif head == "f":
            for corner in rest.split():
                index = int(corner.split("/")[0])
                pieces[-1].add(index - 1 if index > 0 else len(vertices) + index)
    points = np.asarray(vertices, dtype=np.float64)
    return [points[sorted(piece)] for piece in pieces if piece]


def robot_row(collection: str, robot: Path) -> dict:
    """One robot's comparison (run in a process of its own)."""
    row: dict = {"collection": collection, "robot": robot.name, "path": str(robot)}
    pairs = check_pairs(robot)
    if isinstance(pairs, str):
        row["note"] = pairs
        return row
    mjcf = robot.suffix != ".urdf"
    try:
        oracle, ellipsoids = mjcf_oracle(robot) if mjcf else urdf_oracle(robot)
    except Exception as error:  # noqa: BLE001 - the oracle's failure is this row's note
        row["note"] = f"oracle: {type(error).__name__}: {str(error).splitlines()[0][:80]}"
        return row
    compared = left_out = signs = 0
    worst, worst_pair = 0.0, None
    for pair in pairs:
        a, b = pair["body_a"], pair["body_b"]
        expected = oracle[(a, b)]
        measured = pair["signed_distance"]
        if expected is None or measured is None or {a, b} & ellipsoids or expected < -1e300:
            left_out += 1
            continue
        compared += 1
        if expected >= 0.0 and measured >= 0.0:
            if abs(measured - expected) > worst:
                worst, worst_pair = abs(measured - expected), f"{a} / {b}"
        elif (measured < -1e-9) != (expected < -1e-9):
            signs += 1
    row.update(
        compared=compared, worst=worst, worst_pair=worst_pair, signs=signs, left_out=left_out
    )
    return row


def isolated(collection: str, robot: Path) -> dict:
    with ProcessPoolExecutor(max_workers=1, max_tasks_per_child=1) as pool:
        try:
            return pool.submit(robot_row, collection, robot).result(timeout=1200)
        except Exception as error:  # noqa: BLE001 - a crashed oracle is the row's note
            return {"collection": collection, "robot": robot.name, "note": repr(error)[:100]}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--only", choices=sorted(COLLECTIONS), action="append")
    parser.add_argument("--limit", type=int, default=None, help="robots per collection")
    parser.add_argument("--match", action="append", help="only robots of this file name")
    parser.add_argument("--json", type=Path, default=None, help="every row, as JSON")
    args = parser.parse_args()
    rows = []
    print("| collection | robot | pairs | separated: worst (m) | signs differ | left out | note |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for collection in args.only or sorted(COLLECTIONS):
        robots = COLLECTIONS[collection]()
        if args.match:
            robots = [r for r in robots if r.name in args.match]
        for robot in robots[: args.limit]:
            row = isolated(collection, robot)
            rows.append(row)
            worst = f"{row['worst']:.2g} ({row['worst_pair']})" if row.get("worst") else "0"
            print(
                f"| {collection} | {robot.name} | {row.get('compared', '')} | "
                f"{worst if 'compared' in row else ''} | {row.get('signs', '')} | "
                f"{row.get('left_out', '')} | {row.get('note', '')} |",
                flush=True,
            )
    done = [r for r in rows if "compared" in r]
    total = sum(r["compared"] for r in done)
    worst = max((r["worst"] for r in done), default=0.0)
    print(
        f"\n{len(done)} robots compared, {total} pairs; largest separated difference "
        f"{worst:.3g} m; sign differences {sum(r['signs'] for r in done)}; "
        f"{len(rows) - len(done)} robots with a note"
    )
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
