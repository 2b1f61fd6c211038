"""Capsules in a URDF written (``--to urdf``): URDF has none, so each is written as the same
solid in standard elements, a ``<cylinder>`` and a ``<sphere>`` at each end
(:mod:`meshcol.io.urdf_write`), or as ``<capsule>`` with ``--urdf-capsules extension``.

The oracles are the consumers themselves (urdfdom's ``check_urdf``, yourdfpy, urdf_parser_py,
the ROS Python parser, pybullet, MuJoCo's URDF importer; each skipped with the reason when
missing: urdfdom drops a ``<capsule>`` element, yourdfpy and urdf_parser_py refuse the file)
and the geometry: meshcol's reading of the file written
holds a cylinder and two spheres whose union is the fitted capsule (the fit oracles' signed
distances of tests/fit_oracle.py), so it holds every vertex the capsule held.
"""

from __future__ import annotations

import contextlib
import io
import os
from pathlib import Path

import numpy as np
import pytest
from fit_oracle import signed_distances
from test_robot_write import run

from meshcol.types import Capsule, Cylinder

pytest.importorskip("yourdfpy")
etree = pytest.importorskip("lxml.etree")

ARM = Path(__file__).resolve().parents[2] / "samples" / "robot" / "arm.urdf"
#: The sample arm's elbow is outside its limits at zero: held where the tests want it.
ELBOW = ("--joint", "elbow=1.0")

#: A link whose mesh a capsule fits (a rod along x), a named element beside a kept capsule
#: (at an origin, turned) and a kept capsule of length 0 (a ball).
ROD_URDF = """\
<?xml version="1.0"?>
<robot name="rods">
  <link name="base">
    <collision name="rod">
      <origin xyz="0 0 0.1" rpy="0 0 0.3"/>
      <geometry><mesh filename="rod.obj"/></geometry>
    </collision>
    <collision name="post"><origin xyz="0.3 0 0" rpy="0.4 0 0"/><geometry><capsule radius="0.02" length="0.2"/></geometry></collision>
  </link>
  <link name="tip">
    <collision><geometry><capsule radius="0.03" length="0"/></geometry></collision>
  </link>
  <joint name="j" type="revolute"><parent link="base"/><child link="tip"/><origin xyz="0 0 0.5"/>
    <axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
</robot>
"""


@pytest.fixture
def rods(tmp_path: Path) -> Path:
    import trimesh

    rod = trimesh.creation.capsule(height=0.4, radius=0.05, count=[16, 16])
    rod.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [0, 1, 0]))
    rod.export(tmp_path / "rod.obj")
    (tmp_path / "rods.urdf").write_text(ROD_URDF)
    return tmp_path / "rods.urdf"


def fitted(robot: Path, out: Path, *args: str) -> Path:
    """``meshcol fit ROBOT --shape capsule --out-dir OUT``: the URDF written."""
    code, _, err = run("fit", str(robot), "--out-dir", str(out), "--shape", "capsule", *args)
    assert code == 0, err
    return out / (robot.stem + ".urdf")


# -- the consumers --------------------------------------------------------------------------


def _yourdfpy(path: Path) -> None:
    import yourdfpy

    model = yourdfpy.URDF.load(str(path), load_collision_meshes=True)
    assert any(link.collisions for link in model.robot.links)


def _urdf_parser_py(path: Path) -> None:
    urdf = pytest.importorskip("urdf_parser_py.urdf", reason="urdf-parser-py is not installed")
    with contextlib.redirect_stderr(io.StringIO()):  # it prints what it does not know
        model = urdf.URDF.from_xml_string(path.read_bytes())
    assert any(link.collisions for link in model.links)


def _pybullet(path: Path) -> None:
    pybullet = pytest.importorskip("pybullet", reason="pybullet is not installed (robots-wild)")
    client = pybullet.connect(pybullet.DIRECT)
    try:
        body = pybullet.loadURDF(str(path), useFixedBase=True, physicsClientId=client)
        shapes = pybullet.getCollisionShapeData(body, 0, physicsClientId=client)
        assert shapes
    finally:
        pybullet.disconnect(client)


