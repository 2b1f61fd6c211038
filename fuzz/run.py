"""Fuzz one target of ``fuzz/targets.py`` with atheris (libFuzzer for Python), seeded.

Usage::

    python fuzz/run.py TARGET [--seconds S | --runs N] [--artifacts DIR] [--seed K]
    python fuzz/run.py TARGET --replay

``--replay`` runs the target once on every seed and every regression input of
``fuzz/regressions/TARGET/``, then on ``--mutations M`` (default 0) seeded mutations of them
(bytes flipped, dropped, repeated, special float64 values written in), without atheris:
``make test-sanitize`` runs the sanitized core on them this way. It prints
``fuzz TARGET: replayed N inputs``.

``TARGET`` is ``readers``, ``convex``, ``meshes`` or ``manifest``. The seeds are built afresh in
a temporary folder: for ``readers`` every sample mesh and manifest in ``samples/`` and every
corpus file under 64 KB in ``../shared/corpus`` (each prefixed with its format byte); for
``manifest`` the JSON manifests in ``samples/`` and plain manifests of primitive bodies (every
type, rotation form and shape; numbers of every spelling), of mesh bodies and of both; for
the numeric targets a few hand-made inputs (a cube, a flat square, huge and tiny coordinates).

A crash, a timeout (10 s for one input) or an unexpected exception stops the run: the input is
written to ``--artifacts`` (default ``fuzz/crashes/``) and the exit code is non-zero. Turn it
into a regression by moving it to ``fuzz/regressions/TARGET/`` with a name that says what it
was; ``tests/test_fuzz.py`` replays every file there. The last line printed is
``fuzz TARGET: N executions, 0 crashes`` (or the crash), for the record.
"""

from __future__ import annotations

import argparse
import os
import struct
import sys
import tempfile
from pathlib import Path
from random import Random

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
CORPUS = REPO.parent / "shared" / "corpus"
MAX_SEED_BYTES = 64 * 1024

sys.path.insert(0, str(HERE))


def _reader_seeds(folder: Path) -> int:
    from targets import FORMATS

    files = sorted((REPO / "samples").rglob("*"))
    if CORPUS.is_dir():
        files += sorted(CORPUS.rglob("*"))
    count = 0
    for path in files:
        suffix = path.suffix.lower()
        if suffix not in FORMATS or not path.is_file():
            continue
        if path.stat().st_size > MAX_SEED_BYTES:
            continue
        data = bytes([FORMATS.index(suffix)]) + path.read_bytes()
        (folder / f"seed{count:04d}{suffix}").write_bytes(data)
        count += 1
    return count


def _manifest_seeds(folder: Path) -> int:
    files = [p for p in sorted((REPO / "samples").rglob("*.json")) if p.is_file()]
    seeds = [p.read_bytes() for p in files if p.stat().st_size <= MAX_SEED_BYTES]
    kinds = [
        '{"type": "sphere", "radius": 0.5}',
        '{"size": [1, 2.5e-1, 3E0], "type": "box"}',
        '{"type": "capsule", "radius": 1, "length": 0.25}',
        '{"length": 2, "type": "cylinder", "radius": 0.1000000000000000055511151231257827}',
        '{"semi_axes": [0.5, 2e-1, 1E0], "type": "ellipsoid"}',
    ]
    extras = [
        ', "shape": "hull"',
        ', "rotation": {"quaternion": [1, -0.0, 0, 2]}',
        ', "rotation": {"euler_deg": [90, -0, 45.5], "order": "zyx"}',
    ]
    bodies = [
        f'{{"name": "bNAME{i}", "primitive": {kinds[i % len(kinds)]}, "position": [{i}, -0, 1e-3]'
        + extras[i % 3]
        + "}"
        for i in range(12)
    ]
    text = '{"units": "m", "duration": 2, "bodies": [' + ", ".join(bodies) + "]}"
    seeds.append(text.replace("NAME", "").encode())
    seeds.append(text.replace("NAME", "\u00e9").encode())  # not ASCII
    seeds.append(text.replace("NAME", "\\u00e9").encode())  # an escape
    seeds.append(b"\xef\xbb\xbf" + text.replace("NAME", "").encode())
    # mesh bodies, alone and among primitives (a file name as written; one escaped)
    meshes = [
        f'{{"name": "m{i}", "mesh": "assets/a{i:06d}.obj", "position": [{i}, 0.5, -0]'
        + extras[i % 3]
        + "}"
        for i in range(8)
    ]
    seeds.append(('{"units": "m", "bodies": [' + ", ".join(meshes) + "]}").encode())
    mixed = [body for pair in zip(bodies, meshes) for body in pair]
    mixed_text = '{"bodies": [' + ", ".join(mixed).replace("NAME", "") + "]}"
    seeds.append(mixed_text.encode())
    seeds.append(mixed_text.replace("assets/", "../\\u00e9/").encode())
    for i, data in enumerate(seeds):
        (folder / f"seed{i}.json").write_bytes(data)
    return len(seeds)


