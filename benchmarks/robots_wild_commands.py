"""Robots from the wild through ``inspect``, ``fit`` and ``collision-matrix``: the robots of
``bench_robots_wild.py``'s collections (its finder, its consumers), the three commands robot
users run that its hull sweep does not (session 42).

For each robot, every command under a time cap (``--timeout``; 124 when over it):

1. ``meshcol inspect ROBOT --report R.json``: exit 0 or 1 passes; exit 2 passes with its
   one-line reason (listed in the table, to be judged true); a traceback, a crash or any
   other exit code is a failure;
2. ``meshcol fit ROBOT --out-dir OUT --to FMT`` for ``urdf`` (URDF inputs), ``mjcf`` and
   ``usd``, each output loaded by the consumers exactly as the hull sweep loads hull's
   (pybullet and yourdfpy, and urdfdom's ``check_urdf`` where installed; MuJoCo: compiled,
   ``mj_forward`` at rest, 100 steps finite, no contact at rest between the pairs meshcol
   excludes; usd-core: collision prims). Then
   containment, independent of meshcol: every vertex of each collision mesh of the input (MJCF:
   MuJoCo's reading, ``mesh_vert`` in the body frame; URDF: yourdfpy's elements, on the XML
   as pybullet reads it, and trimesh's reading of each mesh with its ``scale``, in the link
   frame) must lie in one of the fitted colliders of its body in the output (MJCF: MuJoCo's
   geoms; URDF: yourdfpy's elements, a capsule's cylinder and spheres among them), within
   1e-6 of the body's size: "outside" counts the vertices that do not;
3. ``meshcol collision-matrix ROBOT --samples S --seed 0 -o M.srdf --report M.json``; the SRDF
   read here with ``xml.etree`` against the description's own links (URDF: yourdfpy's; MJCF:
   MuJoCo's bodies): every link named exists, no pair twice, every ``Adjacent`` pair joined by
   a chain of the kinematic tree whose inner links have no collision geometry (MoveIt's
   rule); then, for MJCF robots, MuJoCo as the oracle of the ``Never`` pairs: ``--configs``
   configurations drawn with another seed (hinge and slide joints uniform within their range,
   an unlimited hinge over [-pi, pi]; free, ball and unlimited slide joints at ``qpos0``, as
   meshcol holds them; joint equalities applied), and every Never pair's least
   ``mj_geomDistance``: "never hit" counts the pairs found within 1e-6 m in at least one
   configuration (sampling can miss a rare contact: a hit is a finding to explain).

Run:  .venv/bin/python benchmarks/robots_wild_commands.py [--only C] [--limit N] [--match NAME]
      [--json F] [--samples S] [--configs K] [--timeout SEC]; --table F.json ... prints rows
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent / "tests"))

import bench_robots_wild as wild

#: Tolerance of containment, relative to the body's extent (a fit is grown by its rounding).
CONTAIN = 1e-6
#: Seed of the Never oracle's configurations (collision-matrix's default is 0).
ORACLE_SEED = 20261207


def robot_name(collection: str, robot: Path) -> str:
    if collection == "example-robot-data":
        return f"{robot.parent.parent.name}/{robot.name}"
    if collection in wild.DATA_WHEELS:
        return f"{robot.parent.name}/{robot.name}"
    return robot.name


def run_inspect(robot: Path, work: Path) -> dict:
    code, line = wild.meshcol("inspect", str(robot), "--report", str(work / "inspect.json"))
    out = {"exit": code, "line": line}
    if code in (0, 1) and not line.startswith("TRACEBACK"):
        report = json.loads((work / "inspect.json").read_text())
        out["rules"] = sorted({f["rule"] for f in report.get("findings", [])})
    return out


def run_fit(robot: Path, work: Path, excluded: set, empty: bool, shape: str = "auto") -> dict:
    formats = ["urdf", "mjcf", "usd"] if robot.suffix == ".urdf" else ["mjcf", "usd"]
    out: dict = {}
    for fmt in formats:
        folder = work / f"fit_{fmt}"
        args = ("--out-dir", str(folder), "--to", fmt, "--shape", shape)
        code, line = wild.meshcol("fit", str(robot), *args)
        if code != 0:
            out[fmt] = f"FAIL fit exit {code}: {line[:100]}"
            continue
        suffix = {"urdf": ".urdf", "mjcf": ".xml", "usd": ".usda"}[fmt]
        description = next(p for p in folder.iterdir() if p.suffix == suffix and p.is_file())
        if fmt == "urdf":
            out["urdf"] = {
                "pybullet": wild.load_pybullet(description),
                "yourdfpy": wild.load_yourdfpy(description, not empty),
                "urdfdom": _urdfdom_beside_input(description, robot),
            }
            out["contain"] = contained_urdf(robot, description)
        elif fmt == "mjcf":
            out["mjcf"] = wild.simulate(description, excluded)
            if robot.suffix == ".xml":
                out["contain"] = contained_mjcf(robot, description)
        else:
            out["usd"] = wild.load_usd(description, not empty)
    return out


# -- containment: numpy on MuJoCo's and trimesh's readings -------------------------------------


def outside(points: np.ndarray, shapes: list[tuple[str, np.ndarray, np.ndarray]]) -> np.ndarray:
    """Distance outside the union of ``shapes`` of each point (0 inside one), every shape
    ``(kind, parameters, 4x4 pose)`` in the points' frame; kinds: sphere (r), capsule and
    cylinder (r, half length, along z), box (half sizes), ellipsoid (semi-axes), hull (its
    (k, 4) plane equations, normal out)."""
    best = np.full(len(points), np.inf)
    for kind, p, pose in shapes:
        local = (points - pose[:3, 3]) @ pose[:3, :3]
        if kind == "sphere":
            d = np.linalg.norm(local, axis=1) - p[0]
        elif kind == "capsule":
            z = np.clip(local[:, 2], -p[1], p[1])
            d = np.linalg.norm(local - np.c_[0 * z, 0 * z, z], axis=1) - p[0]
        elif kind == "cylinder":
            radial = np.linalg.norm(local[:, :2], axis=1) - p[0]
            d = np.maximum(radial, np.abs(local[:, 2]) - p[1])
        elif kind == "box":
            d = np.max(np.abs(local) - p[:3], axis=1)
        elif kind == "ellipsoid":  # outside by the scaled radius, a bound good near the surface
            d = (np.linalg.norm(local / p[:3], axis=1) - 1.0) * np.min(p[:3])
        else:
            d = np.max(local @ p[:, :3].T + p[:, 3], axis=1)
        best = np.minimum(best, np.maximum(d, 0.0))
    return best


def _hull_planes(vertices: np.ndarray) -> np.ndarray:
    from scipy.spatial import ConvexHull

    return ConvexHull(vertices).equations


def _containment(per_body: dict[str, tuple[list[np.ndarray], list]]) -> dict:
    bodies = points = out = 0
    worst = 0.0
    for clouds, shapes in per_body.values():
        if not clouds:
            continue
        cloud = np.concatenate(clouds)
        bodies += 1
        points += len(cloud)
        if not shapes:
            out += len(cloud)
            worst = np.inf
            continue
        extent = float(np.max(np.ptp(cloud, axis=0))) or 1.0
        gap = outside(cloud, shapes)
        out += int(np.sum(gap > CONTAIN * extent + 1e-12))
        worst = max(worst, float(np.max(gap / extent)))
    return {"bodies": bodies, "vertices": points, "outside": out, "worst_relative": worst}


def _mjcf_geoms(model, mujoco, meshes: bool) -> dict[str, list]:
    """Body -> its collision geoms in the body frame: (kind, parameters, pose) (``meshes``:
    a mesh geom's vertices instead, as a (n, 3) array)."""
    from mujoco_oracle import collision_geoms

    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    kinds = {
        int(getattr(mujoco.mjtGeom, f"mjGEOM_{k.upper()}")): k
        for k in ("sphere", "capsule", "cylinder", "box", "ellipsoid", "mesh")
    }
    out: dict[str, list] = {}
    for body, geoms in collision_geoms(mujoco, model).items():
        b = int(model.geom_bodyid[geoms[0]])
        inverse = np.linalg.inv(_pose(data.xpos[b], data.xmat[b]))
        for g in geoms:
            kind = kinds.get(int(model.geom_type[g]))
            pose = inverse @ _pose(data.geom_xpos[g], data.geom_xmat[g])
            if kind == "mesh":
                m = int(model.geom_dataid[g])
                start, n = int(model.mesh_vertadr[m]), int(model.mesh_vertnum[m])
                vertices = model.mesh_vert[start : start + n] @ pose[:3, :3].T + pose[:3, 3]
                if meshes:
                    out.setdefault(body, []).append(vertices)
                else:
                    out.setdefault(body, []).append(("hull", _hull_planes(vertices), np.eye(4)))
            elif kind is not None and not meshes:
                size = np.array(model.geom_size[g], dtype=np.float64)
                out.setdefault(body, []).append((kind, size, pose))
    return out


def _pose(position, matrix) -> np.ndarray:
    pose = np.eye(4)
    pose[:3, :3] = np.asarray(matrix).reshape(3, 3)
    pose[:3, 3] = position
    return pose


def contained_mjcf(source: Path, fitted: Path) -> dict:
    import mujoco

    try:
        clouds = _mjcf_geoms(mujoco.MjModel.from_xml_path(str(source)), mujoco, meshes=True)
        shapes = _mjcf_geoms(mujoco.MjModel.from_xml_path(str(fitted)), mujoco, meshes=False)
    except Exception as exc:  # noqa: BLE001 - the row says why the oracle could not run
        return {"error": " ".join(str(exc).split())[:80]}
    return _containment({b: (c, shapes.get(b, [])) for b, c in clouds.items()})


def _urdfdom_beside_input(written: Path, source: Path) -> str:
    """urdfdom's verdict on a written URDF; a failure the input has too is the input's
    (PartNet's mobility.urdf has joint limits without ``effort``, which urdfdom refuses,
    and the writer keeps the input's joints as they are): "ok (...)" then."""
    verdict = wild.load_urdfdom(written)
    if verdict.startswith("FAIL") and wild.load_urdfdom(source) == verdict:
        return f"ok (the input fails urdfdom alike: {verdict[6:-1]})"
    return verdict


def _mesh_files(folder: Path):
    """yourdfpy's file handler with pybullet's rule first: ``package://REST`` is ``REST``
    beside the description when that file exists (``package://meshes/link0.obj`` of
    Genesis's pybullet Panda, ``package://wheel.obj``), which yourdfpy's own handler does
    not find (it fails on the second)."""
    from yourdfpy import filename_handler_magic

    def handler(fname: str) -> str:
        if fname.startswith("package://") and (folder / fname[len("package://") :]).is_file():
            return str(folder / fname[len("package://") :])
        return filename_handler_magic(fname, dir=str(folder))

    return handler


def urdf_model(path: Path, capsules: bool = False):
    """yourdfpy's model of a URDF (links, joints, collision elements, its own ``package://``
    and relative file handler), the XML read first as pybullet reads it
    (:func:`meshcol.io.urdf_lenient.read_description_xml`: pybullet_data's numbers such as
    "0.07," and its misplaced declarations), so that every URDF row has a reading. With
    ``capsules`` (an INPUT, which pybullet's ``<capsule>`` may be in: pybullet_data's
    humanoid), each capsule is read as a sphere, as meshcol's reader stands one in for
    yourdfpy: the oracle takes the input's meshes and its tree, not its primitives; an
    output's capsule stays an error."""
    import yourdfpy
    from lxml import etree

    from meshcol.io.urdf_lenient import read_description_xml

    root = read_description_xml(str(path), [])
    etree.strip_tags(root, etree.Comment)
    for capsule in root.iter("capsule") if capsules else ():
        capsule.tag = "sphere"
    return yourdfpy.URDF(
        robot=yourdfpy.URDF._parse_robot(xml_element=root),
        build_scene_graph=False,
        load_meshes=False,
        filename_handler=_mesh_files(path.parent),
        mesh_dir=str(path.parent),
    )


def _mesh_vertices(model, mesh, pose: np.ndarray) -> np.ndarray:
    """A ``<mesh>``'s vertices (trimesh's reading of the file yourdfpy's handler names, every
    object), its ``scale`` applied, at ``pose``."""
    import trimesh

    loaded = trimesh.load(model._filename_handler(mesh.filename), force="mesh")
    vertices = np.asarray(loaded.vertices, dtype=np.float64)
    if mesh.scale is not None:
        vertices = vertices * np.broadcast_to(np.asarray(mesh.scale, dtype=np.float64), (3,))
    return vertices @ pose[:3, :3].T + pose[:3, 3]


def _urdf_shape(model, element) -> tuple[str, np.ndarray, np.ndarray]:
    """A collision element of the output as ``outside`` takes it (link frame)."""
    g = element.geometry
    pose = np.eye(4) if element.origin is None else np.asarray(element.origin, dtype=np.float64)
    if g.box is not None:
        return ("box", np.asarray(g.box.size, dtype=np.float64) / 2, pose)
    if g.sphere is not None:
        return ("sphere", np.array([g.sphere.radius]), pose)
    if g.cylinder is not None:
        return ("cylinder", np.array([g.cylinder.radius, g.cylinder.length / 2]), pose)
    return ("hull", _hull_planes(_mesh_vertices(model, g.mesh, pose)), np.eye(4))


def contained_urdf(source: Path, fitted: Path) -> dict:
    """The input's collision mesh vertices (yourdfpy's elements, each mesh read by trimesh
    with its scale, in the link frame) in the output URDF's colliders (yourdfpy's reading of
    it: a ``<capsule>``, which it does not know, is an error)."""
    try:
        model = urdf_model(source, capsules=True)
        per_body: dict[str, tuple[list, list]] = {}
        for link in model.robot.links:
            for element in link.collisions:
                if element.geometry.mesh is None:
                    continue
                pose = np.eye(4) if element.origin is None else np.asarray(element.origin)
                vertices = _mesh_vertices(model, element.geometry.mesh, pose)
                per_body.setdefault(link.name, ([], []))[0].append(vertices)
        output = urdf_model(fitted)
        for link in output.robot.links:
            if link.name in per_body:
                shapes = [_urdf_shape(output, element) for element in link.collisions]
                per_body[link.name][1].extend(shapes)
    except Exception as exc:  # noqa: BLE001 - the row says why the oracle could not run
        return {"error": " ".join(str(exc).split())[:80]}
    return _containment(per_body)


# -- collision-matrix: the SRDF read here, MuJoCo as the Never oracle --------------------------


def run_matrix(robot: Path, work: Path, samples: int, configs: int) -> dict:
    srdf, report = work / "matrix.srdf", work / "matrix.json"
    code, line = wild.meshcol(
        "collision-matrix",
        str(robot),
        "--samples",
        str(samples),
        "--seed",
        "0",
        "-o",
        str(srdf),
        "--report",
        str(report),
        "--threads",
        "1",
    )
    out: dict = {"exit": code, "line": line}
    if code != 0:
        return out
    try:
        pairs = [
            (e.get("link1"), e.get("link2"), e.get("reason"))
            for e in ET.parse(srdf).getroot().iter("disable_collisions")
        ]
        links, edges, solid = (_urdf_tree if robot.suffix == ".urdf" else _mjcf_tree)(robot)
    except Exception as exc:  # noqa: BLE001 - the row says why the reader could not run
        out["srdf"] = f"FAIL ({' '.join(str(exc).split())[:80]})"
        return out
    out["disabled"] = len(pairs)
    out["srdf"] = srdf_faults(pairs, links, edges, solid) or "ok"
    out["never"] = sum(reason == "Never" for _, _, reason in pairs)
    if robot.suffix == ".xml" and configs:
        never = [(a, b) for a, b, reason in pairs if reason == "Never"]
        out["oracle"] = never_oracle(robot, never, configs, json.loads(report.read_text()))
    return out


def srdf_faults(pairs: list, links: set, edges: set, solid: set) -> list[str]:
    """What is wrong with the SRDF's pairs: a link that does not exist, a pair twice, an
    Adjacent pair not joined through links without collision geometry."""
    faults, seen = [], set()
    neighbours: dict[str, set] = {}
    for a, b in edges:
        neighbours.setdefault(a, set()).add(b)
        neighbours.setdefault(b, set()).add(a)
    for a, b, reason in pairs:
        missing = [n for n in (a, b) if n not in links]
        if missing:
            faults.append(f"no link {missing[0]!r}")
        key = (min(a, b), max(a, b))
        if key in seen:
            faults.append(f"{a}/{b} twice")
        seen.add(key)
        if reason == "Adjacent" and not _joined(a, b, neighbours, solid):
            faults.append(f"{a}/{b} Adjacent but not joined")
    return faults[:5]


def _joined(a: str, b: str, neighbours: dict, solid: set) -> bool:
    """b is reached from a through links without collision geometry only (MoveIt)."""
    todo, seen = [a], {a}
    while todo:
        here = todo.pop()
        for nxt in neighbours.get(here, ()):
            if nxt == b:
                return True
            if nxt not in seen and nxt not in solid:
                seen.add(nxt)
                todo.append(nxt)
    return False


def _urdf_tree(robot: Path) -> tuple[set, set, set]:
    robot_model = urdf_model(robot, capsules=True).robot
    links = {link.name for link in robot_model.links}
    solid = {link.name for link in robot_model.links if link.collisions}
    edges = {(joint.parent, joint.child) for joint in robot_model.joints}
    return links, edges, solid


def _mjcf_tree(robot: Path) -> tuple[set, set, set]:
    import mujoco
    from mujoco_oracle import collision_geoms

    model = mujoco.MjModel.from_xml_path(str(robot))
    names = [
        mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, b) or f"body{b}"
        for b in range(model.nbody)
    ]
    edges = {(names[int(model.body_parentid[b])], names[b]) for b in range(1, model.nbody)}
    return set(names), edges, set(collision_geoms(mujoco, model))


