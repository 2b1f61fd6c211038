"""FBX binary to FBX ASCII, for the test fixtures (Blender 4.2 writes binary FBX only).

    python scripts/fbx_ascii.py level.fbx level_ascii.fbx

Every node record becomes a line ``Name: properties`` with its children in braces, arrays
(zlib-compressed or not) as ``*N { a: ... }``, numbers at full precision (``repr``), so the
ASCII file holds exactly what the binary one does; ``Name\\x00\\x01Class`` strings become
``Class::Name`` as ASCII FBX writes them. Standard library only.
"""

from __future__ import annotations

import base64
import struct
import sys
import zlib
from pathlib import Path

_SCALARS = {"Y": "<h", "C": "<B", "I": "<i", "L": "<q", "F": "<f", "D": "<d"}
_ARRAYS = {"f": "f", "d": "d", "l": "q", "i": "i", "b": "B"}


class _Reader:
    def __init__(self, data: bytes) -> None:
        if not data.startswith(b"Kaydara FBX Binary  \x00"):
            raise ValueError("not a binary FBX file")
        self.data = data
        self.version = struct.unpack_from("<I", data, 23)[0]
        self.wide = self.version >= 7500  # 64-bit record headers from 7.5
        self.lines = [f"; FBX {self.version // 1000}.{self.version % 1000 // 100}.0 project file"]

    def value(self, kind: str, at: int) -> tuple[str, int]:
        data = self.data
        if kind in _SCALARS:
            (v,) = struct.unpack_from(_SCALARS[kind], data, at)
            text = repr(float(v)) if kind in "FD" else str(int(v))
            return text, at + struct.calcsize(_SCALARS[kind])
        if kind in _ARRAYS:
            count, encoding, size = struct.unpack_from("<III", data, at)
            raw = data[at + 12 : at + 12 + size]
            if encoding == 1:
                raw = zlib.decompress(raw)
            values = struct.unpack(f"<{count}{_ARRAYS[kind]}", raw)
            items = ",".join(repr(float(v)) if kind in "fd" else str(int(v)) for v in values)
            return f"*{count} {{\n\ta: {items}\n}}", at + 12 + size
        if kind in "SR":
            (size,) = struct.unpack_from("<I", data, at)
            raw = data[at + 4 : at + 4 + size]
            if kind == "R":
                return '"' + base64.b64encode(raw).decode() + '"', at + 4 + size
            text = raw.decode("utf-8", "replace")
            if "\x00\x01" in text:
                name, cls = text.split("\x00\x01", 1)
                text = f"{cls}::{name}"
            return '"' + text.replace('"', "&quot;") + '"', at + 4 + size
        raise ValueError(f"unknown property type {kind!r} at byte {at - 1}")

    def node(self, at: int, depth: int) -> int | None:
        """Write the record at ``at``; the byte after it, or None for the closing record."""
        if self.wide:
            end, count, _ = struct.unpack_from("<QQQ", self.data, at)
            head = 25
        else:
            end, count, _ = struct.unpack_from("<III", self.data, at)
            head = 13
        if end == 0:
            return None
        length = self.data[at + head - 1]
        name = self.data[at + head : at + head + length].decode()
        cursor = at + head + length
        properties = []
        for _ in range(count):
            text, cursor = self.value(chr(self.data[cursor]), cursor + 1)
            properties.append(text)
        tab = "\t" * depth
        line = f"{tab}{name}: {', '.join(properties)}"
        if cursor < end or not properties:
            self.lines.append(line + " {")
            while cursor < end:
                after = self.node(cursor, depth + 1)
                if after is None:
                    break
                cursor = after
            self.lines.append(f"{tab}}}")
        else:
            self.lines.append(line)
        return end


def to_ascii(data: bytes) -> str:
    """The ASCII FBX text of a binary FBX file's bytes."""
    reader = _Reader(data)
    at = 27
    while at < len(data):
        after = reader.node(at, 0)
        if after is None:
            break
        at = after
    return "\n".join(reader.lines) + "\n"


if __name__ == "__main__":
    Path(sys.argv[2]).write_text(to_ascii(Path(sys.argv[1]).read_bytes()))
