"""Load generated kernels (NumPy modules, or C through the cffi JIT) and call them uniformly.

Everything about an element the runtime needs is in ``generated/<kind>/element.json``; SymPy
is never imported here.
"""

from __future__ import annotations

import importlib.util
import json
import time
from dataclasses import dataclass, field
from functools import cache
from importlib import resources
from pathlib import Path

import numpy as np
import scipy.sparse

from runtime import jit

BACKENDS = ("c", "numpy")


def generated_dir() -> Path:
    """The folder of the generated kernels (inside the installed package)."""
    return Path(str(resources.files("generated")))


def known_kinds() -> list[str]:
    """Element kinds with generated kernels, sorted."""
    return sorted(p.parent.name for p in generated_dir().glob("*/element.json"))


@dataclass(frozen=True)
class ElementKind:
    """Metadata of one generated element kind (see ``symgen.emit.element_metadata``)."""

    name: str
    dim: int
    n_shape: int
    ndof: int
    position_vectors: tuple[int, ...]
    quadrature: tuple[int, ...]
    meta: dict = field(repr=False, compare=False)

    def straight_reference(self, length: float) -> np.ndarray:
        """Coordinates e0 (ndof,) of the straight element along x from the origin."""
        coeffs = np.array(self.meta["straight_reference"], dtype=float)
        return coeffs[:, 0] * length + coeffs[:, 1]

    def pattern(self, variant: str, name: str) -> np.ndarray:
        """Storage pattern ``name`` (i4, gram, cij) of ``variant`` as an int array."""
        return np.array(self.meta["patterns"][variant][name], dtype=np.int64)

    def operations(self, family: str, kernel: str) -> int:
        """Floating-point operations per element counted from the generated code."""
        return self.meta["families"][family][kernel]["operations"]


@cache
def element_kind(name: str) -> ElementKind:
    """The generated element kind ``name``; ValueError naming the known kinds otherwise."""
    if not isinstance(name, str) or name not in known_kinds():
        raise ValueError(f"kind: unknown element kind {name!r}; known kinds: "
                         f"{', '.join(known_kinds())}")
    meta = json.loads((generated_dir() / name / "element.json").read_text())
    return ElementKind(meta["name"], meta["dim"], meta["n_shape"], meta["ndof"],
                       tuple(meta["position_vectors"]), tuple(meta["quadrature"]), meta)


class KernelFamily:
    """The kernels of one family of one element kind, in one backend.

    ``compile_s`` is the time spent compiling (C, first use on this machine) and ``load_s``
    the time to load; both are zero for cached NumPy modules.
    """

    def __init__(self, kind: ElementKind, family: str, backend: str) -> None:
        if backend not in BACKENDS:
            raise ValueError(f"backend: expected one of {BACKENDS}, got {backend!r}")
        if family not in kind.meta["families"]:
            raise ValueError(f"unknown kernel family {family!r} for {kind.name}")
        self.kind, self.family, self.backend = kind, family, backend
        self.signatures = kind.meta["families"][family]
        folder = generated_dir() / kind.name
        start = time.perf_counter()
        self.compile_s = 0.0
        if backend == "c":
            compiled = jit.compile_module(f"{kind.name}_{family}",
                                          (folder / f"{family}.c").read_text(),
                                          (folder / f"{family}.h").read_text())
            self.compile_s = compiled.seconds if compiled.compiled or compiled.waited else 0.0
            self._module = compiled.module
        else:
            spec = importlib.util.spec_from_file_location(
                f"ancf_generated_{kind.name}_{family}", folder / f"{family}.py")
            self._module = importlib.util.module_from_spec(spec)
            spec.loader.exec_module(self._module)
        self.load_s = time.perf_counter() - start - self.compile_s

    def __call__(self, kernel: str, inputs: dict, out: dict | None = None) -> dict:
        """Run ``kernel`` on a batch.

        inputs: batch arrays as (m, size) or (1, size) (broadcast), shared arrays (size,),
        sparse operators as scipy CSR matrices, the table as (points, width).
        out: optional preallocated C-contiguous float64 (m, size) arrays, by output name
        (reusing them avoids page-faulting fresh memory on large batches).
        Returns each output as an (m, size) array.
        """
        # a one-shot call: everything but the first batch array is bound for this call only
        first = next(a["name"] for a in self.signatures[kernel]["arrays"]
                     if a["role"] == "batch")
        fixed = {name: value for name, value in inputs.items() if name != first}
        return self.bind(kernel, fixed)({first: inputs[first]}, out)

    def address(self, kernel: str) -> int:
        """Address of the C function of ``kernel`` (for generated code that calls it, such
        as the compiled stepper); valid while this family is loaded."""
        if self.backend != "c":
            raise ValueError(f"backend: kernel addresses exist only for backend 'c', not "
                             f"{self.backend!r}")
        ffi, lib = self._module.ffi, self._module.lib
        function = ffi.addressof(lib, f"{self.kind.name}_{self.family}_{kernel}")
        return int(ffi.cast("uintptr_t", function))

    def bind(self, kernel: str, fixed: dict) -> BoundKernel:
        """``kernel`` with every input but the per-call batch arrays converted once."""
        return BoundKernel(self, kernel, fixed)


