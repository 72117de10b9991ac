"""Shaped views of packed buffers (:mod:`hexapod_model.kinematics.newton.views`), compiled and in Python."""

from __future__ import annotations

import gc

import numpy as np
import pytest
from numba import njit
from numba.core.errors import TypingError

from hexapod_model import Hexapod
from hexapod_model.kinematics.newton.packing import (
    WORK_NAMES,
    unpack,
    unpack_constants,
    unpack_floats,
    unpack_ints,
    unpack_iwork,
    unpack_work,
)
from hexapod_model.kinematics.newton.views import view


def _views(f, i, n):
    """One view of each rank, shapes mixing constants and run-time values, and an int64 one."""
    return (
        view(f, 3, (n,)),
        view(f, 5, (2, n)),
        view(f, 1, (n, 2, 3)),
        view(f, 7, (2, 1, n, 2)),
        view(f, 0, (1, 2, 2, n, 2)),
        view(i, 4, (n, 3)),
    )


_compiled_views = njit(cache=False)(_views)


def _same_memory(a, b):
    """Whether ``a`` and ``b`` are the same view: shape, strides, data pointer and values."""
    return (
        a.shape == b.shape
        and a.strides == b.strides
        and a.__array_interface__["data"][0] == b.__array_interface__["data"][0]
        and np.array_equal(a, b)
    )


def test_a_compiled_view_is_the_slice_reshaped_for_every_rank():
    f = np.random.default_rng(0).normal(size=200)
    i = np.arange(100, dtype=np.int64) * 7
    for n in (1, 3, 5):
        got, expected = _compiled_views(f, i, n), _views(f, i, n)
        for g, e in zip(got, expected):
            assert g.dtype == e.dtype
            assert _same_memory(g, e)
        assert np.array_equal(expected[1], f[5 : 5 + 2 * n].reshape(2, n))


@njit(cache=False)
def _write_through(buffer, start, value):
    v = view(buffer, start, (2, 3))
    v[1, 2] = value
    return v


def test_a_compiled_view_shares_its_buffer_and_writes_reach_it():
    buffer = np.zeros(20)
    v = _write_through(buffer, 4, 2.5)
    assert buffer[4 + 5] == 2.5 and np.count_nonzero(buffer) == 1
    assert np.shares_memory(v, buffer) and v.flags.c_contiguous and v.shape == (2, 3)


@njit(cache=False)
def _view_of_a_new_buffer(n):
    buffer = np.arange(float(n))
    return view(buffer, 2, (2, 3))  # the buffer is referenced by its view alone once this returns


def test_a_view_keeps_its_buffer_alive():
    v = _view_of_a_new_buffer(20)
    assert v.base is not None  # the buffer's owner, held by the view
    gc.collect()
    np.arange(1000.0) * 3.0  # memory reused if the buffer had been freed
    assert np.array_equal(v, np.arange(2.0, 8.0).reshape(2, 3))


@njit(cache=False)
def _view_at(buffer, start, a, b):
    return view(buffer, start, (a, b))


@pytest.mark.parametrize("start, shape", [(-1, (2, 3)), (15, (2, 3)), (0, (5, 5)), (20, (1, 1)), (4, (-2, -3))])
def test_a_view_reaching_outside_its_buffer_raises_compiled_and_in_python(start, shape):
    buffer = np.zeros(20)
    with pytest.raises(ValueError, match="outside"):
        _view_at(buffer, start, *shape)
    with pytest.raises(ValueError, match="outside"):
        view(buffer, start, shape)


def test_the_last_elements_of_a_buffer_make_a_view():
    buffer = np.arange(20.0)
    assert np.array_equal(_view_at(buffer, 14, 2, 3), buffer[14:].reshape(2, 3))
    assert _view_at(buffer, 20, 0, 3).shape == (0, 3)


@njit(cache=False)
def _first(buffer):
    return view(buffer, 0, (2, 2))[0, 0]


@njit(cache=False)
def _write_first(buffer):
    view(buffer, 0, (2, 2))[0, 0] = 1.0


def test_a_view_of_a_read_only_buffer_is_read_only():
    buffer = np.arange(20.0)
    buffer.setflags(write=False)
    assert _first(buffer) == 0.0
    with pytest.raises(TypingError):
        _write_first(buffer)
    with pytest.raises(ValueError):
        view(buffer, 0, (2, 2))[0, 0] = 1.0


def test_a_view_has_one_or_more_extents():
    with pytest.raises(ValueError, match="extents"):
        view(np.zeros(4), 0, ())


@njit(cache=False)
def _strided_view(buffer):
    return view(buffer[::2], 0, (2, 2))


def test_a_strided_buffer_is_refused_when_compiling():
    with pytest.raises(TypingError):
        _strided_view(np.zeros(20))


@njit(cache=False)
def _compiled_unpack(ints, floats, work, iwork):
    """The solver's views made in compiled code (what every entry makes), and the constants' views."""
    return unpack(ints, floats, work, iwork), unpack_constants(ints, floats)[0]


@pytest.mark.parametrize("preset", ["reference", "spherical", "3-6"])
def test_the_solvers_compiled_views_are_its_python_views(preset):
    """Every view an entry makes of the packed arrays points where ``Packed``'s Python views point."""
    hexa = Hexapod.from_preset(preset, check_body=False)
    for held in (hexa.engine.held_forward, hexa.engine.held_inverse):
        packed = hexa.engine.solver(held).packed
        ints, floats, work, iwork = packed.arrays
        (tables, frames, buffers, pivots), constants = _compiled_unpack(ints, floats, work, iwork)
        python = (
            unpack_ints.py_func(ints)[0],
            unpack_floats.py_func(ints, floats)[0],
            unpack_work.py_func(ints, work)[0],
            unpack_iwork.py_func(ints, iwork)[0],
        )
        for compiled_views, python_views in zip((tables, frames, buffers, pivots), python):
            assert len(compiled_views) == len(python_views)
            for c, p in zip(compiled_views, python_views):
                assert _same_memory(c, p)
        for name, c in zip(WORK_NAMES, buffers):
            assert _same_memory(c, packed.views[name])
        assert _same_memory(constants[5], unpack_constants.py_func(ints, floats)[0][5])  # home (4, 4)
