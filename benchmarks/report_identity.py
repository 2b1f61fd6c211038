"""Every report of two meshcol builds compared byte for byte (issue 28: a refactor keeps every
report identical unless a change is on purpose and in the CHANGELOG).

Runs one list of commands (check, sweep, inspect, hull, fit, decompose, collision-matrix in
every report format, review pages, snapshot pictures, robot outputs) with each meshcol executable, from the
repository root, writing into the same folder so that paths inside the reports agree, then
moves each side's outputs aside and compares every file, the exit code, stdout and stderr.
Only clocks are masked: JSON fields ``generated_at`` and ``*seconds``, JUnit ``time``
attributes, ``N.NNN s`` figures and progress lines in text; and the installed package's own
paths (``meshcol targets`` prints them).

Inputs: ``samples/``, the corpus robots (``../shared/corpus/robots``, skipped when absent), a
10,000-body scene of unique assets (``bench_scale.scene_folder``, written once) and manifests
of 5,000 primitives (``bench_scale.primitives_folder``).

Run: .venv/bin/python benchmarks/report_identity.py --baseline ../base/.venv/bin/meshcol
     [--only check,inspect] [--keep DIR]
Exit 0 when every output is identical, 1 otherwise (the differing files are listed).
"""

from __future__ import annotations

import argparse
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_scale import primitives_folder, scene_folder

ROOT = Path(__file__).resolve().parent.parent
ROBOTS = ROOT.parent / "shared" / "corpus" / "robots"
PANDA = ROBOTS / "panda_description" / "urdf" / "panda.urdf"
SOLO = ROBOTS / "solo_description" / "robots" / "solo12.urdf"
PROPS = sorted(str(p.relative_to(ROOT)) for p in (ROOT / "samples/level/props").glob("*.obj"))

