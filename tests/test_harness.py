"""The test tree itself: no folder may hide a package the tests import or check for."""

from __future__ import annotations

import importlib.util
from pathlib import Path

TESTS = Path(__file__).resolve().parent
#: Import names of the dependencies that tests or engine checks import.
DEPENDENCIES = {
    "mitsuba", "drjit", "moderngl", "glfw", "PIL", "trimesh", "pyradiance", "yaml", "numpy", "scipy", "skimage",
    "imageio", "dask", "distributed", "pygltflib", "jupyter_rfb", "nbconvert", "jsonschema", "embreex", "tqdm",
    "omnirender",
}  # fmt: skip


def test_no_test_folder_is_named_like_a_package():
    """tests/ goes on sys.path (rootdir-relative imports): a folder ``tests/mitsuba`` without ``__init__.py``
    imports as a namespace package ``mitsuba``, so a machine without Mitsuba ran its tests instead of skipping
    them.  Engine tests live in ``tests/<engine>_engine`` or in folders whose name no package uses."""
    shadowing = []
    for folder in TESTS.iterdir():
        if folder.is_dir() and folder.name in DEPENDENCIES and not (folder / "__init__.py").exists():
            shadowing.append(folder.name)
        elif folder.is_dir() and not (folder / "__init__.py").exists():
            spec = importlib.util.find_spec(folder.name)
            if spec is not None and spec.origin not in (None, "namespace") and TESTS not in Path(spec.origin).parents:
                shadowing.append(folder.name)
    assert not shadowing, f"rename these test folders, they shadow packages: {shadowing}"
