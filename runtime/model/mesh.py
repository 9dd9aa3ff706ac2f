"""Structured meshes by connectivity: elements of one kind sharing nodes, built from the kind's
node layout (element.json: the node points of the reference domain), never from a full grid.

A structured mesh tiles the meshed axes with ``counts`` elements; element (i, j) spans
[i, i + 1] x [j, j + 1] in element units and places exactly the nodes its layout has (the
ends of a 2-node beam, the middle too for a 3-node beam, the corners of a 4-node plate, the
corners and mid-sides of a serendipity shell); nodes at the same point are one node.  Node
positions are points of the *node lattice*: ``ElementKind.lattice_steps`` grid steps per
element along each axis (1 for corner layouts, 2 with mid-side or mid-length nodes), so grid
point (I, J) lies at (I / sx, J / sy) element units, and it is a node only where the layout
puts one (a serendipity shell has none at its elements' centres).
"""

from __future__ import annotations

import functools
import itertools
import math
from dataclasses import dataclass

import numpy as np

from runtime.kernels.kind import ElementKind, element_kind


@dataclass(frozen=True)
class Mesh:
    """Elements of one kind sharing nodes: ``points`` (nodes, axes) the node coordinates in
    element units along the meshed axes (``mesh_axes``), ``lattice`` (nodes, axes) the grid
    point of every node on the node lattice (integers, ``points`` times the lattice steps),
    ``connectivity`` (elements, n_nodes) the global node of each element node, in the
    kind's node order.  Nodes are numbered in order of y, then x (a line along x)."""

    points: np.ndarray
    lattice: np.ndarray
    connectivity: np.ndarray

    def dofs(self, kind: ElementKind) -> np.ndarray:
        """Global coordinate indices (elements, ndof) of every element (node-major)."""
        per_node = kind.per_node
        return (self.connectivity[:, :, None] * per_node
                + np.arange(per_node)[None, None, :]).reshape(len(self.connectivity), -1)

    @functools.cached_property
    def _by_grid(self) -> dict[tuple[int, ...], int]:
        return {tuple(p): i for i, p in enumerate(self.lattice.tolist())}

    def node_at(self, grid: tuple[int, ...]) -> int | None:
        """The node at lattice point ``grid`` (one index per meshed axis), None if the layout
        places none there."""
        return self._by_grid.get(tuple(int(g) for g in grid))

    def nearest(self, grid: tuple[int, ...], count: int = 4) -> list[int]:
        """The ``count`` nodes nearest to lattice point ``grid`` (by distance in grid steps,
        then node order)."""
        distance = np.sum((self.lattice - np.asarray(grid)) ** 2, axis=1)
        return [int(i) for i in np.lexsort((np.arange(len(distance)), distance))[:count]]

    def on_line(self, axis: int, line: int) -> np.ndarray:
        """The nodes on lattice line ``axis`` = ``line`` (x = I: axis 0), in order along
        the other axis (node order)."""
        return np.flatnonzero(self.lattice[:, axis] == line)


def lattice_shape(kind: ElementKind, counts) -> tuple[int, ...]:
    """Grid points of the node lattice along each meshed axis of a structured mesh of
    ``counts`` elements: ``c s + 1`` for ``s`` lattice steps per element (2-node beams
    m + 1, 3-node beams 2 m + 1, 4-node plates (nx + 1, ny + 1), 8-node shells
    (2 nx + 1, 2 ny + 1))."""
    return tuple(int(c) * s + 1 for c, s in zip(np.atleast_1d(counts), kind.lattice_steps,
                                                 strict=True))


def node_count(kind: ElementKind, counts) -> int:
    """Number of nodes of a structured mesh of ``counts`` elements, computed without building
    it: the count is affine in each element count (every element adds the nodes its layout
    does not share with the previous one), so it is interpolated exactly from the meshes of
    1 and 2 elements per axis (29 nodes for a 3 x 2 grid of 8-node shells, 12 of 4-node
    plates)."""
    counts = [int(c) for c in np.atleast_1d(counts)]
    total = 0
    for corner in itertools.product((1, 2), repeat=len(counts)):
        weight = math.prod(n - 1 if c == 2 else 2 - n for c, n in zip(corner, counts,
                                                                         strict=True))
        total += weight * len(structured_mesh(kind, corner).points)
    return total


def structured_mesh(kind: ElementKind, counts) -> Mesh:
    """The structured mesh of ``counts`` elements along each meshed axis (one number for a
    beam, (nx, ny) for a plate or shell): see the module docstring.  Built once per kind and
    counts (its arrays are read-only)."""
    counts = tuple(int(c) for c in np.atleast_1d(counts))
    if len(counts) != len(kind.mesh_axes) or min(counts) < 1:
        raise ValueError(f"counts: expected {len(kind.mesh_axes)} positive element counts for "
                         f"{kind.name}, got {counts}")
    return _structured_mesh(kind.name, counts)


@functools.lru_cache(maxsize=64)
def _structured_mesh(name: str, counts: tuple[int, ...]) -> Mesh:
    kind = element_kind(name)
    axes = kind.mesh_axes
    steps = np.array(kind.lattice_steps)
    offsets = np.round(kind.node_fractions[:, axes] * steps).astype(np.int64)  # (n, axes)
    cells = np.stack(np.meshgrid(*[np.arange(c) for c in counts], indexing="ij"),
                     axis=-1).reshape(-1, len(axes))
    # element order: x fastest (a line: along x; a plate: rows of constant y)
    cells = cells[np.lexsort(cells.T)]
    grid = (cells[:, None, :] * steps + offsets[None, :, :]).reshape(-1, len(axes))
    unique, inverse = np.unique(grid[:, ::-1], axis=0, return_inverse=True)
    lattice = unique[:, ::-1]
    mesh = Mesh(lattice / steps, lattice, inverse.reshape(len(cells), kind.n_nodes))
    for array in (mesh.points, mesh.lattice, mesh.connectivity):
        array.flags.writeable = False
    return mesh
