"""The kernels' orbit stores as vector code: each orbit built in registers and stored in 64-byte vectors.

numba compiles a row written value by value into as many scalar stores (72 or 144 per orbit), and
the float32 kernels were bounded by them: each store holds a store-buffer entry until its cache line
arrives, a vector store one for up to 16 values.  These stores are numba intrinsics (LLVM IR built
here, inlined where called, no call or reference count per orbit) that write the same values as the
tables give, bit for bit: :func:`orbit_mask` reads the tables of :mod:`symsphere.symmetry`, and the
rotated store sums ``(x w0 + y w1) + z w2`` without fused multiply-adds, as the kernels always have
(tests/test_public_outputs.py pins the rows).
tests/test_kernels.py compares every image with the tables and with the numpy path.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, cast

from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

from .symmetry import SIGNS, SOURCES, orbit_size

_item_pointer = cast(Callable[..., Any], cgutils.get_item_pointer)  # numba: untyped

__all__ = ["orbit_mask", "store_hemisphere_orbit", "store_rotated_hemisphere", "store_sphere_orbit"]


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
