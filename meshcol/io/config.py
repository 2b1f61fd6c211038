"""The repository's configuration: ``meshcol.toml``, or ``[tool.meshcol]`` in ``pyproject.toml``.

Found as ruff finds its own: from the working folder upwards, the closest folder holding a
``meshcol.toml`` (or a ``pyproject.toml`` with a ``[tool.meshcol]`` table; ``meshcol.toml``
first in one folder) wins, and nothing above it is read. The file's keys are those of
``schemas/config.schema.json`` (documented in docs/config.md), checked here against that
schema: a bad key or value is one :class:`ConfigError` naming the file, the line and the key
(``meshcol.toml:12: assets[1].inspect.fail_on: unknown key ...``). tomllib gives no line
numbers, so the line is found by scanning the text for the key (:func:`line_of`).

:func:`resolve` gives the settings of one file (an asset a glob section matches, a scene a
scene section names) and where each came from: ``meshcol.toml:7``, a flag (``--set``,
``--shape``, ``--target``) or ``default``.
"""

from __future__ import annotations

import dataclasses
import functools
import json
import os
import re
import sys
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path
from typing import Any

from meshcol.errors import MeshcolError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    import tomli as tomllib

__all__ = [
    "COMMANDS",
    "CONFIG_NAMES",
    "SCHEMA_PATH",
    "Config",
    "ConfigError",
    "Resolved",
    "find_config",
    "glob_regex",
    "line_of",
    "load_config",
    "parse_override",
    "resolve",
    "resolve_all",
    "run_settings",
]

#: The files that hold a configuration, in the order one folder is searched.
CONFIG_NAMES = ("meshcol.toml", "pyproject.toml")
SCHEMA_PATH = Path(__file__).resolve().parent.parent / "schemas" / "config.schema.json"
#: The commands a section runs, in the order a run lists them; each is a table of the section.
COMMANDS = ("inspect", "hull", "fit", "check")
#: The command a section runs when it names none.
DEFAULT_COMMAND = {"assets": "inspect", "scenes": "check"}
#: The keys of a section that are no settings (what it matches).
_MATCH_KEYS = {"assets": "glob", "scenes": "path"}
#: Folders never walked for assets.
_SKIPPED_FOLDERS = frozenset({".git", ".hg", ".svn", ".venv", "node_modules", "__pycache__"})


class ConfigError(MeshcolError, ValueError):
    """The configuration file is malformed: a bad key or value (the message names the key
    and the line)."""


@cache
def schema() -> dict[str, Any]:
    """The configuration's JSON Schema (``schemas/config.schema.json``)."""
    loaded: dict[str, Any] = json.loads(SCHEMA_PATH.read_text(encoding="utf-8"))
    return loaded


def _ref(node: Mapping[str, Any]) -> Mapping[str, Any]:
    while "$ref" in node:
        node = schema()["$defs"][node["$ref"].rsplit("/", 1)[1]]
    return node


# --- finding and reading -------------------------------------------------------------------------


def _has_table(pyproject: Path) -> bool:
    try:
        data = tomllib.loads(pyproject.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError):
        return False
    return isinstance(data.get("tool"), dict) and "meshcol" in data["tool"]


def find_config(start: str | os.PathLike[str] | None = None) -> Path | None:
    """The configuration file for ``start`` (default the working folder): in it or the
    closest folder above holding ``meshcol.toml`` or a ``pyproject.toml`` with
    ``[tool.meshcol]``; None when there is none."""
    folder = Path(start if start is not None else os.getcwd()).resolve()
    if folder.is_file():
        folder = folder.parent
    for candidate in (folder, *folder.parents):
        if (candidate / "meshcol.toml").is_file():
            return candidate / "meshcol.toml"
        if (candidate / "pyproject.toml").is_file() and _has_table(candidate / "pyproject.toml"):
            return candidate / "pyproject.toml"
    return None


