"""SARIF 2.1.0: a run's findings for code-scanning services (GitHub code scanning, Azure DevOps).

Written from a report's CI suite (:class:`meshcol.io.ci.CiSuite`), like JUnit, so every
command that has one writes it. One ``result`` per rule a case breaks (a mesh with two
findings is two results), with:

- ``ruleId`` the rule's stable id (``MC401``) and ``ruleIndex`` its place in
  ``tool.driver.rules``, which describes every rule the command can report from the rules
  registry (:data:`meshcol.analysis.rules.RULES`, passed in as ``suite.rules``): short and
  full descriptions, the fix as help (embedded: a consumer needs no link), the default
  level from the rule's severity, and ``helpUri`` the rule's anchor in the rules page
  (``docs/rules.md``, generated from the registry) under the docs' base URL when one is set
  (:func:`docs_base`: ``$MESHCOL_DOCS_URL``, else the configuration's ``docs-url``); with
  none, no ``helpUri`` and no ``informationUri`` (no link to a host that is not there). A
  case whose kind is no registered rule (decompose's
  ``max-hausdorff``, hull's ``max-vertices``, sweep's ``HIT``) cites its kind as the rule, with
  a descriptor made for it.
- ``level`` from the severity (``error``, ``warning``; ``info`` is ``note``); a kind that is no
  registered rule is ``error`` when the policy fails on it, else ``warning``.
- a physical location on the asset file: ``artifactLocation.uri`` relative to the repository
  root (``$GITHUB_WORKSPACE``, else the working folder) with ``uriBaseId`` ``%SRCROOT%``
  (``run.originalUriBaseIds`` says where that is); in a text input (a manifest, a robot
  description) the line that names the case's (first) body as its ``region``, so that a
  pull request shows the alert on that line; a mesh file has no region (a finding is about
  the whole mesh). The body or pair is the logical location.
- ``partialFingerprints`` that hash the command, the rule, the file and the body or pair, and
  none of the numbers, so that a code-scanning service keeps tracking one alert across runs
  whose depths differ.
- ``suppressions`` for a case the user's ``--ignore`` spares.

Inputs that could not be read (``error`` cases) are the invocation's
``toolExecutionNotifications``, not results: they are about the run, not the code.
``run.automationDetails.id`` is ``meshcol/COMMAND/``, so the alerts of each command are one
category.
"""

from __future__ import annotations

import hashlib
import json
import os
import urllib.parse
from collections.abc import Mapping
from typing import Any

from meshcol.io.ci import CiCase, CiSuite
from meshcol.io.report import dumps_json

__all__ = [
    "SARIF_SCHEMA",
    "SARIF_VERSION",
    "docs_base",
    "dumps_sarif",
    "rule_uri",
    "sarif_log",
    "source_root",
]

SARIF_VERSION = "2.1.0"
#: The OASIS schema of SARIF 2.1.0 (errata 01), as ``$schema`` names it.
SARIF_SCHEMA = (
    "https://docs.oasis-open.org/sarif/sarif/v2.1.0/errata01/os/schemas/sarif-schema-2.1.0.json"
)
#: The rules page, as the docs folder holds it (generated from the registry).
RULES_PAGE = "rules.md"
#: The environment variable that sets the docs' base URL (over the config's ``docs-url``).
HOME_ENV = "MESHCOL_DOCS_URL"
#: Suffixes of a base URL that is the rules page itself (a rendered site's ``rules.html``).
_PAGE_SUFFIXES = (".md", ".html", ".htm")
#: ``uriBaseId`` of every location: the repository root.
ROOT_ID = "%SRCROOT%"
#: SARIF level of each rule severity.
LEVELS = {"error": "error", "warning": "warning", "info": "note"}
#: Name of the partial fingerprint (versioned: a change of recipe is a new name).
FINGERPRINT = "meshcolFinding/v1"


