"""Load generated kernels (NumPy modules, or C through the cffi JIT) and call them uniformly.

Everything about an element the runtime needs is in ``generated/<kind>/element.json``; SymPy
is never imported here.
"""

from __future__ import annotations

import importlib.util
import json
import reprlib
import time
from dataclasses import dataclass, field
from functools import cache
from importlib import resources
from pathlib import Path

import numpy as np
import scipy.sparse

from runtime.kernels import jit

BACKENDS = ("c", "numpy")
_FLOAT = np.dtype(np.float64)


def generated_dir() -> Path:
    """The folder of the generated kernels (inside the installed package)."""
    return Path(str(resources.files("generated")))


def generated_kinds() -> list[str]:
    """Every element kind with generated kernels (``runtime.Element`` takes any), sorted."""
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

    def _linear(self, coeffs, geometry) -> np.ndarray:
        """Values of entries linear in the domain parameters ([a0, a1, a2, b] each)."""
        coeffs = np.array(coeffs, dtype=float).reshape(-1, 4)
        values = np.zeros(3)
        for i, value in enumerate(geometry):
            if value is not None:
                values[i] = value
        missing = [self.parameter_labels[i] for i in range(3)
                   if (i >= len(geometry) or geometry[i] is None) and coeffs[:, i].any()]
        if missing:
            raise ValueError(f"{', '.join(missing)}: needed for the reference of {self.name}")
        return coeffs[:, :3] @ values + coeffs[:, 3]

    def straight_reference(self, length: float, height: float | None = None,
                           width: float | None = None) -> np.ndarray:
        """Coordinates e0 (ndof,) of the straight (flat) element from the origin: positions at
        the node points, unit gradients (a beam's depends on the length only, a plate's on
        its sides: ``length`` and ``height`` are the sizes along local x and y)."""
        return self._linear(self.meta["straight_reference"], (length, height, width))

    @property
    def n_nodes(self) -> int:
        """Nodes per element."""
        return len(self.meta["nodes"])

    @property
    def vectors(self) -> tuple[str, ...]:
        """Nodal vectors of every node, in storage order (``r``, ``r_x``, ...)."""
        return tuple(self.meta["vectors"])

    @property
    def per_node(self) -> int:
        """Coordinates per node: nodal vectors times dim."""
        return len(self.meta["vectors"]) * self.dim

    @property
    def parameter_labels(self) -> tuple[str, ...]:
        """What the three geometry parameters (length, height, width) are for this kind."""
        return tuple(self.meta["domain"]["labels"])

    def node_points(self, length: float, height: float | None = None,
                    width: float | None = None) -> np.ndarray:
        """Local coordinates (n_nodes, dim) of the nodes in the reference domain."""
        points = self._linear([c for node in self.meta["nodes"] for c in node],
                              (length, height, width))
        return points.reshape(self.n_nodes, self.dim)

    def law_not_applicable(self, law: str) -> str | None:
        """Why material law ``law`` does not apply to this kind (None when it does or is
        unknown)."""
        return self.meta.get("laws_not_applicable", {}).get(law)

    def pattern(self, variant: str, name: str) -> np.ndarray:
        """Storage pattern ``name`` (i4, gram, cij) of ``variant`` as an int array."""
        return np.array(self.meta["patterns"][variant][name], dtype=np.int64)

    def operations(self, family: str, kernel: str) -> int:
        """Floating-point operations per element counted from the generated code."""
        return self.meta["families"][family][kernel]["operations"]


def element_kind(name: str) -> ElementKind:
    """The generated element kind ``name``; ValueError naming the known kinds otherwise."""
    if not isinstance(name, str):  # checked before the cache, which needs hashable names
        raise ValueError(f"kind: expected an element kind name ({', '.join(generated_kinds())}), "
                         f"got {name!r}")
    return _load_kind(str(name))


@cache
def _load_kind(name: str) -> ElementKind:
    if name not in generated_kinds():
        raise ValueError(f"kind: unknown element kind {name!r}; known kinds: "
                         f"{', '.join(generated_kinds())}")
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
                                          (folder / f"{family}.h").read_text(),
                                          label=f"{kind.name}/{family}",
                                          optimization=kind.meta["optimization"][family])
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

    def __init__(self, family: KernelFamily, kernel: str, fixed: dict) -> None:
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
        self._slots: list = []  # fixed cffi arguments, or the name of a per-call input
        for a in self.arrays:
            name, role, value = a["name"], a["role"], self._fixed.get(a["name"])
            if role == "batch" and name in self._fixed:
                self._slots += [ffi.from_buffer("double[]", value),
                                0 if value.shape[0] == 1 else a["size"]]
            elif role == "batch":
                self._slots += [("batch", name, a["size"])]
            elif role == "shared":
                self._slots.append(ffi.from_buffer("double[]", value))
            elif role == "csr":
                self._slots += [ffi.from_buffer("int[]", value.indptr),
                                ffi.from_buffer("int[]", value.indices),
                                ffi.from_buffer("double[]", value.data)]
            elif role == "table":
                self._slots += [value.shape[0], ffi.from_buffer("double[]", value)]
            elif role == "output":
                self._slots.append(("output", name, a["size"]))

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