def oracle_configurations(mujoco, model, count: int) -> np.ndarray:
    """(count, nq): hinge and slide joints uniform within their range (an unlimited hinge over
    [-pi, pi]), the others at qpos0; joint equalities applied (MuJoCo's polynomial)."""
    rng = np.random.default_rng(ORACLE_SEED)
    qpos = np.repeat(np.asarray(model.qpos0, dtype=np.float64)[None], count, axis=0)
    hinge, slide = int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE)
    for j in range(model.njnt):
        kind, adr = int(model.jnt_type[j]), int(model.jnt_qposadr[j])
        if kind not in (hinge, slide):
            continue
        if model.jnt_limited[j]:
            lo, hi = model.jnt_range[j]
        elif kind == hinge:
            lo, hi = -np.pi, np.pi
        else:
            continue
        qpos[:, adr] = rng.uniform(lo, hi, count)
    for e in range(model.neq):
        if int(model.eq_type[e]) != int(mujoco.mjtEq.mjEQ_JOINT) or not model.eq_active0[e]:
            continue
        j1, j2 = int(model.eq_obj1id[e]), int(model.eq_obj2id[e])
        a1 = int(model.jnt_qposadr[j1])
        c = model.eq_data[e][:5]
        x = (
            0.0
            if j2 < 0
            else qpos[:, int(model.jnt_qposadr[j2])] - model.qpos0[model.jnt_qposadr[j2]]
        )
        qpos[:, a1] = model.qpos0[a1] + c[0] + c[1] * x + c[2] * x**2 + c[3] * x**3 + c[4] * x**4
    return qpos


