"""Element definitions as data: what an ANCF element file in `symgen/elements/` provides.

An element is described once, symbolically: its reference domain (symgen/domains.py), its
nodes as points of that domain, the nodal vectors every node carries, one shape function per
nodal vector and its default Gauss orders.  Every derivation (gradients, invariants, kernels,
the straight reference, the metadata the runtime meshes with) is shared by all elements and
lives elsewhere in `symgen`.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import sympy as sp

from symgen import domains, energies
from symgen.domains import (  # noqa: F401  (element files import these)
    AXIS_LETTERS,
    LOCAL,
    Domain,
    x,
    y,
    z,
)

# The beam box parameters, kept importable from here for the element files.
length, height, width = domains.length, domains.height, domains.width



def vector_axes(name: str, dim: int) -> tuple[int, ...] | None:
    """The local axes a nodal vector differentiates the position along, in order: ``"r"``
    (the position) (), ``"r_x"`` (0,), ``"r_zz"`` (2, 2) (d^2 r / dz^2), ``"r_xy"`` (0, 1).
    Names are ``r`` or ``r_`` followed by axis letters of the first ``dim`` in alphabetical
    order (one name per derivative: ``r_xy``, never ``r_yx``); None for any other name."""
    if name == "r":
        return ()
    letters = AXIS_LETTERS[:dim]
    if not name.startswith("r_") or len(name) < 3 or any(c not in letters for c in name[2:]):
        return None
    axes = tuple(letters.index(c) for c in name[2:])
    return axes if list(axes) == sorted(axes) else None


@dataclass(frozen=True)
class ElementSpec:
    """A fully parameterised ANCF element.

    name: registry key (e.g. ``"beam3d"``).
    domain: the reference domain (``domains.beam(dim)``, ``domains.plate()``, ...); its
        dimension is the element's.
    nodes: each node as a point of the domain: ``dim`` expressions in the domain parameters
        (e.g. ``(l / 2, 0, 0)``).
    vectors: the nodal vectors carried by every node, in storage order: the position ``r``
        and its local derivatives, first (``r_x``, ``r_y``, ``r_z``) or higher (``r_zz``,
        ``r_xy``, ...; ``vector_axes``).
    shape_functions: one SymPy expression per nodal vector (node-major), in the local
        coordinates and the domain parameters; s_k must be 1 for its own nodal vector and 0
        for the others at the nodes (checked).
    quadrature: default Gauss order per local direction (length ``dim``).
    description: one line for listings.
    energy: the strain energy (``symgen.energies.ENERGIES``): ``continuum`` (the Green-Lagrange
        strain of the full deformation gradient with a material law, the default) or
        ``cable`` (axial strain and bending of a structural beam carrying r, r_x[, r_xx]).
    """

    name: str
    domain: Domain
    nodes: tuple[tuple[sp.Expr, ...], ...]
    vectors: tuple[str, ...]
    shape_functions: tuple[sp.Expr, ...]
    quadrature: tuple[int, ...]
    description: str = ""
    energy: str = "continuum"

    def __post_init__(self) -> None:
        nodes = tuple(tuple(sp.sympify(c) for c in node) for node in self.nodes)
        object.__setattr__(self, "nodes", nodes)
        object.__setattr__(self, "shape_functions",
                           tuple(sp.sympify(s) for s in self.shape_functions))
        unknown = [v for v in self.vectors if vector_axes(v, self.dim) is None]
        if unknown:
            raise ValueError(f"element {self.name!r}: unknown nodal vectors {unknown} "
                             f"(expected r or r_ and axis letters of {AXIS_LETTERS[:self.dim]} "
                             "in order: r_x, r_zz, r_xy, ...)")
        if len(set(self.vectors)) != len(self.vectors):
            raise ValueError(f"element {self.name!r}: repeated nodal vectors {self.vectors}")
        if "r" not in self.vectors:
            raise ValueError(f"element {self.name!r}: every node needs its position r")
        if any(len(node) != self.dim for node in nodes):
            raise ValueError(f"element {self.name!r}: every node is a point of {self.dim} "
                             "coordinates")
        if len(self.shape_functions) != self.n_shape:
            raise ValueError(
                f"element {self.name!r}: expected {self.n_shape} shape functions "
                f"({len(nodes)} nodes x {len(self.vectors)} vectors), "
                f"got {len(self.shape_functions)}"
            )
        if len(self.quadrature) != self.dim:
            raise ValueError(f"element {self.name!r}: quadrature needs {self.dim} orders")
        energies.check(self)
        allowed = set(self.coordinates) | set(self.domain.parameters)
        for s in self.shape_functions:
            extra = s.free_symbols - allowed
            if extra:
                raise ValueError(f"element {self.name!r}: shape function {s} uses unknown "
                                 f"symbols {sorted(map(str, extra))}")

    @property
    def dim(self) -> int:
        """Spatial dimension of positions (2 or 3): the domain's."""
        return self.domain.dim

    @property
    def n_nodes(self) -> int:
        return len(self.nodes)

    @property
    def n_shape(self) -> int:
        """Number of shape functions = nodal vectors per element."""
        return len(self.nodes) * len(self.vectors)

    @property
    def ndof(self) -> int:
        """Number of element coordinates."""
        return self.n_shape * self.dim

    @property
    def coordinates(self) -> tuple[sp.Symbol, ...]:
        """Local coordinates the shape functions depend on (x, y[, z])."""
        return self.domain.coordinates

    @cached_property
    def position_vectors(self) -> tuple[int, ...]:
        """Indices (into the shape-function list) of nodal position vectors."""
        per_node = len(self.vectors)
        return tuple(
            node * per_node + i
            for node in range(len(self.nodes))
            for i, kind in enumerate(self.vectors)
            if kind == "r"
        )

    def straight_reference(self) -> list[sp.Expr]:
        """Reference coordinates e0 of the straight (flat) element: r0(x) = x.

        Positions sit at the nodes' points; first gradients are the unit vectors, higher
        derivatives (r_zz, ...) of the linear map are zero.
        """
        e0: list[sp.Expr] = []
        for node in self.nodes:
            for kind in self.vectors:
                axes = vector_axes(kind, self.dim)
                if not axes:
                    e0.extend(node)
                    continue
                vec = [sp.Integer(0)] * self.dim
                if len(axes) == 1:
                    vec[axes[0]] = sp.Integer(1)
                e0.extend(vec)
        return e0

    def check_interpolation(self) -> None:
        """Raise ValueError unless the shape functions interpolate the nodal vectors: at node
        i, s_k = 1 for its position and 0 for the others, the derivative of s_k that a nodal
        vector names (d s_k/d x_a for r_a, d^2 s_k/d z^2 for r_zz, ...) 1 for its own and 0
        for every other nodal vector."""
        for i, node in enumerate(self.nodes):
            at = dict(zip(self.coordinates, node, strict=True))
            for j, kind in enumerate(self.vectors):
                row = i * len(self.vectors) + j
                for k, s in enumerate(self.shape_functions):
                    value = s
                    for axis in vector_axes(kind, self.dim):
                        value = sp.diff(value, LOCAL[axis])
                    value = value.subs(at)
                    expected = 1 if k == row else 0
                    if sp.simplify(value - expected) != 0:
                        raise ValueError(
                            f"element {self.name!r}: shape function {k} gives {value} for "
                            f"{kind} of node {i} (expected {expected})")
