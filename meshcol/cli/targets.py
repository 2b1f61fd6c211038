"""``meshcol targets``: the engine target profiles and their limits."""

from __future__ import annotations

import click

from meshcol.cli import CONTEXT_SETTINGS
from meshcol.vocabulary import LIMITS

#: Table columns: (header, limit key).
_COLUMNS = tuple((header, key) for key, (_, _, header) in LIMITS.items())


@click.command(
    "targets",
    short_help="Engine target profiles (--target) and their limits, with sources.",
    context_settings=CONTEXT_SETTINGS,
)
@click.argument("profiles", nargs=-1, metavar="[NAME|FILE.toml]...")
@click.option(
    "--format",
    "fmt",
    type=click.Choice(["table", "json"]),
    default=None,
    help="table (one line per profile, as `meshcol rules` prints) or json (one object per "
    "profile, with every source).  [default: table]",
)
def targets(profiles: tuple[str, ...], fmt: str | None) -> None:
    """List the engine target profiles of --target (hull, decompose) and their limits.

    Each profile is a TOML file in the package (meshcol/targets/) citing, for every limit,
    the document and the sentence it comes from, and whether it is a documented hard limit
    or a convention (a default or a practice). Give NAMEs or your own FILE.toml to show
    only those (a file is validated: unknown keys, wrong types and negative limits exit 2).
    A '-' in the table is no limit. Lengths are metres; each profile converts them to the
    mesh's units (Unreal: centimetres).

    \b
    Examples:
      meshcol targets
      meshcol targets physx-gpu --format json
      meshcol targets my_engine.toml
    """
    from meshcol.io.report import dumps_json
    from meshcol.io.targets import list_targets, load_target

    found = [load_target(p) for p in profiles] if profiles else list_targets()
    if fmt == "json":
        click.echo(dumps_json({"targets": [t.to_dict() for t in found]}), nl=False)
        return
    rows = [("name", "units", *(header for header, _ in _COLUMNS), "convention")]
    for t in found:
        cells = []
        for _, key in _COLUMNS:
            value = t.limits.get(key)
            cells.append("-" if value is None else f"{value:g}")
        conventions = sorted({s.limit for s in t.sources if s.kind == "convention"})
        rows.append((t.name, t.units, *cells, ", ".join(conventions) or "-"))
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]))]
    for row in rows:
        click.echo("  ".join(cell.ljust(width) for cell, width in zip(row, widths)).rstrip())