def source_root() -> str:
    """The folder locations are relative to: ``$GITHUB_WORKSPACE``, else the working folder."""
    return os.path.abspath(os.environ.get("GITHUB_WORKSPACE") or os.getcwd())


def docs_base(configured: str | None = None) -> str | None:
    """The base URL of the docs the rules' ``helpUri`` point into: ``$MESHCOL_DOCS_URL``,
    else ``configured`` (the configuration's ``docs-url``), else None (no links)."""
    base = os.environ.get(HOME_ENV) or configured
    return base or None


def rule_uri(base: str | None, rule_id: str) -> str | None:
    """The rule's anchor in the rules page under ``base``: the docs folder
    (``https://host/docs/`` gives ``https://host/docs/rules.md#mc501``), or the page itself
    when ``base`` ends in ``.md`` or ``.html`` (``https://host/rules.html#mc501``); None
    without a base."""
    if base is None:
        return None
    page = base if base.lower().endswith(_PAGE_SUFFIXES) else base.rstrip("/") + "/" + RULES_PAGE
    return f"{page}#{rule_id.lower()}"


def _text(value: Any) -> str:
    return " ".join(str(value).split())


def _registered(rule_id: str, rule: Mapping[str, Any], base: str | None) -> dict[str, Any]:
    """A ``reportingDescriptor`` of a registered rule (``helpUri`` under ``base``, if any)."""
    summary = _text(rule.get("summary", ""))
    measured = _text(rule.get("measured", ""))
    fix = _text(rule.get("fix", ""))
    name = str(rule.get("name", rule_id))
    severity = str(rule.get("severity", "error"))
    uri = rule_uri(base, rule_id)
    see = f"\n\nSee [{rule_id}]({uri})." if uri is not None else ""
    descriptor = {
        "id": rule_id,
        "name": name,
        "shortDescription": {"text": f"{name}: {summary}"},
        "fullDescription": {"text": f"{summary} {measured}".strip()},
        "help": {
            "text": f"{summary}\nMeasured: {measured}\nFix: {fix}",
            "markdown": f"**{rule_id} `{name}`** ({severity}): {summary}\n\n"
            f"*Measured*: {measured}\n\n*Fix*: {fix}{see}",
        },
        "defaultConfiguration": {"level": LEVELS.get(severity, "warning")},
        "properties": {
            "tags": ["meshcol", str(rule.get("category", "")) or "rule"],
            "precision": "very-high",
        },
    }
    if uri is not None:
        descriptor["helpUri"] = uri
    return descriptor


def _kind_descriptor(kind: str, command: str) -> dict[str, Any]:
    """A ``reportingDescriptor`` of a kind that is no registered rule (``max-hausdorff``)."""
    return {
        "id": kind,
        "name": kind,
        "shortDescription": {"text": f"meshcol {command}: {kind}"},
        "fullDescription": {
            "text": f"A case of meshcol {command} that its policy judged ({kind}); the "
            "result's message has the numbers."
        },
        "defaultConfiguration": {"level": "error"},
        "properties": {"tags": ["meshcol", command]},
    }


def _uri(path: str, root: str) -> tuple[str, str | None]:
    """``path`` as a URI relative to ``root`` (with the root's base id), else absolute."""
    absolute = os.path.abspath(path)
    relative = (
        os.path.relpath(absolute, root)
        if os.path.splitdrive(absolute)[0] == (os.path.splitdrive(root)[0])
        else None
    )
    if relative is not None and relative != ".." and not relative.startswith(".." + os.sep):
        return urllib.parse.quote(relative.replace(os.sep, "/")), ROOT_ID
    return urllib.parse.urljoin("file:", urllib.parse.quote(absolute.replace(os.sep, "/"))), None


#: Text files whose lines name bodies (manifests, robot descriptions): a result on one gets
#: the line that names its (first) body as its region.
TEXT_INPUTS = (".json", ".toml", ".urdf", ".xml", ".mjcf", ".srdf")
#: Largest text file searched for a body's line.
MAX_REGION_BYTES = 8 * 1024 * 1024


