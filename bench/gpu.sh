#!/usr/bin/env bash
# The GL benchmarks on a machine with a GPU (NVIDIA, EGL), in one go, in under five minutes.
#
#   bash bench/gpu.sh            # from the repository root; PYTHON=/path/to/python to choose the interpreter
#
# Needs no network: python3 (>= 3.10) with numpy, moderngl and pillow importable (carry wheels and
# `pip install --no-index --find-links WHEELS numpy moderngl glcontext pillow` if they are missing), and
# an EGL driver (libEGL.so.1 from the NVIDIA driver).  The repository itself is used in place
# (PYTHONPATH), nothing is installed.  Each script prints ratios against a baseline measured in the same
# run; bench/frame_cost.py runs twice: on the GPU, and with --cpu under Mesa's no-op driver when Mesa is
# installed (the CPU side alone, for comparison with the GPU's frame).
set -u
cd "$(dirname "$0")/.."
PY="${PYTHON:-python3}"
export PYTHONPATH="$PWD${PYTHONPATH:+:$PYTHONPATH}"

if ! command -v "$PY" >/dev/null 2>&1; then
    echo "gpu.sh: no $PY; set PYTHON=/path/to/python3 (3.10 or newer)" >&2
    exit 2
fi
missing=$("$PY" - <<'EOF'
import importlib.util
need = ["numpy", "moderngl", "glcontext", "PIL"]
print(" ".join(n for n in need if importlib.util.find_spec(n) is None))
EOF
)
if [ -n "$missing" ]; then
    echo "gpu.sh: missing Python packages: $missing" >&2
    echo "  install them without network from carried wheels:" >&2
    echo "  $PY -m pip install --no-index --find-links WHEELS_DIR numpy moderngl glcontext pillow" >&2
    exit 2
fi

echo "=== machine"
date -u
command -v nvidia-smi >/dev/null 2>&1 && nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader
"$PY" -c "import omnirender, sys; from omnirender.gl.engine.context import gl_renderer; print(sys.version.split()[0], omnirender.__file__); print('GL renderer:', gl_renderer())" || {
    echo "gpu.sh: no EGL context: is libEGL.so.1 (the NVIDIA driver's EGL) installed?" >&2
    exit 3
}

failed=0
run() {
    echo
    echo "=== $*"
    timeout 150 "$PY" "$@" || { echo "gpu.sh: '$*' failed or ran past 150 s (exit $?)"; failed=$((failed + 1)); }
}
run bench/frame_cost.py --quick --timer wall
run bench/dynamic.py --quick
run bench/gl_objects.py --quick
run bench/shadows.py --frames 6
run bench/deferred.py --frames 3
run bench/postfx.py --frames 3
run bench/splats.py --timer wall --size 1920 1080 --frames 5
run bench/instance_order.py --quick
run bench/shadow_probe.py --frames 10
if "$PY" -c "import sys; sys.exit(0)" && ls /usr/lib/*/dri/swrast_dri.so /usr/lib/*/libgallium* >/dev/null 2>&1; then
    run bench/frame_cost.py --cpu --quick --timer wall
else
    echo; echo "=== bench/frame_cost.py --cpu skipped: Mesa (the no-op driver) is not installed"
fi
echo
echo "gpu.sh: done, $failed failed"
exit $((failed > 0))
