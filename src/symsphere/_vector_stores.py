"""The kernels' orbit stores as vector code: each orbit built in registers and stored in 64-byte vectors.

numba compiles a row written value by value into as many scalar stores (72 or 144 per orbit), and
the float32 kernels were bounded by them: each store holds a store-buffer entry until its cache line
arrives, a vector store one for up to 16 values.  These stores are numba intrinsics (LLVM IR built
here, inlined where called, no call or reference count per orbit) that write the same values as the
tables give, bit for bit: :func:`orbit_mask` reads the tables of :mod:`symsphere.symmetry`, and the
rotated store sums ``(x w0 + y w1) + z w2`` without fused multiply-adds, as the kernels always have
(tests/test_public_outputs.py pins the rows).
tests/test_kernels.py compares every image with the tables and with the numpy path.

:func:`stream_rows` copies stored orbits out of a stage with non-temporal stores (whole 64-byte lines
only, the partial ones plain, as a memset does), for outputs the kernels write that way.
:func:`aligned_empty` gives the arrays these stores and loads want to start a line (the stage, the
rotation's weights, fresh outputs).
"""

from __future__ import annotations

import platform
from collections.abc import Callable
from typing import Any, cast

import numpy as np
from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic, register_jitable

from .symmetry import SIGNS, SOURCES, orbit_size

_item_pointer = cast(Callable[..., Any], cgutils.get_item_pointer)  # numba: untyped
_function = cast(Callable[..., Any], cgutils.get_or_insert_function)  # numba: untyped

__all__ = [
    "LINE",
    "aligned_empty",
    "orbit_mask",
    "store_fence",
    "store_hemisphere_orbit",
    "store_rotated_hemisphere",
    "store_sphere_orbit",
    "stream_rows",
]


def _int32(value: int | list[int]) -> Any:
    """An LLVM i32 constant, or a constant vector of them (a shuffle's mask)."""
    if isinstance(value, int):
        return ir.Constant(ir.IntType(32), value)
    return ir.Constant(ir.VectorType(ir.IntType(32), len(value)), value)


def _intp(context: Any, value: int) -> Any:
    return context.get_constant(types.intp, value)


def _row_pointer(context: Any, builder: Any, array_type: Any, array: Any, index: Any, index_type: Any) -> Any:
    """A pointer to ``array[index, 0]`` of a C-contiguous 2-d array (*index* an LLVM value or an int)."""
    if isinstance(index, int):
        index = _intp(context, index)
    else:
        index = context.cast(builder, index, index_type, types.intp)
    view = context.make_array(array_type)(context, builder, array)
    return _item_pointer(context, builder, array_type, view, [index, _intp(context, 0)])


def _coordinates(context: Any, builder: Any, signature: Any, args: Any, dtype: Any) -> list[Any]:
    """The store's first three arguments (x, y, z), each converted to *dtype*."""
    return [context.cast(builder, args[k], signature.args[k], dtype) for k in range(3)]


def _store_at(context: Any, builder: Any, row: Any, at: int, vector: Any) -> None:
    """Store *vector* at ``row + at`` (elements; unaligned beyond the element's own alignment)."""
    pointer = builder.bitcast(builder.gep(row, [_intp(context, at)]), vector.type.as_pointer())
    builder.store(vector, pointer, align=context.get_abi_sizeof(vector.type.element))


def orbit_mask(count: int) -> list[int]:
    """Value 3k + l of an orbit (image k, coordinate l) as an index into (x, y, z, -x, -y, -z): the
    tables' SOURCES[k, l], and + 3 where SIGNS[k, l] is negative."""
    return [int(SOURCES[k, l]) + (3 if SIGNS[k, l] < 0 else 0) for k in range(count) for l in range(3)]


