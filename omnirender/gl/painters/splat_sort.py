"""Back-to-front order of Gaussian splats: a bitonic sort in compute shaders, a numpy fallback without them.

:class:`GPUSplatSorter` (OpenGL 4.3: compute shaders and shader storage
buffers) writes one 32-bit key per splat -- its view-space z made an
order-preserving unsigned integer, so ascending keys are farthest first -- and
the splat's index, then sorts the (key, index) pairs with a bitonic network:
one dispatch sorts every block of 1024 pairs in shared memory, and for each
larger merge size ``k`` the steps with a stride of 1024 or more run as global
compare-exchange dispatches and the rest as one shared-memory dispatch.  The
CPU only issues ``1 + (L - 9)(L - 8) / 2`` dispatches, L = log2(n) rounded up (16 for 10,000 splats,
67 for a million), so a frame's CPU cost hardly depends on the splat count;
nothing is read back.  The sorted indices are the painter's per-instance
attribute buffer.

:class:`NumpySplatSorter` is the fallback where compute shaders are missing
(an OpenGL 4.1 context, e.g. macOS or ``MESA_GL_VERSION_OVERRIDE=4.1``): the
same order from ``np.argsort`` of the view-space z, written to the same
buffer.  Its CPU cost grows with the splat count (about n log n), which is why
it is the fallback only.

Both re-sort only when the model-view matrix or the splats changed, keeping
the order of the last two views (a stereo frame's two eyes alternate).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..engine.resources import gpu_call

__all__ = ["GPUSplatSorter", "NumpySplatSorter", "SortPrograms", "sorter_for", "compute_available", "BLOCK"]

#: pairs sorted by one workgroup in shared memory (512 invocations, two pairs each)
BLOCK = 1024
_GLOBAL_GROUP = 256

_FETCH = """
uniform sampler2D u_geom;
uniform int u_width;
vec4 fetch(int t) { return texelFetch(u_geom, ivec2(t % u_width, t / u_width), 0); }
"""

_KEYS = (
    """#version 430
layout(local_size_x = 256) in;
layout(std430, binding = 0) buffer Keys { uint keys[]; };
layout(std430, binding = 1) buffer Values { uint values[]; };
uniform vec4 u_zrow;   // row 2 of the model-view matrix: view-space z of a local point
uniform int u_count;
uniform int u_total;
"""
    + _FETCH
    + """
void main() {
    int i = int(gl_GlobalInvocationID.x);
    if (i >= u_total) return;
    uint key = 0xFFFFFFFFu;   // padding sorts last
    if (i < u_count) {
        float z = dot(u_zrow.xyz, fetch(3 * i).xyz) + u_zrow.w;
        uint u = floatBitsToUint(z);
        key = (u & 0x80000000u) != 0u ? ~u : (u | 0x80000000u);   // ascending keys = ascending z = far first
    }
    keys[i] = key;
    values[i] = uint(i);
}
"""
)

_LOCAL = """#version 430
layout(local_size_x = 512) in;
layout(std430, binding = 0) buffer Keys { uint keys[]; };
layout(std430, binding = 1) buffer Values { uint values[]; };
uniform uint u_k;      // 0: sort each block completely; else the merge size whose strides < 1024 remain
shared uint sk[1024];
shared uint sv[1024];
void exchange(uint base, uint t, uint k, uint j) {
    uint i = ((t & ~(j - 1u)) << 1) | (t & (j - 1u));
    uint l = i + j;
    bool ascending = ((base + i) & k) == 0u;
    uint a = sk[i], b = sk[l];
    if ((a > b) == ascending && a != b) {
        sk[i] = b; sk[l] = a;
        uint v = sv[i]; sv[i] = sv[l]; sv[l] = v;
    }
}
void main() {
    uint t = gl_LocalInvocationID.x;
    uint base = gl_WorkGroupID.x * 1024u;
    sk[t] = keys[base + t]; sk[t + 512u] = keys[base + t + 512u];
    sv[t] = values[base + t]; sv[t + 512u] = values[base + t + 512u];
    barrier();
    if (u_k == 0u) {
        for (uint k = 2u; k <= 1024u; k <<= 1) {
            for (uint j = k >> 1; j > 0u; j >>= 1) {
                exchange(base, t, k, j);
                barrier();
            }
        }
    } else {
        for (uint j = 512u; j > 0u; j >>= 1) {
            exchange(base, t, u_k, j);
            barrier();
        }
    }
    keys[base + t] = sk[t]; keys[base + t + 512u] = sk[t + 512u];
    values[base + t] = sv[t]; values[base + t + 512u] = sv[t + 512u];
}
"""

_GLOBAL = """#version 430
layout(local_size_x = 256) in;
layout(std430, binding = 0) buffer Keys { uint keys[]; };
layout(std430, binding = 1) buffer Values { uint values[]; };
uniform uint u_k;
uniform uint u_j;
void main() {
    uint t = gl_GlobalInvocationID.x;
    uint i = ((t & ~(u_j - 1u)) << 1) | (t & (u_j - 1u));
    uint l = i + u_j;
    bool ascending = (i & u_k) == 0u;
    uint a = keys[i], b = keys[l];
    if ((a > b) == ascending && a != b) {
        keys[i] = b; keys[l] = a;
        uint v = values[i]; values[i] = values[l]; values[l] = v;
    }
}
"""


def compute_available(ctx: Any) -> bool:
    """Whether ``ctx`` runs compute shaders with storage buffers (OpenGL 4.3 or later)."""
    return int(getattr(ctx, "version_code", 0)) >= 430


class SortPrograms:
    """The three compute programs of the GPU sort on one context (made once per engine)."""

    def __init__(self, ctx: Any) -> None:
        self.keys = ctx.compute_shader(_KEYS)
        self.local = ctx.compute_shader(_LOCAL)
        self.merge = ctx.compute_shader(_GLOBAL)

    def release(self) -> None:
        for p in (self.keys, self.local, self.merge):
            p.release()


class _Sorter:
    """The order of one splat set's ``count`` splats for the last two model-view matrices."""

    method = ""

    def __init__(self, ctx: Any, count: int, label: str) -> None:
        self.ctx = ctx
        self.count = count
        self.label = label
        #: (model-view bytes, instance buffer) of the last two views, most recent last
        self._orders: list[tuple[bytes, Any]] = []
        #: sorts made (tests and benchmarks read it: a still camera sorts once)
        self.sorts = 0

    def order(self, mv: np.ndarray, geom_texture: Any, width: int) -> Any:
        """The buffer of splat indices back to front for model-view ``mv`` (sorting only for a new view)."""
        key = np.ascontiguousarray(mv, dtype=np.float32).tobytes()
        for i, (seen, buf) in enumerate(self._orders):
            if seen == key:
                if i != len(self._orders) - 1:
                    self._orders.append(self._orders.pop(i))
                return buf
        buf = self._orders.pop(0)[1] if len(self._orders) >= 2 else None
        buf = self._sort(mv, geom_texture, width, buf)
        self._orders.append((key, buf))
        self.sorts += 1
        return buf

    def _sort(self, mv: np.ndarray, geom_texture: Any, width: int, reuse: Any) -> Any:
        raise NotImplementedError

    def release(self) -> None:
        for _, buf in self._orders:
            buf.release()
        self._orders = []


