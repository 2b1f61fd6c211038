"""The analyses behind the commands: colliders (body to parts), check, sweep, inspect, hull.

Each takes loaded bodies (or input paths) and returns a report object; the command line only
formats and writes it.
"""
