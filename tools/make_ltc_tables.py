"""Write omnirender/assets/ltc.npz: the LTC fit tables of Heitz et al. 2016 for GGX, as three.js ships them.

The GL engine's rectangle and disc lights shade by linearly transformed cosines
("Real-Time Polygonal-Light Shading with Linearly Transformed Cosines", Eric
Heitz, Jonathan Dupuy, Stephen Hill and David Neubelt, 2016).  The specular
lobe needs the fitted tables: ``ltc_1`` (64 x 64 x 4, the inverse LTC matrix's
four non-trivial entries) and ``ltc_2`` (64 x 64 x 4: the GGX norm, Hill's
Fresnel term, 0, the horizon-clipped sphere term), indexed by
``(sqrt(GGX alpha), sqrt(1 - cos(theta_view)))``.  They are data, taken
unchanged from three.js (MIT licence, ``examples/jsm/lights/RectAreaLightTexturesLib.js``,
whose source is https://github.com/selfshadow/ltc_code/tree/master/fit/results/ltc.js).

Run after ``npm install --prefix tools/web-viewer`` (three.js is the web viewer's dependency)::

    python tools/make_ltc_tables.py [path/to/RectAreaLightTexturesLib.js]
"""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
DEFAULT = ROOT / "tools/web-viewer/node_modules/three/examples/jsm/lights/RectAreaLightTexturesLib.js"


def read_table(text: str, name: str) -> np.ndarray:
    match = re.search(rf"const {name} = (\[[^\]]*\])", text)
    if match is None:
        raise SystemExit(f"{name} not found: is this three.js's RectAreaLightTexturesLib.js?")
    values = json.loads(re.sub(r"-\s+", "-", match.group(1)))
    table = np.asarray(values, dtype=np.float32)
    if table.size != 64 * 64 * 4:
        raise SystemExit(f"{name}: expected 64 x 64 x 4 values, got {table.size}")
    return table.reshape(64, 64, 4)


def main() -> None:
    source = Path(sys.argv[1]) if len(sys.argv) > 1 else DEFAULT
    text = source.read_text()
    version = "unknown"
    package = source.parents[3] / "package.json"
    if package.exists():
        version = json.loads(package.read_text())["version"]
    out = ROOT / "omnirender/assets/ltc.npz"
    np.savez_compressed(
        out,
        ltc_1=read_table(text, "LTC_MAT_1"),
        ltc_2=read_table(text, "LTC_MAT_2"),
        source=np.array(f"three.js {version} RectAreaLightTexturesLib.js (MIT); fit by Heitz et al. 2016"),
    )
    print(f"wrote {out} from {source} (three.js {version})")


if __name__ == "__main__":
    main()
