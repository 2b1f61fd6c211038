"""Geometry on plain arrays: mesh topology, triangles.

Pure numpy; nothing here imports the native core, so every layer above can use it. Convex
hulls run in the core: :mod:`meshcol.collision.hull`.
"""
