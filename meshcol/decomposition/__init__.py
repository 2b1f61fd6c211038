"""Convex decomposition: engines, canonical forms, fidelity metrics, the content cache and
runs over many files.

The package is ``decomposition`` (not ``decompose``) so that ``meshcol.decompose`` stays the
function.
"""