@dataclass(frozen=True)
class Section:
    """One ``[[assets]]`` or ``[[scenes]]`` table: its kind, index, keys and its patterns."""

    kind: str
    index: int
    data: Mapping[str, Any]
    patterns: tuple[re.Pattern[str], ...]
    exclude: tuple[re.Pattern[str], ...]

    @property
    def label(self) -> str:
        return f"{self.kind}[{self.index}]"

    def matches(self, relative: str) -> bool:
        return self.regex.fullmatch(relative) is not None

    @functools.cached_property
    def regex(self) -> re.Pattern[str]:
        """The section's globs and its ``exclude`` globs as one pattern (to ``fullmatch``)."""
        include = "|".join(f"(?:{p.pattern})" for p in self.patterns)
        if not self.exclude:
            return re.compile(include)
        exclude = "|".join(f"(?:{p.pattern})" for p in self.exclude)
        return re.compile(f"(?!(?:{exclude})\\Z)(?:{include})")


@dataclass(frozen=True)
class Config:
    """A configuration read and checked: its file, the folder paths are relative to, its
    keys, its text (for line numbers) and its sections."""

    path: Path
    data: Mapping[str, Any]
    text: str
    table: tuple[str, ...]
    sections: tuple[Section, ...] = ()
    #: resolutions shared by the files the same sections match (:func:`resolve`)
    memo: dict[str, Any] = field(default_factory=dict, compare=False, repr=False)

    @property
    def folder(self) -> Path:
        return self.path.parent

    def get(self, key: str) -> Any:
        value = self.data.get(key, _ref(schema()["properties"][key]).get("default"))
        return value

    def origin(self, *keys: str | int) -> str:
        """``FILE:LINE`` of a key (``("assets", 1, "shape")``), as :func:`line_of` finds it."""
        line = line_of(self.text, self.table + tuple(keys))
        return f"{self.path.name}:{line}" if line else self.path.name

    def error(self, keys: Sequence[str | int], problem: str) -> ConfigError:
        """A :class:`ConfigError` naming the file, the key's line and the key."""
        line = line_of(self.text, self.table + tuple(keys))
        where = f"{self.path}:{line}" if line else os.fspath(self.path)
        return ConfigError(f"{key_name(keys)}: {problem}", where)

    def files(self) -> Iterator[str]:
        """Every file under the config's folder (relative, ``/``-separated, sorted), outside
        the top-level ``exclude`` globs and version-control folders."""
        globs = self.get("exclude")
        exclude = re.compile("|".join(f"(?:{glob_regex(g).pattern})" for g in globs))
        for top, folders, names in os.walk(self.folder):
            folders[:] = sorted(f for f in folders if f not in _SKIPPED_FOLDERS)
            prefix = os.path.relpath(top, self.folder).replace(os.sep, "/")
            for name in sorted(names):
                relative = name if prefix == "." else f"{prefix}/{name}"
                if not globs or exclude.fullmatch(relative) is None:
                    yield relative


def key_name(keys: Sequence[str | int]) -> str:
    """``assets[1].inspect.fail-on``."""
    text = ""
    for key in keys:
        text += f"[{key}]" if isinstance(key, int) else (f".{key}" if text else key)
    return text or "(top level)"


def load_config(path: str | os.PathLike[str]) -> Config:
    """Read and check a configuration file (``meshcol.toml`` or a ``pyproject.toml``).

    Raises
    ------
    ConfigError
        Unreadable, not TOML (tomllib's line and column), or a key or value against the
        schema (the key and its line).
    """
    file = Path(path).resolve()
    try:
        text = file.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(f"cannot read the configuration: {exc}", os.fspath(path)) from None
    try:
        document = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"not TOML: {exc}", os.fspath(path)) from None
    table: tuple[str, ...] = ()
    if file.name == "pyproject.toml":
        table = ("tool", "meshcol")
        document = document.get("tool", {}).get("meshcol", {})
        if not isinstance(document, dict):
            raise ConfigError("[tool.meshcol] is not a table", os.fspath(path))
    config = Config(file, document, text, table)
    _validate(config, document, schema(), ())
    sections = []
    for kind in ("assets", "scenes"):
        for index, data in enumerate(document.get(kind, [])):
            match = data[_MATCH_KEYS[kind]]
            globs = [match] if isinstance(match, str) else list(match)
            sections.append(
                Section(
                    kind,
                    index,
                    data,
                    tuple(glob_regex(g) for g in globs),
                    tuple(glob_regex(g) for g in data.get("exclude", [])),
                )
            )
    return Config(file, document, text, table, tuple(sections))


