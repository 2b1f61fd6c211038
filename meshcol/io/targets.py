"""Engine target profiles: the limits a physics engine puts on convex colliders.

A profile is a TOML file: the package's own in ``meshcol/targets/<name>.toml`` (every file
of that folder is one, by its name: ``meshcol targets`` lists them; there is no list to edit),
or a user's file given by path. :func:`load_target` reads and validates one,
:func:`list_targets` the package's, :func:`targets_markdown` writes them as the page
``docs/targets.md`` (a test keeps it current). The limits are measured by
:mod:`meshcol.collision.limits`; this module only reads files.

A profile::

    name = "physx-gpu"
    title = "NVIDIA PhysX 5, GPU pipeline"
    units = "m"                         # the length unit the engine expects meshes in
    description = "..."

    [limits]                            # every key optional; absent = no limit
    max_hull_vertices = 64
    max_hull_polygons = 64
    max_faces_per_vertex = 32
    max_oblong_ratio = 100.0
    min_thickness = 0.001               # metres (converted to the mesh's units)

    [naming]                            # optional: how the engine names convex parts
    convex_prefix = "UCX_"

    [[sources]]                         # where each number comes from
    limit = "max_hull_vertices"
    url = "https://..."
    quote = "the sentence of the document that gives the number"
    kind = "documented"                 # or "convention": a default or a practice, not a hard limit
    note = "optional: why this value"
"""

from __future__ import annotations

import math
import os
import sys
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from meshcol.errors import TargetError
from meshcol.vocabulary import COUNT_LIMITS, LIMIT_KEYS

__all__ = [
    "COUNT_LIMITS",
    "LENGTH_UNITS",
    "LIMIT_KEYS",
    "TARGETS_DIR",
    "Source",
    "Target",
    "list_targets",
    "load_target",
    "metres_per_unit",
    "target_names",
    "targets_markdown",
]

#: The folder of the package's profiles.
TARGETS_DIR = Path(__file__).resolve().parent.parent / "targets"

#: Length units a profile or a scene manifest may declare, in metres.
LENGTH_UNITS: dict[str, float] = {
    "m": 1.0,
    "cm": 0.01,
    "mm": 0.001,
    "km": 1000.0,
    "in": 0.0254,
    "ft": 0.3048,
}

_TOP_KEYS = frozenset({"name", "title", "units", "description", "limits", "naming", "sources"})
_NAMING_KEYS = frozenset({"convex_prefix", "box_prefix", "capsule_prefix", "sphere_prefix"})
_SOURCE_KEYS = frozenset({"limit", "url", "quote", "kind", "note"})
_SOURCE_KINDS = ("documented", "convention")


@dataclass(frozen=True)
class Source:
    """Where a limit's number comes from.

    Attributes
    ----------
    limit : str
        The limit key (or ``naming`` / ``units``) the source is for.
    url : str
        The document.
    quote : str
        The sentence or figure of the document that gives the number.
    kind : {"documented", "convention"}
        ``documented``: a hard limit the document states. ``convention``: a default, a
        recommended practice, or a number meshcol chose where the document is silent.
    note : str or None
        Why this value, when the quote alone does not say.
    """

    limit: str
    url: str
    quote: str
    kind: str
    note: str | None = None

    def to_dict(self) -> dict[str, Any]:
        return {
            "limit": self.limit,
            "url": self.url,
            "quote": self.quote,
            "kind": self.kind,
            "note": self.note,
        }


@dataclass(frozen=True)
class Target:
    """An engine target profile.

    Attributes
    ----------
    name : str
        The profile's name (``physx-gpu``), or the file's stem for a user profile.
    title : str
        What engine and pipeline it describes.
    units : str
        The length unit the engine expects meshes in (a key of :data:`LENGTH_UNITS`):
        ``min_thickness`` (metres) and ``min_volume`` (cubic metres) are converted to it
        when the input does not declare its own units.
    limits : mapping of str to int or float
        The limits (keys of :data:`LIMIT_KEYS`); an absent key is no limit.
    naming : mapping of str to str
        How the engine names collider parts (``convex_prefix = "UCX_"``).
    sources : tuple of Source
        Where the numbers come from.
    description : str or None
    path : str
        The file the profile was read from.
    """

    name: str
    title: str
    units: str
    limits: Mapping[str, float]
    naming: Mapping[str, str] = field(default_factory=dict)
    sources: tuple[Source, ...] = ()
    description: str | None = None
    path: str = ""

    def limit(self, key: str) -> float | None:
        """The limit ``key`` (:data:`LIMIT_KEYS`), or None when the profile sets none."""
        if key not in LIMIT_KEYS:
            raise KeyError(key)
        return self.limits.get(key)

    def length_scale(self, units: str | None = None) -> float:
        """Mesh units per metre: ``min_thickness * length_scale(units)`` is the thickness
        limit in the mesh's units. ``units`` is the input's declared unit (a scene
        manifest's ``units``); None, or a unit meshcol does not know, means the profile's."""
        unit = units if units in LENGTH_UNITS else self.units
        return 1.0 / metres_per_unit(unit)

    def to_dict(self) -> dict[str, Any]:
        """The profile as ``meshcol targets --format json`` lists it."""
        return {
            "name": self.name,
            "title": self.title,
            "units": self.units,
            "description": self.description,
            "limits": {key: self.limits[key] for key in LIMIT_KEYS if key in self.limits},
            "naming": dict(self.naming),
            "sources": [s.to_dict() for s in self.sources],
            "path": self.path,
        }


