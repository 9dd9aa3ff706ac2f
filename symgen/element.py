"""Element definitions as data: what an ANCF element file in `symgen/elements/` provides.

An element is described once, symbolically; every derivation (gradients, invariants,
kernels) is shared by all elements and lives elsewhere in `symgen`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import sympy as sp

# Local coordinates of the straight element box and its dimensions (metres).
x, y, z = sp.symbols("x y z", real=True)
length, height, width = sp.symbols("l h w", positive=True)
LOCAL = (x, y, z)

#: Names of the nodal vectors an element may carry: the position and its local gradients.
VECTOR_KINDS = ("r", "r_x", "r_y", "r_z")


@dataclass(frozen=True)
class ElementSpec:
    """A fully parameterised ANCF element.

    name: registry key (e.g. ``"beam3d"``).
    dim: spatial dimension of positions (2 or 3).
    node_x: local x coordinate of each node (expressions in ``l``).
    vectors: the nodal vectors carried by every node, from ``VECTOR_KINDS``, in storage order.
    shape_functions: one SymPy expression per nodal vector (node-major), in x, y, z, l.
    quadrature: default Gauss order per local direction (length ``dim``).
    description: one line for listings.
    """

    name: str
    dim: int
    node_x: tuple[sp.Expr, ...]
    vectors: tuple[str, ...]
    shape_functions: tuple[sp.Expr, ...]
    quadrature: tuple[int, ...]
    description: str = ""
    box: tuple[tuple[sp.Symbol, sp.Expr, sp.Expr], ...] = field(init=False)

    def __post_init__(self) -> None:
        if self.dim not in (2, 3):
            raise ValueError(f"element {self.name!r}: dim must be 2 or 3, got {self.dim}")
        unknown = [v for v in self.vectors if v not in VECTOR_KINDS[: self.dim + 1]]
        if unknown:
            raise ValueError(f"element {self.name!r}: unknown nodal vectors {unknown}")
        if len(self.shape_functions) != self.n_shape:
            raise ValueError(
                f"element {self.name!r}: expected {self.n_shape} shape functions "
                f"({len(self.node_x)} nodes x {len(self.vectors)} vectors), "
                f"got {len(self.shape_functions)}"
            )
        if len(self.quadrature) != self.dim:
            raise ValueError(f"element {self.name!r}: quadrature needs {self.dim} orders")
        box = [(x, sp.Integer(0), length), (y, -height / 2, height / 2)]
        if self.dim == 3:
            box.append((z, -width / 2, width / 2))
        object.__setattr__(self, "box", tuple(box))

    @property
    def n_shape(self) -> int:
        """Number of shape functions = nodal vectors per element."""
        return len(self.node_x) * len(self.vectors)

    @property
    def ndof(self) -> int:
        """Number of element coordinates."""
        return self.n_shape * self.dim

    @property
    def coordinates(self) -> tuple[sp.Symbol, ...]:
        """Local coordinates the shape functions depend on (x, y[, z])."""
        return LOCAL[: self.dim]

    @cached_property
    def position_vectors(self) -> tuple[int, ...]:
        """Indices (into the shape-function list) of nodal position vectors."""
        per_node = len(self.vectors)
        return tuple(
            node * per_node + i
            for node in range(len(self.node_x))
            for i, kind in enumerate(self.vectors)
            if kind == "r"
        )

    def straight_reference(self) -> list[sp.Expr]:
        """Reference coordinates e0 of the straight element along local x from the origin.

        Positions sit at (node_x, 0[, 0]); gradients are the unit vectors, so r0(x) = x.
        """
        e0: list[sp.Expr] = []
        for node_x in self.node_x:
            for kind in self.vectors:
                vec = [sp.Integer(0)] * self.dim
                if kind == "r":
                    vec[0] = node_x
                else:
                    vec["xyz".index(kind[-1])] = sp.Integer(1)
                e0.extend(vec)
        return e0
