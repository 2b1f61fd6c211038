"""``MeshInspection.to_dict`` (a shallow copy, for 100,000-body glTF files) against
``dataclasses.asdict``, which it replaced: the same value, and no list shared with the
inspection."""

from __future__ import annotations

import dataclasses

import numpy as np
import trimesh

from meshcol.analysis.health import inspect_body
from meshcol.types import Body


def test_to_dict_is_asdict() -> None:
    box = trimesh.creation.box()
    for faces in (np.asarray(box.faces), np.asarray(box.faces)[:-2]):  # closed, then open
        found = inspect_body(Body("b", "b.obj", np.asarray(box.vertices), faces), "mm")
        plain = found.to_dict()
        assert plain == dataclasses.asdict(found)
        assert list(plain) == [f.name for f in dataclasses.fields(found)]
        plain["bounds"][0][0] = plain["size"][0] = 99.0
        plain["findings"].append("x")
        assert found.bounds[0][0] != 99.0 and found.size[0] != 99.0 and "x" not in found.findings