def never_oracle(robot: Path, never: list[tuple[str, str]], count: int, report: dict) -> dict:
    """MuJoCo at ``count`` configurations: the Never pairs found colliding (within 1e-6 m);
    then each pair found is measured by MuJoCo again at collision-matrix's own samples (drawn
    again from its report: ``mujoco_oracle.matrix_qpos``): none there says the samples missed
    a rare contact ("sampling"), some says meshcol missed what its samples hold ("MISSED")."""
    import mujoco
    from mujoco_oracle import collision_geoms, least_distance, matrix_qpos

    model = mujoco.MjModel.from_xml_path(str(robot))
    data = mujoco.MjData(model)
    geoms = collision_geoms(mujoco, model)
    pairs = [
        (a, b, x, y)
        for a, b in never
        if a in geoms and b in geoms
        for x in geoms[a]
        for y in geoms[b]
    ]
    if not pairs:
        return {"configs": count, "pairs": 0, "hit": []}
    x = np.array([p[2] for p in pairs])
    y = np.array([p[3] for p in pairs])
    rbound = np.asarray(model.geom_rbound)
    hits: dict[str, list] = {}
    for q in oracle_configurations(mujoco, model, count):
        data.qpos[:] = q
        mujoco.mj_kinematics(model, data)
        centres = np.linalg.norm(data.geom_xpos[x] - data.geom_xpos[y], axis=1)
        near = np.flatnonzero(centres <= rbound[x] + rbound[y] + 1e-3)
        for k in near:
            d = mujoco.mj_geomDistance(model, data, int(x[k]), int(y[k]), 1e-3, None)
            if d <= 1e-6:
                found = hits.setdefault(pairs[k][:2], [0, 0.0])
                found[0] += 1
                found[1] = min(found[1], float(d))
    own = matrix_qpos(mujoco, model, robot, report) if hits else []
    missed = dict.fromkeys(hits, 0)
    for q in own:
        data.qpos[:] = q
        mujoco.mj_kinematics(model, data)
        for a, b in hits:
            missed[a, b] += least_distance(mujoco, model, data, geoms[a], geoms[b], 1e-3) <= 1e-6
    # a pair counts once per configuration: its geoms' hits within one configuration collapse
    return {
        "configs": count,
        "pairs": len(never),
        "hit": sorted(
            f"{k[0]}/{k[1]} (<= {v[0]} configs, {v[1]:+.2g} m; "
            f"{f'MISSED in {missed[k]}' if missed[k] else 'sampling: 0'} of its {len(own)})"
            for k, v in hits.items()
        ),
        "missed": sorted(f"{a}/{b}" for (a, b), n in missed.items() if n),
    }


