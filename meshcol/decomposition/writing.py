"""The parts of a run over files, planned and written.

Each file's bodies are planned as the file is read (:class:`OutputGuard`): no two bodies write
the same files, and no body's parts replace an input or another output of the caller. The
parts are written at the end, all together (:func:`meshcol.io.outputs.staged_folder`), in the
world frame (each body's pose applied), and each file's report entry and CSV rows are made
from what was written (:func:`write_files`).
"""

from __future__ import annotations

import contextlib
import os
import re
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from meshcol.decomposition.options import DecomposeOptions
from meshcol.decomposition.report import body_report
from meshcol.decomposition.tasks import BodyMesh
from meshcol.errors import MeshcolError

__all__ = ["FileResult", "OutputGuard", "PartsLayout", "write_files"]


@dataclass(frozen=True)
class PartsLayout:
    """Where and how the parts are written: the folder, the files per body
    (:func:`meshcol.io.mesh_write.write_parts`) and their format."""

    out_dir: str
    layout: str = "parts"
    fmt: str = "obj"


@dataclass(frozen=True)
class FileResult:
    """What became of one input file: ``status`` ``ok``, ``failed`` or ``timeout``; ``value``
    the (body name, decomposition or search) of each body when ok."""

    path: str
    bodies: list[BodyMesh]
    status: str
    value: Any
    message: str | None
    seconds: float


class OutputGuard:
    """Refuses, before anything is written, parts that would replace a protected file (an
    input, a source file a manifest names, the caller's report) or another body's parts:
    each body's file-name pattern in the output folder is checked against each protected
    file, whichever comes first."""

    def __init__(self, parts: PartsLayout, protected: list[str]) -> None:
        from meshcol.io.outputs import same_file

        self._same_file = same_file
        self.parts = parts
        self.out_dir = parts.out_dir
        self.patterns: list[tuple[str, re.Pattern[str]]] = []
        self.protected: set[str] = set()
        self.inside: list[str] = []  # the protected files in the output folder, in order
        self.names: dict[str, str] = {}  # safe name -> the file of the body that has it
        for path in protected:
            self.protect(path)

    def plan_file(self, path: str, bodies: Sequence[BodyMesh]) -> None:
        """A file read: protect it, and plan its bodies' files."""
        from meshcol.io.mesh_write import layout_file_pattern, safe_name

        self.protect(path)
        for name, _, _, _ in bodies:
            clean = safe_name(name)
            if clean in self.names:
                raise MeshcolError(
                    f"two bodies would write {clean!r} (also from {self.names[clean]}): rename one",
                    path,
                )
            self.names[clean] = path
            self.plan(name, layout_file_pattern(clean, self.parts.layout, self.parts.fmt))

    def _in_out_dir(self, path: str) -> bool:
        return self._same_file(os.path.dirname(os.path.abspath(path)), self.out_dir)

    def protect(self, path: str) -> None:
        """Each file is placed once (in or out of the output folder): a library of n files
        checks each body's pattern against the few files inside, not n resolved paths."""
        if path in self.protected:
            return
        self.protected.add(path)
        if self._in_out_dir(path):
            self.inside.append(path)
            for body, pattern in self.patterns:
                self._check(body, pattern, path)

    def plan(self, body: str, pattern: re.Pattern[str]) -> None:
        self.patterns.append((body, pattern))
        for path in self.inside:
            self._check(body, pattern, path)

    def _check(self, body: str, pattern: re.Pattern[str], path: str) -> None:
        if pattern.fullmatch(os.path.basename(path)):
            raise MeshcolError(
                f"the parts of body {body!r} would replace this file (output folder "
                f"{self.out_dir}): choose another output folder",
                path,
            )


def write_files(
    results: Sequence[FileResult],
    parts: PartsLayout,
    options: DecomposeOptions,
    target: Any = None,
    threads: int = 0,
) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
    """Write every body's parts (fitted to ``target`` first) and report them: the file
    entries and the CSV rows, in input order. The folder is written all at once, and only
    when a body has parts to write."""
    from meshcol.io.outputs import staged_folder

    rows: list[dict[str, Any]] = []
    entries: list[dict[str, Any]] = []
    writes = any(r.status == "ok" and r.value for r in results)
    with staged_folder(parts.out_dir) if writes else contextlib.nullcontext(parts.out_dir) as stage:
        for result in results:
            entry: dict[str, Any] = {
                "path": result.path,
                "status": result.status,
                "message": result.message,
                "bodies": [],
                "seconds": round(result.seconds, 3),
            }
            if result.status == "ok":
                for body, row in _written_bodies(result, stage, parts, options, target, threads):
                    entry["bodies"].append(body)
                    rows.append(row)
            else:
                rows.append(
                    {"path": result.path, "status": result.status, "message": result.message}
                )
            entries.append(entry)
    return entries, rows


def _written_bodies(
    result: FileResult,
    stage: str,
    parts: PartsLayout,
    options: DecomposeOptions,
    target: Any,
    threads: int,
) -> list[tuple[dict[str, Any], dict[str, Any]]]:
    """Each body of a file that was decomposed: its parts written to ``stage`` in the world
    frame, its report entry and CSV row."""
    from meshcol.decomposition.target import apply_target
    from meshcol.io.mesh_write import write_parts

    searching = options.search_target() is not None
    meshes = {name: (v, f, pose) for name, v, f, pose in result.bodies}
    reported = []
    for name, found in result.value:
        searched = found if searching else None
        decomposition = found.decomposition if searched is not None else found
        vertices, faces, pose = meshes[name]
        target_entry = None
        if target is not None:
            decomposition, target_entry = apply_target(
                target, decomposition, vertices, faces, threads=threads
            )
        world = [(v @ pose[:3, :3].T + pose[:3, 3], f) for v, f in decomposition.parts]
        written = write_parts(name, world, stage, parts.layout, parts.fmt)
        outputs = [os.path.relpath(path, stage) for path in written]
        body, row = body_report(
            result.path,
            name,
            outputs,
            decomposition,
            options.max_hausdorff,
            options.max_parts,
            searched,
        )
        if target_entry is not None:
            body["target"] = target_entry
            body["target_ok"] = target_entry["met"]
            row["target_ok"] = target_entry["met"]
        reported.append((body, row))
    return reported
