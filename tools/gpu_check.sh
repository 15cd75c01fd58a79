#!/usr/bin/env bash
# The GL and compositing tests, then the GL benchmarks (bench/gpu.sh), on a machine with a GPU (NVIDIA, EGL):
# the next run on real hardware is one command, done in under 8 minutes.
#
#   bash tools/gpu_check.sh          # from anywhere; PYTHON=/path/to/python3 to choose the interpreter
#
# Needs no network and installs nothing: the repository is used in place (PYTHONPATH).  Python 3.10+ with
# numpy, moderngl, glcontext and pillow (pytest for the tests; pytest-xdist runs them in parallel) must be
# importable; what is missing is listed with the command that installs it from carried wheels, and the parts
# that can run still do.  With $OUT set, everything printed plus the test report (JUnit XML), the images of
# the reference tests (tests/gl/actual) and the GL driver's description are written there.
# Exit status: 0 when everything ran and passed, 1 when tests or benchmarks failed, 2/3 when Python or an
# EGL context is missing.
set -u
cd "$(dirname "$0")/.."
ROOT="$PWD"
PY="${PYTHON:-python3}"
export PYTHONPATH="$ROOT${PYTHONPATH:+:$PYTHONPATH}"
TEST_SECONDS="${GPU_TEST_SECONDS:-240}"     # the tests' share of the 8 minutes (bench/gpu.sh takes under 5)
BENCH_SECONDS="${GPU_BENCH_SECONDS:-210}"

if [ -n "${OUT:-}" ]; then
    mkdir -p "$OUT"
    exec > >(tee "$OUT/gpu_check.log") 2>&1
fi

if ! command -v "$PY" >/dev/null 2>&1; then
    echo "gpu_check: no $PY; set PYTHON=/path/to/python3 (3.10 or newer)"
    exit 2
fi

echo "=== machine"
date -u
command -v nvidia-smi >/dev/null 2>&1 && nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader
"$PY" --version

missing=$("$PY" - <<'EOF'
import importlib.util
need = ["numpy", "moderngl", "glcontext", "PIL", "pytest", "xdist"]
print(" ".join(n for n in need if importlib.util.find_spec(n) is None))
EOF
)
for name in numpy moderngl glcontext PIL; do
    case " $missing " in *" $name "*)
        echo "gpu_check: missing Python packages: $missing"
        echo "  nothing can run without numpy, moderngl, glcontext and pillow; install them from carried wheels:"
        echo "  $PY -m pip install --no-index --find-links WHEELS_DIR numpy moderngl glcontext pillow pytest pytest-xdist"
        exit 2
    esac
done
[ -n "$missing" ] && echo "gpu_check: missing (optional) Python packages: $missing"

echo
echo "=== OpenGL context (EGL)"
if ! "$PY" - <<'EOF'
import moderngl
ctx = moderngl.create_standalone_context(backend="egl")
info = ctx.info
for key in ("GL_VENDOR", "GL_RENDERER", "GL_VERSION", "GL_MAX_TEXTURE_SIZE", "GL_MAX_3D_TEXTURE_SIZE",
            "GL_MAX_SAMPLES", "GL_ALIASED_LINE_WIDTH_RANGE", "GL_POINT_SIZE_RANGE"):
    print(f"{key}: {info.get(key, ctx.max_samples if key == 'GL_MAX_SAMPLES' else '?')}")
EOF
then
    echo "gpu_check: no EGL context: is libEGL.so.1 of the GPU's driver installed (NVIDIA: libnvidia-egl)?"
    exit 3
fi
[ -n "${OUT:-}" ] && "$PY" -c "import moderngl, json; c = moderngl.create_standalone_context(backend='egl'); print(json.dumps({k: str(v) for k, v in c.info.items()}, indent=1))" > "$OUT/gl_info.json" 2>/dev/null

failed=0
echo
echo "=== tests: tests/gl tests/compositing (at most ${TEST_SECONDS} s)"
case " $missing " in
*" pytest "*)
    echo "gpu_check: pytest is missing: the tests are skipped ($PY -m pip install --no-index --find-links WHEELS_DIR pytest pytest-xdist)"
    failed=$((failed + 1))
    ;;
*)
    parallel=()
    case " $missing " in *" xdist "*) ;; *)
        cores=$(nproc 2>/dev/null || echo 2)
        parallel=(-n "$(( cores > 8 ? 8 : cores ))")
    esac
    report=()
    [ -n "${OUT:-}" ] && report=(--junitxml "$OUT/tests.xml")
    # -p no:cacheprovider: the working tree may be read-only; -rfEs lists failures, errors and skip reasons
    # SIGINT: pytest stops, still printing its summary and writing the report
    timeout -s INT -k 30 "$TEST_SECONDS" "$PY" -m pytest tests/gl tests/compositing -q -rfEs -p no:cacheprovider \
        "${parallel[@]}" "${report[@]}" --durations=10
    status=$?
    { [ "$status" -eq 124 ] || [ "$status" -eq 137 ]; } && echo "gpu_check: the tests ran past ${TEST_SECONDS} s and were stopped"
    [ "$status" -ne 0 ] && failed=$((failed + 1))
    if [ -n "${OUT:-}" ] && [ -d tests/gl/actual ]; then
        cp -r tests/gl/actual "$OUT/actual" 2>/dev/null
    fi
    ;;
esac

echo
echo "=== benchmarks: bench/gpu.sh (at most ${BENCH_SECONDS} s)"
if [ -f bench/gpu.sh ]; then
    timeout "$BENCH_SECONDS" bash bench/gpu.sh
    status=$?
    { [ "$status" -eq 124 ] || [ "$status" -eq 137 ]; } && echo "gpu_check: the benchmarks ran past ${BENCH_SECONDS} s and were stopped"
    [ "$status" -ne 0 ] && failed=$((failed + 1))
else
    echo "gpu_check: bench/gpu.sh is not in this tree; no benchmarks"
fi

echo
date -u
if [ "$failed" -eq 0 ]; then
    echo "gpu_check: done, everything passed"
    exit 0
fi
echo "gpu_check: done, $failed part(s) failed (see above)"
exit 1
