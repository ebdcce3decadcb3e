"""The memory write limit the sampling benchmarks compare with: the fastest of four ways to write bytes.

The samplers write with all of numba's threads, so the limit does too.  Four fills of the same bytes
are timed side by side, and the fastest of them (smallest median) is the limit:

* ``numpy fill``                  -- ``ndarray.fill``, one thread (the reference of the earlier tables);
* ``numba prange``                -- a ``prange`` loop of plain stores on numba's threads (LLVM
                                     vectorises it: 64-byte stores on AVX-512);
* ``numba prange, non-temporal``  -- the same with 64-byte non-temporal stores (``!nontemporal``
                                     metadata: the lines go to memory without being read first),
                                     which no sampler uses;
* ``numba, threads``              -- a serial numba loop (``nogil``) on Python threads, one stretch
                                     each, as symsphere runs its kernels (symsphere._threads).

Each for output written into a touched buffer (``out=``) and for fresh output (allocated as the
samplers allocate theirs, :func:`symsphere._blocks.empty_rows`: on a line, from 4 MiB on a 2 MiB page,
then the fill, so that the page faults are counted as for a sampler that allocates; where that
function does not exist, in an older revision, ``np.empty``: the limit is the faster of the two workers').  The code is the
benchmark's own, not symsphere's: both revisions of ``regress.py`` compile the same fills.

numba's OpenMP threads must wait passively (``OMP_WAIT_POLICY=passive``, as symsphere starts them),
else after each ``prange`` they spin on the cores that the samplers' threads need; the callers set it
before the first fill starts the threads.
"""

from __future__ import annotations

import numpy as np
from llvmlite import ir
from numba import njit, prange, types
from numba.extending import intrinsic

__all__ = ["FILLS", "fills"]

LINE = 64  # bytes per store: a cache line, an AVX-512 register


@intrinsic
def _store_line(typingctx, flat, i, value):
    """``flat[i : i + 64 // itemsize] = value`` as one aligned 64-byte non-temporal store."""
    dtype = flat.dtype

    def codegen(context, builder, signature, args):
        array = context.make_array(signature.args[0])(context, builder, args[0])
        element = context.get_value_type(dtype)
        vector_type = ir.VectorType(element, LINE // context.get_abi_sizeof(element))
        value = context.cast(builder, args[2], signature.args[2], dtype)
        vector = ir.Constant(vector_type, ir.Undefined)
        for k in range(vector_type.count):
            vector = builder.insert_element(vector, value, ir.Constant(ir.IntType(32), k))
        pointer = builder.gep(array.data, [context.cast(builder, args[1], signature.args[1], types.intp)])
        store = builder.store(vector, builder.bitcast(pointer, vector_type.as_pointer()), align=LINE)
        store.set_metadata("nontemporal", builder.module.add_metadata([ir.Constant(ir.IntType(32), 1)]))
        return context.get_dummy_value()

    return types.none(flat, i, value), codegen


@njit(parallel=True, cache=True)
def _prange_fill(flat, value):  # pragma: no cover - compiled by numba
    for i in prange(flat.shape[0]):
        flat[i] = value


@njit(parallel=True, cache=True)
def _prange_fill_nontemporal(flat, value, parts):  # pragma: no cover - compiled by numba
    n = flat.shape[0]
    width = LINE // flat.itemsize
    head = 0  # the elements before the first 64-byte boundary
    while head < n and (flat.ctypes.data + head * flat.itemsize) % LINE != 0:
        flat[head] = value
        head += 1
    lines = (n - head) // width
    for part in prange(parts):
        for line in range(lines * part // parts, lines * (part + 1) // parts):
            _store_line(flat, head + line * width, value)
    for i in range(head + lines * width, n):
        flat[i] = value


@njit(nogil=True, cache=True)
def _serial_fill(flat, lo, hi, value):  # pragma: no cover - compiled by numba
    for i in range(lo, hi):
        flat[i] = value


_pool = []


def _threads(flat, value):
    from concurrent.futures import ThreadPoolExecutor

    import numba

    parts = numba.get_num_threads()
    if parts > 1 and not _pool:
        _pool.append(ThreadPoolExecutor(parts - 1))
    bounds = [len(flat) * k // parts for k in range(parts + 1)]
    futures = [_pool[0].submit(_serial_fill, flat, bounds[k], bounds[k + 1], value) for k in range(1, parts)]
    _serial_fill(flat, bounds[0], bounds[1], value)
    for future in futures:
        future.result()


def _numpy(flat, value):
    flat.fill(value)


def _prange(flat, value):
    _prange_fill(flat, value)


def _nontemporal(flat, value):
    import numba

    _prange_fill_nontemporal(flat, value, numba.get_num_threads())


FILLS = {
    "numpy fill": _numpy,
    "numba prange": _prange,
    "numba prange, non-temporal": _nontemporal,
    "numba, threads": _threads,
}
"""The ways to write, by name: ``fill(flat, value)`` for a 1-d C-contiguous array."""


def fills(n, dtype, value=0.5):
    """``{(way, kind): callable}`` for kind ``'out='`` (into a touched (n, 3) buffer) and ``'fresh'``.

    Each way writes its own buffer: the host's cache can hold the buffer written before, and a buffer
    last written with non-temporal stores is in memory, not in the cache, which would slow the next way.
    """
    try:
        from symsphere._blocks import empty_rows

        def fresh():
            return empty_rows(n, np.dtype(dtype)).reshape(-1)
    except ImportError:  # a revision before it: numpy's own allocation

        def fresh():
            return np.empty(n * 3, dtype=dtype)

    rows = {}
    for way, fill in FILLS.items():
        touched = np.full(n * 3, value, dtype=dtype)
        rows[way, "out="] = lambda f=fill, t=touched: f(t, value)
        rows[way, "fresh"] = lambda f=fill: f(fresh(), value)
    return rows
