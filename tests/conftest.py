"""Shared helpers of the element tests: parameters, reference shapes, rigid motions, a cache
of constructed elements (construction may compile C kernels, so each one is built once)."""

from __future__ import annotations

import functools
import zlib

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from runtime import Element
from runtime.catalog import generated_kinds
from runtime.kernels.kind import element_kind, vector_axes

#: Every generated element kind (generated/*/element.json): the tests cover each one.
KINDS = generated_kinds()
METHODS = ["gram", "cij", "quadrature"]
BACKENDS = ["c", "numpy"]
DIMS = {kind: element_kind(kind).dim for kind in KINDS}

# Typical element: steel, 1 m long, 0.1 m x 0.05 m section (a plate: 1 m x 0.1 m, 0.05 m
# thick).  The curved one is bent to a radius of 2 m over 0.5 rad along x (an arc; a
# cylindrical panel for a plate), so it is 1 m long as well.
LENGTH, HEIGHT, WIDTH = 1.0, 0.1, 0.05
E_MODULUS, NU, RHO = 2.1e11, 0.3, 7800.0
ARC_RADIUS, ARC_ANGLE = 2.0, 0.5


def dim_of(kind: str) -> int:
    return DIMS[kind]


def vectors_per_node(kind: str) -> int:
    """Nodal vectors per node (r, r_x, r_y[, r_z] for the 2-node beams)."""
    return len(element_kind(kind).vectors)


def position_rows(kind: str) -> list[int]:
    """Rows of the (n, dim) nodal-vector matrix that hold node positions."""
    return list(element_kind(kind).position_vectors)


def position_mask(kind: str) -> np.ndarray:
    """Boolean (ndof,) mask of the position coordinates."""
    info = element_kind(kind)
    mask = np.zeros((info.n_shape, info.dim), dtype=bool)
    mask[position_rows(kind)] = True
    return mask.ravel()


def across_rows(kind: str) -> list[int]:
    """Rows of the (n, dim) nodal-vector matrix holding the gradient across the element, one
    per node: along the first local axis on which every node sits at the same coordinate and
    that the nodes carry a gradient for (r_y for beams, whose nodes vary along x only; r_z for
    plates; r_z for a solid, whose nodes vary along every axis)."""
    info = element_kind(kind)
    points = info.node_points(LENGTH, HEIGHT, WIDTH)
    if info.energy.structural:  # a cable's nodes carry no gradient across: its tangent r_x
        return [node * len(info.vectors) + info.vectors.index("r_x")
                for node in range(info.n_nodes)]
    axis = next((a for a in range(info.dim)
                 if np.ptp(points[:, a]) == 0 and f"r_{'xyz'[a]}" in info.vectors),
                info.dim - 1)                  # a solid: its last axis (z)
    column = info.vectors.index(f"r_{'xyz'[axis]}")
    return [node * len(info.vectors) + column for node in range(info.n_nodes)]


def solid(kind: str) -> bool:
    """Whether the kind meshes every axis (a brick): no axis is across the element."""
    return len(element_kind(kind).mesh_axes) == dim_of(kind)


def across_positions(kind: str) -> tuple[list[int], int]:
    """(position rows, axis) of a solid's nodes spread across its last axis (z), which
    ``inverted_reference`` and ``degenerate_reference`` mirror or flatten with r_z; no rows for
    the other kinds (their nodes sit at one coordinate across the element)."""
    return (position_rows(kind), dim_of(kind) - 1) if solid(kind) else ([], 0)


def inverted_reference(kind: str) -> np.ndarray:
    """Straight reference with the gradient across the element (across_rows) of every node
    flipped (a solid: r_z and the nodes' z, mirrored in z = 0): a mirror image, det J0 < 0."""
    q = straight_reference(kind).reshape(-1, dim_of(kind)).copy()
    rows, axis = across_positions(kind)
    q[across_rows(kind)] *= -1
    q[rows, axis] *= -1
    return q.ravel()


def degenerate_reference(kind: str) -> np.ndarray:
    """Straight reference with the gradient across the element (across_rows) = 0 at every
    node (a solid: r_z and the nodes' z, flattened into z = 0): det J0 = 0."""
    q = straight_reference(kind).reshape(-1, dim_of(kind)).copy()
    rows, axis = across_positions(kind)
    q[across_rows(kind)] = 0.0
    q[rows, axis] = 0.0
    return q.ravel()


def _nodal_reference(kind: str, position, frame, curvature=None) -> np.ndarray:
    """e0 from the node points of the kind: ``position(p)``, ``frame(p)`` (columns
    dr0/dx, dr0/dy[, dr0/dz]) and ``curvature(p)`` (d^2 r0/dx^2, the r_xx of a quintic
    cable; zero when None) at each node's local point p; other higher derivatives (r_zz)
    zero (the straight fibres of every reference here)."""
    info = element_kind(kind)
    vectors = []
    for point in info.node_points(LENGTH, HEIGHT, WIDTH):
        columns = frame(point)
        for name in info.vectors:
            axes = vector_axes(name)
            if not axes:
                vectors.append(position(point))
            elif len(axes) == 1:
                vectors.append(columns[:, axes[0]])
            elif axes == (0, 0) and curvature is not None:
                vectors.append(curvature(point))
            else:
                vectors.append(np.zeros(info.dim))
    return np.concatenate(vectors)


