"""The C calling convention of generated kernels, as symgen wrote it into element.json (each
kernel's ``parameters`` next to its ``arrays``, ``symgen.emit.c_parameters``): read here for
the cffi boundary (``runtime.kernels.boundary``) and for the kernel calls of the generated
stepper (``runtime.solve.compiled_engine``), so neither repeats which C parameters an array
of each role takes.
"""

from __future__ import annotations

from dataclasses import dataclass

#: Roles of the arrays a kernel takes once for a whole run (not per element).
INVARIANT_ROLES = ("shared", "csr", "table")


@dataclass(frozen=True)
class Parameter:
    """One C parameter of a kernel: its C ``type`` and ``name``, the ``part`` it carries
    (``count``: the batch size m; ``values`` of an array; ``stride``: the row stride of a
    batch array, 0 for one row shared by the batch; ``indptr``, ``indices``, ``data`` of a
    CSR matrix; ``points``: the rows of a table) and, except for the count, the ``array`` it
    belongs to with that array's ``role`` and ``size``."""

    type: str
    name: str
    part: str
    array: str | None = None
    role: str | None = None
    size: int | None = None

    @property
    def buffer(self) -> str:
        """The cffi buffer type of a pointer parameter (``double[]`` or ``int[]``)."""
        return "int[]" if self.type.startswith("const int") else "double[]"


def parameters(signature: dict) -> tuple[Parameter, ...]:
    """The C parameters of a kernel in order, from its element.json entry ``signature``."""
    arrays = {a["name"]: a for a in signature["arrays"]}
    out = []
    for p in signature["parameters"]:
        array = arrays.get(p.get("array"), {})
        out.append(Parameter(p["type"], p["name"], p["part"], p.get("array"), array.get("role"),
                             array.get("size")))
    return tuple(out)


def c_types(signature: dict) -> str:
    """The C parameter types of a kernel, comma-separated (for a function-pointer type)."""
    return ", ".join(p.type for p in parameters(signature))


def invariant_inputs(signature: dict) -> list[str]:
    """Names of the arrays a kernel takes once for a run (shared, csr, table), in order."""
    return list(dict.fromkeys(p.array for p in parameters(signature)
                              if p.role in INVARIANT_ROLES))
