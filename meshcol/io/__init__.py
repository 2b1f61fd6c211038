"""Input and output: mesh readers and writers, scene manifests, reports and atomic writes.

Nothing here runs a collision query.
"""