class BoundKernel:
    """A kernel whose shared inputs are prepared once; call it with the batch arrays.

    Calling it costs a few microseconds of Python on top of the kernel itself, which matters
    when a simulation calls it thousands of times on small batches.
    """

    def __init__(self, family: KernelFamily, kernel: str, fixed: dict) -> None:
        self.family, self.kernel = family, kernel
        self.arrays = family.signatures[kernel]["arrays"]
        self.outputs = [(a["name"], a["size"]) for a in self.arrays if a["role"] == "output"]
        self.varying = [a["name"] for a in self.arrays
                        if a["role"] == "batch" and a["name"] not in fixed]
        self._keep: list = []
        if family.backend == "numpy":
            self._function = getattr(family._module, kernel)
            self._fixed = fixed
            return
        ffi = family._module.ffi
        self._function = getattr(family._module.lib, f"{family.kind.name}_{family.family}_"
                                 f"{kernel}")
        self._slots: list = []  # fixed cffi arguments, or the name of a per-call input
        for a in self.arrays:
            name, role = a["name"], a["role"]
            if role == "batch" and name in fixed:
                self._slots += [self._pointer(ffi, fixed[name], "double"),
                                0 if fixed[name].shape[0] == 1 else a["size"]]
            elif role == "batch":
                self._slots += [("batch", name, a["size"])]
            elif role == "shared":
                self._slots.append(self._pointer(ffi, fixed[name], "double"))
            elif role == "csr":
                matrix = fixed[name]
                self._slots += [self._pointer(ffi, matrix.indptr, "int"),
                                self._pointer(ffi, matrix.indices, "int"),
                                self._pointer(ffi, matrix.data, "double")]
            elif role == "table":
                self._slots += [fixed[name].shape[0], self._pointer(ffi, fixed[name], "double")]
            elif role == "output":
                self._slots.append(("output", name, a["size"]))

    def _pointer(self, ffi, array, ctype: str):
        array = np.ascontiguousarray(array, dtype=np.float64 if ctype == "double" else np.int32)
        self._keep.append(array)
        return ffi.from_buffer(f"{ctype}[]", array)

    def __call__(self, batch: dict, out: dict | None = None) -> dict[str, np.ndarray]:
        """Run on ``batch`` ({name: (m, size) C-contiguous float64}); see KernelFamily."""
        out = out or {}
        m = max(batch[name].shape[0] for name in self.varying)
        outputs = {}
        for name, size in self.outputs:
            target = out.get(name)
            if target is None:
                target = np.empty((m, size))
            elif (target.shape != (m, size) or target.dtype != np.float64
                  or not target.flags.c_contiguous):
                raise ValueError(f"out: expected a C-contiguous float64 array of shape "
                                 f"{(m, size)} for {name}")
            outputs[name] = target
        if self.family.backend == "numpy":
            args = [batch[a["name"]] if a["name"] in batch else self._fixed[a["name"]]
                    for a in self.arrays if a["role"] not in ("output", "local")]
            result = self._function(*args)
            result = result if isinstance(result, tuple) else (result,)
            for (name, _), value in zip(self.outputs, result, strict=True):
                np.copyto(outputs[name], value)
            return outputs
        ffi = self.family._module.ffi
        args = [m]
        for slot in self._slots:
            if isinstance(slot, tuple):
                role, name, size = slot
                if role == "batch":
                    value = batch[name]
                    args += [ffi.from_buffer("double[]", value),
                             0 if value.shape[0] == 1 else size]
                else:
                    args.append(ffi.from_buffer("double[]", outputs[name]))
            else:
                args.append(slot)
        self._function(*args)
        return outputs


@cache
def kernel_family(kind: str, family: str, backend: str) -> KernelFamily:
    """Loaded (and, for C, compiled once per machine) kernel family; memoised per process."""
    return KernelFamily(element_kind(kind), family, backend)


def csr(matrix) -> scipy.sparse.csr_matrix:
    """A canonical CSR matrix (sorted indices, duplicates summed) for the kernels."""
    matrix = scipy.sparse.csr_matrix(matrix)
    matrix.sum_duplicates()
    matrix.sort_indices()
    return matrix