#: (name, arguments); ``{out}`` is the shared output folder. Robots need the corpus.
COMMANDS: list[tuple[str, list[str]]] = [
    ("check-level-json", ["check", "samples/level/scene.json", "--report", "{out}/level.json"]),
    (
        "check-level-csv",
        ["check", "samples/level/scene.json", "--format", "csv", "--report", "{out}/level.csv"],
    ),
    (
        "check-level-junit",
        ["check", "samples/level/scene.json", "--format", "junit", "--report", "{out}/level.xml"],
    ),
    ("check-level-github", ["check", "samples/level/scene.json", "--format", "github"]),
    ("check-level-html", ["check", "samples/level/scene.json", "--html", "{out}/level.html"]),
    (
        "check-level-snapshots",
        [
            "check",
            "samples/level/scene.json",
            "--fail-on",
            "contact",
            "--format",
            "markdown",
            "--report",
            "{out}/level-shots.md",
            "--snapshots",
            "{out}/level-shots",
        ],
    ),
    (
        "check-level-margin",
        [
            "check",
            "samples/level/scene.json",
            "--clearance",
            "0.05",
            "--report",
            "{out}/level-clear.json",
        ],
    ),
    (
        "check-bowl-hull",
        ["check", "samples/bowl/scene.json", "--shape", "hull", "--report", "{out}/bowl-hull.json"],
    ),
    (
        "check-bowl-mesh",
        ["check", "samples/bowl/scene.json", "--shape", "mesh", "--report", "{out}/bowl-mesh.json"],
    ),
    (
        "check-bowl-fit",
        ["check", "samples/bowl/scene.json", "--shape", "fit", "--report", "{out}/bowl-fit.json"],
    ),
    (
        "check-bowl-decomposed",
        [
            "check",
            "samples/bowl/scene.json",
            "--shape",
            "decomposed",
            "--cache-dir",
            "{out}/cache",
            "--report",
            "{out}/bowl-dec.json",
        ],
    ),
    (
        "check-bowl-mesh-html",
        ["check", "samples/bowl/scene.json", "--shape", "mesh", "--html", "{out}/bowl.html"],
    ),
    ("sweep-json", ["sweep", "samples/bullet/scene.json", "--report", "{out}/sweep.json"]),
    (
        "sweep-csv",
        ["sweep", "samples/bullet/scene.json", "--format", "csv", "--report", "{out}/sweep.csv"],
    ),
    (
        "sweep-junit",
        ["sweep", "samples/bullet/scene.json", "--format", "junit", "--report", "{out}/sweep.xml"],
    ),
    ("sweep-github", ["sweep", "samples/bullet/scene.json", "--format", "github"]),
    ("sweep-html", ["sweep", "samples/bullet/scene.json", "--html", "{out}/sweep.html"]),
    (
        "sweep-snapshots",
        [
            "sweep",
            "samples/bullet/scene.json",
            "--format",
            "markdown",
            "--report",
            "{out}/sweep-shots.md",
            "--snapshots",
            "{out}/sweep-shots",
        ],
    ),
    ("inspect-props-json", ["inspect", *PROPS, "--report", "{out}/inspect.json"]),
    ("inspect-props-csv", ["inspect", *PROPS, "--format", "csv", "--report", "{out}/inspect.csv"]),
    (
        "inspect-props-junit",
        ["inspect", *PROPS, "--format", "junit", "--report", "{out}/inspect.xml"],
    ),
    ("inspect-props-github", ["inspect", *PROPS, "--format", "github"]),
    (
        "inspect-props-target",
        ["inspect", *PROPS, "--target", "physx-gpu", "--report", "{out}/inspect-gpu.json"],
    ),
    (
        "inspect-level",
        ["inspect", "samples/level/scene.json", "--report", "{out}/inspect-level.json"],
    ),
    (
        "inspect-level-mesh",
        [
            "inspect",
            "samples/level/scene.json",
            "--shape",
            "mesh",
            "--report",
            "{out}/inspect-level-mesh.json",
        ],
    ),
    (
        "inspect-level-fit",
        [
            "inspect",
            "samples/level/scene.json",
            "--shape",
            "fit",
            "--report",
            "{out}/inspect-level-fit.json",
        ],
    ),
    ("inspect-bowl-html", ["inspect", "samples/bowl/scene.json", "--html", "{out}/inspect.html"]),
    ("inspect-jobs", ["inspect", *PROPS, "--jobs", "2", "--report", "{out}/inspect-j2.json"]),
    (
        "hull-bowl",
        [
            "hull",
            "samples/bowl/bowl.obj",
            "--max-vertices",
            "64",
            "-o",
            "{out}/bowl_hull.obj",
            "--report",
            "{out}/hull.json",
        ],
    ),
    (
        "hull-props-target",
        [
            "hull",
            *PROPS,
            "--target",
            "unreal",
            "--out-dir",
            "{out}/hulls",
            "--report",
            "{out}/hull-unreal.json",
        ],
    ),
    ("hull-props-csv", ["hull", *PROPS, "--format", "csv", "--report", "{out}/hull.csv"]),
    ("hull-html", ["hull", "samples/bowl/bowl.obj", "--html", "{out}/hull.html"]),
    ("fit-props", ["fit", *PROPS, "--out-dir", "{out}/fits", "--report", "{out}/fit.json"]),
    ("fit-props-junit", ["fit", *PROPS, "--format", "junit", "--report", "{out}/fit.xml"]),
    (
        "decompose-bowl",
        [
            "decompose",
            "samples/bowl/bowl.obj",
            "--out-dir",
            "{out}/parts",
            "--cache-dir",
            "{out}/cache",
            "--report",
            "{out}/decompose.json",
        ],
    ),
    (
        "decompose-bowl-csv",
        [
            "decompose",
            "samples/bowl/bowl.obj",
            "--cache-dir",
            "{out}/cache",
            "--format",
            "csv",
            "--report",
            "{out}/decompose.csv",
        ],
    ),
    (
        "decompose-bowl-html",
        [
            "decompose",
            "samples/bowl/bowl.obj",
            "--cache-dir",
            "{out}/cache",
            "--html",
            "{out}/decompose.html",
        ],
    ),
    ("rules", ["rules"]),
    ("targets", ["targets"]),
    # the sample arm's links fit capsules: the URDF written holds them (session 43)
    (
        "fit-arm-urdf",
        [
            "fit",
            "samples/robot/arm.urdf",
            "--joint",
            "elbow=1.0",
            "--out-dir",
            "{out}/arm-urdf",
            "--report",
            "{out}/fit-arm.json",
        ],
    ),
]
ROBOT_COMMANDS: list[tuple[str, list[str]]] = [
    ("check-panda", ["check", str(PANDA), "--report", "{out}/panda.json"]),
    (
        "check-panda-adjacent",
        [
            "check",
            str(PANDA),
            "--include-adjacent",
            "--format",
            "csv",
            "--report",
            "{out}/panda.csv",
        ],
    ),
    ("check-solo", ["check", str(SOLO), "--report", "{out}/solo.json"]),
    ("inspect-panda", ["inspect", str(PANDA), "--report", "{out}/inspect-panda.json"]),
    (
        "matrix-panda",
        [
            "collision-matrix",
            str(PANDA),
            "--samples",
            "300",
            "-o",
            "{out}/panda.srdf",
            "--report",
            "{out}/matrix.json",
        ],
    ),
    (
        "matrix-solo",
        [
            "collision-matrix",
            str(SOLO),
            "--samples",
            "300",
            "--shape",
            "fit",
            "-o",
            "{out}/solo.srdf",
        ],
    ),
    (
        "hull-panda-urdf",
        [
            "hull",
            str(PANDA),
            "--to",
            "urdf",
            "--out-dir",
            "{out}/panda-urdf",
            "--report",
            "{out}/hull-panda.json",
        ],
    ),
    ("hull-panda-mjcf", ["hull", str(PANDA), "--to", "mjcf", "--out-dir", "{out}/panda-mjcf"]),
    ("fit-solo-urdf", ["fit", str(SOLO), "--to", "urdf", "--out-dir", "{out}/solo-urdf"]),
    ("fit-solo-glb", ["fit", str(SOLO), "--to", "glb", "--out-dir", "{out}/solo-glb"]),
    ("hull-solo-usd", ["hull", str(SOLO), "--to", "usd", "--out-dir", "{out}/solo-usd"]),
]