def _bodies(case: CiCase) -> list[str]:
    """The names the (first) body a case is about may have in its file, longest first: ``a``
    of ``a <-> b`` or ``body`` of ``file::body``, then that name cut at each ``/`` from the
    right (``arm/link/part``: the part of link ``arm/link``, or of body ``arm``)."""
    name = case.name.split("::")[-1] if "::" in case.name else case.name
    name = name.split(" <-> ")[0]
    pieces = name.split("/")
    return ["/".join(pieces[:k]) for k in range(len(pieces), 0, -1)]


def body_line(path: str, body: str, lines: dict[str, _TextIndex | None]) -> int | None:
    """The first line (1-based) of the text file ``path`` that names ``body`` as a name
    (``"name": "crate"``, ``name = "crate"``, ``name="crate"``): a line holding "name" and
    the body's JSON string or its single-quoted spelling; None when none does or the file is
    not a text input. ``lines`` caches each file's lines and their quoted texts, so a run
    of many bodies reads and searches each file once."""
    if not path.lower().endswith(TEXT_INPUTS) or not body:
        return None
    if path not in lines:
        try:
            if os.path.getsize(path) > MAX_REGION_BYTES:
                raise OSError
            with open(path, encoding="utf-8", errors="replace") as handle:
                lines[path] = _TextIndex(handle.read().splitlines())
        except OSError:
            lines[path] = None
    text = lines[path]
    return None if text is None else text.first_line(body)


class _TextIndex:
    """A text file's lines that hold "name", and the first of them (1-based) holding each
    text between two neighbouring equal quotes, the quotes included. A spelling with no
    quote inside it (``"crate"``, ``'crate'``) is in a line exactly when it lies between two
    neighbouring quotes of that line, so one lookup finds its first line."""

    def __init__(self, text: list[str]) -> None:
        self.named = [(number, line) for number, line in enumerate(text, 1) if "name" in line]
        self.first: dict[str, int] = {}
        for number, line in self.named:
            for quote in ('"', "'"):
                for inner in line.split(quote)[1:-1]:
                    self.first.setdefault(f"{quote}{inner}{quote}", number)

    def first_line(self, body: str) -> int | None:
        quoted = (json.dumps(body), f"'{body}'")
        if '"' in body or "'" in body:  # a quote inside a spelling: search the lines
            return next(
                (number for number, line in self.named if any(q in line for q in quoted)), None
            )
        found = [self.first[q] for q in quoted if q in self.first]
        return min(found) if found else None


def _location(
    case: CiCase, root: str, lines: dict[str, _TextIndex | None] | None = None
) -> dict[str, Any]:
    location: dict[str, Any] = {}
    if case.file:
        uri, base = _uri(case.file, root)
        artifact = {"uri": uri, **({"uriBaseId": base} if base else {})}
        location["physicalLocation"] = {"artifactLocation": artifact}
        cache = lines if lines is not None else {}
        found = (body_line(case.file, body, cache) for body in _bodies(case))
        line = next((number for number in found if number is not None), None)
        if line is not None:
            location["physicalLocation"]["region"] = {"startLine": line}
    location["logicalLocations"] = [{"fullyQualifiedName": case.name, "kind": "object"}]
    return location


def _fingerprint(command: str, rule_id: str, case: CiCase) -> str:
    key = "\0".join((command, rule_id, case.file or "", case.name))
    return hashlib.sha256(key.encode("utf-8", "surrogatepass")).hexdigest()[:32]


def _case_rules(case: CiCase) -> tuple[str, ...]:
    """The rules a case reports: its registered rules, else its kind; none for a case that
    neither fails, is spared, nor warns."""
    if case.outcome == "passed" and not case.warn:
        return ()
    if case.rules:
        return case.rules
    return (case.kind,) if case.kind else ()


