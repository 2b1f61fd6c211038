"""A USD stage's collision filters as excluded body pairs (for :mod:`meshcol.io.usd_read`).

Two sources, both UsdPhysics:

- ``FilteredPairsAPI``: a prim's ``physics:filteredPairs`` targets never collide with it;
- ``CollisionGroup``: the bodies of a group (its ``colliders`` collection) never collide with
  the bodies of the groups in its ``physics:filteredGroups`` (a group may name itself; with
  ``physics:invertFilteredGroups``, with those of every group not listed).

A prim stands for every body at or under it, and for the body it is part of. Each pair is
``(key_a, key_b, reason)``, keys the bodies' prim paths (``FileScene.excluded``).
"""

from __future__ import annotations

from typing import Any

__all__ = ["excluded_pairs"]


def _bodies_of(path: str, keys: list[str]) -> list[str]:
    """The bodies a prim path stands for: bodies at or under it, or the one it is under."""
    inside = [key for key in keys if key == path or key.startswith(path + "/")]
    if inside:
        return inside
    return [key for key in keys if path.startswith(key + "/")]


def _pairs(left: list[str], right: list[str], reason: str, out: dict[tuple[str, str], str]) -> None:
    for a in left:
        for b in right:
            if a != b:
                out.setdefault((min(a, b), max(a, b)), reason)


def excluded_pairs(stage: Any, names: list[str]) -> list[tuple[str, str, str]]:
    """Every body pair the stage's filters exclude.

    Parameters
    ----------
    stage : Usd.Stage
    names : list of str
        The prim path of each body (its rigid body, link or collision prim).

    Returns
    -------
    list of (str, str, str)
        ``(path_a, path_b, reason)``, ``path_a < path_b``, sorted.
    """
    from pxr import Usd, UsdPhysics

    out: dict[tuple[str, str], str] = {}
    groups: dict[str, list[str]] = {}
    filters: list[tuple[str, list[str]]] = []
    predicate = Usd.TraverseInstanceProxies(Usd.PrimDefaultPredicate)
    for prim in Usd.PrimRange.Stage(stage, predicate):
        path = str(prim.GetPath())
        if prim.HasAPI(UsdPhysics.FilteredPairsAPI):
            targets = UsdPhysics.FilteredPairsAPI(prim).GetFilteredPairsRel().GetTargets()
            for target in targets:
                _pairs(
                    _bodies_of(path, names),
                    _bodies_of(str(target), names),
                    f"UsdPhysics FilteredPairsAPI: <{path}> and <{target}>",
                    out,
                )
        if prim.IsA(UsdPhysics.CollisionGroup):
            group = UsdPhysics.CollisionGroup(prim)
            query = group.GetCollidersCollectionAPI().ComputeMembershipQuery()
            members = Usd.CollectionAPI.ComputeIncludedPaths(query, stage)
            groups[path] = sorted(
                {body for member in members for body in _bodies_of(str(member), names)}
            )
            filtered = [str(t) for t in group.GetFilteredGroupsRel().GetTargets()]
            if group.GetInvertFilteredGroupsAttr().Get():
                # it collides only with the groups listed: every other group is filtered
                others = [
                    str(p.GetPath()) for p in stage.Traverse() if p.IsA(UsdPhysics.CollisionGroup)
                ]
                filtered = [g for g in others if g not in filtered]
            filters.append((path, filtered))
    for path, filtered in filters:
        for other in filtered:
            _pairs(
                groups.get(path, []),
                groups.get(other, []),
                f"UsdPhysics CollisionGroup <{path}> filters <{other}>",
                out,
            )
    return [(a, b, reason) for (a, b), reason in sorted(out.items())]
