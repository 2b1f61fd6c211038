"""What the --snapshots tests read from a PNG (tests/io/test_snapshots*.py): its pixels, and
the pixels of one colour under flat shading or exactly."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from meshcol.io.raster import hex_rgb

Image = pytest.importorskip("PIL.Image", reason="Pillow (meshcol[snapshots]) is not installed")


def pixels(path: Path) -> np.ndarray:
    with Image.open(path) as image:
        assert image.mode == "RGB" and image.size == (800, 600)
        return np.asarray(image)


def hue_mask(image: np.ndarray, color: str) -> np.ndarray:
    """Pixels of ``color`` under any flat shade: proportional to it channel by channel."""
    target = np.asarray(hex_rgb(color), dtype=np.float32)
    rgb = image.astype(np.float32)
    total = rgb.sum(axis=2)
    scale = total / target.sum()
    close = np.abs(rgb - scale[..., None] * target).max(axis=2) <= 6
    return close & (scale > 0.3) & (total > 60)


def exact_mask(image: np.ndarray, color: str) -> np.ndarray:
    return np.all(image == np.asarray(hex_rgb(color), dtype=np.uint8), axis=2)