def _orbit_store(count: int) -> Any:
    """``store(x, y, z, rows, i)``: rows[i, 3k:3k+3] = (x, y, z) @ SPHERE_MAPS[k] for k < *count* (48 or 24).

    Every value of an orbit is one of x, y, z, -x, -y, -z (in the output's dtype: rounding commutes with
    the sign), so the orbit is one vector shuffle of those six by a constant mask from the tables
    (:func:`orbit_mask`) and one store of the whole row.  Written out as scalar stores, the 3 count
    stores per orbit bounded the float32 kernels: each takes a store-buffer entry until its cache line
    arrives, where a vector store takes one for up to 16 values.  tests/test_kernels.py compares every
    image with the tables.
    """
    mask = orbit_mask(count)

    @intrinsic
    def store(typingctx: Any, x: Any, y: Any, z: Any, rows: Any, i: Any) -> Any:
        if not (isinstance(rows, types.Array) and rows.ndim == 2 and rows.layout == "C"):
            return None

        def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
            rows_type = signature.args[3]
            element = context.get_value_type(rows_type.dtype)
            width = 64 // context.get_abi_sizeof(element)  # values per 64-byte vector (one AVX-512 register)
            values = _coordinates(context, builder, signature, args, rows_type.dtype)
            six = ir.Constant(ir.VectorType(element, width), ir.Undefined)
            for place, value in enumerate(values + [builder.fneg(v) for v in values]):
                six = builder.insert_element(six, value, _int32(place))
            row = _row_pointer(context, builder, rows_type, args[3], args[4], signature.args[4])
            for at in range(0, len(mask), width):  # one single-source permutation and one store per vector
                _store_at(context, builder, row, at, builder.shuffle_vector(six, six, _int32(mask[at : at + width])))
            return context.get_dummy_value()

        return types.void(x, y, z, rows, i), codegen

    return store


store_sphere_orbit = _orbit_store(orbit_size("sphere"))
store_hemisphere_orbit = _orbit_store(orbit_size("hemisphere"))


def _rotated_store(count: int) -> Any:
    """``store(x, y, z, rows, i, weights)``: rows[i] = x W[0] + y W[1] + z W[2] (float64, rounded once to
    the output's dtype), W the (3, 3 count) weights of ``_kernels._rotated_weights``: image k in columns
    3k ... 3k + 2.

    In vectors of 8 columns (one AVX-512 register of float64), each value summed as ``(x w0 + y w1) + z w2``
    without fused multiply-adds (the order tests/test_public_outputs.py pins), and each vector stored at
    once: numba's loop over the columns vectorises to half this width, and is a call per orbit unless
    LLVM inlines it.
    """
    columns = 3 * count

    @intrinsic
    def store(typingctx: Any, x: Any, y: Any, z: Any, rows: Any, i: Any, weights: Any) -> Any:
        if not all(isinstance(a, types.Array) and a.ndim == 2 and a.layout == "C" for a in (rows, weights)):
            return None

        def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
            rows_type, weights_type = signature.args[3], signature.args[5]
            element = context.get_value_type(rows_type.dtype)
            row = _row_pointer(context, builder, rows_type, args[3], args[4], signature.args[4])
            weight_rows = [_row_pointer(context, builder, weights_type, args[5], r, types.intp) for r in range(3)]
            coordinates = _coordinates(context, builder, signature, args, types.float64)
            for at in range(0, columns, 8):
                vector = ir.VectorType(ir.DoubleType(), min(8, columns - at))
                terms = []
                for coordinate, weights_row in zip(coordinates, weight_rows, strict=True):
                    spread = builder.insert_element(ir.Constant(vector, ir.Undefined), coordinate, _int32(0))
                    spread = builder.shuffle_vector(spread, spread, _int32([0] * vector.count))
                    pointer = builder.bitcast(builder.gep(weights_row, [_intp(context, at)]), vector.as_pointer())
                    terms.append(builder.fmul(spread, builder.load(pointer, align=8)))
                total = builder.fadd(builder.fadd(terms[0], terms[1]), terms[2])
                if element != ir.DoubleType():
                    total = builder.fptrunc(total, ir.VectorType(element, vector.count))
                _store_at(context, builder, row, at, total)
            return context.get_dummy_value()

        return types.void(x, y, z, rows, i, weights), codegen

    return store


store_rotated_hemisphere = _rotated_store(orbit_size("hemisphere"))


LINE = 64  # bytes: a cache line, and a non-temporal store's size and alignment


@register_jitable
def aligned_empty(size: int, dtype: Any, align: int) -> Any:
    """An empty 1-d array of *size* elements of *dtype* whose first element starts on *align* bytes (a
    multiple of the itemsize): a view of an allocation *align* bytes larger (numpy's and numba's arrays
    start on 16 or 32 bytes).  Python and numba alike."""
    pad = align // np.empty(1, dtype=dtype).itemsize  # (numba has no np.dtype(dtype).itemsize)
    raw = np.empty(size + pad, dtype=dtype)
    start = (-raw.ctypes.data % align) // raw.itemsize
    return raw[start : start + size]


