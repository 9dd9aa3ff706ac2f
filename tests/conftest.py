"""Shared helpers of the element tests: parameters, reference shapes, rigid motions, a cache
of constructed elements (construction may compile C kernels, so each one is built once)."""

from __future__ import annotations

import functools
import zlib

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from runtime import Element

KINDS = ["beam2d", "beam3d"]
METHODS = ["gram", "cij", "quadrature"]
BACKENDS = ["c", "numpy"]
DIMS = {"beam2d": 2, "beam3d": 3}

# Typical element: steel, 1 m long, 0.1 m x 0.05 m section.  The curved one is an arc of
# radius 2 m and opening 0.5 rad, so it is 1 m long as well.
LENGTH, HEIGHT, WIDTH = 1.0, 0.1, 0.05
E_MODULUS, NU, RHO = 2.1e11, 0.3, 7800.0
ARC_RADIUS, ARC_ANGLE = 2.0, 0.5


def dim_of(kind: str) -> int:
    return DIMS[kind]


def vectors_per_node(kind: str) -> int:
    """r, r_x, r_y[, r_z]: dim + 1 vectors per node."""
    return dim_of(kind) + 1


def position_rows(kind: str) -> list[int]:
    """Rows of the (n, dim) nodal-vector matrix that hold node positions."""
    return [0, vectors_per_node(kind)]


def position_mask(kind: str) -> np.ndarray:
    """Boolean (ndof,) mask of the position coordinates."""
    d = dim_of(kind)
    mask = np.zeros((2 * vectors_per_node(kind), d), dtype=bool)
    mask[position_rows(kind)] = True
    return mask.ravel()


def straight_reference(kind: str, length: float = LENGTH) -> np.ndarray:
    """Straight element along x from the origin, unit gradients (DESIGN.md section 3)."""
    d = dim_of(kind)
    eye = np.eye(d)
    node = lambda x: [np.eye(d)[0] * x, *eye]  # noqa: E731
    return np.concatenate([np.concatenate(node(0.0)), np.concatenate(node(length))])


def arc_reference(kind: str, radius: float = ARC_RADIUS, angle: float = ARC_ANGLE) -> np.ndarray:
    """e0 of ONE element bent into a circular arc of ``radius`` (m) and opening ``angle`` (rad).

    The arc lies in the x-y plane, starts at the origin tangent to x and turns towards +y.
    Element length = radius * angle (x is arc length).  At each node: the position on the arc,
    r_x = unit tangent, r_y = unit normal (the tangent rotated by +90 deg, pointing to the
    centre) and, in 3D, r_z = (0, 0, 1).
    """
    d = dim_of(kind)
    vectors = []
    for theta in (0.0, angle):
        position = radius * np.array([np.sin(theta), 1.0 - np.cos(theta)])
        tangent = np.array([np.cos(theta), np.sin(theta)])
        normal = np.array([-np.sin(theta), np.cos(theta)])
        node = [position, tangent, normal]
        if d == 3:
            node = [np.append(v, 0.0) for v in node] + [np.array([0.0, 0.0, 1.0])]
        vectors.extend(node)
    return np.concatenate(vectors)


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


def rel_diff(a, b) -> float:
    """max |a - b| / max |b|: the relative difference used throughout."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


@pytest.fixture
def rng(request) -> np.random.Generator:
    """A generator seeded from the test id, so every parametrisation is reproducible."""
    seed = zlib.crc32(request.node.nodeid.encode())
    return np.random.default_rng(seed)