_CLOCK_JSON = re.compile(rb'("(?:generated_at|[a-z_]*seconds[a-z_]*)": )[^,\n]*')
_CLOCK_XML = re.compile(rb'( time=")[^"]*"')
_CLOCK_TEXT = re.compile(rb"\d+(?:\.\d+)? (?:s|us|ms)\b")
#: Progress lines: how many a run prints depends on the clock.
_PROGRESS = re.compile(rb"^.*(?:elapsed|left\)).*\n", re.MULTILINE)
#: The installed package's own files (``meshcol targets`` lists their paths).
_PACKAGE = re.compile(rb'/[^"\s]*/meshcol/(targets|schemas)/')


def masked(data: bytes) -> bytes:
    """``data`` with its clocks, progress lines and package paths replaced by fixed tokens."""
    data = _PROGRESS.sub(b"", data)
    data = _CLOCK_JSON.sub(rb"\1<clock>", data)
    data = _CLOCK_XML.sub(rb'\1<clock>"', data)
    data = _PACKAGE.sub(rb"<package>/\1/", data)
    return _CLOCK_TEXT.sub(b"<s>", data)


def run_side(meshcol: str, commands: list[tuple[str, list[str]]], out: Path, keep: Path) -> None:
    """Run every command with ``meshcol`` into ``out``; keep each command's outputs under
    ``keep/<name>/`` (files, and ``rc``, ``stdout``, ``stderr``)."""
    for name, arguments in commands:
        if out.exists():
            shutil.rmtree(out)
        out.mkdir(parents=True)
        argv = [meshcol, *(a.replace("{out}", str(out)) for a in arguments)]
        done = subprocess.run(argv, cwd=ROOT, capture_output=True, timeout=900)
        target = keep / name
        shutil.copytree(out, target)
        (target / "rc").write_text(str(done.returncode))
        (target / "stdout").write_bytes(done.stdout)
        (target / "stderr").write_bytes(done.stderr)


