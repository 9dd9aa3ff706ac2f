"""The checked call boundary of generated kernels: ``BoundKernel`` (shared inputs converted
once, batch inputs and outputs checked at every call, identically for both backends) and the
array checks every public entry point uses (``real_array``, ``batch_input``, ``output_array``).
"""

from __future__ import annotations

import reprlib
from typing import Any, Protocol

import numpy as np
import scipy.sparse

from runtime.kernels import abi
from runtime.kernels.kind import ElementKind

_FLOAT = np.dtype(np.float64)


class LoadedFamily(Protocol):
    """What a bound kernel needs of its loaded family (``runtime.kernels.loader``)."""

    kind: ElementKind
    family: str
    backend: str
    signatures: dict
    _module: Any

    def _kernel_arrays(self, kernel: str, role: str) -> list[str]: ...


class BoundKernel:
    """A kernel whose shared inputs are prepared once; call it with the batch arrays.

    Every call is checked at this boundary, identically for both backends, so that no kernel
    reads or writes past a buffer or reinterprets its bytes:

    * batch inputs: (m, size) or (1, size) (one row is shared by the whole batch), real
      numbers.  C-contiguous float64 arrays are used as they are; other real arrays (integer,
      float32, non-native byte order, non-contiguous) and nested lists are converted to
      float64 (a copy); complex, bool, object and string values are rejected.  Values are
      not checked for NaN (they propagate to the results).
    * ``out``: writable C-contiguous float64 (m, size) arrays, filled in place and returned;
      never converted (a copy would be left unfilled), so anything else is rejected.
    * m = 0 (an empty batch) returns empty outputs without running the kernel.

    Names the kernel does not take are ignored (e.g. ``e0`` for ``cij``, whose invariants
    do not depend on the placement).  Every fault raises ValueError naming the argument and
    what was expected.  The checks are a few attribute tests on valid input (no copies), so
    calling costs a few microseconds of Python on top of the kernel itself, which matters
    when a simulation calls it thousands of times on small batches.
    """

    def __init__(self, family: LoadedFamily, kernel: str, fixed: dict) -> None:
        family._kernel_arrays(kernel, "batch")
        if not isinstance(fixed, dict):
            raise ValueError(f"fixed: expected a dict of inputs, got {describe(fixed)}")
        self.family, self.kernel = family, kernel
        self.arrays = family.signatures[kernel]["arrays"]
        self.outputs = [(a["name"], a["size"]) for a in self.arrays if a["role"] == "output"]
        self.varying = [(a["name"], a["size"]) for a in self.arrays
                        if a["role"] == "batch" and a["name"] not in fixed]
        self._what = f"for {family.kind.name}"
        self._fixed: dict = {}
        self._rows = 1  # rows of the fixed batch arrays (1: broadcast)
        for a in self.arrays:
            name, role, size = a["name"], a["role"], a["size"]
            if role in ("output", "local") or (role == "batch" and name not in fixed):
                continue
            if name not in fixed:
                raise ValueError(f"{name}: missing input of the {kernel} kernel of "
                                 f"{family.kind.name} ({family.family})")
            self._fixed[name] = self._prepared(name, role, size, fixed[name])
            if role == "batch":
                self._rows = self._batch_rows(name, size, self._fixed[name], self._rows)
        if family.backend == "numpy":
            self._function = getattr(family._module, kernel)
            return
        ffi = family._module.ffi
        self._function = getattr(family._module.lib, f"{family.kind.name}_{family.family}_"
                                 f"{kernel}")
        self._slots: list = []  # fixed cffi arguments, or (part, name, size) of a per-call one
        for p in abi.parameters(family.signatures[kernel])[1:]:  # after the count m
            value = self._fixed.get(p.array)
            if p.role == "output" or (p.role == "batch" and value is None):
                self._slots.append((p.role if p.part == "values" else p.part, p.array, p.size))
            elif p.part == "stride":
                self._slots.append(0 if value.shape[0] == 1 else p.size)
            elif p.part == "points":
                self._slots.append(value.shape[0])
            else:
                self._slots.append(ffi.from_buffer(
                    p.buffer, getattr(value, p.part) if p.role == "csr" else value))

    def _prepared(self, name: str, role: str, size: int, value):
        """A fixed input checked and converted once (C-contiguous float64 / int32 CSR)."""
        if role == "batch":
            return batch_input(name, value, size, self._what)
        if role == "csr":
            if not scipy.sparse.issparse(value) or value.format != "csr" \
                    or value.shape[0] != size:
                raise ValueError(f"{name}: expected a scipy CSR matrix with {size} rows "
                                 f"{self._what}, got {describe(value)}")
            matrix = value.copy()
            matrix.indptr = np.ascontiguousarray(value.indptr, dtype=np.int32)
            matrix.indices = np.ascontiguousarray(value.indices, dtype=np.int32)
            matrix.data = np.ascontiguousarray(value.data, dtype=np.float64)
            return matrix
        shape, expected = ((size,), f"({size},)") if role == "shared" else \
            ((None, size), f"(points, {size})")
        array = real_array(name, value, f"shape {expected} {self._what}")
        if array.ndim != len(shape) or array.shape[-1] != size:
            raise ValueError(f"{name}: expected shape {expected} float64 {self._what}, got "
                             f"{array.shape}")
        return np.ascontiguousarray(array, dtype=np.float64)

    def _batch_rows(self, name: str, size: int, array: np.ndarray, m: int) -> int:
        """The batch size after ``array``: its rows unless it has one (shared by all)."""
        rows = array.shape[0]
        if rows == 1 or rows == m:
            return m
        if m == 1:
            return rows
        raise ValueError(f"{name}: expected shape ({m}, {size}) or (1, {size}) float64 "
                         f"{self._what} (as many rows as the other batch arrays), got "
                         f"{array.shape}")

    def __call__(self, batch: dict, out: dict | None = None) -> dict[str, np.ndarray]:
        """Run on ``batch`` ({name: (m, size) array}); see the class docstring."""
        if not isinstance(batch, dict):
            raise ValueError(f"batch: expected a dict {{name: (m, size) array}} of "
                             f"{', '.join(n for n, _ in self.varying)}, got "
                             f"{describe(batch)}")
        arrays, m = {}, self._rows
        for name, size in self.varying:
            value = batch.get(name)
            if value is None:
                raise ValueError(f"{name}: missing; the {self.kernel} kernel "
                                 f"{self._what} takes {', '.join(n for n, _ in self.varying)}")
            if not (isinstance(value, np.ndarray) and value.dtype is _FLOAT and value.ndim == 2
                    and value.shape[1] == size and value.flags.c_contiguous):
                value = batch_input(name, value, size, self._what)
            arrays[name] = value
            if value.shape[0] != m and value.shape[0] != 1:
                m = self._batch_rows(name, size, value, m)
        if out is not None and not isinstance(out, dict):
            raise ValueError(f"out: expected a dict {{name: (m, size) array}} of "
                             f"{', '.join(n for n, _ in self.outputs)}, got {describe(out)}")
        outputs = {}
        for name, size in self.outputs:
            target = out.get(name) if out else None
            outputs[name] = (np.empty((m, size)) if target is None
                             else output_array(f"out[{name!r}]", target, (m, size)))
        return self.unchecked(m, arrays, outputs)

    def unchecked(self, m: int, batch: dict, outputs: dict) -> dict[str, np.ndarray]:
        """Run without the checks: ``batch`` C-contiguous float64 (m or 1, size) arrays and
        ``outputs`` writable C-contiguous float64 (m, size) arrays, as ``__call__`` makes."""
        if m == 0:
            return outputs
        if self.family.backend == "numpy":
            args = []
            for a in self.arrays:
                if a["role"] in ("output", "local"):
                    continue
                value = batch[a["name"]] if a["name"] in batch else self._fixed[a["name"]]
                if a["role"] == "batch" and value.shape[0] != m:
                    value = np.broadcast_to(value, (m, a["size"]))
                args.append(value)
            result = self._function(*args)
            result = result if isinstance(result, tuple) else (result,)
            for (name, _), value in zip(self.outputs, result, strict=True):
                np.copyto(outputs[name], value)
            return outputs
        ffi = self.family._module.ffi
        args = [m]
        for slot in self._slots:
            if isinstance(slot, tuple):
                part, name, size = slot
                if part == "batch":
                    args.append(ffi.from_buffer("double[]", batch[name]))
                elif part == "stride":
                    args.append(0 if batch[name].shape[0] == 1 else size)
                else:
                    args.append(ffi.from_buffer("double[]", outputs[name]))
            else:
                args.append(slot)
        self._function(*args)
        return outputs