# --- the schema's checks ------------------------------------------------------------------------

_TYPES: dict[str, tuple[type, ...]] = {
    "string": (str,),
    "number": (int, float),
    "integer": (int,),
    "boolean": (bool,),
    "object": (dict,),
    "array": (list,),
}


def _type_ok(value: Any, name: str) -> bool:
    if isinstance(value, bool) and name in ("number", "integer"):
        return False
    return isinstance(value, _TYPES[name])


def _validate(config: Config, value: Any, node: Mapping[str, Any], keys: tuple) -> None:
    """Check ``value`` against the schema ``node`` (the subset the config schema uses)."""
    node = _ref(node)
    if "anyOf" in node:
        problems = []
        for option in node["anyOf"]:
            try:
                _validate(config, value, option, keys)
                return
            except ConfigError as exc:
                problems.append(exc.message.split(": ", 1)[-1])
        raise config.error(keys, " or ".join(dict.fromkeys(problems)))
    if "enum" in node and value not in node["enum"]:
        choices = ", ".join(map(str, node["enum"]))
        raise config.error(keys, f"must be one of {choices}, got {value!r}")
    kind = node.get("type")
    if kind is not None and not _type_ok(value, kind):
        raise config.error(keys, f"must be {_article(kind)}, got {_toml_type(value)} {value!r}")
    if "minimum" in node and value < node["minimum"]:
        raise config.error(keys, f"must be >= {node['minimum']}, got {value!r}")
    if "minLength" in node and len(value) < node["minLength"]:
        raise config.error(keys, "must not be empty")
    if kind == "array":
        if len(value) < node.get("minItems", 0):
            raise config.error(keys, "must not be empty")
        for i, item in enumerate(value):
            _validate(config, item, node.get("items", {}), keys + (i,))
    if kind == "object":
        _validate_object(config, value, node, keys)


def _validate_object(config: Config, value: dict, node: Mapping[str, Any], keys: tuple) -> None:
    properties = node.get("properties", {})
    extra = node.get("additionalProperties", True)
    for key, item in value.items():
        if key in properties:
            _validate(config, item, properties[key], keys + (key,))
        elif extra is False:
            hint = _close_key(key, properties)
            raise config.error(
                keys + (key,),
                f"unknown key{hint} (expected one of {', '.join(properties)})",
            )
        elif isinstance(extra, dict):
            _validate(config, item, extra, keys + (key,))
    for key in node.get("required", ()):
        if key not in value:
            raise config.error(keys, f"missing the required key {key!r}")


def _close_key(key: str, properties: Mapping[str, Any]) -> str:
    dashed = key.replace("_", "-")
    return f" (did you mean {dashed!r}?)" if dashed != key and dashed in properties else ""


def _article(kind: str) -> str:
    return {"integer": "an integer", "object": "a table", "array": "an array"}.get(
        kind, f"a {kind}"
    )


def _toml_type(value: Any) -> str:
    for name, types in (("boolean", (bool,)), ("table", (dict,)), ("array", (list,))):
        if isinstance(value, types):
            return name
    return "number" if isinstance(value, (int, float)) else "string"


# --- lines ----------------------------------------------------------------------------------------

_HEADER = re.compile(r"^\s*(\[\[?)\s*([^\]]+?)\s*\]\]?")


def _key_pattern(key: str) -> re.Pattern[str]:
    quoted = re.escape(key)
    return re.compile(rf"(^|[\s{{,.])(\"{quoted}\"|'{quoted}'|{quoted})\s*[=.]")