def _mujoco(path: Path) -> None:
    mujoco = pytest.importorskip("mujoco", reason="mujoco is not installed")
    model = mujoco.MjModel.from_xml_path(str(path))
    assert model.ngeom > 0


def _urdfdom(path: Path) -> None:
    """ROS's own parser, urdfdom, by its ``check_urdf`` (Debian's liburdfdom-tools): version
    3.0.1 drops a ``<capsule>`` collision element with "Unknown geometry type 'capsule'"."""
    import shutil
    import subprocess

    if shutil.which("check_urdf") is None:
        pytest.skip("check_urdf is not installed (liburdfdom-tools)")
    done = subprocess.run(["check_urdf", str(path)], capture_output=True, text=True, check=False)
    said = done.stdout + done.stderr
    assert done.returncode == 0 and "Successfully Parsed XML" in said, said
    assert "Error" not in said, said


CONSUMERS = {
    "urdfdom": _urdfdom,
    "yourdfpy": _yourdfpy,
    "urdf_parser_py": _urdf_parser_py,
    "pybullet": _pybullet,
    "mujoco": _mujoco,
}


@pytest.mark.parametrize("consumer", list(CONSUMERS))
@pytest.mark.parametrize("shape", ["capsule", "auto"])
def test_every_urdf_reader_loads_the_capsules_written(tmp_path, consumer, shape) -> None:
    """The sample arm's links fit capsules (``auto`` takes them too): the URDF written loads
    in each consumer (main wrote ``<capsule>``, which yourdfpy and urdf_parser_py refuse)."""
    out = tmp_path / "out"
    code, _, err = run("fit", str(ARM), "--out-dir", str(out), "--shape", shape, *ELBOW)
    assert code == 0, err
    written = out / "arm.urdf"
    assert "<capsule" not in written.read_text()
    assert "<cylinder" in written.read_text()
    cwd = os.getcwd()
    os.chdir(out)  # pybullet and MuJoCo's log: files of the output folder
    try:
        CONSUMERS[consumer](written)
    finally:
        os.chdir(cwd)


def test_the_extension_form_is_the_capsule_element_pybullet_reads(tmp_path) -> None:
    """``--urdf-capsules extension``: one ``<capsule>`` per fit, which pybullet and MuJoCo
    load and yourdfpy refuses (why it is not the default)."""
    import yourdfpy

    written = fitted(ARM, tmp_path / "out", *ELBOW, "--urdf-capsules", "extension")
    root = etree.fromstring(written.read_bytes())
    assert len(root.findall("link/collision/geometry/capsule")) == 2
    assert not root.findall("link[@name='upper_arm']/collision/geometry/sphere")
    with pytest.raises(ValueError, match="Unknown tag: capsule"):
        yourdfpy.URDF.load(str(written))
    _mujoco(written)
    _pybullet(written)


# -- the geometry ---------------------------------------------------------------------------


def _elements(path: Path) -> dict[str, list]:
    """meshcol's reading of a URDF (what check and inspect read): each link's collision
    elements, (primitive or None, origin)."""
    from meshcol.io.robot import load_robot

    elements: list = []
    load_robot(path, elements=elements)
    out: dict[str, list] = {}
    for e in elements:
        out.setdefault(e.link, []).append((e.primitive, np.asarray(e.origin)))
    return out


def _outside(points: np.ndarray, parts: list) -> np.ndarray:
    """How far each point (link frame) lies outside the union of ``parts`` (the fit
    oracles' distances: <= 0 inside; the sign is exact, the value a bound for a cylinder)."""
    return np.min([signed_distances(p, (points - o[:3, 3]) @ o[:3, :3]) for p, o in parts], axis=0)


