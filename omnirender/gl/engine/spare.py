"""Arrays that grow in place: storage with spare rows, so that appending a few rows copies nothing.

The move plan (:mod:`.dynamic`) and the translation map (:mod:`.translations`) hold per-item and per-transform
arrays as attributes; a splice appends rows to them frame after frame.  Each attribute is a view of a larger
store; :func:`extend_held` hands out the view with more rows, copying only when the store is full (amortised:
the store grows by a quarter).
"""

from __future__ import annotations

from typing import Any

import numpy as np


def extend_held(owner: Any, stores: dict[str, tuple[np.ndarray, np.ndarray]], name: str, extra: int) -> np.ndarray:
    """``owner``'s array attribute ``name`` with ``extra`` more rows (their values unset), set on ``owner``.

    ``stores`` maps each name to (its store, the view last handed out); a view replaced on ``owner`` by other
    code (not the one handed out) starts a new store from its values."""
    view = getattr(owner, name)
    n = len(view)
    held = stores.get(name)
    if held is not None and held[1] is view and n + extra <= len(held[0]):
        store = held[0]
    else:
        store = np.empty((max(n + extra, n + n // 4, 16), *view.shape[1:]), view.dtype)
        store[:n] = view
    out = store[: n + extra]
    stores[name] = (store, out)
    setattr(owner, name, out)
    return out