def metres_per_unit(unit: str) -> float:
    """Metres in one ``unit`` (:data:`LENGTH_UNITS`); KeyError for another."""
    return LENGTH_UNITS[unit]


def list_targets() -> list[Target]:
    """Every profile of the package, sorted by name."""
    return [_read(path) for path in sorted(TARGETS_DIR.glob("*.toml"))]


def target_names() -> list[str]:
    """The names of the package's profiles, sorted."""
    return sorted(path.stem for path in TARGETS_DIR.glob("*.toml"))


def targets_markdown(targets: list[Target] | None = None) -> str:
    """The package's profiles (or ``targets``) as the Markdown page ``docs/targets.md``: one
    table of every limit, then each profile's sources (document, sentence, kind, note)."""
    targets = list_targets() if targets is None else targets
    lines = [
        "# meshcol engine targets",
        "",
        "The profiles of `--target NAME` (`meshcol hull`, `decompose`, `inspect`, `check`), one",
        "file each in `meshcol/targets/`, every number cited below; `-` is no limit, lengths",
        "are metres. Generated from those files (a test keeps this page current):",
        "",
        "```",
        'python -c "from meshcol.io.targets import targets_markdown; '
        "print(targets_markdown(), end='')\" > docs/targets.md",
        "```",
        "",
        "| name | engine | units | " + " | ".join(LIMIT_KEYS) + " |",
        "| --- | --- | --- | " + " | ".join("---" for _ in LIMIT_KEYS) + " |",
    ]
    for t in targets:
        cells = ["-" if t.limits.get(k) is None else f"{t.limits[k]:g}" for k in LIMIT_KEYS]
        lines.append(f"| `{t.name}` | {t.title} | {t.units} | " + " | ".join(cells) + " |")
    for t in targets:
        lines += ["", f"## {t.name}", ""]
        if t.description:
            lines += [t.description, ""]
        for s in t.sources:
            note = f" {s.note}" if s.note else ""
            lines.append(f'- `{s.limit}` ({s.kind}): <{s.url}>: "{s.quote}"{note}')
    return "\n".join(lines) + "\n"


def load_target(name_or_path: str | os.PathLike[str]) -> Target:
    """A target profile by name (``physx-gpu``) or by the path of a TOML file.

    Raises
    ------
    TargetError
        No profile of that name and no such file, or a file that is not valid TOML, has an
        unknown key, a value of the wrong type, or a negative (or zero) limit; the message
        names the file and the key.
    """
    text = os.fspath(name_or_path)
    builtin = TARGETS_DIR / f"{text}.toml"
    if os.sep not in text and "/" not in text and not text.endswith(".toml"):
        if builtin.is_file():
            return _read(builtin)
        raise TargetError(
            f"unknown target {text!r}: choose one of {', '.join(target_names())}, "
            "or give the path of a .toml profile"
        )
    path = Path(text)
    if not path.is_file():
        raise TargetError("target profile not found", text)
    return _read(path)


def _read(path: Path) -> Target:
    if sys.version_info >= (3, 11):
        import tomllib
    else:  # pragma: no cover - Python 3.10
        import tomli as tomllib
    where = os.fspath(path)
    try:
        document = tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as error:
        raise TargetError(f"invalid TOML: {str(error).splitlines()[0]}", where) from None
    except (OSError, UnicodeDecodeError) as error:
        raise TargetError(f"cannot read the profile: {error}", where) from None
    return _validate(document, where, path.stem)


def _fail(where: str, key: str, problem: str) -> TargetError:
    return TargetError(f"{key}: {problem}", where)


def _string(document: Mapping[str, Any], key: str, where: str, prefix: str = "") -> str | None:
    value = document.get(key)
    if value is None:
        return None
    if not isinstance(value, str) or not value.strip():
        raise _fail(where, prefix + key, f"must be a non-empty string, got {value!r}")
    return value