# -- the rows -----------------------------------------------------------------------------------


def run_robot(
    collection: str, robot: Path, work: Path, samples: int, configs: int, shape: str = "auto"
) -> dict:
    began = time.perf_counter()
    row: dict = {
        "collection": wild.collection_label(collection),
        "robot": robot_name(collection, robot),
        "path": str(robot),
    }
    if robot.suffix == ".xml" and collection in wild.DATA_WHEELS:
        refused = wild.compiles_in_mujoco(robot)
        if refused is not None:
            row["inspect"] = "fragment"
            row["note"] = f"{wild.FRAGMENT}: MuJoCo: {refused}"
            row["seconds"] = round(time.perf_counter() - began, 1)
            return row
    row["inspect"] = run_inspect(robot, work)
    empty = "MC506" in row["inspect"].get("rules", [])
    excluded = wild.excluded_pairs(robot)
    row["fit"] = run_fit(robot, work, excluded, empty, shape)
    row["fit"]["shape"] = shape
    row["matrix"] = run_matrix(robot, work, samples, configs)
    row["seconds"] = round(time.perf_counter() - began, 1)
    return row


def failures(row: dict) -> list[str]:
    """Each failure class of a row (empty: passed)."""
    if row["inspect"] == "fragment":
        return []
    out = []
    inspect = row["inspect"]
    if inspect["line"].startswith("TRACEBACK") or inspect["exit"] not in (0, 1, 2):
        out.append(f"inspect exit {inspect['exit']}")
    fit = row["fit"]
    for fmt in ("urdf", "mjcf", "usd"):
        value = fit.get(fmt)
        if value is None:
            continue
        if isinstance(value, str):
            if not value.startswith(("ok", "skip")) and not _refusal(value):
                out.append(f"fit --to {fmt}: {value[:60]}")
        elif fmt == "urdf":
            out += [
                f"fit --to urdf: {k} {v[:50]}"
                for k, v in value.items()
                if not v.startswith(("ok", "skip"))
            ]
        elif value["mujoco"] != "ok":
            out.append(f"fit --to mjcf: MuJoCo {value['mujoco'][:50]}")
        else:
            out += ["fit --to mjcf: rest contacts"] * bool(value["rest_contacts"])
            out += ["fit --to mjcf: not finite"] * (not value["finite"])
    contain = fit.get("contain")
    if contain and (contain.get("error") or contain["outside"]):
        out.append(f"fit containment: {contain.get('error') or 'vertices outside'}")
    matrix = row["matrix"]
    if matrix["exit"] != 0 and not _refusal(f"exit {matrix['exit']}: {matrix['line']}"):
        out.append(f"collision-matrix exit {matrix['exit']}: {matrix['line'][:60]}")
    elif matrix.get("oracle", {}).get("missed"):
        out.append("collision-matrix: Never pair colliding at its own samples")
    if matrix["exit"] == 0 and matrix["srdf"] != "ok":
        out.append(
            f"SRDF: {matrix['srdf'] if isinstance(matrix['srdf'], str) else matrix['srdf'][0]}"
        )
    return out


