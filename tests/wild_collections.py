"""Files of the real collections installed from the registries (example-robot-data, gymnasium,
dm_control, the Menagerie wheels, pybullet_data): a test that needs one skips, with the
reason, when its package is missing. Shared by the tests of robots from the wild.
"""

from __future__ import annotations

from pathlib import Path

import pytest


def collection_file(package: str, *parts: str) -> Path:
    """A file of an installed collection; the test skips when the package is missing."""
    import importlib.util
    import site

    if package == "example-robot-data":
        for base in site.getsitepackages():
            path = Path(base, "cmeel.prefix", "share", "example-robot-data", "robots", *parts)
            if path.is_file():
                return path
        pytest.skip("example-robot-data is not installed (pip install 'meshcol[robots-wild]')")
    spec = importlib.util.find_spec(package)
    if spec is None or not spec.submodule_search_locations:
        pytest.skip(f"{package} is not installed (pip install 'meshcol[robots-wild]')")
    path = Path(next(iter(spec.submodule_search_locations)), *parts)
    if not path.is_file():
        pytest.skip(f"{package} has no {'/'.join(parts)}")
    return path
