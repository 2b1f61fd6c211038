"""The content-addressed cache of convex decompositions.

One entry per key (:func:`meshcol.decomposition.canonical.cache_key`): ``<dir>/<key[:2]>/<key>.npz`` holding
all part vertices and faces concatenated, their offsets, and a JSON header (engine, version,
parameters, metrics and the version of their definitions, notes). An unreadable entry, or
one whose header names another key, counts as a miss.

The cache is a folder (local, or on a file system several machines share: NFS, Lustre, SMB)
or an fsspec URL (``file://``, ``memory://``, ``s3://``, ``gs://``, ... with the user's
fsspec backend installed). Writes are atomic, so concurrent writers, on one machine or many,
never leave a partial entry and a killed run leaves none:

- a folder (or ``file://``): the entry is written to a temporary file in its folder and
  renamed into place (``os.replace``, atomic on POSIX and Windows, and on NFS within a folder);
- an object store (``s3``, ``gs``, ``az``, ``memory``, ...): one whole-object put, which
  readers see entirely or not at all;
- any other fsspec file system: a temporary object, then a move onto the entry.

Two writers of one key write the same bytes (a key names one geometry, engine version and
parameter set, and the engines are deterministic), so the last write winning is correct.
"""

from __future__ import annotations

import io
import json
import os
import sys
import uuid
import zipfile
from pathlib import Path
from typing import TYPE_CHECKING, Any

from meshcol.io.report import atomic_path

if TYPE_CHECKING:  # numpy and the results load with an entry: a warm `meshcol ci` needs neither
    from meshcol.decomposition.result import Decomposition

__all__ = [
    "default_cache_dir",
    "entry_path",
    "is_url",
    "load",
    "local_folder",
    "read_bytes",
    "store",
    "write_bytes",
]

# fsspec protocols whose single put is atomic (object stores): written in one call.
_OBJECT_STORES = frozenset(
    {"s3", "s3a", "gs", "gcs", "az", "abfs", "abfss", "adl", "memory", "oss", "r2"}
)


def is_url(cache_dir: str | os.PathLike[str] | None) -> bool:
    """Whether ``cache_dir`` is an fsspec URL (``scheme://...``) rather than a folder."""
    return cache_dir is not None and "://" in os.fspath(cache_dir)


def local_folder(cache_dir: str | os.PathLike[str] | None) -> str | None:
    """The local folder of ``cache_dir`` (a path, or a ``file://`` URL); None for any other
    URL (checked by its backend when used) and for None."""
    if cache_dir is None:
        return None
    text = os.fspath(cache_dir)
    if not is_url(text):
        return text
    scheme, _, rest = text.partition("://")
    if scheme in ("file", "local"):
        return rest or "/"
    return None


def _filesystem(url: str) -> tuple[Any, str]:
    """(fsspec file system, root path inside it) for a cache URL."""
    try:
        import fsspec
    except ImportError:
        from meshcol.errors import MissingDependencyError

        raise MissingDependencyError(
            f"cache URL {url!r} needs fsspec (and its backend, e.g. s3fs or gcsfs): "
            "pip install fsspec"
        ) from None
    try:
        fs, root = fsspec.core.url_to_fs(url)
    except (ImportError, ValueError) as exc:
        from meshcol.errors import MissingDependencyError

        raise MissingDependencyError(f"cache URL {url!r}: {exc}") from None
    return fs, root.rstrip("/")


def _entry_name(key: str) -> str:
    return f"{key[:2]}/{key}.npz"


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


def _read(key: str, cache_dir: str | os.PathLike[str] | None) -> Any:
    """The entry's bytes (for np.load); None when it is absent or not a regular file."""
    data = read_bytes(_entry_name(key), cache_dir)
    return None if data is None else io.BytesIO(data)


def read_bytes(name: str, cache_dir: str | os.PathLike[str] | None = None) -> bytes | None:
    """The bytes of the entry ``name`` (a path inside the store, ``ab/abcd.npz``); None
    when it is absent or unreadable. A local entry is read through the guarded read
    (:func:`meshcol.io.safe_read.read_input`): one that is not a regular file (a FIFO
    planted in a shared cache) or over the cap is a miss, never a read that blocks."""
    from meshcol.errors import MeshcolError
    from meshcol.io.safe_read import read_input

    local = local_folder(cache_dir) if cache_dir is not None else None
    if cache_dir is None or local is not None:
        root = Path(local) if local is not None else default_cache_dir()
        try:
            return read_input(root / name, "mesh")
        except (OSError, MeshcolError):
            return None
    fs, root_path = _filesystem(os.fspath(cache_dir))
    try:
        data: bytes = fs.cat_file(f"{root_path}/{name}")
    except (FileNotFoundError, OSError):
        return None
    return data


def load(key: str, cache_dir: str | os.PathLike[str] | None = None) -> Decomposition | None:
    """The cached decomposition for ``key``, or None when absent or unreadable."""
    import numpy as np

    from meshcol.decomposition.fidelity import METRICS_VERSION
    from meshcol.decomposition.result import Decomposition, Fidelity

    source = _read(key, cache_dir)
    if source is None:
        return None
    try:
        with np.load(source, allow_pickle=False) as z:
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


def store(result: Decomposition, cache_dir: str | os.PathLike[str] | None = None) -> Path | str:
    """Write ``result`` under its key, atomically (see the module's notes); returns where the
    entry is (a Path, or the entry's URL)."""
    import numpy as np

    from meshcol.collision.arrays import as_offsets
    from meshcol.decomposition.fidelity import METRICS_VERSION

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
        vertex_offsets=as_offsets(vcount),
        face_offsets=as_offsets(fcount),
    )
    return write_bytes(_entry_name(result.cache_key), buf.getvalue(), cache_dir)


def write_bytes(
    name: str, data: bytes, cache_dir: str | os.PathLike[str] | None = None
) -> Path | str:
    """Write ``data`` as the entry ``name`` (a path inside the store), atomically (see the
    module's notes); returns where it is (a Path, or its URL)."""
    local = local_folder(cache_dir) if cache_dir is not None else None
    if cache_dir is None or local is not None:
        path = (Path(local) if local is not None else default_cache_dir()) / name
        path.parent.mkdir(parents=True, exist_ok=True)
        with atomic_path(path, staged=False) as tmp, open(tmp, "wb") as f:
            f.write(data)
        return path
    url = os.fspath(cache_dir)
    fs, root = _filesystem(url)
    target = f"{root}/{name}"
    protocol = fs.protocol if isinstance(fs.protocol, str) else fs.protocol[0]
    if protocol in _OBJECT_STORES:
        fs.pipe_file(target, data)  # one put: readers see the whole object or none
    else:
        fs.makedirs(target.rsplit("/", 1)[0], exist_ok=True)
        tmp = f"{target}.{uuid.uuid4().hex}.tmp"
        try:
            fs.pipe_file(tmp, data)
            fs.mv(tmp, target)
        except BaseException:
            try:
                fs.rm(tmp)
            except (FileNotFoundError, OSError):
                pass
            raise
    return f"{url.rstrip('/')}/{name}"
