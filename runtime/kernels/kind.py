"""The typed view of one generated element kind: ``generated/<kind>/element.json`` as written
by ``symgen.emit.element_metadata`` (domain, nodes, nodal vectors, laws, kernel families and
their calling conventions, storage patterns).  The runtime reads element metadata only through
``ElementKind``; physics that depends on the kind of domain (beam, plate) is asked of it here.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from fractions import Fraction
from functools import cache
from typing import Any

import numpy as np

from runtime.catalog import VARIANTS, generated_dir, generated_kinds

#: Rules of reduced integration of a subdomain axis (element.json ``domain.subdomains`` names
#: one in place of a fixed value; symgen.domains.AXIS_RULES): (points, weights) on [-1, 1].
AXIS_RULES = {"gauss2": np.polynomial.legendre.leggauss(2),
              "lobatto2": (np.array([-1.0, 1.0]), np.ones(2))}


def vector_axes(name: str) -> tuple[int, ...]:
    """The local axes a nodal vector of element.json differentiates the position along
    (``symgen.element.vector_axes``, which checked the name): "r" (), "r_x" (0,),
    "r_zz" (2, 2), "r_xy" (0, 1)."""
    return () if name == "r" else tuple("xyz".index(c) for c in name[2:])


def is_first_gradient(name: str) -> bool:
    """Whether nodal vector ``name`` is a first gradient (r_x, r_y, r_z): the vectors a node
    frame is made of; higher derivatives (r_zz, ...) are not directions of the node."""
    return len(vector_axes(name)) == 1


@dataclass(frozen=True)
class Axis:
    """One axis of the reference domain: ``coordinate`` (x, y, z), its bounds ``low`` and
    ``high`` as (numerator, denominator) multiples of the parameter ``scale``."""

    coordinate: str
    low: tuple[int, int]
    high: tuple[int, int]
    scale: str

    @property
    def meshed(self) -> bool:
        """Whether a mesh tiles this axis: it spans [0, 1] of its parameter (a beam's x, a
        plate's x and y), unlike a symmetric section or thickness axis."""
        return self.low == (0, 1) and self.high == (1, 1)


@dataclass(frozen=True)
class Domain:
    """The reference domain of a kind: ``name`` (beam, plate), its ``parameters`` (symbols,
    e.g. l, h, w) and what they are called as ``Element`` arguments (``labels``), its axes,
    integration ``subdomains`` and the thickness parameter of 2D kinds (or None)."""

    name: str
    parameters: tuple[str, ...]
    labels: tuple[str, ...]
    axes: tuple[Axis, ...]
    subdomains: dict[str, Any]
    thickness: str | None

    def values(self, geometry) -> dict[str, Any]:
        """{parameter: value} of the geometry (length, height, width) as ``Element`` takes it
        (floats, or exact numbers for the high-precision reference)."""
        return dict(zip(self.parameters, geometry, strict=True))

    def bounds(self, geometry) -> list[tuple[Any, Any]]:
        """(low, high) of every axis for the geometry (length, height, width)."""
        values = self.values(geometry)
        return [tuple(num * values[axis.scale] / den for num, den in (axis.low, axis.high))
                for axis in self.axes]

    def thickness_of(self, geometry) -> Any:
        """The thickness that scales the volume of a 2D kind (1 for 3D kinds)."""
        return self.values(geometry)[self.thickness] if self.thickness else 1

    def fixed_axes(self, subdomain: str) -> dict[int, float]:
        """{axis: fraction of its parameter} of the axes that ``subdomain`` holds fixed (the
        beam axis fixes y and z at 0; the volume fixes none)."""
        return {axis: value[0] / value[1] for axis, value in self.subdomains[subdomain]
                if not isinstance(value, str)}

    def reduced_axes(self, subdomain: str) -> dict[int, tuple[np.ndarray, np.ndarray]]:
        """{axis: (points, weights) on [-1, 1]} of the axes that ``subdomain`` integrates by a
        rule of reduced integration (the beam's ``volume_gauss2``: x by 2-point Gauss)."""
        return {axis: AXIS_RULES[value] for axis, value in self.subdomains[subdomain]
                if isinstance(value, str)}


@dataclass(frozen=True)
class LawInfo:
    """A material law as generated for a kind: its shear ``corrections`` (names of the
    factors it takes), ``description``, ``parts`` (each {name, domain}) and the ``storage``
    variant of its invariants on a straight element (``straight``: closed form in the svk
    patterns; ``general``: by quadrature, for laws with reduced integration)."""

    name: str
    corrections: tuple[str, ...]
    description: str
    parts: tuple[dict[str, str], ...]
    storage: str = "straight"
    #: the bending model of a cable law (``symgen.energies.BENDING_MODELS``), None for a
    #: continuum law
    bending: str | None = None
    #: the reference variants the law takes (a cable law may refuse curved ones) and, when
    #: it refuses curved references, why
    variants: tuple[str, ...] = VARIANTS
    curved: str | None = None
    #: a structural law's strains of the centre line (``symgen/structural.py``): each
    #: {name, directions: [a, b] (indices into ``directions``), domain, doc}; empty for a law
    #: of the Green-Lagrange strain
    strains: tuple[dict, ...] = ()
    #: the centre-line directions the strains dot (``r_<name>``), in table order
    directions: tuple[str, ...] = ()

    @property
    def structural(self) -> bool:
        """Whether the law evaluates structural strains of the centre line."""
        return bool(self.strains)


@dataclass(frozen=True)
class Energy:
    """The strain energy of a kind (``symgen/energies.py``): ``name`` ``continuum`` (the
    Green-Lagrange strain of the full deformation gradient with a material law) or ``cable``
    (axial strain and bending of r, r_x; the bending model is the law's, ``LawInfo``), the
    reference ``variants`` it takes and, when it refuses curved references, why
    (``curved``)."""

    name: str
    variants: tuple[str, ...]
    curved: str | None

    @classmethod
    def from_document(cls, meta: dict | None) -> Energy:
        """The energy entry of element.json (absent: the continuum, every variant)."""
        if meta is None:
            return cls("continuum", VARIANTS, None)
        return cls(meta["name"], tuple(meta["variants"]), meta["curved"])

    @property
    def structural(self) -> bool:
        """Whether the energy is a structural (beam) one rather than a continuum's."""
        return self.name != "continuum"


def complete_pattern(n_shape: int, name: str) -> np.ndarray:
    """Every key of storage pattern ``name`` for ``n_shape`` shape functions, in storage order
    (as ``symgen.derive.patterns`` of the general variant; element.json ``"complete"``):
    ``i4`` and ``gram`` the pairs (a, b), a <= b, of the n(n+1)/2 shape-function pairs;
    ``cij`` the (k, p, m, q) with k <= p, row-major."""
    if name in ("i4", "gram"):
        a, b = np.triu_indices(n_shape * (n_shape + 1) // 2)
        return np.column_stack([a, b]).astype(np.int64)
    k, p = np.triu_indices(n_shape)
    m, q = np.divmod(np.arange(n_shape * n_shape), n_shape)
    return np.column_stack([np.repeat(k, m.size), np.repeat(p, m.size),
                            np.tile(m, k.size), np.tile(q, k.size)]).astype(np.int64)


@dataclass(frozen=True)
class ElementKind:
    """Metadata of one generated element kind (see the module docstring).

    ``families`` maps a kernel family to its kernels, each {"arrays": [{name, role, size}],
    "operations": count}; ``patterns`` the stored index patterns per reference variant;
    ``energy`` the strain energy (``Energy``); ``meta`` keeps the document as read (for
    tools that print it; the runtime reads the typed fields).
    """

    name: str
    description: str
    dim: int
    n_shape: int
    ndof: int
    position_vectors: tuple[int, ...]
    quadrature: tuple[int, ...]
    exact_orders: tuple[int, ...]
    domain: Domain
    nodes: tuple
    vectors: tuple[str, ...]
    laws: dict[str, LawInfo]
    law_domains: tuple[str, ...]
    laws_not_applicable: dict[str, str]
    families: dict[str, dict]
    optimization: dict[str, int]
    patterns: dict[str, dict]
    cij_sizes: dict[str, dict]
    gradient_pattern: tuple[tuple[int, int], ...]
    closed_tables: str | None
    #: how the straight invariants are obtained when not by kernels or closed.json:
    #: ``quadrature`` (an exact Gauss rule at load time; element.json ``straight_invariants``)
    straight_invariants: str | None
    straight_reference_coefficients: tuple
    energy: Energy
    meta: dict = field(repr=False, compare=False)

    @classmethod
    def from_document(cls, meta: dict) -> ElementKind:
        """The view of an element.json document."""
        d = meta["domain"]
        domain = Domain(d["name"], tuple(d["parameters"]), tuple(d["labels"]),
                        tuple(Axis(a["coordinate"], tuple(a["low"]), tuple(a["high"]),
                                   a["scale"]) for a in d["axes"]),
                        d["subdomains"], d["thickness"])
        laws = {name: LawInfo(name, tuple(law["corrections"]), law["description"],
                              tuple(law["parts"]), law["storage"], law.get("bending"),
                              tuple(law.get("variants", VARIANTS)), law.get("curved"),
                              tuple(law.get("strains", ())), tuple(law.get("directions", ())))
                for name, law in meta["laws"].items()}
        return cls(meta["name"], meta["description"], meta["dim"], meta["n_shape"],
                   meta["ndof"], tuple(meta["position_vectors"]), tuple(meta["quadrature"]),
                   tuple(meta["exact_orders"]), domain, tuple(meta["nodes"]),
                   tuple(meta["vectors"]), laws, tuple(meta["law_domains"]),
                   dict(meta.get("laws_not_applicable", {})), meta["families"],
                   meta["optimization"], meta["patterns"], meta["cij_sizes"],
                   tuple(tuple(p) for p in meta["gradient_pattern"]), meta.get("closed_tables"),
                   meta.get("straight_invariants"),
                   tuple(meta["straight_reference"]), Energy.from_document(meta.get("energy")),
                   meta)

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
        return self._linear(self.straight_reference_coefficients, (length, height, width))

    @property
    def n_nodes(self) -> int:
        """Nodes per element."""
        return len(self.nodes)

    @property
    def per_node(self) -> int:
        """Coordinates per node: nodal vectors times dim."""
        return len(self.vectors) * self.dim

    @property
    def parameter_labels(self) -> tuple[str, ...]:
        """What the three geometry parameters (length, height, width) are for this kind."""
        return self.domain.labels

    @property
    def mesh_axes(self) -> list[int]:
        """The axes a mesh of this kind tiles (``Axis.meshed``): [0] for beams, [0, 1] for
        plates."""
        return [a for a, axis in enumerate(self.domain.axes) if axis.meshed]

    @property
    def node_fractions(self) -> np.ndarray:
        """Local node coordinates (n_nodes, dim) as fractions of the domain parameters along
        the meshed axes (x for beams; x and y for plates): 0, 1/2, 1 for a 3-node beam."""
        out = np.zeros((self.n_nodes, self.dim))
        for i, node in enumerate(self.nodes):
            for a, coeffs in enumerate(node):
                scale = self.domain.parameters.index(self.domain.axes[a].scale)
                out[i, a] = coeffs[scale]
        return out

    @property
    def lattice_steps(self) -> tuple[int, ...]:
        """Steps of the node lattice per element along each meshed axis: the common
        denominator of the node fractions (1 for 2-node beams and 4-node plates; 2 for 3-node
        beams and for a layout with mid-side nodes).  A mesh's grid indices count these
        steps, so a grid point is a node only where the layout places one."""
        fractions = self.node_fractions[:, self.mesh_axes]
        return tuple(math.lcm(*(Fraction(float(f)).limit_denominator(1000).denominator
                                for f in fractions[:, a]))
                     for a in range(fractions.shape[1]))

    @property
    def first_gradients(self) -> tuple[str, ...]:
        """The first gradients its nodes carry (r_x, r_y, r_z), in storage order."""
        return tuple(v for v in self.vectors if is_first_gradient(v))

    @property
    def held_vectors(self) -> tuple[str, ...]:
        """The nodal vectors a clamp (and a prescribed rotation) holds, in storage order: the
        position, the first gradients (the node's frame) and the derivatives across the
        section only (r_zz of a shell: the clamped section keeps its shape).  A derivative
        along a meshed axis (r_xx of the quintic cable, the curvature) is the bending of the
        clamped end, which stays free."""
        return tuple(v for v in self.vectors if v == "r" or is_first_gradient(v)
                     or not set(vector_axes(v)) & set(self.mesh_axes))

    def frame_gap(self) -> str | None:
        """Why a node of this kind cannot carry an orthonormal frame (None when it can): the
        gradients it carries must fix every axis, r_x, r_y and r_z completed from two in 3D,
        from one in 2D.  One gradient in 3D fixes one direction only: the normal of a
        surface (r_z of a shell) or the tangent of a line (r_x of a cable), not the turn
        about it."""
        gradients = self.first_gradients
        if len(gradients) >= self.dim - 1:
            return None
        carried = f"its nodes carry only {', '.join(self.vectors)}"
        if not gradients:
            return f"{carried}: no gradient, no frame"
        axis = "xyz".index(gradients[0][-1])
        what = "tangent" if axis in self.mesh_axes else "normal"
        return (f"{carried}: {gradients[0]} fixes only the node's {what}, not the turn about "
                f"it (a frame in {self.dim}D needs {self.dim - 1} gradients)")

    def node_points(self, length: float, height: float | None = None,
                    width: float | None = None) -> np.ndarray:
        """Local coordinates (n_nodes, dim) of the nodes in the reference domain."""
        points = self._linear([c for node in self.nodes for c in node],
                              (length, height, width))
        return points.reshape(self.n_nodes, self.dim)

    def law_not_applicable(self, law: str) -> str | None:
        """Why material law ``law`` does not apply to this kind (None when it does or is
        unknown)."""
        return self.laws_not_applicable.get(law)

    def pattern(self, variant: str, name: str) -> np.ndarray:
        """Storage pattern ``name`` (i4, gram, cij) of ``variant`` as a read-only int array,
        converted from element.json's lists once per kind (50 ms for ANCF-3833's: every
        element of a mesh of distinct shapes reads them)."""
        converted = self.__dict__.setdefault("_patterns", {})   # not a field: not compared
        if (variant, name) not in converted:
            stored = self.patterns[variant][name]
            array = (complete_pattern(self.n_shape, name) if stored == "complete"
                     else np.array(stored, dtype=np.int64))
            array.flags.writeable = False
            converted[variant, name] = array
        return converted[variant, name]

    def operations(self, family: str, kernel: str) -> int:
        """Floating-point operations per element counted from the generated code."""
        return self.families[family][kernel]["operations"]

    def svk_locking(self, nu: float) -> tuple[str, float] | None:
        """How much too stiff in bending the St. Venant-Kirchhoff law makes this kind at
        Poisson's ratio ``nu``: (what locks, relative excess stiffness), None without
        locking.  Beam bending sees lam + 2G instead of E (Poisson locking), plate bending
        lam + 2G instead of E / (1 - nu^2) (Poisson thickness locking), unless the kind
        carries a second derivative across the thickness (r_zz of ANCF-3833): its thickness
        strain then varies across the thickness, which frees the bending of that locking."""
        if nu == 0 or self.energy.structural:  # a cable's 1D law has no Poisson part
            return None
        across = [a for a in range(self.dim) if a not in self.mesh_axes]
        if self.domain.name == "plate" and any(vector_axes(name) == (a, a) for name in
                                               self.vectors for a in across):
            return None
        if self.domain.name == "beam":
            return "beams", (1 - nu) / ((1 + nu) * (1 - 2 * nu)) - 1   # (lam + 2G) / E - 1
        if self.domain.name == "plate":
            return "plates", nu * nu / (1 - 2 * nu)    # (lam + 2G) (1 - nu^2) / E - 1
        return None


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
    return ElementKind.from_document(
        json.loads((generated_dir() / name / "element.json").read_text()))
