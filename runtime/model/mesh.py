"""Structured meshes by connectivity: elements of one kind sharing nodes, built from the kind's
node layout (a line of beam elements, interior nodes included for 3-node beams; a grid of
plate elements), and their node counts computed without building them."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from runtime.kernels.kind import ElementKind


@dataclass(frozen=True)
class Mesh:
    """Elements of one kind sharing nodes: ``points`` (nodes, axes) the node coordinates in
    element units along the meshed axes (``mesh_axes``), ``connectivity`` (elements,
    n_nodes) the global node of each element node, in the kind's node order."""

    points: np.ndarray
    connectivity: np.ndarray

    def dofs(self, kind: ElementKind) -> np.ndarray:
        """Global coordinate indices (elements, ndof) of every element (node-major)."""
        per_node = kind.per_node
        return (self.connectivity[:, :, None] * per_node
                + np.arange(per_node)[None, None, :]).reshape(len(self.connectivity), -1)


def grid_shape(kind: ElementKind, counts) -> tuple[int, ...]:
    """Node points along each meshed axis of a structured mesh of ``counts`` elements (one
    count per meshed axis): ``c (k - 1) + 1`` for k node points per element along the axis
    (tensor node layouts: 2-node beams m + 1, 3-node beams 2 m + 1, 4-node plates
    (nx + 1, ny + 1))."""
    fractions = kind.node_fractions[:, kind.mesh_axes]
    per_axis = [len(np.unique(fractions[:, a])) for a in range(fractions.shape[1])]
    return tuple(int(c) * (k - 1) + 1 for c, k in zip(np.atleast_1d(counts), per_axis,
                                                       strict=True))


def node_count(kind: ElementKind, counts) -> int:
    """Number of nodes of a structured mesh of ``counts`` elements (see ``grid_shape``),
    computed without building the mesh."""
    return math.prod(grid_shape(kind, counts))


def structured_mesh(kind: ElementKind, counts) -> Mesh:
    """A structured mesh of ``counts`` elements along each meshed axis (one number for a
    beam, (nx, ny) for a plate): element (i, j) spans [i, i + 1] x [j, j + 1]; nodes at the
    same point are shared, numbered in order of y, then x (so a line is numbered along x)."""
    axes = kind.mesh_axes
    counts = tuple(int(c) for c in np.atleast_1d(counts))
    if len(counts) != len(axes) or min(counts) < 1:
        raise ValueError(f"counts: expected {len(axes)} positive element counts for "
                         f"{kind.name}, got {counts}")
    fractions = kind.node_fractions[:, axes]
    cells = np.stack(np.meshgrid(*[np.arange(c) for c in counts], indexing="ij"),
                     axis=-1).reshape(-1, len(axes))
    # element order: x fastest (a line: along x; a plate: rows of constant y)
    cells = cells[np.lexsort(cells.T)]
    points = cells[:, None, :] + fractions[None, :, :]
    keys = np.round(points * 2**20).astype(np.int64).reshape(-1, len(axes))
    unique, inverse = np.unique(keys[:, ::-1], axis=0, return_inverse=True)
    connectivity = inverse.reshape(len(cells), kind.n_nodes)
    return Mesh(unique[:, ::-1] / 2**20, connectivity)
