"""The 24 axis-aligned viewing rotations (``om.AxisAlignedRotation``).

Each member names where two world axes appear on the screen: the first part
is the world axis that points to the screen's right (+x of the eye frame), the
second the world axis that points up (+y of the eye frame).  An ``N`` prefix
negates the axis.  The eye looks along the remaining axis, so ``X_Z`` is the
classic front view of a z-up world (right = +x, up = +z, the eye at -y looking
towards +y), ``X_Y`` looks down -z at the xy plane, ``NX_Z`` is the back view of a
z-up world.  6 choices for the right axis times 4 perpendicular up axes give all
24 proper rotations of the cube.
"""

from __future__ import annotations

import enum
import itertools

import numpy as np

__all__ = ["AxisAlignedRotation"]

_AXES = {
    "X": (1.0, 0.0, 0.0),
    "NX": (-1.0, 0.0, 0.0),
    "Y": (0.0, 1.0, 0.0),
    "NY": (0.0, -1.0, 0.0),
    "Z": (0.0, 0.0, 1.0),
    "NZ": (0.0, 0.0, -1.0),
}


def _members() -> dict[str, tuple[str, str]]:
    out = {}
    for right, up in itertools.product(_AXES, _AXES):
        if abs(float(np.dot(_AXES[right], _AXES[up]))) < 0.5:
            out[f"{right}_{up}"] = (right, up)
    return out


class AxisAlignedRotation(enum.Enum):
    """Eye-to-world rotation whose screen right and up are world axes (see module docs)."""

    X_Y = ("X", "Y")
    X_NY = ("X", "NY")
    X_Z = ("X", "Z")
    X_NZ = ("X", "NZ")
    NX_Y = ("NX", "Y")
    NX_NY = ("NX", "NY")
    NX_Z = ("NX", "Z")
    NX_NZ = ("NX", "NZ")
    Y_X = ("Y", "X")
    Y_NX = ("Y", "NX")
    Y_Z = ("Y", "Z")
    Y_NZ = ("Y", "NZ")
    NY_X = ("NY", "X")
    NY_NX = ("NY", "NX")
    NY_Z = ("NY", "Z")
    NY_NZ = ("NY", "NZ")
    Z_X = ("Z", "X")
    Z_NX = ("Z", "NX")
    Z_Y = ("Z", "Y")
    Z_NY = ("Z", "NY")
    NZ_X = ("NZ", "X")
    NZ_NX = ("NZ", "NX")
    NZ_Y = ("NZ", "Y")
    NZ_NY = ("NZ", "NY")

    @property
    def right(self) -> np.ndarray:
        """The world direction that appears pointing right on screen."""
        return np.array(_AXES[self.value[0]])

    @property
    def up(self) -> np.ndarray:
        """The world direction that appears pointing up on screen."""
        return np.array(_AXES[self.value[1]])

    @property
    def backward(self) -> np.ndarray:
        """The world direction from the centre towards the eye (the eye's +z)."""
        return np.cross(self.right, self.up)

    def matrix(self) -> np.ndarray:
        """The 3x3 eye-to-world rotation: columns are the eye's x, y and z axes in world coordinates."""
        return np.column_stack([self.right, self.up, self.backward])

    @classmethod
    def from_name(cls, name: str) -> AxisAlignedRotation:
        """Look a member up by name, case-insensitively (``"x_z"`` -> ``X_Z``)."""
        try:
            return cls[name.upper()]
        except KeyError:
            raise ValueError(
                f"unknown axis-aligned rotation {name!r}; names are RIGHT_UP with axes X, NX, Y, NY, Z, NZ "
                f"(e.g. X_Z), one of {[m.name for m in cls]}"
            ) from None


assert set(_members()) == set(AxisAlignedRotation.__members__), "AxisAlignedRotation must list all 24 rotations"