def straight_reference(kind: str, length: float = LENGTH) -> np.ndarray:
    """Straight (flat) element from the origin, unit gradients (DESIGN.md section 3)."""
    d = dim_of(kind)
    return _nodal_reference(kind, lambda p: np.array(p, float) * [length / LENGTH, 1, 1][:d],
                            lambda p: np.eye(d))


def arc_reference(kind: str, radius: float = ARC_RADIUS, angle: float = ARC_ANGLE) -> np.ndarray:
    """e0 of ONE element bent along its local x onto a circle of ``radius`` (m); the element
    length LENGTH = radius * angle (x is arc length).

    Beams: the arc lies in the x-y plane, starts at the origin tangent to x and turns towards
    +y; at each node r_x is the unit tangent, r_y the unit normal (pointing to the centre)
    and, in 3D, r_z = (0, 0, 1).  Kinds meshing two axes (plates, shells): a cylindrical
    panel, x bent in the x-z plane towards +z about an axis parallel to y: r_x the tangent,
    r_y = (0, 1, 0), r_z the normal.  Solids (bricks): the same bend of the whole box, a node
    at local z on the circle of radius ``radius - z`` (its r_x shortened by that ratio).
    """
    assert abs(radius * angle - LENGTH) < 1e-12 or angle != ARC_ANGLE
    d = dim_of(kind)
    if len(element_kind(kind).mesh_axes) >= 2:    # a surface or a solid: a cylindrical panel
        def position(p):
            t, r = p[0] / radius, radius - p[2]
            return np.array([r * np.sin(t), p[1], radius - r * np.cos(t)])

        def frame(p):
            t, stretch = p[0] / radius, (radius - p[2]) / radius
            return np.column_stack([[stretch * np.cos(t), 0.0, stretch * np.sin(t)],
                                    [0.0, 1.0, 0.0], [-np.sin(t), 0.0, np.cos(t)]])
        return _nodal_reference(kind, position, frame)

    def position(p):
        t = p[0] / radius
        return radius * np.array([np.sin(t), 1.0 - np.cos(t), 0.0])[:d]

    def frame(p):
        t = p[0] / radius
        columns = np.column_stack([[np.cos(t), np.sin(t), 0.0], [-np.sin(t), np.cos(t), 0.0],
                                   [0.0, 0.0, 1.0]])
        return columns[:d, :d]

    def curvature(p):
        t = p[0] / radius
        return np.array([-np.sin(t), np.cos(t), 0.0])[:d] / radius
    return _nodal_reference(kind, position, frame, curvature)


def invariant_rounding(kind: str) -> float:
    """How much more the sums over the invariants round for ``kind`` than for the 16 shape
    functions of the plates, on which the tolerances below were set: their terms are products
    of two shape-function pairs, (n (n + 1) / 2)^2 of them (136^2 for 16), and the rounding
    left after their cancellation grows with that count (measured on curved references
    against the 50-digit reference: the 8-node shell's gram force 4.3e-13, energy 1.7e-13;
    the 24 shape functions of ANCF-3833, 4.9 times the terms: 2.0e-12 and 3.0e-12, varying
    by 1.7e-12 with a rigid rotation of the same problem; the quadrature method, which sums
    no invariants, stays at 1e-15 on both); 1 up to 16 shape functions."""
    n = element_kind(kind).n_shape
    return max(1.0, (n * (n + 1) / 2 / 136) ** 2)


def reference(kind: str, curved: bool) -> np.ndarray:
    return arc_reference(kind) if curved else straight_reference(kind)


def random_rotation(dim: int, rng: np.random.Generator) -> np.ndarray:
    """A random proper rotation matrix (dim x dim)."""
    if dim == 3:
        return Rotation.random(random_state=rng).as_matrix()
    angle = rng.uniform(-np.pi, np.pi)
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s], [s, c]])


