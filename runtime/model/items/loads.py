"""External loads of scenes (``[[load]]`` tables): a typed registry, ``LOADS``.

A load is a constant generalised force vector (``nominal``, N per coordinate, at a time-law
value of 1) scaled by its ``time_law`` (default: constant 1).  Each class declares its TOML
keys as fields (``runtime.model.schema.Record``); adding one is one class here and one entry in
``LOADS``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from runtime.element import invariants
from runtime.kernels.kind import element_kind
from runtime.kernels.loader import kernel_family
from runtime.model.errors import SceneError, show
from runtime.model.items.base import ModelView
from runtime.model.schema import (
    Context,
    EdgeRef,
    NodeRef,
    Record,
    edge_key,
    key,
    law_key,
    node_key,
    registry,
    rotation_vector,
    vector,
)
from runtime.model.time_laws import Constant, Law

__all__ = ["LOADS", "Gravity", "LineForce", "Load", "NodeLoad", "PointForce", "PointMoment"]

#: Gauss points along an element side for line loads (exact for the side's shape functions
#: times its length element up to degree 15)
EDGE_GAUSS_ORDER = 8


@dataclass(frozen=True)
class Load(Record):
    """Base of the loads: ``nominal(model)`` times ``time_law.value(t)``; ``potential``: its
    work is the potential energy of the ``potential_energy`` sensor (gravity)."""

    potential: ClassVar[bool] = False
    time_law: Law | dict = key(law_key, Constant(), kw_only=True)

    def nominal(self, model: ModelView) -> np.ndarray:
        """Generalised force (size,) in N (per coordinate) at a time-law value of 1."""
        raise NotImplementedError

    #: the key that names its nodes ("node", "edge"; none for a field such as gravity)
    target_key: ClassVar[str] = ""

    def targets(self) -> list[NodeRef]:
        """The nodes it acts on (none for a field such as gravity)."""
        return []


@dataclass(frozen=True)
class NodeLoad(Load):
    """A load on one ``node``; ``on_gradients``: it acts on the node's gradients (a moment),
    else on its position (a force); ``noun`` names it in messages."""

    on_gradients: ClassVar[bool] = False
    noun: ClassVar[str] = "force"
    target_key: ClassVar[str] = "node"
    node: NodeRef | str = key(node_key)

    def targets(self) -> list[NodeRef]:
        return [self.node]


def _vector_key(value: Any, path: str, context: Context) -> tuple[float, ...]:
    return vector(value, path, context.dim, f"the scene is {context.dim}D")


@dataclass(frozen=True)
class PointForce(NodeLoad):
    """A force ``force`` (dim,) in N on the position of ``node`` (fixed direction)."""

    type: ClassVar[str] = "point_force"
    force: tuple[float, ...] = key(_vector_key)

    def nominal(self, model: ModelView) -> np.ndarray:
        out = np.zeros(model.size)
        out[model.node_dofs(model.node_index(self.node), "r")] = self.force
        return out


def _moment_key(value: Any, path: str, context: Context) -> float | tuple[float, ...]:
    return rotation_vector(value, path, context.dim, "the moment in N m")


def _section_node_key(value: Any, path: str, context: Context) -> NodeRef:
    """A node a moment can act on: one whose gradients define a frame
    (``ElementKind.frame_gap``: r_y, or in 2D r_x of a cable node); a 3D cable node's r_x or a
    shell node's r_z fixes one direction only."""
    ref = node_key(value, path, context)
    kind = element_kind(context.node.bodies[ref.body].element)
    gap = kind.frame_gap()
    if gap is not None or "r_y" not in kind.vectors and context.dim == 3:
        raise SceneError(f"{path}: node {show(value)} of body {show(ref.body)} ({kind.name}) "
                         f"cannot take a moment: {gap or 'a moment in 3D acts on r_y and r_z'}; "
                         "a moment needs the node's frame")
    return ref