def _stream_rows(typingctx: Any, stage: Any, start: Any, rows: Any, first: Any, count: Any) -> Any:
    """``rows[first : first + count] = stage[start : start + count]``, the whole 64-byte lines of the destination with
    non-temporal stores and its partial first and last lines with plain ones (as a memset does).

    A plain store reads its line from memory before writing it; a non-temporal one writes whole
    lines to memory without reading them (and without keeping them in the cache), but only at 64-byte
    boundaries, where numpy's large arrays start 16 bytes into a line: so the kernels store a batch of
    orbits into *stage* (in L1) and copy it out here.  The values are copied, not changed.  Call
    :func:`store_fence` after the last copy.  An output not aligned to its element size is copied with
    plain stores only.
    """
    arrays = (stage, rows)
    if not all(isinstance(a, types.Array) and a.ndim == 2 and a.layout == "C" for a in arrays):
        return None
    if stage.dtype != rows.dtype:
        return None

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        stage_type, rows_type = signature.args[0], signature.args[2]
        element = context.get_value_type(rows_type.dtype)
        size = context.get_abi_sizeof(element)
        width = LINE // size
        intp = context.get_value_type(types.intp)
        source = _row_pointer(context, builder, stage_type, args[0], args[1], signature.args[1])
        target = _row_pointer(context, builder, rows_type, args[2], args[3], signature.args[3])
        columns = builder.extract_value(context.make_array(rows_type)(context, builder, args[2]).shape, 1)
        rows_count = context.cast(builder, args[4], signature.args[4], types.intp)
        total = builder.mul(builder.select(builder.icmp_signed(">", rows_count, ir.Constant(intp, 0)), rows_count,
                                           ir.Constant(intp, 0)), columns)  # fmt: skip
        address = builder.ptrtoint(target, intp)
        head = builder.lshr(builder.and_(builder.neg(address), ir.Constant(intp, LINE - 1)),
                            ir.Constant(intp, size.bit_length() - 1))  # fmt: skip
        misaligned = builder.icmp_unsigned(
            "!=", builder.and_(address, ir.Constant(intp, size - 1)), ir.Constant(intp, 0)
        )
        head = builder.select(builder.or_(misaligned, builder.icmp_unsigned(">", head, total)), total, head)
        lines = builder.udiv(builder.sub(total, head), ir.Constant(intp, width))
        body_end = builder.add(head, builder.mul(lines, ir.Constant(intp, width)))
        vector = ir.VectorType(element, width)
        nontemporal = builder.module.add_metadata([ir.Constant(ir.IntType(32), 1)])

        def copy_one(at: Any) -> None:
            value = builder.load(builder.gep(source, [at]), align=size)
            builder.store(value, builder.gep(target, [at]), align=size)

        with cgutils.for_range(builder, head) as loop:
            copy_one(loop.index)
        with cgutils.for_range(builder, lines) as loop:
            at = builder.add(head, builder.mul(loop.index, ir.Constant(intp, width)))
            value = builder.load(builder.bitcast(builder.gep(source, [at]), vector.as_pointer()), align=size)
            store = builder.store(value, builder.bitcast(builder.gep(target, [at]), vector.as_pointer()), align=LINE)
            store.set_metadata("nontemporal", nontemporal)
        with cgutils.for_range(builder, builder.sub(total, body_end)) as loop:
            copy_one(builder.add(body_end, loop.index))
        return context.get_dummy_value()

    return types.void(stage, start, rows, first, count), codegen


stream_rows: Any = intrinsic(_stream_rows)  # Any: the intrinsic's call signature is not the function's


def _store_fence(typingctx: Any) -> Any:
    """Order the non-temporal stores before it before every later store and load: the kernel's caller,
    on another thread, then sees the copied rows.  On x86 an ``sfence`` (what the stores' weak order
    asks for: LLVM makes a sequentially consistent fence a locked ``or`` there), then that fence."""

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        if platform.machine().lower() in ("x86_64", "amd64"):
            sfence = _function(builder.module, ir.FunctionType(ir.VoidType(), []), "llvm.x86.sse.sfence")
            builder.call(sfence, [])
        builder.fence("seq_cst")
        return context.get_dummy_value()

    return types.void(), codegen


store_fence: Any = intrinsic(_store_fence)
