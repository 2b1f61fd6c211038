"""``meshcol decompose``: layouts, determinism, cache, jobs, timeouts, kills, errors."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import trimesh
from click.testing import CliRunner
from conftest import FAST_DECOMPOSE

from meshcol.cli import main

FAST = FAST_DECOMPOSE


@pytest.fixture(scope="module")
def meshes(tmp_path_factory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("inputs")
    shapes = {
        "torus": trimesh.creation.torus(1.0, 0.3, major_sections=24, minor_sections=12),
        "box": trimesh.creation.box(extents=(2, 1, 1)),
        "flat": trimesh.creation.box(extents=(1, 1, 0)),
        "l_shape": trimesh.creation.box(bounds=[(0, 0, 0), (2, 1, 1)]).union(
            trimesh.creation.box(bounds=[(0, 0, 0.5), (1, 1, 2)]), engine="manifold"
        ),
    }
    paths = {}
    for name, mesh in shapes.items():
        paths[name] = folder / f"{name}.obj"
        mesh.export(paths[name])
    paths["empty"] = folder / "empty.obj"
    paths["empty"].write_text("# nothing\n")
    return paths


def run(args: list[str]) -> tuple[int, str, str]:
    """``meshcol decompose ARGS`` with its report on stdout (``--report -`` unless given)."""
    report = [] if "--report" in args else ["--report", "-"]
    result = CliRunner().invoke(main, ["decompose", *args, *report])
    if result.exception and not isinstance(result.exception, SystemExit):
        raise result.exception
    return result.exit_code, result.stdout, result.stderr


def files(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir()) if p.is_file()}


def object_names(path: Path) -> list[str]:
    return [line[2:] for line in path.read_text().splitlines() if line.startswith("o ")]


def test_parts_layout_and_report(meshes, tmp_path) -> None:
    out = tmp_path / "out"
    code, stdout, _ = run([str(meshes["torus"]), "-o", str(out), "--no-cache", *FAST])
    assert code == 0
    report = json.loads(stdout)
    (entry,) = report["files"]
    assert entry["status"] == "ok" and entry["message"] is None
    (body,) = entry["bodies"]
    n = body["metrics"]["parts"]
    assert n >= 2
    assert body["outputs"] == [f"torus_{i:02d}.obj" for i in range(n)]
    assert sorted(files(out)) == body["outputs"]
    for name in body["outputs"]:
        part = trimesh.load(out / name, force="mesh")
        assert part.is_convex and part.is_watertight and part.volume > 0
    assert body["metrics"]["vertices_per_part"] == [
        len(trimesh.load(out / p).vertices) for p in body["outputs"]
    ]
    assert report["summary"] == {
        "bodies": 1,
        "failed": 0,
        "files": 1,
        "hausdorff_exceeded": 0,
        "ok": 1,
        "parts": n,
        "parts_exceeded": 0,
        "timeout": 0,
    }


def test_combined_ucx_and_glb_layouts(meshes, tmp_path) -> None:
    base = [str(meshes["l_shape"]), "--cache-dir", str(tmp_path / "cache"), *FAST]
    code, stdout, _ = run([*base, "-o", str(tmp_path / "c"), "--layout", "combined"])
    assert code == 0
    n = json.loads(stdout)["summary"]["parts"]
    assert n >= 2
    assert object_names(tmp_path / "c" / "l_shape.obj") == [f"l_shape_{i:02d}" for i in range(n)]
    code, _, _ = run([*base, "-o", str(tmp_path / "u"), "--layout", "ucx"])
    assert code == 0
    assert object_names(tmp_path / "u" / "l_shape_ucx.obj") == [
        f"UCX_l_shape_{i:02d}" for i in range(n)
    ]
    code, _, _ = run([*base, "-o", str(tmp_path / "g"), "--layout", "combined", "--format", "glb"])
    assert code == 0
    scene = trimesh.load(tmp_path / "g" / "l_shape.glb")
    assert sorted(scene.graph.nodes_geometry) == [f"l_shape_{i:02d}" for i in range(n)]
    code, _, _ = run([*base, "-o", str(tmp_path / "p")])
    assert code == 0
    for node in scene.graph.nodes_geometry:
        glb_part = scene.geometry[scene.graph[node][1]]
        obj_part = trimesh.load(tmp_path / "p" / f"{node}.obj")
        assert np.allclose(glb_part.vertices, obj_part.vertices, atol=1e-6)  # float32 in glTF
        assert np.array_equal(glb_part.faces, obj_part.faces)
    code, _, _ = run([*base, "-o", str(tmp_path / "pg"), "--format", "glb"])
    assert code == 0
    assert sorted(files(tmp_path / "pg")) == [f"l_shape_{i:02d}.glb" for i in range(n)]


def test_same_input_gives_identical_bytes_and_cache_hit_is_fast(meshes, tmp_path) -> None:
    cache = tmp_path / "cache"
    args = [str(meshes["torus"]), "--cache-dir", str(cache), "--layout", "combined", *FAST]
    start = time.perf_counter()
    code, first, _ = run([*args, "-o", str(tmp_path / "a")])
    miss = time.perf_counter() - start
    code2, _, _ = run(
        [
            str(meshes["torus"]),
            "--no-cache",
            "--layout",
            "combined",
            *FAST,
            "-o",
            str(tmp_path / "b"),
        ]
    )
    start = time.perf_counter()
    code3, third, _ = run([*args, "-o", str(tmp_path / "c")])
    hit = time.perf_counter() - start
    assert code == code2 == code3 == 0
    assert files(tmp_path / "a") == files(tmp_path / "b") == files(tmp_path / "c")
    assert json.loads(first)["files"][0]["bodies"][0]["from_cache"] is False
    assert json.loads(third)["files"][0]["bodies"][0]["from_cache"] is True
    assert hit < miss / 5
    assert len(list(cache.rglob("*.npz"))) == 1


def test_jobs_two_gives_the_same_output_as_jobs_one(meshes, tmp_path) -> None:
    inputs = [str(meshes["torus"]), str(meshes["l_shape"]), str(meshes["box"])]
    code1, r1, _ = run([*inputs, "--no-cache", "-o", str(tmp_path / "j1"), "--jobs", "1", *FAST])
    code2, r2, _ = run([*inputs, "--no-cache", "-o", str(tmp_path / "j2"), "--jobs", "2", *FAST])
    assert code1 == code2 == 0
    assert files(tmp_path / "j1") == files(tmp_path / "j2")
    strip = lambda report: [{k: v for k, v in f.items() if k != "seconds"} for f in report["files"]]
    assert strip(json.loads(r1)) == strip(json.loads(r2))


def test_timeout_stops_one_file_and_the_others_finish(meshes, corpus, tmp_path) -> None:
    slow = corpus / "coacd-examples" / "Octocat-v2.obj"  # minutes with CoACD's defaults
    start = time.perf_counter()
    code, stdout, stderr = run(
        [
            str(slow),
            str(meshes["box"]),
            "--no-cache",
            "-o",
            str(tmp_path / "o"),
            "--jobs",
            "2",
            "--timeout",
            "5",
            "--preprocess",
            "off",
        ]
    )
    assert time.perf_counter() - start < 60
    assert code == 1
    report = json.loads(stdout)
    assert [f["status"] for f in report["files"]] == ["timeout", "ok"]
    assert report["files"][0]["message"] == "timed out after 5 s"
    assert report["summary"]["timeout"] == 1 and report["summary"]["ok"] == 1
    assert f"meshcol: timeout: {slow}: timed out after 5 s" in stderr
    assert sorted(files(tmp_path / "o")) == ["box_00.obj"]


def test_killed_run_leaves_no_cache_entry_or_output(corpus, tmp_path) -> None:
    slow = corpus / "coacd-examples" / "Octocat-v2.obj"
    cache, out = tmp_path / "cache", tmp_path / "out"
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "meshcol",
            "decompose",
            str(slow),
            "-o",
            str(out),
            "--cache-dir",
            str(cache),
            "--jobs",
            "2",
            "--timeout",
            "600",
            "--preprocess",
            "off",
        ],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,
    )
    try:
        time.sleep(4.0)
        assert proc.poll() is None, "the run finished before it could be killed"
    finally:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
    assert [p for p in cache.rglob("*") if p.is_file()] == []  # rglob of a missing folder is empty
    assert [p for p in out.rglob("*") if p.is_file()] == []


@pytest.mark.slow
def test_max_hausdorff_fails_the_run(meshes, tmp_path) -> None:
    args = [
        str(meshes["torus"]),
        "--cache-dir",
        str(tmp_path / "cache"),
        "-o",
        str(tmp_path / "o"),
        *FAST,
    ]
    # --search off: the limit is only checked (without it the run would search for it).
    code, stdout, _ = run([*args, "--max-hausdorff", "1e-9", "--search", "off"])
    assert code == 1
    report = json.loads(stdout)
    assert report["files"][0]["bodies"][0]["hausdorff_ok"] is False
    assert report["summary"]["hausdorff_exceeded"] == 1
    code, stdout, _ = run([*args, "--max-hausdorff", "10", "--search", "off"])
    assert code == 0 and json.loads(stdout)["summary"]["hausdorff_exceeded"] == 0


@pytest.mark.slow
def test_csv_report(meshes, tmp_path) -> None:
    report = tmp_path / "r.csv"
    code, stdout, _ = run(
        [str(meshes["box"]), "--no-cache", "-o", str(tmp_path / "o"), "--report", str(report)]
    )
    assert code == 0 and stdout == ""
    header, row = report.read_text().splitlines()
    assert header.startswith("path,body,status,message,parts,vertices_per_part,")
    assert row.startswith(f"{meshes['box']},box,ok,,1,8,")


def test_vhacd_engine(meshes, tmp_path) -> None:
    pytest.importorskip("vhacdx")
    code, stdout, _ = run(
        [
            str(meshes["torus"]),
            "--no-cache",
            "-o",
            str(tmp_path / "o"),
            "--engine",
            "vhacd",
            "--max-hulls",
            "8",
            "--resolution",
            "20000",
        ]
    )
    assert code == 0
    body = json.loads(stdout)["files"][0]["bodies"][0]
    assert body["engine"] == "vhacd" and 1 <= body["metrics"]["parts"] <= 8


def test_corpus_torus_and_octocat(corpus, tmp_path) -> None:
    inputs = [corpus / "trimesh-models" / "torus.STL", corpus / "coacd-examples" / "Octocat-v2.obj"]
    code, stdout, _ = run(
        [
            *map(str, inputs),
            "--no-cache",
            "-o",
            str(tmp_path / "o"),
            "--preprocess",
            "off",
            "--jobs",
            "2",
            *FAST,
        ]
    )
    assert code == 0
    for entry in json.loads(stdout)["files"]:
        (body,) = entry["bodies"]
        m = body["metrics"]
        assert m["parts"] >= 2
        assert m["uncovered_fraction"] < 0.02
        assert 0.98 < m["volume_ratio"] < 2.0  # coarse threshold 0.2: loose hulls


def test_corpus_bottle_is_repaired(corpus, tmp_path) -> None:
    code, stdout, _ = run(
        [
            str(corpus / "coacd-examples" / "Bottle.obj"),
            "--no-cache",
            "-o",
            str(tmp_path / "o"),
            "--threshold",
            "0.3",
            "--resolution",
            "300",
            "-E",
            "preprocess_resolution=20",
            "-E",
            "mcts_iterations=10",
            "-E",
            "mcts_nodes=4",
            "-E",
            "mcts_max_depth=1",
        ]
    )
    assert code == 0
    body = json.loads(stdout)["files"][0]["bodies"][0]
    assert body["repaired"] is True and body["params"]["preprocess_mode"] == "on"
    assert body["notes"] == [
        "input is not a closed manifold: CoACD's preprocessing rebuilt it before decomposing"
    ]


@pytest.mark.slow
def test_corpus_snowflake_thin_features(corpus, tmp_path) -> None:
    code, stdout, _ = run(
        [
            str(corpus / "coacd-examples" / "SnowFlake.obj"),
            "--no-cache",
            "-o",
            str(tmp_path / "o"),
            "--preprocess",
            "off",
            "--threshold",
            "0.02",
            "--resolution",
            "500",
            "-E",
            "mcts_iterations=20",
            "-E",
            "mcts_nodes=8",
            "-E",
            "mcts_max_depth=2",
        ]
    )
    assert code == 0
    m = json.loads(stdout)["files"][0]["bodies"][0]["metrics"]
    assert m["parts"] >= 20
    assert m["uncovered_fraction"] < 0.02
    assert m["volume_ratio"] < 1.2


# ---------------------------------------------------------------------------- errors


def test_bad_inputs_exit_2_with_one_line(meshes, tmp_path) -> None:
    out = str(tmp_path / "o")
    cases = {
        str(tmp_path / "missing.obj"): "file not found",
        str(meshes["empty"]): "mesh has no faces",
        str(meshes["flat"]): "mesh is flat (all vertices lie in one plane): it encloses no volume",
    }
    for path, message in cases.items():
        code, stdout, stderr = run([path, "-o", out, "--no-cache"])
        assert code == 2
        assert stderr == f"meshcol: error: {path}: {message}\n"
        assert stdout == ""
    assert not Path(out).exists() or not files(Path(out))


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--layout", "ucx", "--format", "glb"], "--layout ucx writes OBJ only: drop --format glb"),
        (["--no-cache", "--cache-dir", "x"], "--cache-dir and --no-cache exclude each other"),
        (["--engine", "vhacd", "--threshold", "0.1"], "--threshold applies to --engine coacd only"),
        (
            ["-E", "bogus=1"],
            "meshcol: error: invalid value for '--engine-option': unknown coacd option 'bogus': "
            "known options are",
        ),
        (
            ["-E", "mcts_nodes"],
            "meshcol: error: invalid value for '--engine-option' / '-E': expected KEY=VALUE, got "
            "'mcts_nodes'",
        ),
        (
            ["--max-vertices", "3"],
            "meshcol: error: invalid value for '--max-vertices': 3 is not in the range x>=4 "
            "(see 'meshcol decompose -h')",
        ),
        (
            ["--threshold", "0"],
            "meshcol: error: invalid value for '--threshold': 0.0 is not in the range 0<x<=1",
        ),
    ],
)
def test_usage_errors(meshes, tmp_path, extra, message) -> None:
    code, _, stderr = run([str(meshes["box"]), "-o", str(tmp_path / "o"), *extra])
    assert code == 2
    assert message in stderr


@pytest.mark.slow  # 1-2 s: the fast lane (make test-fast) stays under 40 s
def test_same_stem_in_two_folders_gets_two_names(meshes, tmp_path) -> None:
    other = tmp_path / "again"
    other.mkdir()
    copy = other / "box.obj"
    copy.write_bytes(meshes["box"].read_bytes())
    code, stdout, _ = run([str(meshes["box"]), str(copy), "-o", str(tmp_path / "o"), "--no-cache"])
    assert code == 0
    names = [b["name"] for f in json.loads(stdout)["files"] for b in f["bodies"]]
    assert names == ["box", "box#2"]
    assert sorted(files(tmp_path / "o")) == ["box_00.obj", "box_2_00.obj"]
    first, second = (files(tmp_path / "o")[n].decode() for n in ("box_00.obj", "box_2_00.obj"))
    assert first.replace("o box_00", "o box_2_00") == second


def test_clashing_output_names_are_refused(meshes, tmp_path) -> None:
    clash = tmp_path / "box_2.obj"  # box#2 and box_2 would both write box_2_NN.obj
    clash.write_bytes(meshes["box"].read_bytes())
    copy = tmp_path / "sub" / "box.obj"
    copy.parent.mkdir()
    copy.write_bytes(meshes["box"].read_bytes())
    code, _, stderr = run(
        [str(meshes["box"]), str(copy), str(clash), "-o", str(tmp_path / "o"), "--no-cache"]
    )
    assert code == 2
    assert (
        stderr
        == f"meshcol: error: {clash}: two bodies would write 'box_2' (also from {copy}): rename one\n"
    )


def test_obj_numbers_round_trip_exactly(meshes, tmp_path) -> None:
    from meshcol.io.mesh_write import obj_text

    v = np.array([[0.1, -0.0, 1e-300], [1 / 3, 2.5, -7.0]])
    text = obj_text([("a", v, np.array([[0, 1, 1]]))])
    assert text == f"# meshcol\no a\nv 0.1 0.0 1e-300\nv {1 / 3!r} 2.5 -7.0\nf 1 2 2\n"


def test_worker_threads_share_the_cores(monkeypatch) -> None:
    from meshcol.decomposition import jobs as decompose_jobs

    for name in ("OMP_NUM_THREADS", "OMP_WAIT_POLICY", "OPENBLAS_NUM_THREADS"):
        monkeypatch.delenv(name, raising=False)
    monkeypatch.setattr(decompose_jobs.os, "cpu_count", lambda: 8)
    # Engines get 2 * cores / jobs sleeping threads (at most all cores); BLAS its plain share.
    assert decompose_jobs.worker_env(2) == {
        "OMP_NUM_THREADS": "8",
        "OMP_WAIT_POLICY": "PASSIVE",
        "OPENBLAS_NUM_THREADS": "4",
    }
    assert decompose_jobs.worker_env(3)["OMP_NUM_THREADS"] == "6"
    assert decompose_jobs.worker_env(16)["OMP_NUM_THREADS"] == "1"
    assert decompose_jobs.worker_env(16)["OPENBLAS_NUM_THREADS"] == "1"
    assert decompose_jobs.worker_env(4, threads_per_job=3)["OMP_NUM_THREADS"] == "3"
    # The user's own settings win.
    monkeypatch.setenv("OMP_NUM_THREADS", "5")
    monkeypatch.setenv("OMP_WAIT_POLICY", "ACTIVE")
    assert decompose_jobs.worker_env(2) == {"OPENBLAS_NUM_THREADS": "4"}


def test_worker_pool_starts_before_its_tasks() -> None:
    import functools

    from meshcol.decomposition.engines import prepare_engine
    from meshcol.decomposition.jobs import WorkerPool
    from meshcol.io.mesh_write import safe_name

    with WorkerPool(safe_name, 2, prepare=functools.partial(prepare_engine, "coacd")) as pool:
        pool.start()
        workers = list(pool._idle)
        assert len(workers) == 2 and all(w.process.is_alive() for w in workers)
        outcomes = sorted(pool.run(["a b", "c", "d/e"]), key=lambda o: o.index)
        assert [(o.status, o.value) for o in outcomes] == [
            ("ok", "a_b"),
            ("ok", "c"),
            ("ok", "d_e"),
        ]
        assert set(pool._idle) == set(workers)  # the early workers ran the tasks
    assert not any(w.process.is_alive() for w in workers)
    # A pool that never gets a task stops at once, even while its workers still load (a
    # load of 60 s here, so that the bound tells the two apart on a loaded machine too).
    start = time.perf_counter()
    with WorkerPool(safe_name, 2, prepare=functools.partial(time.sleep, 60)) as pool:
        pool.start()
        workers = list(pool._idle)
    assert time.perf_counter() - start < 30
    assert not any(w.process.is_alive() for w in workers)


def test_worker_pool_reads_tasks_ahead_and_fails_fast() -> None:
    from meshcol.decomposition.jobs import WorkerPool
    from meshcol.errors import MeshcolError

    pulled = []

    def tasks():
        for k in range(3):
            pulled.append(k)
            yield 0.3  # time.sleep(0.3) in the worker

    with WorkerPool(time.sleep, 1) as pool:
        pool.start()
        outcomes = pool.run(tasks())
        first = next(outcomes)
        # The generator (a file read per task, in the CLI) ran ahead while the worker slept.
        assert first.status == "ok" and len(pulled) == 3
        assert len(list(outcomes)) == 2

    def broken():
        yield 60.0
        raise MeshcolError("mesh has no faces", "bad.obj")

    # One worker, busy for 60 s with the first task: the bad second "file" is read at once,
    # not when the worker is free, and close() kills the busy worker.
    start = time.perf_counter()
    with WorkerPool(time.sleep, 1) as pool:
        with pytest.raises(MeshcolError):
            list(pool.run(broken()))
        workers = list(pool._busy)
        assert len(workers) == 1
    assert time.perf_counter() - start < 30
    assert not any(w.process.is_alive() for w in workers)


def test_decompose_bad_file_after_good_ones_fails_before_writing(meshes, tmp_path) -> None:
    for jobs in ("1", "2"):
        out = tmp_path / f"out{jobs}"
        code, _, stderr = run(
            [
                str(meshes["torus"]),
                str(meshes["l_shape"]),
                str(meshes["empty"]),
                "-o",
                str(out),
                "--no-cache",
                "--jobs",
                jobs,
                *FAST,
            ]
        )
        assert code == 2
        assert stderr.startswith(f"meshcol: error: {meshes['empty']}: ")
        assert not out.exists()


# ------------------------------------------------------------------- --max-hausdorff gate


def _cube_parts(extra=()) -> tuple:
    """The cube [-20, 20]^3 as three slabs with 0.006-wide slits (99.97% of its volume)."""
    from meshcol.decomposition.canonical import canonical_part

    a, b, g = -20 / 3, 20 / 3, 0.003
    boxes = [
        ((-20, -20, -20), (a - g, 20, 20)),
        ((a + g, -20, -20), (b - g, 20, 20)),
        ((b + g, -20, -20), (20, 20, 20)),
        *extra,
    ]
    return tuple(
        canonical_part(np.asarray(trimesh.creation.box(bounds=box).vertices), None)[:2]
        for box in boxes
    )


def test_max_hausdorff_gates_what_sticks_out_not_the_cuts(tmp_path) -> None:
    # Regression (#12): three boxes covering 99.97% of a 40-unit cube reported a Hausdorff
    # distance of 9.95 (the slits' faces inside the cube), so no useful --max-hausdorff passed.
    import dataclasses

    from meshcol.decomposition import cache as decompose_cache

    cube = tmp_path / "cube.obj"
    trimesh.creation.box(bounds=[(-20, -20, -20), (20, 20, 20)]).export(cube)
    cache = tmp_path / "cache"
    args = [str(cube), "--cache-dir", str(cache), "-o", str(tmp_path / "o"), *FAST]
    code, stdout, _ = run(args)
    assert code == 0
    key = json.loads(stdout)["files"][0]["bodies"][0]["cache_key"]
    engine_made = decompose_cache.load(key, cache)

    def gate(parts, limit: float) -> tuple[int, dict]:
        # Hand-made parts under the cube's key, without metrics: the run measures them.
        decompose_cache.store(dataclasses.replace(engine_made, parts=parts, metrics=None), cache)
        code, stdout, stderr = run([*args, "--max-hausdorff", repr(limit), "--search", "off"])
        assert stdout, stderr
        body = json.loads(stdout)["files"][0]["bodies"][0]
        return code, body

    code, body = gate(_cube_parts(), 0.01)
    assert code == 0 and body["hausdorff_ok"] is True
    assert body["metrics"]["hausdorff_parts_to_mesh"] <= 1e-9
    assert body["metrics"]["hausdorff_mesh_to_parts"] <= 0.003 + 1e-9
    assert body["metrics"]["volume_ratio"] == pytest.approx(0.9997, abs=1e-9)
    # A box 5 beyond a corner: 5 * sqrt(3) out; the limit is inclusive.
    corner = _cube_parts([((15, 15, 15), (25, 25, 25))])
    height = 5.0 * float(np.sqrt(3.0))
    code, body = gate(corner, height * (1 - 1e-9))
    assert code == 1 and body["hausdorff_ok"] is False
    assert body["metrics"]["hausdorff_parts_to_mesh"] == pytest.approx(height, abs=1e-9)
    code, body = gate(corner, body["metrics"]["hausdorff_parts_to_mesh"])
    assert code == 0 and body["hausdorff_ok"] is True


def test_within_max_hausdorff_never_passes_what_it_could_not_measure() -> None:
    from meshcol.decomposition.search import within_max_hausdorff

    m = {"hausdorff_mesh_to_parts": 0.5, "hausdorff_parts_to_mesh": 1.0}
    assert within_max_hausdorff(m, None)
    assert within_max_hausdorff(m, 1.0) and not within_max_hausdorff(m, 0.999)
    assert not within_max_hausdorff({**m, "hausdorff_mesh_to_parts": float("nan")}, 10.0)
    assert not within_max_hausdorff({**m, "hausdorff_parts_to_mesh": float("nan")}, 10.0)
    assert not within_max_hausdorff({"hausdorff_mesh_to_parts": 0.0}, 10.0)
    assert not within_max_hausdorff({}, 10.0)


# ------------------------------------------------------------------- output locations


def _all_files(folder: Path) -> list[Path]:
    return [p for p in folder.rglob("*") if p.is_file()]


def test_outputs_are_checked_before_any_work(meshes, tmp_path, monkeypatch) -> None:
    # Regression (#13): --report in a missing folder exited 2 after writing the parts; an
    # unusable --cache-dir exited 1, blamed the input and left an empty parts folder.
    monkeypatch.chdir(tmp_path)
    (tmp_path / "a_file").write_text("x")
    box = str(meshes["box"])
    cases = [
        (
            ["-o", "out", "--report", "nodir/sub/r.json"],
            "nodir/sub/r.json: folder nodir/sub does not exist",
        ),
        (["-o", "out", "--report", "a_file/r.json"], "a_file/r.json: a_file is not a folder"),
        (
            ["-o", "out", "--report", box],  # refused by its extension before anything else
            f"invalid value for '--report': unknown report extension '.obj' in '{box}': "
            "expected .json, .csv, .xml, .tap, .sarif or .md (or give --report-format "
            "json|csv|junit|github|tap|sarif|markdown) "
            "(see 'meshcol decompose -h')",
        ),
        (
            ["-o", "out", "--cache-dir", "a_file/cache"],
            "a_file/cache: cannot create the folder: a_file is not a folder",
        ),
        (["-o", "a_file/out"], "a_file/out: cannot create the folder: a_file is not a folder"),
        (["-o", "out", "--report", "out"], "out: --report and --out-dir are the same file"),
    ]
    for extra, message in cases:
        code, stdout, stderr = run([box, "--cache-dir", "cache", *extra])
        assert (code, stdout, stderr) == (2, "", f"meshcol: error: {message}\n"), extra
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a_file"]  # no out/, cache/, r.json


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes in read-only folders")
def test_unwritable_cache_dir_is_exit_2_before_any_work(meshes, tmp_path) -> None:
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o500)
    try:
        code, _, stderr = run(
            [str(meshes["box"]), "-o", str(tmp_path / "out"), "--cache-dir", str(locked / "c")]
        )
    finally:
        locked.chmod(0o700)
    assert code == 2
    assert stderr == (
        f"meshcol: error: {locked / 'c'}: cannot create the folder: cannot write in "
        f"{locked} (permission denied)\n"
    )
    assert not (tmp_path / "out").exists()


def test_parts_that_would_replace_an_input_are_refused(meshes, tmp_path, monkeypatch) -> None:
    # `decompose cube.obj -o . --layout combined` would write cube.obj over its input.
    monkeypatch.chdir(tmp_path)
    cube = tmp_path / "cube.obj"
    cube.write_bytes(meshes["box"].read_bytes())
    part = tmp_path / "cube_00.obj"  # what the parts layout writes first
    part.write_bytes(meshes["box"].read_bytes())
    (tmp_path / "out").mkdir()
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir() if p.is_file()}
    for args, victim in [
        (["cube.obj", "-o", ".", "--layout", "combined"], "cube.obj"),
        (["cube.obj", "-o", tmp_path.as_posix(), "--layout", "combined"], "cube.obj"),
        (["cube.obj", "cube_00.obj", "-o", "."], "cube_00.obj"),
    ]:
        code, stdout, stderr = run([*args, "--no-cache"])
        assert code == 2 and stdout == "", args
        assert stderr.startswith(f"meshcol: error: {victim}: the parts of body 'cube")
        assert stderr.endswith(
            "would replace this file (output folder "
            f"{args[args.index('-o') + 1]}): choose another output folder\n"
        )
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir() if p.is_file()} == before
    assert list((tmp_path / "out").iterdir()) == []


@pytest.mark.slow
def test_a_failed_write_leaves_no_part_and_names_the_users_file(
    meshes, tmp_path, monkeypatch
) -> None:
    from meshcol.io import mesh_write

    calls = []
    real = mesh_write.write_meshes

    def disk_full_on_second(path, meshes):
        calls.append(path)
        if len(calls) == 2:
            raise OSError(28, "No space left on device", path)
        real(path, meshes)

    monkeypatch.setattr(mesh_write, "write_meshes", disk_full_on_second)
    out = tmp_path / "new" / "out"
    code, stdout, stderr = run([str(meshes["torus"]), "-o", str(out), "--no-cache", *FAST])
    assert code == 2 and stdout == ""
    assert stderr.startswith("meshcol: error: ") and ".meshcol-" not in stderr
    assert stderr.endswith("torus_01.obj: No space left on device\n")
    assert not (tmp_path / "new").exists()  # the folders it made are gone too


# ------------------------------------------------------------------- signals


def _session_processes(session: int) -> list[str]:
    """Processes still running (not zombies) in a session, from /proc."""
    alive = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[3]) == session and fields[0] not in ("Z", "X"):
            alive.append(entry.name)
    return alive


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs /proc")
@pytest.mark.parametrize(
    ("jobs", "signum", "to_group", "code"),
    [
        ("1", signal.SIGINT, True, 130),  # Ctrl-C in a terminal: the whole process group
        ("1", signal.SIGINT, False, 130),
        ("1", signal.SIGTERM, False, 143),
        ("2", signal.SIGTERM, False, 143),  # used to orphan the workers, which wrote the cache
        ("2", signal.SIGINT, True, 130),
    ],
)
def test_signals_stop_the_run_and_leave_nothing(tmp_path, jobs, signum, to_group, code) -> None:
    # Regression (#13): Ctrl-C was ignored for a minute while CoACD ran in the one process;
    # SIGTERM with -j 2 left the workers running, writing to the cache after the parent left.
    mesh = tmp_path / "torus.obj"  # about 12 s with CoACD's defaults
    trimesh.creation.torus(1.0, 0.3, major_sections=48, minor_sections=24).export(mesh)
    cache, out = tmp_path / "cache", tmp_path / "out"
    command = [sys.executable, "-m", "meshcol", "decompose", str(mesh), "-o", str(out)]
    proc = subprocess.Popen(
        [*command, "--cache-dir", str(cache), "--jobs", jobs],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        start_new_session=True,
    )
    try:
        # Until the engine runs: the interpreter, the fork server and a worker are up.
        deadline = time.monotonic() + 30
        while len(_session_processes(proc.pid)) < 4 and time.monotonic() < deadline:
            time.sleep(0.1)
        time.sleep(1.0)
        assert proc.poll() is None, "the run finished before the signal"
        sent = time.monotonic()
        (os.killpg if to_group else os.kill)(proc.pid, signum)
        stdout, stderr = proc.communicate(timeout=30)
        stopped = time.monotonic() - sent
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    assert proc.returncode == code
    word = "interrupted" if signum == signal.SIGINT else "terminated"
    # (a loaded machine reaches the progress line's 5 s before the signal: it may precede)
    lines = [line for line in stderr.decode().splitlines() if " elapsed)" not in line]
    assert (stdout, lines) == (b"", [f"meshcol: {word}"])
    # Stopped within seconds, not when CoACD is done (about 12 s); the issue asks for one
    # second, which a loaded CI machine cannot promise: the figures are in the report.
    assert stopped < 8.0
    deadline = time.monotonic() + 30  # a bound: on a loaded machine the workers take seconds
    while _session_processes(proc.pid) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert _session_processes(proc.pid) == []
    assert not out.exists()
    assert _all_files(cache) == []  # rglob of a missing folder is empty


def test_worker_pool_starts_nothing_without_a_task() -> None:
    # One job starts its worker (and the fork server) at the first task only: a run of cache
    # hits spawns no process.
    from meshcol.decomposition.jobs import WorkerPool
    from meshcol.io.mesh_write import safe_name

    with WorkerPool(safe_name, 1) as pool:
        assert list(pool.run(iter(()))) == []
        assert pool._ctx is None and not pool._idle and not pool._busy


def test_an_interrupt_swallowed_by_a_task_source_is_raised_again() -> None:
    # trimesh catches BaseException around its imports: a Ctrl-C that lands there must not
    # be lost while the pool runs.
    from meshcol.decomposition.jobs import WorkerPool
    from meshcol.io.mesh_write import safe_name

    def swallowing_source():
        try:
            signal.raise_signal(signal.SIGINT)
        except BaseException:  # noqa: BLE001 - what trimesh does
            pass
        deadline = time.monotonic() + 20  # a long import, in Python
        while time.monotonic() < deadline:
            time.sleep(0.01)
        yield "never reached"

    start = time.monotonic()
    with WorkerPool(safe_name, 1) as pool, pytest.raises(KeyboardInterrupt):
        list(pool.run(swallowing_source()))
    assert time.monotonic() - start < 10  # delivered again within 0.1 s, not after the loop
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    time.sleep(0.3)  # and never again once it has left the pool
