"""``meshcol config``: the configuration found, and the settings it gives a file, with where
each came from (``meshcol.toml:12``, a flag, or the default)."""

from __future__ import annotations

import functools
import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import click


def settings_options(command: Callable[..., Any]) -> Callable[..., Any]:
    """``--config FILE``, ``--set KEY=VALUE`` (repeatable), ``--shape``, ``--target``: the
    command gets ``config`` (a :class:`meshcol.io.config.Config`) and ``overrides``
    (``key -> (value, "flag --shape")``), the flags that override the file."""

    @functools.wraps(command)
    def run(
        *,
        config_file: str | None,
        set_values: tuple[str, ...],
        shape: str | None,
        target: str | None,
        **others: Any,
    ) -> Any:
        from meshcol.io.config import find_config, load_config, parse_override

        file = config_file or find_config()
        if file is None:
            raise click.UsageError(
                "no meshcol.toml (or [tool.meshcol] in pyproject.toml) in this folder or "
                "above it; give --config FILE"
            )
        overrides: dict[str, tuple[Any, str]] = {}
        flags = [(f"--set {item}", item, "--set") for item in set_values]
        flags += [("--shape", f"shape={json.dumps(shape)}", "--shape")] if shape else []
        flags += [("--target", f"target={json.dumps(target)}", "--target")] if target else []
        for origin, item, name in flags:
            try:
                key, value = parse_override(item, name)
            except ValueError as exc:
                raise click.BadParameter(str(exc), param_hint=f"'{name}'") from None
            overrides[key] = (value, f"flag {origin}")
        return command(config=load_config(file), overrides=overrides, **others)

    options = (
        click.option(
            "--config",
            "config_file",
            type=click.Path(dir_okay=False, exists=True),
            default=None,
            metavar="FILE",
            help="The configuration.  [default: meshcol.toml, or pyproject.toml with "
            "[tool.meshcol], in this folder or the closest above it]",
        ),
        click.option(
            "--set",
            "set_values",
            multiple=True,
            metavar="KEY=VALUE",
            help="Override KEY in every section (a TOML value: shape=decomposed, "
            "inspect.fail-on='[\"all\"]', check.clearance=0.01); repeatable.  [default: "
            "none, the file's settings]",
        ),
        click.option(
            "--shape", default=None, help="Same as --set shape=SHAPE.  [default: the file's]"
        ),
        click.option(
            "--target",
            default=None,
            help="Same as --set target=NAME|FILE.toml.  [default: the file's]",
        ),
    )
    wrapped: Callable[..., Any] = run
    for option in reversed(options):
        wrapped = option(wrapped)
    return wrapped


@click.command(
    "config",
    short_help="The configuration in force, and each setting of a file with its origin.",
)
@click.argument("path", required=False, metavar="[PATH]")
@click.option(
    "--format",
    "fmt",
    type=click.Choice(["text", "json"]),
    default="text",
    show_default=True,
    help="text for people, json for scripts.",
)
@click.option(
    "--jobs",
    "-j",
    type=click.IntRange(min=1),
    default=None,
    help="Show the run with meshcol ci's -j N (the flag over the file's jobs).  "
    "[default: the file's jobs, else 1]",
)
@settings_options
def config_command(
    path: str | None, fmt: str, jobs: int | None, config: Any, overrides: dict
) -> None:
    """Show the configuration meshcol finds (meshcol.toml, or [tool.meshcol] in
    pyproject.toml, in this folder or the closest above it, as ruff finds its own) and,
    for PATH, the settings it gives that file: whether it is an asset, a scene or both,
    the sections that match it, the commands it runs, and every setting with where it came
    from: the file and line, a flag (--set, --shape, --target) or the default. Without
    PATH, the run's own settings too (root, cache-dir, jobs, docs-url), each with its
    origin: a flag (-j), the environment (MESHCOL_DOCS_URL), the file's line or the default.

    \b
    Examples:
      meshcol config                              the file, its run settings, sections
      meshcol config -j 4                         ... with meshcol ci's -j 4
      meshcol config props/crate.obj              what meshcol ci does with this file
      meshcol config level.json --set check.clearance=0.01 --format json
    """
    from meshcol.io.config import resolve, run_settings
    from meshcol.io.paths import display_path

    where = display_path(config.path)
    run = run_settings(config, {"jobs": (jobs, "flag -j")})
    if path is None:
        sections = [
            {"section": s.label, "line": config.origin(s.kind, s.index)} for s in config.sections
        ]
        if fmt == "json":
            settings = {k: {"value": v, "from": origin} for k, (v, origin) in run.items()}
            document = {"config": where, "run": settings, "sections": sections}
            click.echo(json.dumps(document, indent=2))
            return
        click.echo(f"config: {where}")
        for key, (value, origin) in run.items():
            click.echo(f"  {key:<12} {json.dumps(value):<24} # {origin}")
        for item in sections:
            click.echo(f"  {item['section']:<12} {item['line']}")
        return
    resolved = resolve(config, Path(path).resolve(), overrides)
    if fmt == "json":
        out = [
            {
                "path": r.path,
                "kind": r.kind.rstrip("s"),
                "sections": list(r.sections),
                "commands": list(r.commands),
                "settings": {k: {"value": r.values[k], "from": r.origins[k]} for k in r.values},
            }
            for r in resolved
        ]
        click.echo(json.dumps({"config": where, "files": out}, indent=2))
        return
    click.echo(f"config: {where}")
    if not resolved:
        click.echo(f"{path}: no section matches it (not an asset nor a scene)")
    for r in resolved:
        click.echo(f"{r.path}: {r.kind.rstrip('s')} ({', '.join(r.sections)})")
        click.echo(f"  commands: {', '.join(r.commands)}")
        for key in r.values:
            value = json.dumps(r.values[key])
            click.echo(f"  {key:<28} {value:<24} # {r.origins[key]}")
