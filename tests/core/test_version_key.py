"""``version_key``: memo keys made from components follow their changes and never outlive them.

A memo keyed by ``(id(component), version)`` outlived the components it was
made from; a new component made at a dead one's address at the same version
(new components start at version 0) found the dead one's entry, and a glTF
export gave one colour group another group's material, at random (CI saw it
once in about a hundred runs).
"""

from __future__ import annotations

import gc
import weakref

import omnirender as om
from omnirender.core import version_key


def test_the_key_follows_the_components_changes():
    color = om.Color(0.2, 0.4, 0.6)
    before = version_key(color)
    assert version_key(color) == before and hash(version_key(color)) == hash(before)
    color.r = 0.3
    assert version_key(color) != before
    assert version_key(None) is None


def test_equal_components_have_different_keys():
    a, b = om.Color(0.2, 0.4, 0.6), om.Color(0.2, 0.4, 0.6)
    assert a.version == b.version
    assert version_key(a) != version_key(b)


def test_a_memo_keeps_the_components_of_its_keys_alive():
    memo = {version_key(om.Material(diffuse=(1, 0, 0))): "red"}
    ((material, _),) = memo
    alive = weakref.ref(material)
    del material
    gc.collect()
    assert alive() is not None  # so no new component can be made at its address while the entry exists
    memo.clear()
    gc.collect()
    assert alive() is None
