"""Shaped views of packed buffers: ``flat[start : start + size].reshape(shape)``, cheap to compile and to make.

The compiled solver and prover keep their tables and work arrays in a few flat buffers
(:mod:`.packing`, :func:`.proof_kernel.pack`): numba unboxes each array an entry is handed, so
an entry takes four buffers and makes its views inside, dozens of them. numba's ``reshape``
checks the new shape against the old at run time, through functions of its own that it compiles
and code it writes into every unit at every call site: compile time at each view, and time at each
call. :func:`view` is a builtin of its own: typed and written in place, it makes the same
C-contiguous view directly (its data pointer, shape and strides) after one bounds check, a few
instructions that LLVM folds into the caller.

In Python, :func:`view` is the slice and ``reshape`` it stands for (the layout's own check, at
:class:`.packing.Packed`'s construction, runs the same offsets).
"""

from __future__ import annotations

import math

import numpy as np
from numba import types
from numba.core import cgutils
from numba.core.imputils import impl_ret_borrowed, lower_builtin
from numba.extending import type_callable
from numba.np.arrayobj import make_array, populate_array

__all__ = ["view"]


def view(flat: np.ndarray, start: int, shape: tuple[int, ...]) -> np.ndarray:
    """The C-contiguous view of ``flat[start : start + prod(shape)]`` with ``shape``.

    Args:
        flat: a one-dimensional contiguous buffer.
        start: the view's first element in ``flat``.
        shape: the view's shape, a tuple of one or more ints.

    Raises:
        ValueError: the view would reach outside ``flat`` (``start`` or an extent negative, or
            its end past ``flat``'s).
    """
    if not shape:
        raise ValueError("a view needs one or more extents")
    size = math.prod(shape)
    if start < 0 or min(shape) < 0 or start + size > flat.shape[0]:
        raise ValueError(f"a view of {size} elements from {start} reaches outside a buffer of {flat.shape[0]}")
    return flat[start : start + size].reshape(shape)


def _shape_of(flat, start, shape) -> types.Array | None:
    """The view's type, read-only if the buffer is.

    None (no such call) unless the arguments are a contiguous 1-D buffer, an integer and a tuple
    of one or more integers.
    """
    if not (
        isinstance(flat, types.Array)
        and flat.ndim == 1
        and flat.layout == "C"
        and isinstance(start, types.Integer)
        and isinstance(shape, (types.UniTuple, types.Tuple))
        and len(shape.types) >= 1
        and all(isinstance(d, types.Integer) for d in shape.types)
    ):
        return None
    return types.Array(flat.dtype, len(shape), "C", readonly=not flat.mutable, aligned=flat.aligned)


@type_callable(view)
def _type_view(context):
    """The type of :func:`view` in compiled code: a builtin, typed and lowered in place (no function of its own)."""
    return _shape_of


@lower_builtin(view, types.Array, types.Integer, types.BaseTuple)  # UniTuple or Tuple (_shape_of)
def _lower_view(context, builder, signature, args):
    """The view: ``flat``'s data from ``start`` with ``shape``, C strides, sharing ``flat``'s owner (bounds checked)."""
    flat_type, start_type, shape_type = signature.args
    result = signature.return_type
    ndim = result.ndim
    source = make_array(flat_type)(context, builder, args[0])
    out = make_array(result)(context, builder)
    itemsize = context.get_constant(types.intp, context.get_abi_sizeof(context.get_data_type(flat_type.dtype)))
    extents = cgutils.unpack_tuple(builder, args[2], ndim)
    dims = [context.cast(builder, d, t, types.intp) for d, t in zip(extents, shape_type.types)]
    first = context.cast(builder, args[1], start_type, types.intp)
    zero = context.get_constant(types.intp, 0)
    size, outside = context.get_constant(types.intp, 1), builder.icmp_signed("<", first, zero)
    for d in dims:
        size, outside = builder.mul(size, d), builder.or_(outside, builder.icmp_signed("<", d, zero))
    outside = builder.or_(outside, builder.icmp_signed(">", builder.add(first, size), source.nitems))
    with cgutils.if_unlikely(builder, outside):
        context.call_conv.return_user_exc(builder, ValueError, ("a view reaches outside its buffer",))
    strides = [itemsize] * ndim
    for k in range(ndim - 2, -1, -1):  # C order: the last axis contiguous
        strides[k] = builder.mul(strides[k + 1], dims[k + 1])
    populate_array(
        out,
        data=cgutils.gep_inbounds(builder, source.data, first),
        shape=cgutils.pack_array(builder, dims),
        strides=cgutils.pack_array(builder, strides),
        itemsize=itemsize,
        meminfo=source.meminfo,  # the buffer's owner: the view keeps it alive
        parent=source.parent,
    )
    return impl_ret_borrowed(context, builder, result, out._getvalue())
