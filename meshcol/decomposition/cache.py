"""The content-addressed cache of convex decompositions.

One entry per key (:func:`meshcol.decomposition.canonical.cache_key`): ``<dir>/<key[:2]>/<key>.npz`` holding
all part vertices and faces concatenated, their offsets, and a JSON header (engine, version,
parameters, metrics and the version of their definitions, notes). An entry is written to a temporary file in the same folder and
renamed into place (``os.replace`` is atomic on POSIX and Windows), so concurrent runs never
see a partial entry and a killed run leaves none; an unreadable entry counts as a miss.
"""

from __future__ import annotations

import io
import json
import os
import sys
import zipfile
from pathlib import Path

import numpy as np

from meshcol.decomposition.fidelity import METRICS_VERSION
from meshcol.decomposition.result import Decomposition, Fidelity
from meshcol.io.report import atomic_path

__all__ = ["default_cache_dir", "entry_path", "load", "store"]


def default_cache_dir() -> Path:
    """``$XDG_CACHE_HOME/meshcol/decompose``, else the platform's user cache folder.

    Linux and others: ``~/.cache/meshcol/decompose``; macOS: ``~/Library/Caches/meshcol/
    decompose``; Windows: ``%LOCALAPPDATA%\\meshcol\\cache\\decompose``.
    """
    xdg = os.environ.get("XDG_CACHE_HOME")
    if xdg:
        return Path(xdg) / "meshcol" / "decompose"
    if sys.platform == "win32" and os.environ.get("LOCALAPPDATA"):
        return Path(os.environ["LOCALAPPDATA"]) / "meshcol" / "cache" / "decompose"
    if sys.platform == "darwin":
        return Path.home() / "Library" / "Caches" / "meshcol" / "decompose"
    return Path.home() / ".cache" / "meshcol" / "decompose"


def entry_path(key: str, cache_dir: str | os.PathLike[str] | None = None) -> Path:
    """Where the entry for ``key`` lives."""
    root = Path(cache_dir) if cache_dir is not None else default_cache_dir()
    return root / key[:2] / f"{key}.npz"


def load(key: str, cache_dir: str | os.PathLike[str] | None = None) -> Decomposition | None:
    """The cached decomposition for ``key``, or None when absent or unreadable."""
    path = entry_path(key, cache_dir)
    try:
        with np.load(path, allow_pickle=False) as z:
            header = json.loads(bytes(z["header"]).decode())
            vertices, faces = z["vertices"], z["faces"]
            voff, foff = z["vertex_offsets"], z["face_offsets"]
    except (OSError, KeyError, ValueError, zipfile.BadZipFile):
        return None
    if header.get("key") != key:
        return None
    parts = tuple(
        (vertices[voff[i] : voff[i + 1]], faces[foff[i] : foff[i + 1]])
        for i in range(len(voff) - 1)
    )
    m = header.get("metrics")
    metrics = None
    # Metrics of another definition are dropped (measured again by the caller); parts stay.
    if m is not None and header.get("metrics_version") == METRICS_VERSION:
        try:
            metrics = Fidelity(**{**m, "vertices_per_part": tuple(m["vertices_per_part"])})
        except (KeyError, TypeError):
            metrics = None
    return Decomposition(
        parts=parts,
        engine=header["engine"],
        engine_version=header["engine_version"],
        params=header["params"],
        cache_key=key,
        metrics=metrics,
        repaired=header["repaired"],
        notes=tuple(header["notes"]),
        from_cache=True,
    )


def store(result: Decomposition, cache_dir: str | os.PathLike[str] | None = None) -> Path:
    """Write ``result`` under its key, atomically; returns the entry's path."""
    path = entry_path(result.cache_key, cache_dir)
    path.parent.mkdir(parents=True, exist_ok=True)
    header = {
        "key": result.cache_key,
        "engine": result.engine,
        "engine_version": result.engine_version,
        "params": dict(result.params),
        "metrics": None if result.metrics is None else result.metrics.to_dict(),
        "metrics_version": METRICS_VERSION,
        "repaired": result.repaired,
        "notes": list(result.notes),
    }
    vcount = np.array([len(v) for v, _ in result.parts])
    fcount = np.array([len(f) for _, f in result.parts])
    buf = io.BytesIO()
    np.savez(
        buf,
        header=np.frombuffer(json.dumps(header, sort_keys=True).encode(), dtype=np.uint8),
        vertices=np.concatenate([v for v, _ in result.parts]),
        faces=np.concatenate([f for _, f in result.parts]),
        vertex_offsets=np.concatenate([[0], np.cumsum(vcount)]).astype(np.int64),
        face_offsets=np.concatenate([[0], np.cumsum(fcount)]).astype(np.int64),
    )
    with atomic_path(path) as tmp, open(tmp, "wb") as f:
        f.write(buf.getvalue())
    return path
