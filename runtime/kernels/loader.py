"""Load generated kernel families (NumPy modules, or C through the cffi JIT), memoised per
process; calls go through the checked boundary of ``runtime.kernels.boundary``.

Everything about an element the runtime needs is in ``generated/<kind>/element.json``, read
through ``runtime.kernels.kind``; SymPy is never imported here.
"""

from __future__ import annotations

import importlib.util
import time
from functools import cache

import scipy.sparse

from runtime.catalog import BACKENDS
from runtime.kernels import jit
from runtime.kernels.boundary import BoundKernel, describe
from runtime.kernels.kind import ElementKind, element_kind, generated_dir


class KernelFamily:
    """The kernels of one family of one element kind, in one backend.

    ``compile_s`` is the time spent compiling (C, first use on this machine) and ``load_s``
    the time to load; both are zero for cached NumPy modules.
    """

    def __init__(self, kind: ElementKind, family: str, backend: str) -> None:
        if backend not in BACKENDS:
            raise ValueError(f"backend: expected one of {BACKENDS}, got {backend!r}")
        if family not in kind.families:
            raise ValueError(f"unknown kernel family {family!r} for {kind.name}")
        self.kind, self.family, self.backend = kind, family, backend
        self.signatures = kind.families[family]
        folder = generated_dir() / kind.name
        start = time.perf_counter()
        self.compile_s = 0.0
        if backend == "c":
            compiled = jit.compile_module(f"{kind.name}_{family}",
                                          (folder / f"{family}.c").read_text(),
                                          (folder / f"{family}.h").read_text(),
                                          label=f"{kind.name}/{family}",
                                          optimization=kind.optimization[family])
            self.compile_s = compiled.seconds if compiled.compiled or compiled.waited else 0.0
            self._module = compiled.module
        else:
            spec = importlib.util.spec_from_file_location(
                f"ancf_generated_{kind.name}_{family}", folder / f"{family}.py")
            self._module = importlib.util.module_from_spec(spec)
            spec.loader.exec_module(self._module)
        self.load_s = time.perf_counter() - start - self.compile_s
        #: when loading ended (``time.perf_counter``): ``kernel_family`` memoises families per
        #: process, so a caller charges compile_s and load_s only to work that began before
        self.loaded_at = time.perf_counter()

    def __call__(self, kernel: str, inputs: dict, out: dict | None = None) -> dict:
        """Run ``kernel`` on a batch.

        inputs: batch arrays as (m, size) or (1, size) (broadcast), shared arrays (size,),
        sparse operators as scipy CSR matrices, the table as (points, width); validated and
        converted as ``BoundKernel`` documents.
        out: optional preallocated writable C-contiguous float64 (m, size) arrays, by output
        name (reusing them avoids page-faulting fresh memory on large batches).
        Returns each output as an (m, size) array.
        """
        first = self._kernel_arrays(kernel, "batch")[0]
        if not isinstance(inputs, dict):
            raise ValueError(f"inputs: expected a dict {{name: array}}, got {describe(inputs)}")
        # a one-shot call: everything but the first batch array is bound for this call only
        fixed = {name: value for name, value in inputs.items() if name != first}
        return self.bind(kernel, fixed)({first: inputs.get(first)}, out)

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

    def _kernel_arrays(self, kernel: str, role: str) -> list[str]:
        """Names of the arrays of ``role`` that ``kernel`` takes; ValueError if unknown."""
        if not isinstance(kernel, str) or kernel not in self.signatures:
            raise ValueError(f"kernel: expected one of {', '.join(self.signatures)} for "
                             f"{self.kind.name} ({self.family}), got {kernel!r}")
        return [a["name"] for a in self.signatures[kernel]["arrays"] if a["role"] == role]


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