def differences(a: Path, b: Path) -> list[str]:
    """Files that differ (clocks masked) or exist on one side only."""
    names_a = {p.relative_to(a) for p in a.rglob("*") if p.is_file()}
    names_b = {p.relative_to(b) for p in b.rglob("*") if p.is_file()}
    rows = [
        f"only in {side}: {name}"
        for side, name in (
            *(("baseline", n) for n in sorted(names_a - names_b)),
            *(("this", n) for n in sorted(names_b - names_a)),
        )
    ]
    for name in sorted(names_a & names_b):
        if name.parts[1:2] == ("cache",):
            continue  # the decomposition cache: its own format, compared by the reports
        if masked((a / name).read_bytes()) != masked((b / name).read_bytes()):
            rows.append(f"differs: {name}")
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--baseline", required=True, help="the other meshcol executable")
    parser.add_argument("--this", default=str(Path(sys.executable).parent / "meshcol"))
    parser.add_argument("--only", default="", help="comma-separated name prefixes to run")
    parser.add_argument("--keep", default="", help="folder for both sides' outputs")
    parser.add_argument("--no-scale", action="store_true", help="skip the 10,000-body scene")
    parser.add_argument("--compare", action="store_true", help="only compare --keep's outputs")
    args = parser.parse_args()

    commands = list(COMMANDS)
    if PANDA.exists() and SOLO.exists():
        commands += ROBOT_COMMANDS
    else:
        print(f"skipped: robot commands ({ROBOTS} absent)")
    if not args.no_scale:
        scene = scene_folder(10_000) / "scene.json"
        commands += [
            (
                "check-10k-json",
                ["check", str(scene), "--fail-on", "none", "--report", "{out}/10k.json"],
            ),
            (
                "check-10k-csv",
                [
                    "check",
                    str(scene),
                    "--fail-on",
                    "none",
                    "--format",
                    "csv",
                    "--report",
                    "{out}/10k.csv",
                ],
            ),
            ("inspect-10k", ["inspect", str(scene), "--report", "{out}/inspect-10k.json"]),
        ]
        # a manifest of primitives only (read natively, kept as columns: issue 32 item 4)
        for kind in ("mixed", "spheres"):
            manifest = str(primitives_folder(5_000, kind) / "scene.json")
            report = ["--fail-on", "none", "--report", f"{{out}}/primitives-{kind}.json"]
            commands.append((f"check-primitives-{kind}", ["check", manifest, *report]))
        csv = ["--format", "csv", "--report", "{out}/primitives-mixed.csv"]
        manifest = str(primitives_folder(5_000, "mixed") / "scene.json")
        commands.append(("check-primitives-csv", ["check", manifest, "--fail-on", "none", *csv]))
    if args.only:
        prefixes = tuple(args.only.split(","))
        commands = [c for c in commands if c[0].startswith(prefixes)]

    keep = Path(args.keep) if args.keep else Path(tempfile.mkdtemp(prefix="report-identity-"))
    out = Path(tempfile.mkdtemp(prefix="meshcol-out-"))
    for side, meshcol in (("baseline", args.baseline), ("this", args.this)):
        if args.compare:
            break
        if (keep / side).exists():
            shutil.rmtree(keep / side)
        run_side(meshcol, commands, out, keep / side)
    rows = differences(keep / "baseline", keep / "this")
    shutil.rmtree(out, ignore_errors=True)
    print(f"{len(commands)} commands, outputs in {keep}")
    for row in rows:
        print(row)
    print("identical" if not rows else f"{len(rows)} differences")
    sys.exit(1 if rows else 0)


if __name__ == "__main__":
    main()
