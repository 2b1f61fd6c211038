"""A decomposition fitted to an engine target's limits (``meshcol decompose --target``).

The engine aims at the target first (:meth:`meshcol.decomposition.options.DecomposeOptions.
aimed_at`: its vertex budget and hull count); what it returns is then fitted to every limit
here, still enclosing, and measured again, so that the report describes what is written. The
cache keeps the engine's parts.
"""

from __future__ import annotations

import dataclasses
from typing import Any

from meshcol.decomposition.result import Decomposition

__all__ = ["apply_target"]


def apply_target(
    target: Any,
    d: Decomposition,
    vertices: Any,
    faces: Any,
    units: str | None = None,
    threads: int = 0,
) -> tuple[Decomposition, dict[str, Any]]:
    """A body's decomposition fitted to a target, re-measured, and its report entry.

    The parts (``d.parts``, in the body's frame) go through
    :func:`meshcol.collision.target_fit.fit_parts` (merged to ``max_hulls``, each grown and
    simplified to the per-part limits, every part still enclosing what it replaces); the
    fidelity metrics are measured again on the fitted parts (same samples and tolerance),
    so the report describes what is written.

    Returns
    -------
    (Decomposition, dict)
        The fitted decomposition and the body's ``target`` entry (name, met, costs,
        violations, per-part measures).
    """
    from meshcol.collision.target_fit import fit_parts
    from meshcol.decomposition.fidelity import fidelity
    from meshcol.geometry.topology import orient_outward

    fit = fit_parts(d.parts, target.limits, target.length_scale(units))
    metrics = d.metrics
    if metrics is not None:
        outward, _ = orient_outward(vertices, faces)
        metrics = fidelity(
            vertices,
            outward,
            fit.parts,
            samples=metrics.samples,
            tolerance=metrics.tolerance,
            threads=threads,
        )
    notes = tuple(d.notes) + tuple(f"target {target.name}: {note}" for note in fit.notes)
    fitted = dataclasses.replace(d, parts=fit.parts, metrics=metrics, notes=notes)
    return fitted, {"name": target.name, **fit.to_dict()}
