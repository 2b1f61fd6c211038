"""The compatibility rules: one registry of stable ids, and the findings that cite them.

Every finding meshcol reports names a rule of :data:`RULES` by its id (``MC401``) and its name
(``not-watertight``); ids are stable forever (a rule that goes keeps its id retired, never
reused). Ranges: 1xx engine limits of a ``--target`` profile, 2xx physics readiness and mass,
3xx colliders present and named, 4xx mesh health, 5xx pair findings of check and sweep
(and MC506, a robot with no collision geometry: nothing to pair; MC505, undecided, is also
inspect's undecided self-intersection verdict: one rule for "no exact test decided").

:func:`finding` is the one way to make a finding, so nothing can cite an unregistered rule;
:func:`select_rules` is the one parser of ``--fail-on`` lists (ids, names, ``all``).
``meshcol rules`` prints this registry (:class:`RulesReport`).
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterable, Sequence
from dataclasses import asdict, dataclass
from typing import Any

from meshcol.vocabulary import LIMITS

__all__ = [
    "RULES",
    "TARGET_RULES",
    "Finding",
    "Rule",
    "RulesReport",
    "UnknownRuleError",
    "finding",
    "get_rule",
    "robot_findings",
    "robot_warnings",
    "rules_report",
    "select_rules",
    "target_findings",
]

#: Severities, most severe first.
SEVERITIES = ("error", "warning", "info")


@dataclass(frozen=True)
class Rule:
    """One rule of the registry.

    Attributes
    ----------
    id : str
        ``MC`` and three digits, stable forever.
    name : str
        Kebab-case, as ``--fail-on`` and reports spell it.
    severity : str
        ``error`` (an engine rejects or mis-simulates it), ``warning`` (it degrades), ``info``.
    commands : tuple of str
        The commands that can report it.
    summary : str
        One line: what the finding means.
    measured : str
        What ``measured`` and ``limit`` of a finding hold, and the default limit.
    fix : str
        How to make the finding go.
    limit_key : str or None
        The ``[limits]`` key of a target profile that sets the limit (1xx rules).
    """

    id: str
    name: str
    severity: str
    commands: tuple[str, ...]
    summary: str
    measured: str
    fix: str
    limit_key: str | None = None

    @property
    def category(self) -> str:
        return _CATEGORIES[self.id[2]]

    def to_dict(self) -> dict[str, Any]:
        return {**asdict(self), "commands": list(self.commands), "category": self.category}


_CATEGORIES = {
    "1": "engine limit",
    "2": "physics readiness",
    "3": "collider presence",
    "4": "mesh health",
    "5": "pair",
}

_TARGET = ("inspect", "check")
_TARGET_NOTE = " Reported when a --target profile sets the limit."

#: Every rule, in id order.
RULES: tuple[Rule, ...] = (
    Rule(
        *LIMITS["max_hull_vertices"][:2],
        "error",
        _TARGET,
        "A convex part has more vertices than the engine accepts (PhysX 255, GPU 64).",
        "measured: vertices of the part; limit: the target's max_hull_vertices." + _TARGET_NOTE,
        "Rebuild the collider within the budget: meshcol hull --target NAME (or "
        "--max-vertices N); decompose --target NAME.",
        "max_hull_vertices",
    ),
    Rule(
        *LIMITS["max_oblong_ratio"][:2],
        "warning",
        _TARGET,
        "A convex part is too oblong for the GPU pipeline: its largest extent over its "
        "in-sphere radius exceeds the limit (PhysX GPU: 100); the engine falls back to the CPU.",
        "measured: largest extent / in-sphere radius of the part; limit: the target's "
        "max_oblong_ratio." + _TARGET_NOTE,
        "Split the part (decompose with a lower threshold) or thicken it; a box or capsule "
        "fit (meshcol fit) may replace a sliver.",
        "max_oblong_ratio",
    ),
    Rule(
        *LIMITS["max_hull_polygons"][:2],
        "error",
        _TARGET,
        "A convex part has more polygons (coplanar triangles merged) than the engine accepts.",
        "measured: polygons of the part; limit: the target's max_hull_polygons." + _TARGET_NOTE,
        "meshcol hull --target NAME (merges and budgets the faces).",
        "max_hull_polygons",
    ),
    Rule(
        *LIMITS["max_hull_triangles"][:2],
        "error",
        _TARGET,
        "A convex part has more triangles than the engine accepts (Unity: 255).",
        "measured: triangles of the part; limit: the target's max_hull_triangles." + _TARGET_NOTE,
        "meshcol hull --target NAME.",
        "max_hull_triangles",
    ),
    Rule(
        *LIMITS["max_faces_per_vertex"][:2],
        "warning",
        _TARGET,
        "Too many polygons meet at one vertex of a convex part (PhysX GPU: 32).",
        "measured: the largest number of polygons at one vertex; limit: the target's "
        "max_faces_per_vertex." + _TARGET_NOTE,
        "meshcol hull --target NAME.",
        "max_faces_per_vertex",
    ),
    Rule(
        *LIMITS["max_hulls"][:2],
        "error",
        _TARGET,
        "A body has more convex parts than the engine accepts per body or mesh.",
        "measured: convex parts of the body; limit: the target's max_hulls." + _TARGET_NOTE,
        "meshcol decompose --target NAME (or --max-parts N).",
        "max_hulls",
    ),
    Rule(
        *LIMITS["min_thickness"][:2],
        "warning",
        _TARGET,
        "A convex part is thinner than the engine handles reliably (tunnelling, jitter).",
        "measured: the smallest width of the part, in metres; limit: the target's "
        "min_thickness." + _TARGET_NOTE,
        "Thicken the geometry, or merge the sliver into a neighbouring part.",
        "min_thickness",
    ),
    Rule(
        *LIMITS["min_volume"][:2],
        "error",
        _TARGET,
        "A convex part's volume is below the engine's minimum (MuJoCo: 'mesh volume is too "
        "small').",
        "measured: the part's volume; limit: the target's min_volume." + _TARGET_NOTE,
        "Give the part a thickness, or drop it if it is a decal.",
        "min_volume",
    ),
    Rule(
        "MC202",
        "flat-collider",
        "error",
        ("inspect",),
        "A convex part of the collider is flat, a segment or a point, or nearly so: engines "
        "reject it or give it no inertia (PhysX cooking fails, MuJoCo 'mesh volume is too small').",
        "measured: the part's volume over the cube of its bounding-box diagonal (0 when flat "
        "by the flatness rule); limit: --min-relative-volume, default 1e-6 (a 1 m plate 1.4 um "
        "thick).",
        "Give the geometry a thickness, or replace the part by a thin box (meshcol fit --shape "
        "box).",
    ),
    Rule(
        "MC203",
        "tiny-collider",
        "error",
        ("inspect",),
        "The collider's volume is below 1e-15 cubic units, the value below which MuJoCo "
        "refuses a mesh (mjMINVAL): a body too small to simulate, or in the wrong units.",
        "measured: the collider's volume; limit: --min-volume, default 1e-15.",
        "Check the units (inspect's suspect-units), or scale the mesh.",
    ),
    Rule(
        "MC204",
        "inverted-collider",
        "error",
        ("inspect",),
        "Collision geometry given as triangles (a robot's collision mesh, a UCX_ part, a mesh "
        "collider) is closed but inside out: its volume and inertia come out negative, and "
        "one-sided triangle colliders let objects through.",
        "measured: the signed volume of the collision mesh; limit: 0.",
        "Reverse the faces (any mesh tool's 'flip normals'), then inspect again.",
    ),
    Rule(
        "MC205",
        "collider-volume-mismatch",
        "warning",
        ("inspect",),
        "The collider's volume is far from the visual mesh's: the mass an engine derives from "
        "the collider (density x volume) is not the object's.",
        "measured: collider volume / visual volume; limit: --volume-ratio R (default 2): the "
        "finding fires above R or below 1/R; the limit reported is the side crossed. Needs a "
        "closed visual mesh.",
        "Decompose (--shape decomposed) or fit a closer primitive; or set the mass and inertia "
        "explicitly in the engine.",
    ),
    Rule(
        "MC206",
        "center-of-mass-offset",
        "warning",
        ("inspect",),
        "The collider's centre of mass is far from the visual mesh's: the object tips, rolls "
        "or hangs differently from how it looks.",
        "measured: the distance between the two centres over the visual mesh's bounding-box "
        "diagonal (solids; shells when the visual mesh is open); limit: --com-offset, default "
        "0.05.",
        "Decompose instead of hulling a concave or asymmetric object; or set the centre of "
        "mass explicitly.",
    ),
    Rule(
        "MC207",
        "inertia-mismatch",
        "warning",
        ("inspect",),
        "The collider's principal moments of inertia per unit mass differ from the visual "
        "mesh's: the object spins and wobbles differently from how it looks.",
        "measured: the largest ratio (>= 1) between matching principal moments of inertia per "
        "unit mass, sorted; limit: --inertia-ratio, default 1.5. Needs a closed visual mesh.",
        "Decompose or fit a closer primitive; or set the inertia tensor explicitly.",
    ),
    Rule(
        "MC301",
        "missing-collider",
        "error",
        ("inspect", "check"),
        "A body has no usable collider: a robot link with visual geometry but no collision "
        "element, a body of a UCX_ scene that got no UCX_ part, or a body without area.",
        "measured: the collider parts found (or the body's area); limit: 1 part (area > 0).",
        "Add the collision element or the UCX_<body>_NN parts (meshcol decompose --layout "
        "ucx writes them).",
    ),
    Rule(
        "MC302",
        "orphan-ucx-part",
        "warning",
        ("inspect",),
        "A UCX_<name>_NN part names no body or part of the input: the engine attaches it to "
        "nothing (Unreal drops it).",
        "measured: none; limit: none. The message names the part and the name it gives.",
        "Rename the part after its render mesh (UCX_<mesh>_NN).",
    ),
    Rule(
        "MC303",
        "non-convex-ucx-part",
        "warning",
        ("inspect",),
        "A UCX_ part is not convex: the engine uses its convex hull, a larger shape than "
        "the one authored.",
        "measured: the part's volume over its hull's volume; limit: 0.99. Needs a closed part.",
        "Split the part into convex pieces (meshcol decompose --layout ucx).",
    ),
    Rule(
        "MC401",
        "not-watertight",
        "error",
        ("inspect",),
        "The mesh is open: an edge has other than two faces.",
        "measured: boundary and non-manifold edges; limit: 0.",
        "Close the holes (or collide with the hull, which needs no closed mesh).",
    ),
    Rule(
        "MC402",
        "self-intersecting",
        "error",
        ("inspect",),
        "Two faces of the mesh cross (decided exactly).",
        "measured: pairs of crossing faces; limit: 0.",
        "Remesh or boolean-union the crossing pieces.",
    ),
    Rule(
        "MC403",
        "inconsistent-winding",
        "error",
        ("inspect",),
        "Two faces traverse an edge in the same direction: the normals disagree.",
        "measured: edges traversed the same way by their two faces; limit: 0.",
        "Unify the face orientation (any mesh tool's 'recalculate normals').",
    ),
    Rule(
        "MC404",
        "inverted",
        "error",
        ("inspect",),
        "The mesh is closed and consistently wound but inside out: negative volume.",
        "measured: the signed volume; limit: 0.",
        "Reverse the faces.",
    ),
    Rule(
        "MC405",
        "degenerate-faces",
        "warning",
        ("inspect",),
        "Faces with a repeated vertex or a height at most 1e-7 of the bounding-box diagonal.",
        "measured: degenerate faces; limit: 0.",
        "Remove them (merge vertices, drop slivers).",
    ),
    Rule(
        "MC406",
        "non-manifold",
        "error",
        ("inspect",),
        "An edge has more than two faces.",
        "measured: non-manifold edges; limit: 0.",
        "Split the mesh at those edges, or remesh.",
    ),
    Rule(
        "MC407",
        "duplicate-faces",
        "warning",
        ("inspect",),
        "Faces on the same three vertices as an earlier face (either winding).",
        "measured: duplicate faces; limit: 0.",
        "Remove the duplicates.",
    ),
    Rule(
        "MC408",
        "multiple-components",
        "info",
        ("inspect",),
        "The mesh is several disconnected pieces: one hull spans them all.",
        "measured: connected components; limit: 1.",
        "Split it into bodies, or decompose it (--shape decomposed).",
    ),
    Rule(
        "MC409",
        "suspect-units",
        "warning",
        ("inspect",),
        "The size suggests other units than declared (a 400-unit chair is millimetres), or "
        "no plausible unit at all. A part under 0.01 units of a body whose parts together "
        "are a plausible size is a detail of it (a finger pad), not suspect.",
        "measured: the largest extent; limit: the edge of the plausible band crossed (100 "
        "units for metres, 0.01 below, 10,000 for any unit).",
        "Scale the mesh or declare its units in the scene manifest.",
    ),
    Rule(
        "MC501",
        "penetrating",
        "error",
        ("check",),
        "Two bodies interpenetrate deeper than the contact tolerance.",
        "measured: the penetration depth; limit: --tolerance.",
        "Move the bodies apart, or --ignore the pair if it is designed to overlap.",
    ),
    Rule(
        "MC502",
        "contained",
        "error",
        ("check",),
        "One body lies wholly inside the other's closed surface.",
        "measured: the penetration depth; limit: --tolerance.",
        "Move or remove the buried body.",
    ),
    Rule(
        "MC503",
        "contact",
        "info",
        ("check",),
        "Two bodies touch: |signed distance| within the contact tolerance.",
        "measured: |signed distance|; limit: --tolerance.",
        "None needed for resting contact; --ignore the pair if designed.",
    ),
    Rule(
        "MC504",
        "clearance",
        "warning",
        ("check",),
        "Two bodies are closer than the required clearance.",
        "measured: the distance; limit: --clearance.",
        "Move them apart by the shortfall.",
    ),
    Rule(
        "MC505",
        "undecided",
        "warning",
        ("inspect", "check"),
        "An exact test could not reach its verdict. check: the pair's surfaces meet or may "
        "nest, and no inside test decides it: a mesh that cannot be wound consistently "
        "(non-orientable), whose ray parity splits over the directions tried. Neither a "
        "contact nor a penetration is claimed. inspect: the self-intersection test stopped at "
        "its work budget (a fan or a pile of faces whose boxes all "
        "overlap): with no crossing found, the mesh is called neither self-intersecting nor "
        "clean (self_intersecting null); with crossings found it is self-intersecting "
        "(MC402) and their count is a lower bound.",
        "check: measured: depth_upper, the most the pair can penetrate; limit: --tolerance. "
        "inspect: measured: the crossing face pairs found (a lower bound); limit: the work "
        "budget (units of one candidate face pair, MAX_WORK).",
        "check: repair the mesh's winding (inspect reports MC403), or check the pair as hull. "
        "inspect: remesh the fan (rings of faces around its centre) or split the pile into "
        "its pieces; the budget is meshcol.collision.self_intersection.MAX_WORK.",
    ),
    Rule(
        "MC506",
        "no-collision-geometry",
        "warning",
        ("inspect", "check", "collision-matrix"),
        "A robot description (URDF, MJCF) whose links have no collision geometry: no "
        "<collision> element, no geom MuJoCo collides. It loads (pybullet and MuJoCo load it), "
        "but there is nothing to check: zero pairs, an empty collision matrix, outputs "
        "without colliders.",
        "measured: the collision elements found (0); limit: 1. The finding names the file.",
        "Add <collision> elements (URDF) or give geoms a non-zero contype or conaffinity "
        "(MJCF); meshcol hull or decompose of a link's visual mesh file makes a collider mesh "
        "to reference. --fail-on MC506 fails a run on it.",
    ),
)

_BY_ID = {rule.id: rule for rule in RULES}
_BY_NAME = {rule.name: rule for rule in RULES}


class UnknownRuleError(ValueError):
    """A rule id or name that is not registered (or not reported by the command)."""


def get_rule(key: str) -> Rule:
    """The rule of an id (``MC401``, any case) or a name (``not-watertight``).

    Raises
    ------
    UnknownRuleError
        Neither an id nor a name of :data:`RULES`.
    """
    rule = _BY_ID.get(key.strip().upper()) or _BY_NAME.get(key.strip().lower())
    if rule is None:
        raise UnknownRuleError(
            f"unknown rule {key!r} (valid: {', '.join(r.id for r in RULES)}, or their names)"
        )
    return rule


def command_rules(command: str) -> tuple[Rule, ...]:
    """The rules ``command`` can report, in id order."""
    return tuple(rule for rule in RULES if command in rule.commands)


def select_rules(values: str | Iterable[str], command: str) -> tuple[str, ...]:
    """Parse a ``--fail-on`` list into rule ids.

    Parameters
    ----------
    values : str or iterable of str
        Comma-separated (or separate) rule ids, names, or ``all``; case-insensitive ids.
    command : str
        Only the rules this command reports are valid.

    Returns
    -------
    tuple of str
        Ids, in the order given, without repeats (``all``: every rule of the command).

    Raises
    ------
    UnknownRuleError
        A value that names no rule of the command; the message lists the valid ones.
    """
    items = values.split(",") if isinstance(values, str) else list(values)
    mine = command_rules(command)
    valid = {rule.id for rule in mine}
    ids: list[str] = []
    for item in (v.strip() for v in items):
        if not item:
            continue
        if item.lower() == "all":
            ids.extend(rule.id for rule in mine)
            continue
        try:
            rule = get_rule(item)
        except UnknownRuleError:
            rule = None
        if rule is None or rule.id not in valid:
            listing = ", ".join(f"{r.id} {r.name}" for r in mine)
            raise UnknownRuleError(
                f"unknown rule {item!r} for {command} (valid: all, {listing})"
            ) from None
        ids.append(rule.id)
    return tuple(dict.fromkeys(ids))


def _plain(value: Any) -> Any:
    """A JSON-ready measured value or limit: int, float (finite), bool or None."""
    if value is None or isinstance(value, (bool, int, str)):
        return value
    value = float(value)
    return value if math.isfinite(value) else None


@dataclass(frozen=True)
class Finding:
    """One finding: a body (and part) breaking a rule, with the number and the limit.

    Attributes
    ----------
    body : str
        The body (a pair finding: the first body of the pair).
    part : str or None
        The part of the body, or None (a body of one part, or a finding on the whole body).
    rule : str
        The rule id (``MC401``).
    name : str
        The rule name (``not-watertight``).
    severity : str
        The rule's severity.
    measured : float, int, bool or None
        What was measured (the rule's ``measured`` says what).
    limit : float, int or None
        The limit it broke.
    message : str
        One line for people.
    other_body, other_part : str or None
        Pair findings: the second body and its part; None for a body finding.
    """

    body: str
    part: str | None
    rule: str
    name: str
    severity: str
    measured: Any
    limit: Any
    message: str
    other_body: str | None = None
    other_part: str | None = None

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def finding(
    rule_id: str,
    body: str,
    part: str | None,
    measured: Any,
    limit: Any,
    message: str,
    *,
    other_body: str | None = None,
    other_part: str | None = None,
) -> Finding:
    """A :class:`Finding` of a registered rule (the one way findings are made).

    Raises
    ------
    KeyError
        ``rule_id`` is not registered (a programming error, caught by the tests).
    """
    rule = _BY_ID[rule_id]
    return Finding(
        body,
        part,
        rule.id,
        rule.name,
        rule.severity,
        _plain(measured),
        _plain(limit),
        message,
        other_body,
        other_part,
    )


def robot_findings(scene: Any) -> list[Finding]:
    """MC506 for a robot description read with no collision geometry (a scene of no bodies
    whose source is a URDF or MJCF, :func:`meshcol.io.robot.load_robot`); else none.

    The finding's body is the file's name, its message the file's path."""
    from meshcol.io.inputs import is_robot_file
    from meshcol.io.paths import display_path
    from meshcol.io.robot import NO_COLLISION_GEOMETRY

    source = getattr(scene, "source", None)
    if scene.bodies or not source or not is_robot_file(source):
        return []
    shown = display_path(source, posix=True)
    message = (
        f"{shown}: {NO_COLLISION_GEOMETRY} (no <collision> element, no geom that collides): "
        "nothing to check"
    )
    return [finding("MC506", os.path.basename(source), None, 0, 1, message)]


def robot_warnings(scene: Any) -> tuple[str, ...]:
    """The warning lines of :func:`robot_findings` (``... (MC506 no-collision-geometry)``),
    for the commands that report warnings, not findings (``hull``, ``fit``)."""
    return tuple(f"{f.message} ({f.rule} {f.name})" for f in robot_findings(scene))


# ---------------------------------------------------------------------------------------------
# The report behind ``meshcol rules``

#: Columns of :meth:`RulesReport.to_csv`.
CSV_COLUMNS = (
    "id",
    "name",
    "category",
    "severity",
    "commands",
    "limit_key",
    "summary",
    "measured",
    "fix",
)


@dataclass(frozen=True)
class RulesReport:
    """The registry (or the rules asked for), as ``meshcol rules`` prints it."""

    rules: tuple[Rule, ...]
    selected: tuple[str, ...] = ()

    @property
    def summary(self) -> dict[str, Any]:
        return {
            "rules": len(self.rules),
            "by_category": {
                name: sum(rule.category == name for rule in self.rules)
                for name in _CATEGORIES.values()
            },
        }

    def to_dict(self) -> dict[str, Any]:
        from meshcol.io.report import envelope

        return {
            **envelope("rules", {"rules": list(self.selected)}, None),
            "summary": self.summary,
            "rules": [rule.to_dict() for rule in self.rules],
        }

    def to_json(self) -> str:
        from meshcol.io.report import dumps_json

        return dumps_json(self.to_dict())

    def to_markdown(self) -> str:
        """The rules as the Markdown page ``docs/rules.md`` (a test keeps that page current)."""
        lines = [
            "# meshcol rules",
            "",
            "Every finding of `meshcol inspect` and `meshcol check` names one of these rules by",
            "its id; ids are stable (a retired rule keeps its id, never reused). `--fail-on` takes",
            "ids or names, comma separated, or `all`. Generated from `meshcol/analysis/rules.py`",
            "(`meshcol rules`). Each rule's section has the anchor `#` plus its id in lower case",
            "(`rules.md#mc501`): SARIF's `helpUri` links there.",
            "",
            "| id | name | severity | commands | what it means |",
            "| --- | --- | --- | --- | --- |",
        ]
        lines += [
            f"| [{r.id}](#{r.id.lower()}) | `{r.name}` | {r.severity} | "
            f"{', '.join(r.commands)} | {r.summary} |"
            for r in self.rules
        ]
        for r in self.rules:
            lines += [
                "",
                f'<a id="{r.id.lower()}"></a>',
                "",
                f"## {r.id} {r.name}",
                "",
                r.summary,
                "",
                f"- {r.measured[0].upper()}{r.measured[1:]}",
            ]
            if r.limit_key is not None:
                lines.append(f"- Target profile limit: `{r.limit_key}`")
            lines.append(f"- Fix: {r.fix}")
        return "\n".join(lines) + "\n"

    def to_csv(self) -> str:
        from meshcol.io.report import dumps_csv

        rows = [dict(rule.to_dict(), commands=" ".join(rule.commands)) for rule in self.rules]
        return dumps_csv(rows, CSV_COLUMNS)


def rules_report(keys: Sequence[str] = ()) -> RulesReport:
    """The registry, or the rules ``keys`` name (ids or names, any order).

    Raises
    ------
    UnknownRuleError
        A key that names no rule.
    """
    if not keys:
        return RulesReport(RULES)
    chosen = tuple(dict.fromkeys(get_rule(key) for key in keys))
    return RulesReport(chosen, tuple(rule.id for rule in chosen))


#: The rules of a target profile's limits (``limit_key`` set): a target's findings fail
#: a run unless ``--fail-on`` names other rules.
TARGET_RULES: tuple[str, ...] = tuple(rule.id for rule in RULES if rule.limit_key is not None)


def target_findings(colliders: Any, target: Any, units: str | None = None) -> list[Finding]:
    """The engine-limit findings (MC101..MC107, MC201) of built colliders against a target
    profile, body by body.

    Parameters
    ----------
    colliders : meshcol.analysis.colliders.Colliders
        What the command checks (each body's convex parts).
    target : meshcol.io.targets.Target
    units : str, optional
        The scene's units (the profile's lengths and volumes are converted to them).

    Returns
    -------
    list of Finding
        Per body in order, its part-count finding then each convex part's. A part is named
        by its body part (``Body.parts``), or by its index among the body's convex parts
        when the body has several and no names. Primitive parts and ``mesh`` bodies (an
        engine's triangle mesh, not a convex mesh) are counted for ``max_hulls`` only.

    Notes
    -----
    Every part is measured once, by :func:`meshcol.collision.limits.measure_parts` (the
    measurement hull and decompose use to meet the same limits).
    """
    from meshcol.collision.limits import limit_violations, measure_parts

    shapes = colliders.shapes
    offsets = colliders.body_part_offsets
    scale = target.length_scale(units)
    out: list[Finding] = []
    for b, body in enumerate(colliders.bodies):
        if colliders.kinds[b] == "mesh":
            continue
        parts = range(int(offsets[b]), int(offsets[b + 1]))
        convex = [k for k in parts if shapes.offsets[k + 1] > shapes.offsets[k]]
        measures = measure_parts(
            [(shapes.vertices[shapes.offsets[k] : shapes.offsets[k + 1]], None) for k in convex]
        )
        labels = colliders.part_names([b] * len(convex), colliders.part_label[convex])
        for v in limit_violations(target, measures, len(parts), scale):
            if v.part is None:
                part = None
            else:
                part = labels[v.part]
                if part is None and len(parts) > 1:
                    part = str(int(colliders.part_index[convex[v.part]]))
            out.append(
                finding(
                    v.rule,
                    body.name,
                    part,
                    v.measured,
                    v.threshold,
                    f"{target.name}: {v.message}",
                )
            )
    return out
