"""Per-face lists in OpenFOAM field files, where foamlib (1.7) reads them as something else.

foamlib writes a scalar list of 3, 6 or 9 values as a uniform vector or tensor, and a list of
3 or 6 vectors as a uniform tensor, whatever the entry's type. Such lists are written in two
steps: foamlib puts a placeholder word where the list goes (:func:`placeholder`), and
:func:`fill_placeholders` replaces each word by the list written out in full
(``nonuniform List<T> N(...)``), T from the array's shape.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ehlfoam._io import atomic_write_text

#: OpenFOAM's list type for each number of components per value.
_LIST_TYPES = {3: "vector", 6: "symmTensor", 9: "tensor"}


def placeholder(patch: str, key: str) -> str:
    """The word that stands for ``patch``'s ``key`` list until :func:`fill_placeholders`."""
    return f"ehlfoamList_{patch}_{key}"


def list_text(values: np.ndarray) -> str:
    """``nonuniform List<T> N(...)`` of a scalar (F,), vector (F, 3), symmTensor (F, 6) or
    tensor (F, 9) field."""
    values = np.asarray(values, float)
    if values.ndim == 1:
        kind, rows = "scalar", " ".join(repr(float(v)) for v in values)
    elif values.ndim == 2 and values.shape[1] in _LIST_TYPES:
        kind = _LIST_TYPES[values.shape[1]]
        rows = " ".join("(" + " ".join(repr(float(c)) for c in row) + ")" for row in values)
    else:
        raise ValueError(f"values: shape {values.shape} (valid: (F,) or (F, 3 | 6 | 9))")
    return f"nonuniform List<{kind}> {len(values)}({rows})"


def fill_placeholders(path: Path, lists: dict[str, np.ndarray]) -> None:
    """Replace each placeholder word in the field file ``path`` by its list (atomically);
    each word must occur exactly once."""
    text = path.read_text()
    for word, values in lists.items():
        if text.count(word) != 1:
            raise RuntimeError(f"placeholder {word} not written once in {path}")
        text = text.replace(word, list_text(values))
    atomic_write_text(path, text)