def _refusal(said: str) -> bool:
    """An exit 2 with its one-line reason (no traceback): bad input refused, not a failure
    (the table lists each reason, to be judged true)."""
    return "exit 2: " in said and "TRACEBACK" not in said


def refusals(row: dict) -> list[str]:
    """The commands of a row that refused the robot (exit 2), with the reason."""
    if row["inspect"] == "fragment":
        return []
    out = [f"inspect: {row['inspect']['line']}"] * (row["inspect"]["exit"] == 2)
    out += [
        f"fit --to {fmt}: {value.partition('exit 2: ')[2]}"
        for fmt, value in row["fit"].items()
        if isinstance(value, str) and _refusal(value)
    ]
    matrix = row["matrix"]
    out += [f"collision-matrix: {matrix['line']}"] * (matrix["exit"] == 2)
    return out


def cells(row: dict) -> tuple[str, str, str, str]:
    inspect = row["inspect"]
    said = f"exit {inspect['exit']}" + (f": {inspect['line'][:70]}" if inspect["exit"] > 1 else "")
    fit = row["fit"]
    parts = []
    for fmt in ("urdf", "mjcf", "usd"):
        value = fit.get(fmt)
        if isinstance(value, dict) and fmt == "urdf":
            value = "ok" if all(v.startswith("ok") for v in value.values()) else str(value)
        elif isinstance(value, dict):
            value = wild.cell({"mjcf": value}, "mjcf").replace(" among excluded pairs", "")
        if value is not None:
            parts.append(f"{fmt} {'refused (exit 2)' if _refusal(value) else value}")
    contain = fit.get("contain")
    if contain:
        parts.append(
            f"outside {contain['outside']}/{contain['vertices']}"
            if "error" not in contain
            else f"contain error {contain['error']}"
        )
    matrix = row["matrix"]
    if matrix["exit"] != 0:
        srdf = f"exit {matrix['exit']}: {matrix['line'][:70]}"
    else:
        srdf = (
            f"{matrix.get('disabled', '?')} disabled ({matrix.get('never', '?')} Never), "
            f"SRDF {matrix['srdf']}"
        )
    oracle = matrix.get("oracle")
    hits = (
        "-"
        if oracle is None
        else f"{len(oracle['hit'])} of {oracle['pairs']}"
        + (f": {'; '.join(oracle['hit'][:2])}" if oracle["hit"] else "")
    )
    return said, "; ".join(parts), srdf, hits


