"""LAPACK for the dense parts of the compiled step: the addresses of the routines that SciPy
ships (``scipy.linalg.cython_lapack`` exports them as capsules in ``__pyx_capi__``), so the
generated C calls the LAPACK of the installed SciPy, with no library of its own to link.
Fortran calling convention: every argument by pointer, matrices by columns, pivots from 1.
"""

from __future__ import annotations

import ctypes
import functools

import scipy.linalg.cython_lapack

#: routines the compiled step calls: LU factorisation and solve of a general matrix (the
#: Schur complement), Cholesky factorisation and solve of a symmetric band
FUNCTIONS = ("dgetrf", "dgetrs", "dpbtrf", "dpbtrs")
#: bandwidths from which the compiled step's band Cholesky is LAPACK's (dpbtrf, blocked);
#: narrower bands take the step's own loops with the bandwidth a compile-time constant
#: (measured: LAPACK 1.4x slower on beam3d chains, bandwidth 23; 1.1-1.3x faster on 8 x 8
#: and 16 x 16 plates, 119 and 215)
LAPACK_BANDWIDTH = 48


@functools.cache
def functions() -> dict[str, int]:
    """Addresses of ``FUNCTIONS``."""
    name_of, pointer_of = ctypes.pythonapi.PyCapsule_GetName, ctypes.pythonapi.PyCapsule_GetPointer
    name_of.restype, name_of.argtypes = ctypes.c_char_p, [ctypes.py_object]
    pointer_of.restype, pointer_of.argtypes = ctypes.c_void_p, [ctypes.py_object,
                                                                ctypes.c_char_p]
    capsules = scipy.linalg.cython_lapack.__pyx_capi__
    return {name: pointer_of(capsules[name], name_of(capsules[name])) for name in FUNCTIONS}
