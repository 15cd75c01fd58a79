"""Data sequences (the VRS paper's data iterators), numpy-backed.

Shapes accept a sequence or any array-like for their per-vertex data and
painters call ``.array()`` (or :func:`as_array`) to get one ndarray. This
package imports nothing else of omnirender.
"""

from omnirender.data.sequences import (
    Array,
    Composite,
    Constant,
    Indexed,
    Repeat,
    Replicate,
    Sequence,
    Skip,
    as_array,
)

__all__ = [
    "Array",
    "Composite",
    "Constant",
    "Indexed",
    "Repeat",
    "Replicate",
    "Sequence",
    "Skip",
    "as_array",
]