def _seeds(target: str, folder: Path) -> int:
    """The seeds of ``target``, written into ``folder``; their count."""
    if target == "readers":
        return _reader_seeds(folder)
    if target == "manifest":
        return _manifest_seeds(folder)
    return _numeric_seeds(folder)


def _encode(points: list[tuple[float, float, float]]) -> bytes:
    """Points as the numeric targets read them: a count byte, then tagged float64 values."""
    out = bytearray([len(points)])
    for point in points:
        for value in point:
            out += b"\xff" + struct.pack("<d", value)
    return bytes(out)


def _numeric_seeds(folder: Path) -> int:
    cube = [(x, y, z) for x in (-1.0, 1.0) for y in (-1.0, 1.0) for z in (-1.0, 1.0)]
    square = [(x, y, 0.0) for x in (0.0, 1.0) for y in (0.0, 1.0)]
    seeds = [
        _encode(cube) + _encode([(x + 1.5, y, z) for x, y, z in cube]),
        _encode(square) + _encode(cube),
        _encode([(x * 1e300, y, z) for x, y, z in cube]) + _encode(cube),
        _encode([(x * 1e-310, y, z) for x, y, z in cube]) + _encode([(0.0, 0.0, 0.0)]),
        _encode(cube) + _encode(cube) + b"\x01" + b"\xff" + struct.pack("<d", 1e155) * 7,
    ]
    for i, data in enumerate(seeds):
        (folder / f"seed{i}").write_bytes(data)
    return len(seeds)


_SPECIAL = [float("nan"), float("inf"), -float("inf"), 0.0, -0.0, 5e-324, 1e-310, 1e308, 1e155]


def _mutate(data: bytes, random: Random) -> bytes:
    """A few random edits of `data` (the first byte, a reader's format, is kept)."""
    out = bytearray(data)
    for _ in range(random.randint(1, 4)):
        at = random.randrange(1, len(out)) if len(out) > 1 else 1
        edit = random.randrange(5)
        if edit == 0 and len(out) > 1:
            out[at] = random.randrange(256)
        elif edit == 1 and len(out) > 1:
            del out[at : at + random.randint(1, 64)]
        elif edit == 2:
            chunk = out[at : at + random.randint(1, 64)]
            out[at:at] = chunk * random.randint(1, 4)
        elif edit == 3:
            out[at:at] = b"\xff" + struct.pack("<d", random.choice(_SPECIAL))
        else:
            out[at:at] = bytes(random.randrange(256) for _ in range(random.randint(1, 8)))
    return bytes(out)


def _replay(target: str, mutations: int) -> int:
    """Runs `target` on each seed and regression input, then on seeded mutations of them."""
    import targets

    seeds = Path(tempfile.mkdtemp(prefix=f"meshcol-seeds-{target}-"))
    _seeds(target, seeds)
    paths = sorted(seeds.iterdir()) + sorted((HERE / "regressions" / target).glob("*"))
    inputs = [path.read_bytes() for path in paths]
    random = Random(f"meshcol-fuzz-{target}")
    inputs += [_mutate(random.choice(inputs), random) for _ in range(mutations)]
    for data in inputs:
        targets.TARGETS[target](data)
    print(f"fuzz {target}: replayed {len(inputs)} inputs", file=sys.stderr)
    return 0


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("target", choices=("readers", "convex", "meshes", "manifest"))
    limit = parser.add_mutually_exclusive_group()
    limit.add_argument("--seconds", type=int, default=60)
    limit.add_argument("--runs", type=int)
    limit.add_argument("--replay", action="store_true", help="run each seed and regression once")
    parser.add_argument("--mutations", type=int, default=0, help="with --replay: mutated inputs")
    parser.add_argument("--artifacts", type=Path, default=HERE / "crashes")
    parser.add_argument("--seed", type=int, default=0, help="libFuzzer seed; 0 picks one")
    args = parser.parse_args()
    if args.replay:
        return _replay(args.target, args.mutations)

    try:
        import atheris
    except ImportError:
        print("fuzz: atheris is not installed (pip install atheris)", file=sys.stderr)
        return 2

    with atheris.instrument_imports(include=["meshcol"]):
        import targets

    seeds = Path(tempfile.mkdtemp(prefix=f"meshcol-seeds-{args.target}-"))
    count = _seeds(args.target, seeds)
    args.artifacts.mkdir(parents=True, exist_ok=True)
    flags = [
        sys.argv[0],
        f"-artifact_prefix={args.artifacts}{os.sep}{args.target}-",
        "-timeout=10",
        "-rss_limit_mb=4096",
        f"-max_len={MAX_SEED_BYTES + 1}",
        "-print_final_stats=1",
        f"-seed={args.seed}",
    ]
    flags.append(
        f"-runs={args.runs}" if args.runs is not None else f"-max_total_time={args.seconds}"
    )
    print(f"fuzz {args.target}: {count} seeds in {seeds}", file=sys.stderr)
    atheris.Setup([*flags, str(seeds)], targets.TARGETS[args.target])
    atheris.Fuzz()  # exits the process itself: 0 when the run ends without a crash
    return 0


if __name__ == "__main__":
    sys.exit(main())
