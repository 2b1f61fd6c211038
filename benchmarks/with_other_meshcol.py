"""Runs a benchmark script with this interpreter (its numpy, python-fcl and coal) against
another checkout's meshcol package and built core, for an A/B when that checkout's venv lacks
the peers.

Run: .venv/bin/python benchmarks/with_other_meshcol.py CHECKOUT SCRIPT [ARGS...]

CHECKOUT is a checkout with a built `.venv` (e.g. /work/base16): its `meshcol` package comes
first on the path, its `_core` extension from its venv's site-packages, and this venv's
editable finder (which would map `meshcol` to this checkout) is dropped; both are checked to
come from CHECKOUT before SCRIPT runs as `__main__`.
"""

from __future__ import annotations

import runpy
import sys
from pathlib import Path


def main() -> None:
    checkout = Path(sys.argv[1]).resolve()
    script = sys.argv[2]
    sys.meta_path[:] = [f for f in sys.meta_path if "meshcol" not in type(f).__module__.lower()]
    sys.path.insert(0, str(checkout))
    import meshcol

    sites = list((checkout / ".venv" / "lib").glob("python*/site-packages/meshcol"))
    meshcol.__path__.extend(str(s) for s in sites)
    import meshcol._core

    for module in (meshcol, meshcol._core):
        if not str(Path(module.__file__ or "").resolve()).startswith(str(checkout)):
            raise SystemExit(f"{module.__name__} came from {module.__file__}, not {checkout}")
    sys.argv = sys.argv[2:]
    runpy.run_path(script, run_name="__main__")


if __name__ == "__main__":
    main()