def line_of(text: str, keys: Sequence[str | int]) -> int | None:
    """The 1-based line of ``keys`` (``("tool", "meshcol", "assets", 1, "shape")``) in a TOML
    ``text``, found by scanning: the ``N``th ``[[...assets]]`` header, then the key inside
    that table (as ``key =``, or in an inline table or a sub-table header); the line of the
    closest enclosing key found when the key itself is not (a value inside an array)."""
    lines = text.splitlines()
    start, end, best = 0, len(lines), None
    prefix: list[str] = []
    i = 0
    while i < len(keys):
        key = keys[i]
        if isinstance(key, int):
            i += 1
            continue
        index = keys[i + 1] if i + 1 < len(keys) and isinstance(keys[i + 1], int) else None
        prefix.append(key)
        found = _find_table(lines, start, end, ".".join(prefix), index)
        if found is not None:
            start, end = found
            best = start + 1
            i += 1
            continue
        if _has_subtable(lines, start, end, ".".join(prefix)):
            i += 1  # only a dotted part of a header's name (``tool`` of ``[tool.meshcol]``)
            continue
        pattern = _key_pattern(key)
        hit = next((n for n in range(start, end) if pattern.search(_header_free(lines[n]))), None)
        if hit is None:
            return best
        best, start = hit + 1, hit
        i += 1
    return best


def _has_subtable(lines: list[str], start: int, end: int, name: str) -> bool:
    for n in range(start, end):
        match = _HEADER.match(lines[n])
        if match is not None and match.group(2).replace(" ", "").startswith(name + "."):
            return True
    return False


def _header_free(line: str) -> str:
    return "" if _HEADER.match(line) else line


def _find_table(
    lines: list[str], start: int, end: int, name: str, index: int | str | None
) -> tuple[int, int] | None:
    """Lines ``(header, end)`` of the table ``[name]`` or the ``index``th ``[[name]]`` within
    ``start..end``; its end is the next header that is not one of its sub-tables."""
    count = -1
    for n in range(start, end):
        match = _HEADER.match(lines[n])
        if match is None or match.group(2).replace(" ", "") != name:
            continue
        if match.group(1) == "[[":
            count += 1
            if index is None or count != index:
                continue
        for m in range(n + 1, end):
            other = _HEADER.match(lines[m])
            if other is not None and not other.group(2).replace(" ", "").startswith(name + "."):
                return n, m
        return n, end
    return None


# --- globs ----------------------------------------------------------------------------------------


@cache
def glob_regex(glob: str) -> re.Pattern[str]:
    """A glob over ``/``-separated relative paths: ``*`` and ``?`` within one folder name,
    ``**`` any folders (``props/**/*.obj`` matches ``props/a.obj`` and ``props/x/y/a.obj``),
    ``[abc]`` one of."""
    out, i = [], 0
    glob = glob.lstrip("./") if glob.startswith("./") else glob
    while i < len(glob):
        if glob.startswith("**/", i):
            out.append("(?:.*/)?")
            i += 3
        elif glob.startswith("**", i):
            out.append(".*")
            i += 2
        elif glob[i] == "*":
            out.append("[^/]*")
            i += 1
        elif glob[i] == "?":
            out.append("[^/]")
            i += 1
        elif glob[i] == "[" and "]" in glob[i + 1 :]:
            close = glob.index("]", i + 1)
            out.append("[" + glob[i + 1 : close].replace("!", "^", 1) + "]")
            i = close + 1
        else:
            out.append(re.escape(glob[i]))
            i += 1
    return re.compile("".join(out))


# --- resolution -----------------------------------------------------------------------------------


