"""The body pairs MuJoCo's weld and contype/conaffinity filters leave untested
(``meshcol.io.mjcf._filtered_pairs``): one mask pair per body and one array expression per
body's row, against the loop over every geom pair of every body pair that it replaced (a
bin of 2,000 free bodies spent 15 s in that loop), on random compiled models."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

mujoco = pytest.importorskip("mujoco", reason="MuJoCo compiles the models (the test extras)")

from meshcol.io.mjcf import _colliding_geoms, _exclusions, _explicit_body_pairs, _filtered_pairs  # noqa: E402


def _reference(model, names):
    """Every colliding geom of a against every one of b, for every body pair in order."""
    contype = np.asarray(model.geom_contype, dtype=np.int64)
    conaffinity = np.asarray(model.geom_conaffinity, dtype=np.int64)
    colliding = _colliding_geoms(model)
    geom_body = np.asarray(model.geom_bodyid, dtype=np.int64)
    bodies = sorted({int(b) for b in geom_body[colliding]})
    weld = np.asarray(model.body_weldid, dtype=np.int64)
    pairs = []
    for i, a in enumerate(bodies):
        for b in bodies[i + 1 :]:
            if weld[a] == weld[b]:
                pairs.append((names[a], names[b], "mjcf welded"))
                continue
            passes = any(
                (contype[ga] & conaffinity[gb]) or (contype[gb] & conaffinity[ga])
                for ga in colliding[geom_body[colliding] == a]
                for gb in colliding[geom_body[colliding] == b]
            )
            if not passes:
                pairs.append((names[a], names[b], "mjcf contype/conaffinity"))
    return pairs


masks = st.integers(0, 5)
body = st.tuples(
    st.booleans(),  # a free joint (else welded to its parent)
    st.integers(0, 7),  # parent: the world or an earlier body
    st.lists(st.tuples(masks, masks), min_size=1, max_size=3),  # geoms' contype, conaffinity
)


@settings(max_examples=60, deadline=None)
@given(
    bodies=st.lists(body, min_size=1, max_size=8),
    world_geoms=st.lists(st.tuples(masks, masks), max_size=2),
    explicit=st.lists(st.tuples(st.integers(0, 8), st.integers(0, 8)), max_size=3),
)
def test_filtered_pairs_are_the_geom_pair_loops(bodies, world_geoms, explicit) -> None:
    def geoms(owner, specs):
        return "".join(
            f'<geom name="{owner}_g{k}" type="sphere" size="0.1" contype="{c}" conaffinity="{a}"/>'
            for k, (c, a) in enumerate(specs)
        )

    children: dict[int, list[str]] = {}
    for k, (free, parent, specs) in reversed(list(enumerate(bodies))):
        parent = min(parent, k)  # 0 is the world, i + 1 body i
        joint = (
            "<freejoint/>" if free and parent == 0 else ('<joint type="hinge"/>' if free else "")
        )
        inner = "".join(children.pop(k + 1, []))
        children.setdefault(parent, []).insert(
            0, f'<body name="b{k}" pos="0 0 {0.1 * k}">{joint}{geoms(f"b{k}", specs)}{inner}</body>'
        )
    pairs = "".join(
        f'<pair geom1="b{a}_g0" geom2="b{b}_g0"/>'
        for a, b in explicit
        if a != b and a < len(bodies) and b < len(bodies)
    )
    xml = (
        f"<mujoco><worldbody>{geoms('world', world_geoms)}{''.join(children.get(0, []))}"
        f"</worldbody><contact>{pairs}</contact></mujoco>"
    )
    model = mujoco.MjModel.from_xml_string(xml)
    names = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, b) for b in range(model.nbody)]
    filtered = _filtered_pairs(model, names)
    assert filtered == _reference(model, names)
    # a pair a <contact><pair> names is collided: out of every exclusion, these included
    explicit = {frozenset((names[a], names[b])) for a, b in _explicit_body_pairs(model)}
    excluded = _exclusions(model, names, include_adjacent=True)
    kept = [p for p in filtered if frozenset(p[:2]) not in explicit]
    assert [p for p in excluded if p[2].startswith("mjcf w") or p[2].endswith("affinity")] == kept
