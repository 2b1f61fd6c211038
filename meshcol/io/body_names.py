"""The names of the bodies of one file: by where they are in the file's hierarchy.

A file of one body names it after the file's stem (``crate``). A file of several names each
``<stem>/<leaf>``, the leaf being the body's own name (its object, node or prim name), when no
other body of the file has that leaf: the names of files without repeated leaves are what they
always were. When bodies share a leaf (a USD stage of 10,000 prims named ``mesh``, each under
its own ``Xform``), each is named by the shortest suffix of its path, the names of its
ancestors from the file's root down to its leaf, that no other body's path ends with:
``level/crate_01/mesh``, ``level/crate_02/mesh``, ``level/bay_2/crate_01/mesh`` beside
``level/bay_1/crate_01/mesh``. A user finds the prim by the name, and adding a body elsewhere
in the file does not rename it (where ``#k`` counted every earlier body of the leaf).

Rules:

- The separator is ``/`` (USD's prim paths, and the stem's own separator). A name that holds
  ``/`` itself (a glTF, FBX or COLLADA node may be called ``a/b``) is kept as it is; its
  suffix is still counted by names, so ``a/b/mesh`` can be two different paths. Where that
  makes two names equal, and where the full paths are themselves equal (glTF allows sibling
  nodes of one name; a glTF node of several primitives is several bodies of one path), the
  later body in file order gets ``#2``, ``#3``... on its full path
  (:func:`meshcol.types.unique_name`).
- A body whose path is a suffix of another's (a root prim ``/mesh`` beside ``/a/mesh``) has
  no suffix of its own: it is named by its full path (``level/mesh``).
- The names do not depend on the order of the bodies, except for the ``#k`` of equal paths.
- A name takes at most :data:`MAX_ANCESTORS` ancestors: paths deeper than that are told apart
  by their last ones, then by ``#k`` (a hostile chain of 10,000 nodes of one name would
  otherwise make names of 10,000 parts, and count their suffixes in ``n * d * d``).
- Formats without a hierarchy (OBJ groups and objects, STL solids, PLY, OFF) give no
  ancestors: their repeated leaves keep ``#2``, ``#3``...

Where the names go: reports carry them as they are; ``hull -o`` and ``fit -o`` write them as
OBJ object and glTF node names (any string); file names made from them (``--out-dir``,
snapshots) replace ``/`` and every other unsafe character. The robot writers (URDF, MJCF,
SRDF, ``--to usd``) write link names, never these; a link name holding ``/`` passes through
them too (``--to usd`` makes a valid prim name and keeps the name in ``meshcol:link``).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Mapping, Sequence

from meshcol.types import unique_name

__all__ = ["MAX_ANCESTORS", "SEPARATOR", "ancestor_names", "file_body_names"]

#: What joins the stem and the names of a body's path.
SEPARATOR = "/"
#: Most ancestors a body's name takes (the readers keep no more): the nearest ones.
MAX_ANCESTORS = 15


def ancestor_names(k: int, parent: Mapping[int, int], names: Sequence[str]) -> tuple[str, ...]:
    """The names (``names``, one per node) of node ``k``'s ancestors (``parent``: each
    node's, none for a root), from the top down: the nearest :data:`MAX_ANCESTORS` (a cycle
    ends there too). One walk for the readers of node hierarchies (glTF, FBX)."""
    above: list[str] = []
    current = parent.get(k)
    while current is not None and len(above) < MAX_ANCESTORS:
        above.append(names[current])
        current = parent.get(current)
    return tuple(reversed(above))


def file_body_names(
    stem: str, leaves: Sequence[str], ancestors: Sequence[Sequence[str]] | None = None
) -> list[str]:
    """The name of each body of one file (see the module's rules).

    Parameters
    ----------
    stem : str
        The file's stem.
    leaves : sequence of str
        Each body's own name, in file order.
    ancestors : sequence of sequence of str, optional
        Each body's ancestors' names, from the root down to its parent (empty: at the root, or
        a format without a hierarchy; only the last :data:`MAX_ANCESTORS` are read). None: no
        body has any.

    Returns
    -------
    list of str
        Unique names, in the order of ``leaves``.

    Notes
    -----
    Linear in the bodies whose leaf repeats: every suffix of their paths (at most
    ``MAX_ANCESTORS + 1`` names) is counted once in a :class:`collections.Counter`, and each
    body takes its first suffix counted once.
    """
    if len(leaves) == 1:
        return [stem]
    lineage = [tuple(above[-MAX_ANCESTORS:]) for above in ancestors or [()] * len(leaves)]
    if len(lineage) != len(leaves):
        raise ValueError(f"ancestors has {len(lineage)} items, leaves {len(leaves)}")
    repeated = {leaf for leaf, n in Counter(leaves).items() if n > 1}
    suffixes: Counter[tuple[str, ...]] = Counter()
    for leaf, above in zip(leaves, lineage):
        if leaf in repeated:
            path = (*above, leaf)
            suffixes.update(path[k:] for k in range(len(path) - 1))
    used: dict[str, int] = {}
    names = []
    for leaf, above in zip(leaves, lineage):
        where = leaf
        if leaf in repeated:
            where = SEPARATOR.join(_shortest_suffix((*above, leaf), suffixes))
        names.append(unique_name(f"{stem}{SEPARATOR}{where}", used))
    return names


def _shortest_suffix(path: tuple[str, ...], counts: Counter[tuple[str, ...]]) -> tuple[str, ...]:
    """The shortest suffix of ``path`` (longer than its leaf) that ``counts`` counted once;
    the whole path when none is."""
    for k in range(len(path) - 2, -1, -1):
        if counts[path[k:]] == 1:
            return path[k:]
    return path