def rigid_motion(kind: str, e0: np.ndarray, R: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Coordinates after x -> R x + t: positions rotated and translated, gradients rotated."""
    d = dim_of(kind)
    q = np.asarray(e0, float).reshape(-1, d) @ np.asarray(R).T
    q[position_rows(kind)] += np.asarray(t, float)
    return q.ravel()


def translate(kind: str, e: np.ndarray, t) -> np.ndarray:
    """Positions shifted by t (scalar or dim-vector), gradients untouched."""
    return rigid_motion(kind, e, np.eye(dim_of(kind)), np.broadcast_to(t, (dim_of(kind),)))


@functools.cache
def element(kind: str, method: str = "gram", backend: str = "c", curved: bool = False) -> Element:
    """The typical element (straight default e0, or the arc), built once per session."""
    e0 = arc_reference(kind) if curved else None
    return Element(kind, LENGTH, HEIGHT, WIDTH, E_MODULUS, NU, RHO, e0=e0, method=method,
                   backend=backend)


def lame(E: float = E_MODULUS, nu: float = NU) -> tuple[float, float]:
    """Lame lambda and G (Pa), written out here rather than taken from the code under test."""
    return E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))


def force_scale() -> float:
    """A typical elastic force (N): E A times a strain of 1e-3."""
    return E_MODULUS * HEIGHT * WIDTH * 1e-3


def energy_scale() -> float:
    """A typical strain energy (J): E V times a squared strain of 1e-3 squared."""
    return E_MODULUS * LENGTH * HEIGHT * WIDTH * 1e-6


def rigid_cancellation(el: Element, e: np.ndarray) -> tuple[float, float]:
    """(force, |q|) bounds of what the invariant methods (gram, cij) leave at a rigid motion
    ``e`` (ndof,) or (m, ndof): their sums of terms of size |K| |e| cancel there up to a few
    eps |K| |e| per coordinate (|K| ~ the Jacobian, |e| the positions relative to the first
    node), more for the many invariants of large elements (``invariant_rounding``); the
    energy's terms are |q| times larger."""
    d = el.kind.dim
    q = np.asarray(e, float).reshape(-1, el.kind.n_shape, d)
    q = q - q[:, position_rows(el.kind.name)[:1]]
    terms = np.abs(el.elastic_jacobian(e)).max() * np.abs(q).max()
    eps = np.finfo(float).eps
    return 16 * eps * el.ndof * terms * invariant_rounding(el.kind.name), float(np.abs(q).max())


def rel_diff(a, b) -> float:
    """max |a - b| / max |b|: the relative difference used throughout."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


def kind_seed(kind: str) -> int:
    """A seed of the kind's own: from its name, not from its place among the generated
    kinds, which a new kind shifts (it changed the draws, and so the rounding, of every
    kind after it)."""
    return zlib.crc32(kind.encode())


@pytest.fixture
def rng(request) -> np.random.Generator:
    """A generator seeded from the test id, so every parametrisation is reproducible."""
    seed = zlib.crc32(request.node.nodeid.encode())
    return np.random.default_rng(seed)



def curved_refused(kind: str, law: str | None = None) -> str | None:
    """Why ``kind`` with material law ``law`` refuses curved references (element.json
    ``laws.<law>.curved``: the cable's simple bending model is not rotation invariant for
    them), or None; without a law, why some law of the kind does (``energy.curved``)."""
    if law is not None and law in element_kind(kind).laws:
        return element_kind(kind).laws[law].curved
    return element_kind(kind).energy.curved


@pytest.fixture(autouse=True)
def _curved_only_where_the_energy_takes_it(request):
    """The one place the generic tests learn which references an energy takes: a case with a
    kind and a curved reference (parameter ``shape`` = "curved" or ``curved`` = True) is
    skipped, with the reason, for a kind whose energy (or, with a parameter ``law``, whose
    law) refuses curved references; so is a test marked ``curved`` (it builds curved
    references itself)."""
    callspec = getattr(request.node, "callspec", None)
    params = callspec.params if callspec is not None else {}
    kind = params.get("kind")
    curved = (params.get("shape") == "curved" or params.get("curved") is True
              or request.node.get_closest_marker("curved") is not None)
    if kind in KINDS and curved:
        reason = curved_refused(kind, params.get("law"))
        if reason is not None:
            pytest.skip(f"{kind} takes straight references only: {reason}")


def pytest_configure(config) -> None:
    config.addinivalue_line("markers", "curved: the test builds curved references of its "
                            "kind (skipped for kinds whose energy refuses them)")
    config.addinivalue_line("markers", "slow: a test of a minute or more: its file runs "
                            "first, so that the workers of `-n auto` end together")


# ---------------------------------------------------------------- scheduling on the workers
# `-n auto --dist loadfile --no-loadscope-reorder` (pyproject.toml): whole files per worker
# in collection order.  Files with a test marked ``slow`` are collected first, and the tests
# whose node id starts with one of ``APART`` are work units of their own (the regeneration of
# each kind: minutes each, no shared fixture), so that no worker is left alone with a long
# file at the end.

APART = ("tests/test_generate.py::test_regeneration_is_byte_identical[",)


def pytest_collection_modifyitems(config, items) -> None:
    slow_files = {item.path for item in items if item.get_closest_marker("slow")}
    items.sort(key=lambda item: item.path not in slow_files)   # stable: file order kept


def pytest_xdist_make_scheduler(config, log):
    from xdist.scheduler import LoadFileScheduling

    class FilesAndApart(LoadFileScheduling):
        def _split_scope(self, nodeid: str) -> str:
            if nodeid.startswith(APART):
                return nodeid
            return super()._split_scope(nodeid)

    return FilesAndApart(config, log)