def test_the_cylinder_and_spheres_are_the_capsule(rods: Path, tmp_path: Path) -> None:
    """Every element the extension writes as a capsule, the default writes as a cylinder
    and two spheres that meshcol reads back as the same solid: points around the capsule,
    inside and outside, are inside the union exactly when inside the capsule, and the input
    mesh's vertices are inside both."""
    import trimesh

    standard = _elements(fitted(rods, tmp_path / "std"))
    extension = _elements(fitted(rods, tmp_path / "ext", "--urdf-capsules", "extension"))
    rng = np.random.default_rng(7)
    for link, parts in extension.items():
        split = standard[link]
        capsules = [(p, o) for p, o in parts if isinstance(p, Capsule) and p.length > 0]
        cylinders = [p for p, _ in split if isinstance(p, Cylinder)]
        assert len(cylinders) == len(capsules)
        assert len(split) == len(parts) + 2 * len(capsules)
        for capsule, origin in capsules:
            reach = capsule.radius + capsule.length
            points = origin[:3, 3] + rng.uniform(-reach, reach, (4000, 3))
            want = _outside(points, parts)  # the link's solid: every part of it
            got = _outside(points, split)
            far = np.abs(want) > 1e-9  # the sign of points on the surface is rounding's
            assert far.sum() > 3900 and 0 < (want < 0).sum() < 3000
            assert np.array_equal(want[far] > 0, got[far] > 0)
    rod = trimesh.load(rods.parent / "rod.obj", force="mesh")
    pose = trimesh.transformations.euler_matrix(0, 0, 0.3)
    pose[:3, 3] = [0, 0, 0.1]
    vertices = np.asarray(rod.vertices) @ pose[:3, :3].T + pose[:3, 3]
    assert _outside(vertices, standard["base"]).max() <= 1e-12
    assert _outside(vertices, extension["base"]).max() <= 1e-12


def test_names_origins_and_kept_capsules(rods: Path, tmp_path: Path) -> None:
    """A named capsule element becomes NAME_00 (the cylinder, at the capsule's origin),
    NAME_01 and NAME_02 (the spheres at -z and +z of its axis): distinct, and the same run
    after run. A kept ``<capsule>`` is written the same way from its own text; one of
    length 0 is its sphere, one element."""
    written = fitted(rods, tmp_path / "a")
    assert written.read_bytes() == fitted(rods, tmp_path / "b").read_bytes()
    root = etree.fromstring(written.read_bytes())
    base = root.findall("link[@name='base']/collision")
    names = [c.get("name") for c in base]
    assert names == ["rod_00", "rod_01", "rod_02", "post_00", "post_01", "post_02"]
    kinds = [c.find("geometry")[0].tag for c in base]
    assert kinds == ["cylinder", "sphere", "sphere"] * 2
    post = base[3:]
    assert post[0].find("origin").attrib == {"xyz": "0.3 0 0", "rpy": "0.4 0 0"}
    assert post[0].find("geometry/cylinder").attrib == {"radius": "0.02", "length": "0.2"}
    axis = np.array([0.0, -np.sin(0.4), np.cos(0.4)])  # z turned by roll 0.4
    for end, sign in zip(post[1:], (-1, 1)):
        xyz = [float(v) for v in end.find("origin").get("xyz").split()]
        np.testing.assert_allclose(xyz, [0.3, 0, 0] + sign * 0.1 * axis, atol=1e-15)
        assert end.find("geometry/sphere").attrib == {"radius": "0.02"}
    tip = root.findall("link[@name='tip']/collision")
    assert len(tip) == 1 and tip[0].find("geometry/sphere").attrib == {"radius": "0.03"}
    # the extension keeps the input's capsule as it was, the ball a sphere again
    kept = etree.fromstring(
        fitted(rods, tmp_path / "c", "--urdf-capsules", "extension").read_bytes()
    )
    source = etree.fromstring(rods.read_bytes())
    path = "link[@name='base']/collision[2]"
    assert etree.tostring(kept.find(path)) == etree.tostring(source.find(path))
    tip = kept.findall("link[@name='tip']/collision")
    assert len(tip) == 1 and tip[0].find("geometry/sphere").attrib == {"radius": "0.03"}


def test_hull_writes_the_kept_capsules_in_the_standard_form(rods: Path, tmp_path: Path) -> None:
    """``hull`` rebuilds the meshes and keeps the primitives: a kept capsule reaches the
    URDF written as a cylinder and two spheres too (one mechanism for every writer)."""
    import yourdfpy

    out = tmp_path / "out"
    code, _, err = run("hull", str(rods), "--out-dir", str(out))
    assert code == 0, err
    text = (out / "rods.urdf").read_text()
    assert "<capsule" not in text and text.count("<sphere") == 3
    yourdfpy.URDF.load(str(out / "rods.urdf"), load_collision_meshes=True)


