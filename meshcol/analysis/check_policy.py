"""What ``meshcol check`` asks and what fails it: the options of a run, ``--fail-on`` levels and
rules, ``--ignore`` globs, ``--baseline`` reports, and the policy stage that marks each pair of
a classified :class:`~meshcol.analysis.pairs.PairTable` ignored or violating.
"""

from __future__ import annotations

import dataclasses
import fnmatch
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from meshcol.analysis.pairs import SEVERITY, PairTable
from meshcol.errors import InputFileError
from meshcol.vocabulary import COLLIDER_KINDS, PAIR_STATUSES

__all__ = [
    "FAIL_ON",
    "MAX_PAIRS",
    "PAIR_RULES",
    "CheckOptions",
    "apply_policy",
    "failing_rules",
    "load_baseline",
    "parse_ignore_rule",
]

#: ``--fail-on`` level -> least severe status that violates the policy.
FAIL_ON = {
    "penetration": "penetrating",
    "contact": "contact",
    "clearance": "clearance",
    "none": None,
}
#: The rule (meshcol.analysis.rules) of each pair status but ``separated``.
PAIR_RULES = {
    "clearance": "MC504",
    "contact": "MC503",
    "undecided": "MC505",
    "penetrating": "MC501",
    "contained": "MC502",
}


def failing_rules(fail_on: str, target: bool = False) -> tuple[str, ...]:
    """The rule ids a ``--fail-on`` value fails on: a status level (``penetration``,
    ``contact``, ``clearance``, ``none``: that status and the more severe ones, and with a
    ``target`` its limits' rules, :data:`meshcol.analysis.rules.TARGET_RULES`) or comma-separated rule ids or names
    (``MC501,missing-collider``, ``all``).

    Raises
    ------
    UnknownRuleError
        Neither a level nor rules of check (a ValueError; the message lists the valid ones).
    """
    from meshcol.analysis.rules import TARGET_RULES, UnknownRuleError, select_rules

    if fail_on in FAIL_ON:
        least = FAIL_ON[fail_on]
        if least is None:
            return ()
        levels = tuple(PAIR_RULES[s] for s in PAIR_STATUSES[SEVERITY[least] :])
        return levels + (TARGET_RULES if target else ())
    try:
        return select_rules(fail_on, "check")
    except UnknownRuleError as exc:
        raise UnknownRuleError(f"{exc} (or a level: {', '.join(FAIL_ON)})") from None


def parse_ignore_rule(rule: str) -> tuple[str, str]:
    """Split an ``A:B`` ignore rule into its two glob patterns."""
    parts = rule.split(":")
    if len(parts) != 2 or not parts[0] or not parts[1]:
        raise ValueError(f"ignore rule must look like A:B (globs allowed), got {rule!r}")
    return parts[0], parts[1]


#: The default cap on a check's candidate pairs (``--max-pairs``): what a 24 GB machine holds
#: with room to spare (benchmarks/RESULTS.md, "Big manifests": bytes a pair at its peak).
MAX_PAIRS = 4_000_000