@dataclass(frozen=True)
class Resolved:
    """The settings of one file as one kind (``assets`` or ``scenes``): each dotted key's
    value (``shape``, ``inspect.fail-on``) and where it came from (``meshcol.toml:7``,
    ``flag --shape``, ``default``), the commands it runs and the sections that matched."""

    path: str
    kind: str
    commands: tuple[str, ...]
    values: Mapping[str, Any]
    origins: Mapping[str, str]
    sections: tuple[str, ...] = field(default_factory=tuple)

    def command_settings(self, command: str) -> dict[str, Any]:
        """The settings one command reads: the section's own keys, its table's and the
        robot's (``robot.joints`` as ``joints``)."""
        shared = {k: v for k, v in self.values.items() if "." not in k}
        for table in ("robot", command):
            shared |= {
                k.split(".", 1)[1]: v for k, v in self.values.items() if k.startswith(table + ".")
            }
        return shared


def setting_keys() -> dict[str, Mapping[str, Any]]:
    """Every dotted setting key of a section and its schema node (``shape``,
    ``inspect.fail-on``, ``robot.joints``...)."""
    node = _ref(schema()["$defs"]["asset"])["properties"]
    keys: dict[str, Mapping[str, Any]] = {}
    for name, sub in node.items():
        if name in ("glob", "exclude"):
            continue
        sub = _ref(sub)
        if name in COMMANDS or name == "robot":
            for inner, leaf in sub["properties"].items():
                keys[f"{name}.{inner}"] = _ref(leaf)
        else:
            keys[name] = sub
    return keys