def table(rows: list[dict]) -> str:
    lines = [
        "| collection | robot | inspect | fit (consumers; vertices outside) | collision-matrix "
        "| Never pairs MuJoCo hits | ok | s |",
        "| --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for row in rows:
        if row["inspect"] == "fragment":
            continue
        said, fit, srdf, hits = cells(row)
        ok = "NO: " + ", ".join(failures(row)) if failures(row) else "yes"
        if refusals(row) and not failures(row):
            ok = "refused (exit 2): " + refusals(row)[0].split(": ", 1)[1][-90:]
        lines.append(
            f"| {row['collection']} | {row['robot']} | {said} | {fit} | {srdf} | {hits} | {ok} "
            f"| {row['seconds']} |"
        )
    lines += ["", summary(rows)]
    return "\n".join(lines)


def summary(rows: list[dict]) -> str:
    """Per collection: robots run, passed, each failure class with its count."""
    lines = [
        "| collection | robots | passed | refused (exit 2) | failures (class: count) "
        "| Never pairs hit |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    by: dict[str, list[dict]] = {}
    for row in rows:
        if row["inspect"] != "fragment":
            by.setdefault(row["collection"], []).append(row)
    for collection, group in by.items():
        classes: dict[str, int] = {}
        for row in group:
            for name in {f.split(":")[0] for f in failures(row)}:
                classes[name] = classes.get(name, 0) + 1
        oracles = [r["matrix"]["oracle"] for r in group if r["matrix"].get("oracle")]
        hit = sum(len(o["hit"]) for o in oracles)
        pairs = sum(o["pairs"] for o in oracles)
        lines.append(
            f"| {collection} | {len(group)} | "
            f"{sum(not failures(r) and not refusals(r) for r in group)} | "
            f"{sum(bool(refusals(r)) and not failures(r) for r in group)} | "
            f"{', '.join(f'{k}: {v}' for k, v in sorted(classes.items())) or '-'} | "
            f"{hit} of {pairs} ({len(oracles)} MJCF robots) |"
        )
    return "\n".join(lines)


def _row_in_scratch(
    collection: str, robot: Path, samples: int, configs: int, shape: str = "auto"
) -> dict:
    with tempfile.TemporaryDirectory() as work:
        return run_robot(collection, robot, Path(work), samples, configs, shape)


def isolated_row(
    collection: str, robot: Path, samples: int, configs: int, shape: str = "auto"
) -> dict:
    from concurrent.futures import ProcessPoolExecutor

    with ProcessPoolExecutor(max_workers=1, max_tasks_per_child=1) as pool:
        return pool.submit(_row_in_scratch, collection, robot, samples, configs, shape).result()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--only", choices=sorted(wild.COLLECTIONS), action="append")
    parser.add_argument("--limit", type=int, default=None, help="robots per collection")
    parser.add_argument(
        "--match", action="append", help="only robots of this file name (or FOLDER/NAME)"
    )
    parser.add_argument("--json", type=Path, default=None, help="every row, as JSON")
    parser.add_argument("--samples", type=int, default=1000, help="collision-matrix samples")
    parser.add_argument("--configs", type=int, default=300, help="Never oracle configurations")
    parser.add_argument(
        "--shape",
        default="auto",
        choices=["auto", "capsule", "box", "sphere", "cylinder"],
        help="fit's --shape",
    )
    parser.add_argument("--timeout", type=float, default=300.0, help="seconds per command")
    parser.add_argument("--table", type=Path, nargs="+", default=None)
    args = parser.parse_args()
    wild.TIMEOUT = args.timeout
    if args.table:
        merged: dict[str, dict] = {}  # a later file's row of the same robot wins
        for file in args.table:
            merged.update(
                (row["path"], row) for row in json.loads((wild.ORIGIN / file).read_text())
            )
        print(table(list(merged.values())))
        return 0
    rows = []
    for collection in args.only or wild.COLLECTIONS:
        robots = wild.COLLECTIONS[collection]()
        if args.match:
            robots = [
                r
                for r in robots
                if r.name in args.match or f"{r.parent.name}/{r.name}" in args.match
            ]
        for robot in robots[: args.limit]:
            row = isolated_row(collection, robot, args.samples, args.configs, args.shape)
            said = "ok" if not failures(row) else "NO: " + ", ".join(failures(row))
            print(f"{collection} {robot.name}: {said} ({row['seconds']} s)", file=sys.stderr)
            rows.append(row)
            if args.json is not None:
                (wild.ORIGIN / args.json).write_text(json.dumps(rows, indent=1) + "\n")
    print(table(rows))
    return 0 if not any(failures(row) for row in rows) else 1


if __name__ == "__main__":
    os.environ.setdefault("PYTHONHASHSEED", "0")
    with tempfile.TemporaryDirectory() as scratch:
        os.chdir(scratch)  # MuJoCo writes MUJOCO_LOG.TXT into the working folder
        sys.exit(main())