def test_mjcf_from_a_urdf_keeps_capsule_geoms(rods: Path, tmp_path: Path) -> None:
    """MuJoCo has capsules: ``--to mjcf`` writes each as one capsule geom, not three."""
    mujoco = pytest.importorskip("mujoco")
    out = tmp_path / "out"
    code, _, err = run(
        "fit", str(rods), "--out-dir", str(out), "--shape", "capsule", "--to", "mjcf"
    )
    assert code == 0, err
    model = mujoco.MjModel.from_xml_path(str(out / "rods.xml"))
    kinds = [int(t) for t in model.geom_type]
    assert kinds.count(int(mujoco.mjtGeom.mjGEOM_CAPSULE)) == 2
    assert kinds.count(int(mujoco.mjtGeom.mjGEOM_CYLINDER)) == 0


def test_urdf_capsules_needs_a_urdf_written(rods: Path, tmp_path: Path) -> None:
    message = (
        "meshcol: error: --urdf-capsules applies to a URDF written: one URDF input, "
        "--out-dir and --to urdf (see 'meshcol {} -h')"
    )
    for args in (
        ("fit", str(rods), "--out-dir", str(tmp_path / "a"), "--to", "mjcf"),
        ("hull", str(rods)),
        ("decompose", str(rods), "--out-dir", str(tmp_path / "b"), "--to", "glb"),
    ):
        code, _, err = run(*args, "--urdf-capsules", "extension")
        assert (code, err.splitlines()) == (2, [message.format(args[0])])


def test_check_sees_the_same_solid_in_both_forms(tmp_path: Path) -> None:
    """``meshcol check`` of the sample arm's URDF written both ways (every link pair, the
    adjacent ones too): the same pairs, statuses and signed distances (a capsule against a
    neighbour and its cylinder-and-spheres against it are the same solid)."""
    import json

    reports = []
    for form in ("standard", "extension"):
        written = fitted(ARM, tmp_path / form, *ELBOW, "--urdf-capsules", form)
        report = tmp_path / f"{form}.json"
        code, _, err = run(
            "check", str(written), *ELBOW, "--include-adjacent", "--report", str(report)
        )
        assert code in (0, 1), err
        pairs = json.loads(report.read_text())["pairs"]
        reports.append({(p["body_a"], p["body_b"]): p for p in pairs})
    standard, extension = reports
    assert sorted(standard) == sorted(extension) and len(standard) >= 5
    capsules = {"upper_arm", "forearm"}
    assert any(capsules & set(key) for key in standard)
    for key, pair in standard.items():
        assert pair["status"] == extension[key]["status"], key
        assert pair["signed_distance"] == pytest.approx(
            extension[key]["signed_distance"], abs=1e-12
        )


def test_a_kept_capsule_at_the_link_origin_exact_text(tmp_path: Path) -> None:
    """A kept capsule with no ``<origin>``: the spheres get one each, on lines of their own
    as the file is indented (the exact text written)."""
    (tmp_path / "n.urdf").write_text(
        '<robot name="n">\n  <link name="a">\n    <collision name="c">\n      <geometry>\n'
        '        <capsule radius="0.1" length="0.4"/>\n      </geometry>\n    </collision>\n'
        "  </link>\n</robot>\n"
    )
    code, _, err = run("hull", str(tmp_path / "n.urdf"), "--out-dir", str(tmp_path / "o"))
    assert code == 0, err
    element = (
        '    <collision name="c_{k}">\n{origin}      <geometry>\n        {shape}\n'
        "      </geometry>\n    </collision>\n"
    )
    assert (tmp_path / "o" / "n.urdf").read_text() == (
        '<?xml version="1.0" encoding="utf-8"?>\n<robot name="n">\n  <link name="a">\n'
        + element.format(k="00", origin="", shape='<cylinder radius="0.1" length="0.4"/>')
        + element.format(
            k="01", origin='      <origin xyz="0 0 -0.2"/>\n', shape='<sphere radius="0.1"/>'
        )
        + element.format(
            k="02", origin='      <origin xyz="0 0 0.2"/>\n', shape='<sphere radius="0.1"/>'
        )
        + "  </link>\n</robot>\n"
    )
