"""Collision queries in the native core: convex hulls, convex shapes and their packed sets,
the narrow phase (distance, penetration, intersection), time of impact, exact triangle-mesh
queries and the broad phase. Arrays in, arrays out; nothing here reads files or builds reports.
"""
