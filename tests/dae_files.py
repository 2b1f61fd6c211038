"""COLLADA documents written from a small XML template, for the tests of meshcol/io/dae.py:
a cube geometry as triangles, a polylist or polygons, nodes that place it, units and axes."""

from __future__ import annotations

import itertools

#: The cube's corners: index 4 x + 2 y + z of the signs (-, +) on each axis.
CORNERS = list(itertools.product((-1, 1), repeat=3))

#: Its six faces as quads, counter-clockwise seen from outside.
QUADS = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]


def geometry(geometry_id: str, half: float, primitive: str = "triangles") -> str:
    """A ``<geometry>`` of a cube of half side ``half`` centred at its origin, its faces as
    ``triangles``, one ``polylist`` of quads, ``polygons`` (a ``<p>`` per quad) or ``lines``
    (its edges only: no triangle)."""
    floats = " ".join(f"{half * s!r}" for corner in CORNERS for s in corner)
    vertex_input = f'<input semantic="VERTEX" source="#{geometry_id}-vtx" offset="0"/>'
    if primitive == "triangles":
        p = " ".join(f"{a} {b} {c} {a} {c} {d}" for a, b, c, d in QUADS)
        body = f'<triangles count="12">{vertex_input}<p>{p}</p></triangles>'
    elif primitive == "polylist":
        p = " ".join(" ".join(map(str, quad)) for quad in QUADS)
        body = f'<polylist count="6">{vertex_input}<vcount>{"4 " * 6}</vcount><p>{p}</p></polylist>'
    elif primitive == "polygons":
        ps = "".join(f"<p>{' '.join(map(str, quad))}</p>" for quad in QUADS)
        body = f'<polygons count="6">{vertex_input}{ps}</polygons>'
    else:
        p = " ".join(f"{a} {b}" for quad in QUADS for a, b in zip(quad, quad[1:] + quad[:1]))
        body = f'<lines count="24">{vertex_input}<p>{p}</p></lines>'
    return (
        f'<geometry id="{geometry_id}" name="{geometry_id}"><mesh>'
        f'<source id="{geometry_id}-pos"><float_array id="{geometry_id}-arr" count="24">'
        f"{floats}</float_array><technique_common>"
        f'<accessor source="#{geometry_id}-arr" count="8" stride="3">'
        '<param name="X" type="float"/><param name="Y" type="float"/>'
        '<param name="Z" type="float"/></accessor></technique_common></source>'
        f'<vertices id="{geometry_id}-vtx"><input semantic="POSITION" '
        f'source="#{geometry_id}-pos"/></vertices>{body}</mesh></geometry>'
    )


def node(name: str | None, inner: str, transforms: str = "", node_id: str | None = None) -> str:
    """A ``<node>`` (``name`` and ``id`` attributes when given) of ``transforms`` then
    ``inner``."""
    attributes = "".join(
        f' {key}="{value}"' for key, value in (("id", node_id), ("name", name)) if value
    )
    return f"<node{attributes}>{transforms}{inner}</node>"


def instance(geometry_id: str, material: str | None = None) -> str:
    """An ``<instance_geometry>`` of ``geometry_id``, bound to ``material`` when given (a
    material the document need not have)."""
    if material is None:
        return f'<instance_geometry url="#{geometry_id}"/>'
    return (
        f'<instance_geometry url="#{geometry_id}"><bind_material><technique_common>'
        f'<instance_material symbol="m" target="#{material}"/></technique_common>'
        "</bind_material></instance_geometry>"
    )


def document(
    nodes: str,
    geometries: str,
    *,
    meter: str | None = None,
    up_axis: str | None = "Z_UP",
    library_nodes: str = "",
    prolog: str = '<?xml version="1.0" encoding="utf-8"?>\n',
) -> str:
    """A COLLADA 1.4.1 document: ``nodes`` in its visual scene, ``geometries`` and
    ``library_nodes`` in their libraries, ``<unit meter>`` and ``<up_axis>`` when given."""
    unit = "" if meter is None else f'<unit name="u" meter="{meter}"/>'
    up = "" if up_axis is None else f"<up_axis>{up_axis}</up_axis>"
    return (
        f"{prolog}"
        '<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">\n'
        f"<asset>{unit}{up}</asset>\n"
        f"<library_geometries>{geometries}</library_geometries>\n"
        f"<library_nodes>{library_nodes}</library_nodes>\n"
        f'<library_visual_scenes><visual_scene id="Scene">{nodes}</visual_scene>'
        "</library_visual_scenes>\n"
        '<scene><instance_visual_scene url="#Scene"/></scene>\n</COLLADA>\n'
    )


def placed_cube(meter: str | None = None, half: float = 50.0, up_axis: str | None = "Z_UP") -> str:
    """One node ``box``, translated (10, 20, 30) and turned 90 degrees about z, holding a cube
    of half side ``half``: in metres (``meter`` given) a cube of half side ``half * meter``."""
    transforms = "<translate>10 20 30</translate><rotate>0 0 1 90</rotate>"
    return document(
        node("box", instance("cube"), transforms),
        geometry("cube", half),
        meter=meter,
        up_axis=up_axis,
    )
