"""Geometry on plain arrays: convex hulls, mesh topology, triangles.

Pure numpy (and scipy's qhull); nothing here imports the native core, so every layer above
can use it.
"""
