"""Points and directions of rigid bodies as affine functions of the model's coordinates, and
constraint rows that are their dot products (quadratic blocks, ``runtime.model.holonomic``).

In natural coordinates a body point and a body direction are linear in the body's 12
coordinates (``runtime.model.items.rigid.natural_map``), a point or direction of the ground
is a constant; so ``a . b`` of two of them is a quadratic form with a constant Hessian:
the rows of the joints whose axes are fixed in both bodies (cylindrical, universal,
prismatic between two bodies).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from runtime.model.holonomic import QuadraticBlock
from runtime.model.items.base import ModelView
from runtime.model.items.rigid import natural_map

__all__ = ["Affine", "body_point", "combined", "direction", "dot_rows", "frame_deflection",
           "point"]


@dataclass(frozen=True)
class Affine:
    """A vector ``map @ q[dofs] + constant`` (3,) of the coordinates ``dofs`` (k,), map
    (3, k)."""

    dofs: np.ndarray
    map: np.ndarray
    constant: np.ndarray

    def __sub__(self, other: Affine) -> Affine:
        return Affine(np.concatenate([self.dofs, other.dofs]),
                      np.hstack([self.map, -other.map]), self.constant - other.constant)

    def at(self, q: np.ndarray) -> np.ndarray:
        """Its value (3,) at the coordinates q (size,)."""
        return self.map @ q[self.dofs] + self.constant


def point(model: ModelView, body: str | None, world: np.ndarray) -> Affine:
    """The point of the rigid ``body`` (None: the ground) that is at ``world`` (3,) at
    t = 0."""
    if body is None:
        return Affine(np.zeros(0, np.int64), np.zeros((3, 0)), np.asarray(world, float))
    rigid = model.rigid[body]
    local = rigid.item.frame.T @ (np.asarray(world, float) - np.asarray(rigid.item.position))
    return Affine(rigid.dofs, natural_map(local), np.zeros(3))


def body_point(model: ModelView, body: str, local: tuple[float, ...]) -> Affine:
    """The point at body coordinates ``local`` of the rigid body or point mass ``body``."""
    dofs, mapping = model.rigid_point(body, local)
    return Affine(dofs, mapping, np.zeros(3))


def direction(model: ModelView, body: str | None, world: np.ndarray) -> Affine:
    """The direction fixed in the rigid ``body`` (None: the ground) that is ``world`` (3,)
    at t = 0."""
    if body is None:
        return Affine(np.zeros(0, np.int64), np.zeros((3, 0)), np.asarray(world, float))
    rigid = model.rigid[body]
    local = rigid.item.frame.T @ np.asarray(world, float)
    return Affine(rigid.dofs, natural_map(local) - natural_map(np.zeros(3)), np.zeros(3))


def dot_rows(owner: str, pairs: list[tuple[Affine, Affine]],
             constants: list[float] | None = None) -> QuadraticBlock:
    """The rows ``a . b + constant`` of the ``pairs`` (a, b) over the union of their
    coordinates (each once): H = A^T B + B^T A, g = A^T b0 + B^T a0, c = a0 . b0."""
    dofs = np.unique(np.concatenate([x.dofs for pair in pairs for x in pair]))
    k = dofs.size

    def spread(x: Affine) -> np.ndarray:
        full = np.zeros((3, k))
        np.add.at(full.T, np.searchsorted(dofs, x.dofs), x.map.T)
        return full

    hessians, linear, constant = [], [], []
    for a, b in pairs:
        first, second = spread(a), spread(b)
        hessians.append(first.T @ second + second.T @ first)
        linear.append(first.T @ b.constant + second.T @ a.constant)
        constant.append(float(a.constant @ b.constant))
    if constants is not None:
        constant = [c + extra for c, extra in zip(constant, constants, strict=True)]
    return QuadraticBlock(owner, dofs, np.array(hessians).reshape(len(pairs), k, k),
                          np.array(linear).reshape(len(pairs), k), np.array(constant))


def combined(block: QuadraticBlock, matrix: np.ndarray) -> QuadraticBlock:
    """The rows ``matrix @ phi`` (matrix (n, rows)) of ``block``'s rows phi."""
    return QuadraticBlock(block.owner, block.dofs, np.tensordot(matrix, block.hessians, 1),
                          matrix @ block.linear, matrix @ block.constant)


def frame_deflection(model: ModelView, body: str, local: tuple[float, ...],
                     other: str | None, owner: str) -> QuadraticBlock:
    """Six rows: the displacement of the point ``local`` of the rigid ``body`` from the
    other side's point that is there at t = 0 (in m, along the other side's directions
    b_k that are the body's axes a_k at t = 0) and the small rotation of the body's axes
    relative to them (rad, the axial vector of the skew part of [a_k . b_j]:
    theta_1 = (a_2 . b_3 - a_3 . b_2) / 2, ...); all 0 at t = 0, bilinear."""
    here = body_point(model, body, local)
    slide = here - point(model, other, here.at(model.reference))
    axes = model.rigid[body].item.frame.T                 # a_k at t = 0 (rows)
    mine = [direction(model, body, a) for a in axes]
    theirs = [direction(model, other, a) for a in axes]
    pairs = [(slide, b) for b in theirs]
    for i, j in ((1, 2), (2, 0), (0, 1)):                 # a_i . b_j and a_j . b_i
        pairs += [(mine[i], theirs[j]), (mine[j], theirs[i])]
    rows = dot_rows(owner, pairs)
    matrix = np.zeros((6, 9))
    matrix[:3, :3] = np.eye(3)
    for k in range(3):
        matrix[3 + k, 3 + 2 * k], matrix[3 + k, 4 + 2 * k] = 0.5, -0.5
    return combined(rows, matrix)