@dataclass(frozen=True)
class CheckOptions:
    """Settings of one check run.

    Attributes
    ----------
    collider : str
        Default collider kind: ``hull``, ``decomposed`` or ``mesh``
        (:mod:`meshcol.analysis.colliders`); a manifest's per-body ``shape`` overrides it;
        primitives are always exact.
    tolerance : float
        Contact band, in scene units: pairs with ``|signed_distance| <= tolerance`` touch.
    clearance : float
        Minimum gap required; pairs closer than it (but not touching) have status
        ``clearance``. 0 disables the band.
    fail_on : str
        ``penetration`` (default), ``contact``, ``clearance`` or ``none`` (that status and the
        more severe ones fail), or comma-separated rule ids or names (:func:`failing_rules`;
        the resolved ids are ``fail_rules``).
    ignore : tuple of str
        ``A:B`` rules with shell-style globs on body names; matching pairs (either order) are
        reported as ignored and never fail the run.
    baseline : dict or None
        A previous JSON report: only pairs that are new or worse than in it fail the run.
    threads : int
        Threads for the native queries; 0 means all cores.
    decompose_options : dict
        Options for on-the-fly convex decomposition (``decomposed`` bodies not in the cache).
    target : meshcol.io.targets.Target, optional
        An engine profile: each body's convex parts are measured against its limits
        (:func:`meshcol.analysis.rules.target_findings`); with a status level in ``fail_on``
        (not ``none``) its findings fail the run too.
    max_pairs : int or None
        The most candidate pairs a run may hold (:data:`MAX_PAIRS` by default; None: no
        cap); a scene with more is refused before its pairs are measured
        (:class:`~meshcol.errors.TooManyPairsError`).
    pair_cache : meshcol.analysis.pair_cache.PairCache, optional
        Where the narrow phase's answers per pair are kept between runs (``meshcol ci``):
        only pairs with a changed body are measured again. Not a setting of the report.
    """

    collider: str = "hull"
    tolerance: float = 1e-6
    clearance: float = 0.0
    fail_on: str = "penetration"
    ignore: tuple[str, ...] = ()
    baseline: dict | None = None
    baseline_source: str | None = None
    threads: int = 0
    decompose_options: dict = field(default_factory=dict)
    target: Any = None
    max_pairs: int | None = MAX_PAIRS
    pair_cache: Any = field(default=None, compare=False, repr=False)
    #: The rule ids the run fails on (:func:`failing_rules` of ``fail_on`` and ``target``),
    #: made with the options.
    fail_rules: tuple[str, ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        """Validated once, where they are made (also by ``dataclasses.replace``)."""
        self.validate()
        rules = failing_rules(self.fail_on, self.target is not None)
        object.__setattr__(self, "fail_rules", rules)

    @classmethod
    def from_keywords(cls, **options: Any) -> CheckOptions:
        """Options as :func:`meshcol.analysis.check.check` takes them: ``baseline`` a path
        (read here) or a report dict, ``ignore`` any sequence."""
        baseline = options.pop("baseline", None)
        if isinstance(baseline, (str, os.PathLike)):
            options["baseline_source"] = os.fspath(baseline)
            baseline = load_baseline(os.fspath(baseline))
        if "ignore" in options:
            options["ignore"] = tuple(options["ignore"])
        return cls(baseline=baseline, **options)

    def validate(self) -> None:
        """Raise ValueError for a value out of range (:class:`CheckOptions` calls it)."""
        if self.collider not in COLLIDER_KINDS:
            raise ValueError(
                f"collider must be one of {', '.join(COLLIDER_KINDS)}, got {self.collider!r}"
            )
        if not (math.isfinite(self.tolerance) and self.tolerance >= 0):
            raise ValueError(f"tolerance must be a finite number >= 0, got {self.tolerance!r}")
        if not (math.isfinite(self.clearance) and self.clearance >= 0):
            raise ValueError(f"clearance must be a finite number >= 0, got {self.clearance!r}")
        cap = self.max_pairs
        if cap is not None and (isinstance(cap, bool) or not isinstance(cap, int) or cap < 0):
            raise ValueError(f"max_pairs must be an integer >= 0 or None, got {cap!r}")
        failing_rules(self.fail_on)
        for rule in self.ignore:
            parse_ignore_rule(rule)


def load_baseline(path: str) -> dict:
    """Read a previous JSON report for ``--baseline``."""
    from meshcol.io.report import read_json_file

    data = read_json_file(path, "baseline report", "baseline")
    if not isinstance(data, dict) or not isinstance(data.get("pairs"), list):
        raise InputFileError("baseline is not a meshcol check report (no 'pairs' list)", path)
    for p in data["pairs"]:
        if not isinstance(p, dict) or not {"body_a", "body_b", "status"} <= p.keys():
            raise InputFileError(
                "baseline is not a meshcol check report (pair without body_a, body_b, status)",
                path,
            )
    return data


# ---------------------------------------------------------------------------------------------
# The policy stage


def apply_policy(table: PairTable, names: Sequence[str], options: CheckOptions) -> PairTable:
    """Mark each classified pair ``ignored`` (an ``--ignore`` rule matches it) and
    ``violation`` (its status's rule is in ``options.fail_rules``, it is not ignored and, with
    a baseline, it is new or worse than there)."""
    fail_rules = options.fail_rules
    a, b = table.body_a, table.body_b
    ignored = _ignore_mask(names, options.ignore, a, b) if len(table) else np.zeros(0, bool)
    failing_status = [SEVERITY[s] for s, rule in PAIR_RULES.items() if rule in fail_rules]
    violation = np.isin(table.status, failing_status) & ~ignored
    if options.baseline is not None:
        rows = np.flatnonzero(violation)
        violation[rows] = _worse_than_baseline(
            options.baseline,
            names,
            table.body_pairs[rows],
            table.status[rows],
            table.depth[rows],
            table.distance[rows],
            options.tolerance,
        )
    return dataclasses.replace(table, ignored=ignored, violation=violation)


def _ignore_mask(
    names: Sequence[str], rules: Sequence[str], a: np.ndarray, b: np.ndarray
) -> np.ndarray:
    """Boolean mask of pairs (a[k], b[k]) matched by any ``A:B`` glob rule, either order."""
    mask = np.zeros(len(a), dtype=bool)
    for rule in rules:
        pa, pb = parse_ignore_rule(rule)
        ma = np.fromiter((fnmatch.fnmatchcase(n, pa) for n in names), dtype=bool, count=len(names))
        mb = np.fromiter((fnmatch.fnmatchcase(n, pb) for n in names), dtype=bool, count=len(names))
        mask |= (ma[a] & mb[b]) | (mb[a] & ma[b])
    return mask


def _worse_than_baseline(
    baseline: dict,
    names: Sequence[str],
    candidates: np.ndarray,
    status_index: np.ndarray,
    depth: np.ndarray,
    distance: np.ndarray,
    tol: float,
) -> np.ndarray:
    """True for pairs that are new, or worse than in the baseline report."""
    old = {}
    for p in baseline.get("pairs", []):
        a, b = sorted((p["body_a"], p["body_b"]))
        old[(a, b)] = p
    worse = np.ones(len(candidates), dtype=bool)
    for i, (a, b) in enumerate(candidates):  # violating pairs only matter; few
        before = old.get(tuple(sorted((names[a], names[b]))))
        if before is None:
            continue
        prev = SEVERITY.get(before.get("status"), -1)
        if status_index[i] > prev:
            continue
        if status_index[i] < prev:
            worse[i] = False
            continue
        old_depth = before.get("depth") or 0.0
        old_distance = before.get("distance")
        deeper = depth[i] > old_depth + tol
        closer = old_distance is not None and distance[i] < old_distance - tol
        worse[i] = bool(deeper or closer)
    return worse
