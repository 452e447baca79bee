"""Hair files by extension: Cem Yuksel's ``.hair``, USC-HairSalon ``.data``, AMD TressFX 4 ``.tfx`` and USD
``BasisCurves`` text ``.usda`` (the Rust ``hairstyle::formats`` readers and writers)."""

from __future__ import annotations

import os
from typing import List, Sequence, Union

import numpy as np

from . import _coiffure

PathLike = Union[str, "os.PathLike[str]"]


def read_hair(path: PathLike) -> List[np.ndarray]:
    """Reads a hair file; the format follows the extension (``.hair``, ``.data``, ``.tfx``, ``.usda``).

    Returns one float32 array of shape (n_i, 3) per strand, root first, in the file's units (Coiffure writes
    metres). The arrays are views into one block of memory. A malformed or truncated file raises
    ``ValueError`` naming the byte offset (binary formats) or line (``.usda``); nothing is partially loaded.
    A missing file raises ``FileNotFoundError``.
    """
    points, counts = _coiffure.read_hair_flat(os.fspath(path))
    if len(counts) == 0:
        return []
    return np.split(points, np.cumsum(counts)[:-1])


def write_hair(path: PathLike, strands: Sequence[np.ndarray]) -> None:
    """Writes strands (each an array-like of shape (n_i, 3), root first, in metres) to a hair file whose
    format follows the extension. Positions are stored as float32 (every format's precision). Data a format
    cannot hold (e.g. strands of unequal point counts in ``.tfx``) raises ``ValueError``; nothing is written.
    """
    arrays = [np.asarray(s, dtype=np.float32) for s in strands]
    for i, a in enumerate(arrays):
        if a.ndim != 2 or a.shape[1] != 3:
            raise ValueError(f"strand {i} must have shape (n, 3), got {a.shape}")
    counts = np.array([a.shape[0] for a in arrays], dtype=np.int64)
    points = np.ascontiguousarray(np.concatenate(arrays) if arrays else np.zeros((0, 3), np.float32))
    _coiffure.write_hair_flat(os.fspath(path), points, counts)
