"""Print pip constraints pinning every runtime dependency to the lower end of its range
(its newest patch release).

`make test-lowest` installs meshcol with them into .venv-lowest and runs the fast lane, so
the lower bounds in pyproject.toml are versions that work (`make test` installs the newest
versions the ranges allow: the upper end). A dependency without a lower bound is an error.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

PYPROJECT = Path(__file__).resolve().parent.parent / "pyproject.toml"
REQUIREMENT = re.compile(r"^\s*(?P<name>[A-Za-z0-9_.\-]+)\s*>=\s*(?P<low>[0-9][0-9A-Za-z.]*)")


def lowest_constraints(dependencies: list[str]) -> list[str]:
    """``name==low.*`` for each ``name>=low[,...][; marker]`` requirement (``name==low`` when
    ``low`` names a patch release): the newest patch release of the lower bound, markers
    kept."""
    out = []
    for requirement in dependencies:
        spec, _, marker = requirement.partition(";")
        match = REQUIREMENT.match(spec)
        if match is None:
            raise ValueError(f"dependency without a lower bound (name>=version): {requirement!r}")
        low = match["low"]
        pin = f"{match['name']}=={low}" if low.count(".") >= 2 else f"{match['name']}=={low}.*"
        out.append(f"{pin}; {marker.strip()}" if marker.strip() else pin)
    return out


def main() -> None:
    project = tomllib.loads(PYPROJECT.read_text(encoding="utf-8"))["project"]
    print("\n".join(lowest_constraints(project["dependencies"])))


if __name__ == "__main__":
    main()