def parse_override(text: str, flag: str = "--set") -> tuple[str, Any]:
    """``KEY=VALUE`` (a TOML value; a bare word is a string) to ``(key, value)``, checked
    against the schema.

    Raises
    ------
    ValueError
        An unknown key or a bad value, worded for the flag.
    """
    key, sep, raw = text.partition("=")
    key = key.strip()
    keys = setting_keys()
    if not sep or key not in keys:
        raise ValueError(
            f"{text!r}: expected KEY=VALUE with KEY one of {', '.join(keys)}"
            if sep
            else f"{text!r}: expected KEY=VALUE"
        )
    try:
        value = tomllib.loads(f"v = {raw}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw.strip()
    probe = Config(Path(flag), {}, "", ())
    try:
        _validate(probe, value, keys[key], (key,))
    except ConfigError as exc:
        raise ValueError(exc.message) from None
    return key, value


def _section_values(config: Config, section: Section) -> Iterator[tuple[str, Any, str]]:
    """``(dotted key, value, origin)`` of every setting a section gives."""
    for name, value in section.data.items():
        if name in ("glob", "path", "exclude"):
            continue
        base: tuple[str | int, ...] = (section.kind, section.index, name)
        if name in COMMANDS or name == "robot":
            yield name, True, config.origin(*base)
            for inner, item in value.items():
                yield f"{name}.{inner}", item, config.origin(*base, inner)
        else:
            yield name, value, config.origin(*base)


def resolve(
    config: Config,
    path: str | os.PathLike[str],
    overrides: Mapping[str, tuple[Any, str]] = {},
    shared: bool = False,
) -> list[Resolved]:
    """The settings of ``path`` (relative to the config's folder, or absolute): one
    :class:`Resolved` per kind of section that matches it (an asset, a scene, or both), the
    sections applied in file order (a later one's key wins), then ``overrides``
    (``key -> (value, origin)``, the flags), then the schema's defaults. ``shared``: the
    one object of every file the same sections match, its ``path`` empty (a plan of
    10,000 files makes no copy per file)."""
    relative = _relative(config, path)
    out = []
    shared_only = shared
    for kind in ("assets", "scenes"):
        matched = tuple(s for s in config.sections if s.kind == kind and s.matches(relative))
        if not matched:
            continue
        # files the same sections match share one resolution (10,000 props, a few sections)
        memo_key = (
            kind,
            tuple(s.index for s in matched),
            tuple(sorted(overrides.items(), key=str)),
        )
        one = config.memo.get(repr(memo_key))
        if one is None:
            one = config.memo[repr(memo_key)] = _resolve(config, kind, matched, overrides)
        out.append(one if shared_only else dataclasses.replace(one, path=relative))
    return out


def resolve_all(
    config: Config,
    files: Iterable[str],
    overrides: Mapping[str, tuple[Any, str]] = {},
) -> Iterator[tuple[str, list[Resolved]]]:
    """``(path, resolve(config, path, overrides, shared=True))`` of each of ``files`` that
    a section matches, the same objects, for 10,000 files at once: one pattern per section
    (:attr:`Section.regex`), one for them all, and one resolution per set of sections."""
    sections = [section.regex.fullmatch for section in config.sections]
    anyone = re.compile("|".join(f"(?:{s.regex.pattern})" for s in config.sections)).fullmatch
    memo: dict[tuple[int, ...], list[Resolved]] = {}
    for path in files:
        relative = _relative(config, path)
        if len(sections) > 1 and anyone(relative) is None:
            continue
        matched = tuple(i for i, match in enumerate(sections) if match(relative) is not None)
        if not matched:
            continue
        found = memo.get(matched)
        if found is None:
            found = memo[matched] = resolve(config, relative, overrides, shared=True)
        yield path, found


def _resolve(
    config: Config,
    kind: str,
    matched: Sequence[Section],
    overrides: Mapping[str, tuple[Any, str]],
) -> Resolved:
    keys = setting_keys()
    values: dict[str, Any] = {}
    origins: dict[str, str] = {}
    commands: dict[str, None] = {}
    for section in matched:
        for key, value, origin in _section_values(config, section):
            if key in COMMANDS:
                commands[key] = None
            elif key != "robot":
                values[key], origins[key] = value, origin
    for key, (value, origin) in overrides.items():
        values[key], origins[key] = value, origin
    for key, node in keys.items():
        if key not in values:
            values[key], origins[key] = node.get("default"), "default"
    ordered = tuple(c for c in COMMANDS if c in commands) or (DEFAULT_COMMAND[kind],)
    labels = tuple(f"{s.label} ({config.origin(s.kind, s.index)})" for s in matched)
    return Resolved("", kind, ordered, values, origins, labels)


#: What makes a path other than as :meth:`Config.files` gives it (absolute, ``./``, ``..``,
#: ``//``, a backslash).
_ODD_PATH = re.compile(r"\\|/\./|/\.\./|//|\A(?:/|\./|\.\./)")


def _relative(config: Config, path: str | os.PathLike[str]) -> str:
    if isinstance(path, str) and _ODD_PATH.search(path) is None:
        return path  # already as Config.files gives it (the common case, no pathlib)
    file = Path(path)
    if file.is_absolute():
        try:
            file = file.resolve().relative_to(config.folder)
        except ValueError:
            return file.as_posix()
    return os.path.normpath(file).replace(os.sep, "/")


# --- run settings (top-level keys) ------------------------------------------------------------

#: The top-level keys that set how a run runs (not which files are what), in display order.
RUN_KEYS = ("root", "cache-dir", "jobs", "docs-url")


def run_settings(
    config: Config, flags: Mapping[str, tuple[Any, str]] = {}
) -> dict[str, tuple[Any, str]]:
    """Each top-level run setting (:data:`RUN_KEYS`) as ``key -> (value, origin)``: a flag
    given in ``flags`` (``{"jobs": (2, "flag -j")}``, None values ignored) wins over an
    environment variable (``docs-url``: ``$MESHCOL_DOCS_URL``), which wins over the file
    (``meshcol.toml:3``), which wins over the schema's default (``default``)."""
    from meshcol.io.sarif import HOME_ENV

    environment = {"docs-url": HOME_ENV}
    out: dict[str, tuple[Any, str]] = {}
    for key in RUN_KEYS:
        flag = flags.get(key)
        variable = environment.get(key)
        if flag is not None and flag[0] is not None:
            out[key] = flag
        elif variable is not None and os.environ.get(variable):
            out[key] = (os.environ[variable], f"env {variable}")
        elif key in config.data:
            out[key] = (config.data[key], config.origin(key))
        else:
            out[key] = (config.get(key), "default")
    return out