def _result(
    case: CiCase,
    rule_id: str,
    index: int,
    level: str,
    suite: CiSuite,
    root: str,
    lines: dict[str, _TextIndex | None],
) -> dict[str, Any]:
    several = len(_case_rules(case)) > 1
    rule = suite.rules.get(rule_id)
    prefix = f"{rule_id} {rule['name']}: " if several and rule else ""
    result: dict[str, Any] = {
        "ruleId": rule_id,
        "ruleIndex": index,
        "level": level,
        "kind": "fail",
        "message": {"text": prefix + (case.message or case.name)},
        "locations": [_location(case, root, lines)],
        "partialFingerprints": {FINGERPRINT: _fingerprint(suite.command, rule_id, case)},
        "properties": {"case": case.name, "outcome": case.outcome},
    }
    if case.details:
        result["properties"]["details"] = case.details
    if case.numbers:
        result["properties"]["numbers"] = dict(case.numbers)
    if case.outcome == "skipped":
        result["suppressions"] = [
            {"kind": "external", "status": "accepted", "justification": case.message}
        ]
    return result


def _notification(case: CiCase, root: str) -> dict[str, Any]:
    note: dict[str, Any] = {
        "level": "error",
        "message": {"text": case.message or case.name},
        "descriptor": {"id": case.kind or "error"},
    }
    if case.file:
        note["locations"] = [_location(case, root)]
    return note


def sarif_log(suite: CiSuite, root: str | None = None) -> dict[str, Any]:
    """The SARIF log of ``suite`` as a dict (one run); ``root`` the repository root that
    locations are relative to (default :func:`source_root`); rule links under
    :func:`docs_base` of the suite's ``docs_url``."""
    from meshcol._version import __version__

    root = os.path.abspath(root) if root is not None else source_root()
    base = docs_base(suite.docs_url)
    descriptors = [
        _registered(rule_id, suite.rules[rule_id], base) for rule_id in sorted(suite.rules)
    ]
    index = {d["id"]: k for k, d in enumerate(descriptors)}
    results: list[dict[str, Any]] = []
    notes: list[dict[str, Any]] = []
    lines: dict[str, _TextIndex | None] = {}  # each text input read and indexed once
    for case in suite.cases:
        if case.outcome == "error":
            notes.append(_notification(case, root))
            continue
        for rule_id in _case_rules(case):
            if rule_id not in index:
                index[rule_id] = len(descriptors)
                descriptors.append(_kind_descriptor(rule_id, suite.command))
            rule = suite.rules.get(rule_id)
            if rule is not None:
                level = LEVELS.get(str(rule.get("severity")), "warning")
            else:
                level = "error" if case.outcome == "failure" else "warning"
            results.append(_result(case, rule_id, index[rule_id], level, suite, root, lines))
    base_uri = urllib.parse.urljoin("file:", urllib.parse.quote(root.replace(os.sep, "/")))
    driver: dict[str, Any] = {
        "name": "meshcol",
        "version": __version__,
        "semanticVersion": __version__,
        "rules": descriptors,
    }
    if base is not None:
        driver["informationUri"] = base
    run: dict[str, Any] = {
        "tool": {"driver": driver},
        "automationDetails": {"id": f"meshcol/{suite.command}/"},
        "originalUriBaseIds": {ROOT_ID: {"uri": base_uri.rstrip("/") + "/"}},
        "invocations": [
            {
                "executionSuccessful": True,
                "toolExecutionNotifications": notes,
                "properties": {"command": suite.command, "passed": suite.passed},
            }
        ],
        "results": results,
        "columnKind": "unicodeCodePoints",
        "properties": {
            "verdict": suite.verdict,
            "units": suite.units,
            "warnings": list(suite.warnings),
        },
    }
    return {"$schema": SARIF_SCHEMA, "version": SARIF_VERSION, "runs": [run]}


def dumps_sarif(suite: CiSuite) -> str:
    """SARIF 2.1.0 text of ``suite`` (see the module's notes), keys sorted, two-space
    indented, locations relative to :func:`source_root`."""
    return dumps_json(sarif_log(suite))