def describe(value) -> str:
    """What a rejected argument was, for error messages (type; dtype, shape and layout)."""
    if not isinstance(value, np.ndarray):
        return f"{type(value).__name__} {reprlib.repr(value)}"
    flags = value.flags
    layout = ("" if flags.c_contiguous else
              "Fortran-ordered " if flags.f_contiguous else "non-contiguous ")
    return (f"{'' if flags.writeable else 'read-only '}{layout}{value.dtype} array of shape "
            f"{value.shape}")


def real_array(name: str, value, expected: str) -> np.ndarray:
    """``value`` as an array of real numbers (float or integer dtype; not converted).

    ValueError naming ``name`` and ``expected`` for complex, bool, object or string values
    and for ragged nested sequences.
    """
    try:
        array = np.asarray(value)
    except (TypeError, ValueError) as error:
        raise ValueError(f"{name}: expected real numbers, {expected}; {error}") from None
    if array.dtype.kind not in "fiu":
        raise ValueError(f"{name}: expected real numbers (float or integer), {expected}, got "
                         f"{describe(value) if isinstance(value, np.ndarray) else array.dtype}"
                         f"{'' if isinstance(value, np.ndarray) else ' values'}")
    return array


def batch_input(name: str, value, size: int, what: str) -> np.ndarray:
    """A batch input as a C-contiguous float64 (rows, size) array (converted if needed)."""
    expected = f"shape (m, {size}) float64 {what}"
    array = real_array(name, value, expected)
    if array.ndim != 2 or array.shape[1] != size:
        raise ValueError(f"{name}: expected {expected}, got {array.shape}")
    return np.ascontiguousarray(array, dtype=np.float64)


def output_array(name: str, target, shape: tuple[int, ...]) -> np.ndarray:
    """``target`` if it is a writable C-contiguous float64 array of ``shape``; ValueError
    naming ``name`` otherwise (a converted copy would be filled instead of ``target``)."""
    if isinstance(target, np.ndarray) and target.dtype == _FLOAT and target.shape == shape:
        flags = target.flags
        if flags.c_contiguous and flags.writeable:
            return target
    raise ValueError(f"{name}: expected a writable C-contiguous float64 array of shape "
                     f"{shape}, got {describe(target)}")