def _validate(document: dict[str, Any], where: str, stem: str) -> Target:
    unknown = sorted(set(document) - _TOP_KEYS)
    if unknown:
        raise _fail(where, unknown[0], f"unknown key (known: {', '.join(sorted(_TOP_KEYS))})")
    name = _string(document, "name", where) or stem
    title = _string(document, "title", where) or name
    description = _string(document, "description", where)
    units = _string(document, "units", where) or "m"
    if units not in LENGTH_UNITS:
        raise _fail(where, "units", f"unknown unit {units!r} (known: {', '.join(LENGTH_UNITS)})")
    return Target(
        name=name,
        title=title,
        units=units,
        limits=_limits(document.get("limits", {}), where),
        naming=_naming(document.get("naming", {}), where),
        sources=_sources(document.get("sources", []), where),
        description=description,
        path=where,
    )


#: The least value of each count limit, and why (a polytope's least).
_LEAST_COUNTS = {
    "max_hull_vertices": (4, " (a tetrahedron)"),
    "max_hull_polygons": (4, " (a tetrahedron)"),
    "max_faces_per_vertex": (3, " (a polytope's least)"),
}


def _limits(raw: Any, where: str) -> dict[str, float]:
    """The ``[limits]`` table: known keys, counts as integers at least their least, lengths
    and ratios as finite numbers >= 0."""
    if not isinstance(raw, dict):
        raise _fail(where, "limits", "must be a table")
    limits: dict[str, float] = {}
    for key, value in raw.items():
        label = f"limits.{key}"
        if key not in LIMIT_KEYS:
            raise _fail(where, label, f"unknown limit (known: {', '.join(LIMIT_KEYS)})")
        if key in COUNT_LIMITS:
            limits[key] = _count(value, key, label, where)
        else:
            limits[key] = _measure(value, key, label, where)
    if "max_hull_triangles" in limits and limits["max_hull_triangles"] < 4:
        raise _fail(where, "limits.max_hull_triangles", "must be at least 4 (a tetrahedron)")
    return limits


def _count(value: Any, key: str, label: str, where: str) -> int:
    if type(value) is not int:
        raise _fail(where, label, f"must be an integer, got {value!r}")
    if value < 1:
        raise _fail(where, label, f"must be at least 1, got {value}")
    least, why = _LEAST_COUNTS.get(key, (1, ""))
    if value < least:
        raise _fail(where, label, f"must be at least {least}{why}, got {value}")
    return value


def _measure(value: Any, key: str, label: str, where: str) -> float:
    if type(value) not in (int, float):
        raise _fail(where, label, f"must be a number, got {value!r}")
    number = float(value)
    if not math.isfinite(number) or number < 0:
        raise _fail(where, label, f"must be a finite number >= 0, got {value!r}")
    if key == "max_oblong_ratio" and number < 1:
        raise _fail(where, label, f"must be at least 1, got {value!r}")
    return number


def _naming(raw: Any, where: str) -> dict[str, str]:
    if not isinstance(raw, dict):
        raise _fail(where, "naming", "must be a table")
    naming: dict[str, str] = {}
    for key in raw:
        if key not in _NAMING_KEYS:
            raise _fail(
                where, f"naming.{key}", f"unknown key (known: {', '.join(sorted(_NAMING_KEYS))})"
            )
        naming[key] = _string(raw, key, where, "naming.") or ""
    return naming


def _sources(raw: Any, where: str) -> tuple[Source, ...]:
    if not isinstance(raw, list):
        raise _fail(where, "sources", "must be an array of tables ([[sources]])")
    return tuple(_source(entry, f"sources[{i}]", where) for i, entry in enumerate(raw))


def _source(entry: Any, label: str, where: str) -> Source:
    if not isinstance(entry, dict):
        raise _fail(where, label, "must be a table")
    extra = sorted(set(entry) - _SOURCE_KEYS)
    if extra:
        raise _fail(
            where, f"{label}.{extra[0]}", f"unknown key (known: {', '.join(sorted(_SOURCE_KEYS))})"
        )
    values = {}
    for key in ("limit", "url", "quote", "kind"):
        value = _string(entry, key, where, f"{label}.")
        if value is None:
            raise _fail(where, f"{label}.{key}", "is required")
        values[key] = value
    if values["kind"] not in _SOURCE_KINDS:
        raise _fail(
            where,
            f"{label}.kind",
            f"must be one of {', '.join(_SOURCE_KINDS)}, got {values['kind']!r}",
        )
    if values["limit"] not in (*LIMIT_KEYS, "naming", "units"):
        raise _fail(where, f"{label}.limit", f"unknown limit {values['limit']!r}")
    return Source(note=_string(entry, "note", where, f"{label}."), **values)
