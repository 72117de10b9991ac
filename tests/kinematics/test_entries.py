"""The hot paths' direct kernel calls (:mod:`hexapod_model.kinematics.newton.entries`)."""

from __future__ import annotations

import numpy as np
from numba import njit

from hexapod_model.kinematics.newton.entries import direct, plain


@njit(cache=False)
def _scaled_sum(a, k, out):
    s = 0.0
    for i in range(a.shape[0]):
        out[i] = k * a[i]
        s += out[i]
    return s


def test_plain_keeps_an_array_of_the_one_type_and_copies_any_other():
    a = np.arange(6.0)
    assert plain(a) is a
    read_only = np.arange(6.0)
    read_only.setflags(write=False)
    column = np.arange(12.0).reshape(6, 2)[:, 1]
    others = [read_only, column, np.arange(6, dtype=np.float32), np.arange(6), np.asfortranarray(np.eye(3))]
    for other in others:
        got = plain(other)
        assert got is not other and got.dtype == np.float64 and got.flags.carray
        assert np.array_equal(got, other)
    before = read_only.copy()
    plain(read_only)[0] = 99.0  # the copy is the caller's to write, the input stays
    assert np.array_equal(read_only, before)


def test_direct_is_the_machine_code_the_dispatcher_runs_for_those_types():
    a, out = np.arange(5.0), np.empty(5)
    args = (a, 2.0, out)
    want = _scaled_sum(*args)  # compiles the specialisation
    run = direct(_scaled_sum, args)
    assert run is not _scaled_sum and not hasattr(run, "signatures")  # not a dispatcher
    out2 = np.empty(5)
    assert run(a, 2.0, out2) == want and np.array_equal(out2, out)
    assert len(_scaled_sum.signatures) == 1


def test_direct_keeps_the_dispatcher_when_it_has_no_code_for_the_types():
    a = np.arange(5.0)
    _scaled_sum(a, 2.0, np.empty(5))
    a32 = np.arange(5, dtype=np.float32)
    assert direct(_scaled_sum, (a32, 2.0, np.empty(5))) is _scaled_sum  # never compiled for float32

    def python(x):  # a kernel replaced by plain Python (the NumPy kernels, a test's stand-in)
        return x

    assert direct(python, (a,)) is python