@dataclass(frozen=True)
class PointMoment(NodeLoad):
    """A moment ``moment`` in N m on the section of ``node``: a number about +z in 2D, a
    vector (3,) in 3D; fixed in space.

    Consistent generalised force: the virtual work of M on the small rotation d theta of the
    node's section, read from its gradients r_y (and r_z) in the reference.  With (t1, t2,
    t3) the node's reference frame (its gradients r_x, r_y, r_z orthonormalised, r_x first)
    and a rotation d theta, d r_y = d theta x t2 and d r_z = d theta x t3, so
    d theta . t3 = -t1 . d r_y, d theta . t2 = t1 . d r_z and d theta . t1 = (t3 . d r_y -
    t2 . d r_z) / 2 (the twist read from both, averaged); M . d theta = Q_y . d r_y +
    Q_z . d r_z gives, with M_i = M . t_i,

        3D:  Q_y = (M_1 / 2) t3 - M_3 t1,   Q_z = M_2 t1 - (M_1 / 2) t2
        2D:  Q_y = -M t1                     (M about z)

    on the node's r_y and r_z coordinates (nothing on r and r_x).  It is also the work of a
    linear distribution of tractions over the section (the bending stress -M y / I) with
    resultant M.  Assumption: small rotations of the section; Q is constant, so a section
    turned by a finite angle theta receives the moment of those fixed tractions, M cos(theta)
    in bending, not M.  A 2D node without r_y (a cable's) takes the moment on its tangent:
    d r_x = d theta (-r_x,y, r_x,x), so Q_x = M (-r_x,y, r_x,x) / |r_x|^2 at the reference
    (a 3D cable node has no section orientation: refused).
    """

    type: ClassVar[str] = "point_moment"
    on_gradients: ClassVar[bool] = True
    noun: ClassVar[str] = "moment"
    node: NodeRef | str = key(_section_node_key)
    moment: float | tuple[float, ...] = key(_moment_key)

    def nominal(self, model: ModelView) -> np.ndarray:
        node = model.node_index(self.node)
        out = np.zeros(model.size)
        if "r_y" not in model.node_vectors(node):  # a 2D cable node: on its tangent
            tangent = model.reference[model.node_dofs(node, "r_x")]
            out[model.node_dofs(node, "r_x")] = (self.moment * np.array([-tangent[1], tangent[0]])
                                                 / (tangent @ tangent))
            return out
        frame = model.node_frame(model.reference, node)
        if model.dim == 2:
            out[model.node_dofs(node, "r_y")] = -self.moment * frame[:, 0]
            return out
        t1, t2, t3 = frame.T
        m1, m2, m3 = frame.T @ np.asarray(self.moment, float)
        out[model.node_dofs(node, "r_y")] = 0.5 * m1 * t3 - m3 * t1
        out[model.node_dofs(node, "r_z")] = m2 * t1 - 0.5 * m1 * t2
        return out


@dataclass(frozen=True)
class Gravity(Load):
    """A uniform acceleration field ``acceleration`` (dim,) in m/s^2 on every body: the
    consistent generalised force M u of the mass matrix M and the rigid translation u."""

    type: ClassVar[str] = "gravity"
    potential: ClassVar[bool] = True
    acceleration: tuple[float, ...] = key(_vector_key)

    def nominal(self, model: ModelView) -> np.ndarray:
        return model.mass @ model.rigid_field(translation=self.acceleration)


@dataclass(frozen=True)
class LineForce(Load):
    """A uniform force per unit length ``force_per_length`` (dim,) in N/m along the ``edge``
    of a rectangle body (``"BODY:x=-1"``: its last grid column), fixed in direction: the
    consistent generalised force int S^T f ds over the element sides on that grid line
    (Gauss rule along each side, ds from the reference).  Its resultant is f times the edge
    length (a tip line load on a plate strip: P = f b)."""

    type: ClassVar[str] = "line_force"
    on_gradients: ClassVar[bool] = False
    noun: ClassVar[str] = "line force"
    target_key: ClassVar[str] = "edge"
    edge: EdgeRef | str = key(edge_key)
    force_per_length: tuple[float, ...] = key(_vector_key)

    def targets(self) -> list[NodeRef]:
        return self.edge.refs()

    def nominal(self, model: ModelView) -> np.ndarray:
        body = model.bodies[self.edge.body]
        kind, element = body.kind, body.element
        axis = "xy".index(self.edge.axis)     # the side lies at fixed local x (or y) ...
        along = 1 - axis                        # ... and runs along local y (or x)
        size = element.geometry[along]
        family = kernel_family(kind.name, "invariants", element.backend)
        t, w = np.polynomial.legendre.leggauss(EDGE_GAUSS_ORDER)
        fractions = kind.node_fractions
        on_edge = np.isin(body.mesh.connectivity, self.edge.nodes)
        out = np.zeros(model.size)
        sides: set[frozenset] = set()   # an interior line's sides belong to two elements:
        for e in np.flatnonzero(on_edge.sum(axis=1) > 1):   # integrate each side once
            side = frozenset(body.mesh.connectivity[e][on_edge[e]].tolist())
            if side in sides:
                continue
            sides.add(side)
            points = np.zeros((t.size, kind.dim))   # mid-surface (z = 0) of the side
            points[:, axis] = fractions[np.flatnonzero(on_edge[e])[0], axis] * \
                element.geometry[axis]
            points[:, along] = (t + 1) / 2 * size
            data = {"point": points, "geometry": np.asarray(element.geometry, float)}
            values = family("shape_values", data)["values"]                  # (p, n)
            grads = invariants.full_gradients(kind, invariants.shape_gradient_table(
                kind, family, element.geometry, points))                     # (p, n, dim)
            q0 = body.element_e0[e].reshape(kind.n_shape, kind.dim)
            ds = np.linalg.norm(grads[:, :, along] @ q0, axis=1) * w * size / 2
            out[body.element_dofs[e]] += np.outer(values.T @ ds,
                                                  self.force_per_length).ravel()
        return out


LOADS: dict[str, type[Load]] = registry(PointForce, PointMoment, Gravity, LineForce)
