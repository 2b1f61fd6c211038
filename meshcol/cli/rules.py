"""``meshcol rules``: the compatibility rules, their ids and what each means."""

from __future__ import annotations

import sys
import textwrap

import click

from meshcol.cli import CONTEXT_SETTINGS
from meshcol.cli.common import report_format, report_options

#: What ``meshcol rules`` writes: the registry has no findings to annotate (no CI suite), so
#: JSON or CSV only (``formats_for(RulesReport)``, held equal by a test).
RULES_FORMATS = ("json", "csv")


@click.command(
    "rules",
    short_help="The rules findings cite: stable ids, what each measures, how to fix it.",
    context_settings=CONTEXT_SETTINGS,
)
@click.argument("rule_keys", nargs=-1, metavar="[RULE]...")
@report_options(default="a table on stdout (JSON with --format json)", formats=RULES_FORMATS)
def rules(rule_keys: tuple[str, ...], report: str | None, fmt: str | None) -> None:
    """List the rules that inspect and check findings cite, or describe some in full.

    RULE is an id (MC401) or a name (not-watertight). Without one, every rule: a table on
    stdout, or the registry as JSON or CSV with --format or --report. With one or more, each
    rule in full: what it means, what its findings' 'measured' and 'limit' hold (and the
    default limit), how to fix it. Ids are stable: 1xx engine limits of a --target profile,
    2xx physics readiness, 3xx colliders present and named, 4xx mesh health, 5xx pairs. Any
    of them (id or name) goes in --fail-on.

    \b
    Examples:
      meshcol rules                      every rule, one line each
      meshcol rules MC101                one rule in full
      meshcol rules not-watertight MC205
      meshcol rules --format json        the registry as JSON
    """
    from meshcol.analysis.rules import UnknownRuleError, rules_report
    from meshcol.io.formats import formats_for, write_report

    try:
        result = rules_report(rule_keys)
    except UnknownRuleError as exc:
        raise click.BadParameter(str(exc), param_hint="'RULE'") from None
    if report is None and fmt is None:
        click.echo(_full(result.rules) if rule_keys else _table(result.rules))
        sys.exit(0)
    fmt = report_format(report, fmt, formats=formats_for(type(result)))
    write_report(result, fmt, report)
    sys.exit(0)


def _table(rules) -> str:
    width = max(len(rule.name) for rule in rules)
    lines = [f"{'id':<6} {'name':<{width}}  {'severity':<8}  summary"]
    for rule in rules:
        lines.append(f"{rule.id:<6} {rule.name:<{width}}  {rule.severity:<8}  {rule.summary}")
    return "\n".join(lines)


def _full(rules) -> str:
    blocks = []
    for rule in rules:
        wrap = lambda label, text: textwrap.fill(
            text, 96, initial_indent=f"  {label:<10}", subsequent_indent=" " * 12
        )
        lines = [
            f"{rule.id} {rule.name} ({rule.severity}, {rule.category})",
            wrap("what", rule.summary),
            wrap("measured", rule.measured),
            wrap("fix", rule.fix),
            wrap("commands", ", ".join(rule.commands)),
        ]
        if rule.limit_key:
            lines.append(wrap("limit key", f"[limits] {rule.limit_key} of a target profile"))
        blocks.append("\n".join(lines))
    return "\n\n".join(blocks)