class NumpySplatSorter(_Sorter):
    """``np.argsort`` of the view-space z on the CPU (no compute shaders): the fallback."""

    method = "numpy"

    def __init__(self, ctx: Any, positions: np.ndarray, label: str) -> None:
        super().__init__(ctx, len(positions), label)
        self.positions = np.ascontiguousarray(positions, dtype=np.float32)

    def _sort(self, mv: np.ndarray, geom_texture: Any, width: int, reuse: Any) -> Any:
        z = self.positions @ mv[2, :3].astype(np.float32) + np.float32(mv[2, 3])
        order = np.argsort(z, kind="stable").astype(np.uint32)  # most negative z (farthest) first
        if reuse is None:
            reuse = gpu_call(self.ctx.buffer, reserve=max(len(order), 1) * 4, what=f"splat order of {self.label}")
        reuse.write(order.tobytes())
        return reuse


class GPUSplatSorter(_Sorter):
    """Depth keys and a bitonic sort in compute shaders; the CPU issues a few dozen dispatches."""

    method = "gpu bitonic"

    def __init__(self, ctx: Any, count: int, label: str, programs: SortPrograms) -> None:
        super().__init__(ctx, count, label)
        self.programs = programs
        total = BLOCK
        while total < count:
            total *= 2
        self.total = total
        self.keys = gpu_call(ctx.buffer, reserve=total * 4, what=f"splat sort keys of {label}")
        #: dispatches per sort (for the documentation and the benchmark)
        self.dispatches = 2 + sum(_log2(k) - 10 + 1 for k in _merge_sizes(total))

    def _sort(self, mv: np.ndarray, geom_texture: Any, width: int, reuse: Any) -> Any:
        ctx, p = self.ctx, self.programs
        values = reuse or gpu_call(ctx.buffer, reserve=self.total * 4, what=f"splat order of {self.label}")
        self.keys.bind_to_storage_buffer(0)
        values.bind_to_storage_buffer(1)
        geom_texture.use(0)
        p.keys["u_geom"].value = 0
        p.keys["u_width"].value = int(width)
        p.keys["u_zrow"].value = tuple(float(v) for v in mv[2])
        p.keys["u_count"].value = int(self.count)
        p.keys["u_total"].value = int(self.total)
        p.keys.run(self.total // _GLOBAL_GROUP)
        barrier = ctx.SHADER_STORAGE_BARRIER_BIT
        ctx.memory_barrier(barrier)
        p.local["u_k"].value = 0
        p.local.run(self.total // BLOCK)
        ctx.memory_barrier(barrier)
        for k in _merge_sizes(self.total):
            p.merge["u_k"].value = k
            j = k // 2
            while j >= BLOCK:
                p.merge["u_j"].value = j
                p.merge.run(self.total // 2 // _GLOBAL_GROUP)
                ctx.memory_barrier(barrier)
                j //= 2
            p.local["u_k"].value = k
            p.local.run(self.total // BLOCK)
            ctx.memory_barrier(barrier)
        ctx.memory_barrier(ctx.VERTEX_ATTRIB_ARRAY_BARRIER_BIT)  # the values are read as a vertex attribute next
        return values

    def release(self) -> None:
        super().release()
        self.keys.release()


def _merge_sizes(total: int) -> list[int]:
    sizes = []
    k = 2 * BLOCK
    while k <= total:
        sizes.append(k)
        k *= 2
    return sizes


def _log2(n: int) -> int:
    return int(n).bit_length() - 1


def sorter_for(ctx: Any, positions: np.ndarray, label: str, programs: Any) -> _Sorter:
    """A GPU sorter where compute shaders run (``programs`` a :class:`SortPrograms` maker), else the numpy one."""
    if programs is not None:
        return GPUSplatSorter(ctx, len(positions), label, programs)
    return NumpySplatSorter(ctx, positions, label)
