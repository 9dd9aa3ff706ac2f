"""Constraints of scenes (``[[constraint]]`` tables) on ANCF nodes.

A constraint either holds coordinates of one node (``NodeConstraint``: clamp, pin, a hub
whose rotation is prescribed; ``symmetry`` and ``fix``, which hold combinations of them:
``runtime.model.items.symmetry``) or ties two nodes together with joint rows solved
with Lagrange multipliers (``NodePair``; ``Joint``: spherical, revolute, weld, linear rows
``A q = 0`` and the revolute's quadratic ones; the prismatic, cylindrical and universal
joints of ``runtime.model.items.node_frame_joints``).  Each
class declares its TOML keys as fields (``runtime.model.schema.Record``) and implements its effect
on a model in ``apply``; adding one is one class here and one entry in ``CONSTRAINTS``
(``runtime.model.items.constraint_types``, which also holds the joints of rigid bodies).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from runtime.kernels.kind import ElementKind, is_first_gradient
from runtime.model.errors import SceneError, show
from runtime.model.holonomic import DrivenBlock, Driver, QuadraticBlock
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
    unit_axis,
)
from runtime.model.time_laws import Law

__all__ = ["Clamp", "Constraint", "HeldNodes", "Hub", "Joint", "NodeConstraint",
           "NodePair", "Pin", "Revolute", "Spherical", "Weld"]

# weld coefficients below this (relative to 1: the reference frames are unit) are the
# round-off of cosines of right angles, written as exact zeros
WELD_ZERO = 1e-12


@dataclass
class Built:
    """What the constraints of a model do to its ``size`` coordinates (``Constraint.apply``).

    fixed: (size,) bool, coordinates held at their initial values; hubs: (node, angle law,
    axis (3,)) of the nodes that follow a prescribed rigid rotation; rows: joint rows
    ``sum(coefficient * q[index]) = offset`` as {index: coefficient}, with ``offsets``
    {row: offset} where it is not 0 (units of the row: m or 1); blocks: quadratic
    constraint rows ``Phi(q) = 0`` (``runtime.model.holonomic``: rigid bodies, 3D joints)
    and rheonomic ones (prescribed joint motion).
    """

    fixed: np.ndarray
    hubs: list[tuple[int, Law, np.ndarray]] = field(default_factory=list)
    rows: list[dict[int, float]] = field(default_factory=list)
    offsets: dict[int, float] = field(default_factory=dict)
    blocks: list[QuadraticBlock | DrivenBlock] = field(default_factory=list)
    #: the driver coordinates of the constraint being applied (its ``drivers()``, in order)
    drivers: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))


@dataclass(frozen=True)
class Constraint(Record):
    """Base of the constraints."""

    def drivers(self) -> tuple[Driver, ...]:
        """The time coefficients of its rheonomic rows (``runtime.model.holonomic``): the
        model gives each a prescribed coordinate (``Built.drivers`` in ``apply``)."""
        return ()

    def apply(self, model: ModelView, built: Built) -> None:
        """Record the effect of this constraint on ``model``'s coordinates in ``built``."""
        raise NotImplementedError


class NodeSide:
    """A joint whose other side may be a node of a meshed body (its ``node``; None: the
    ground or a rigid body): the node is its scene target."""

    node: NodeRef | None

    def targets(self) -> list[NodeRef]:
        """The node it joins (its ``node``, if any)."""
        return [] if self.node is None else [self.node]


@dataclass(frozen=True)
class NodeConstraint(Constraint):
    """A constraint on one node (``"BODY:INDEX"``, or a NodeRef); ``holds_gradients``: it
    holds the node's gradients (``ElementKind.held_vectors``: the first gradients and the
    derivatives across the section, not a cable's curvature r_xx) as well as its position;
    ``holds_position``: it holds the whole position (not some components of it, as
    ``symmetry`` and ``fix``)."""

    holds_gradients: ClassVar[bool] = True
    holds_position: ClassVar[bool] = True
    node: NodeRef | str = key(node_key)

    def held(self, kind: ElementKind) -> int:
        """Number of coordinates it holds per node of ``kind``."""
        return len(kind.held_vectors) * kind.dim if self.holds_gradients else kind.dim

    def targets(self) -> list[NodeRef]:
        """The nodes it holds."""
        return [self.node]

    @property
    def target_key(self) -> str:
        """The key that names its nodes ("node", or "edge")."""
        return "node"


@dataclass(frozen=True)
class HeldNodes(NodeConstraint):
    """A constraint on one ``node`` or on every node of an ``edge`` of a rectangle body
    (``"BODY:x=0"``: exactly one of the two)."""

    node: NodeRef | str | None = key(node_key, None)
    edge: EdgeRef | str | None = key(edge_key, None)

    @classmethod
    def parse(cls, data: dict, path: str, context: Context) -> Record:
        given = [name for name in ("node", "edge") if name in data]
        if len(given) != 1:
            raise SceneError(f"{path}: expected either node = \"BODY:INDEX\" or edge = "
                             f"\"BODY:x=I\" (a grid line of a rectangle body), got "
                             f"{' and '.join(given) if given else 'neither'}")
        return super().parse(data, path, context)

    def targets(self) -> list[NodeRef]:
        return [self.node] if self.edge is None else self.edge.refs()

    @property
    def target_key(self) -> str:
        return "node" if self.edge is None else "edge"

    def apply(self, model: ModelView, built: Built) -> None:
        for ref in self.targets():
            node = model.node_index(ref)
            held = model.held_dofs(node) if self.holds_gradients else model.node_dofs(node, "r")
            built.fixed[held] = True


@dataclass(frozen=True)
class Clamp(HeldNodes):
    """Holds the position and the gradients of the node(s) (``ElementKind.held_vectors``;
    a quintic cable's curvature r_xx stays free: the clamped end bends)."""

    type: ClassVar[str] = "clamp"


@dataclass(frozen=True)
class Pin(HeldNodes):
    """Holds the position of the node(s); the gradients (the section) turn freely."""

    type: ClassVar[str] = "pin"
    holds_gradients: ClassVar[bool] = False


def _axis_key(value: Any, path: str, context: Context) -> tuple[float, ...]:
    return unit_axis(value, path)


@dataclass(frozen=True)
class Hub(NodeConstraint):
    """``prescribed_rotation``: the node is a rigid hub, its position held and its gradients
    turned by the angle ``angle(t)`` (rad, a time law) about the unit ``axis`` (3D only,
    default +z; None in 2D, where rotations are about z)."""

    type: ClassVar[str] = "prescribed_rotation"
    angle: Law | dict = key(law_key)
    axis: tuple[float, ...] | None = key(_axis_key, None, only_3d="a 2D rotation is about z")

    def resolved(self, context: Context) -> Hub:
        if context.dim == 3 and self.axis is None:
            return dataclasses.replace(self, axis=(0.0, 0.0, 1.0))
        return self

    def apply(self, model: ModelView, built: Built) -> None:
        built.hubs.append((model.node_index(self.node), self.angle,
                           np.asarray(self.axis or (0.0, 0.0, 1.0), float)))


def _nodes_key(value: Any, path: str, context: Context) -> tuple[NodeRef, NodeRef]:
    if not isinstance(value, list) or len(value) != 2:
        raise SceneError(f'{path}: expected two node references ["A:-1", "B:0"], got '
                         f"{show(value)}")
    a, b = context.node(value[0], f"{path}[0]"), context.node(value[1], f"{path}[1]")
    if a == b:
        raise SceneError(f"{path}: expected two different nodes, got {a} twice "
                         f"({show(value[0])} and {show(value[1])})")
    return a, b


@dataclass(frozen=True)
class NodePair(Constraint):
    """A joint between two distinct ``nodes`` (``"BODY:INDEX"``) of meshed bodies."""

    nodes: tuple[NodeRef | str, NodeRef | str] = key(_nodes_key)

    def rows(self, dim: int, per_node: int) -> int:
        """Number of joint rows (multipliers) it adds in a ``dim``-D scene, ``per_node``
        coordinates per node."""
        raise NotImplementedError

    def targets(self) -> list[NodeRef]:
        """The two nodes it joins."""
        return list(self.nodes)


@dataclass(frozen=True)
class Joint(NodePair):
    """A joint between two nodes at the same place in the reference: linear rows
    ``A q = 0`` (Lagrange multipliers).  This base ties the positions: r_A = r_B."""

    def rows(self, dim: int, per_node: int) -> int:
        return dim

    def apply(self, model: ModelView, built: Built) -> None:
        a, b = (model.node_dofs(model.node_index(n), "r") for n in self.nodes)
        built.rows.extend({i: 1.0, j: -1.0} for i, j in zip(a, b, strict=True))


def normals_of(axis: np.ndarray) -> np.ndarray:
    """Two unit vectors (2, 3) normal to the unit ``axis`` (3,) and to each other; in 2D
    (axis (2,)) the one (1, 2) that is the axis turned by +90 degrees."""
    if axis.size == 2:
        return np.array([[-axis[1], axis[0]]])
    helper = np.eye(3)[int(np.argmin(np.abs(axis)))]
    first = np.cross(axis, helper)
    first /= np.linalg.norm(first)
    return np.array([first, np.cross(axis, first)])


def gradient_map(model: ModelView, node: int, vector: np.ndarray,
                 what: str) -> tuple[np.ndarray, np.ndarray]:
    """(the node's coordinates (k,), map (dim, k)) of the fixed combination ``G c`` of a
    node's gradient vectors G that is ``vector`` (dim,) at the reference: it turns and
    stretches with the node's section.  SceneError (``what`` names the vector) when
    ``vector`` is not in the span of the node's gradients."""
    names = [name for name in model.node_vectors(node) if is_first_gradient(name)]
    gradients = np.array([model.reference[model.node_dofs(node, name)] for name in names]).T
    combination, *_ = np.linalg.lstsq(gradients, vector, rcond=None)
    if np.abs(gradients @ combination - vector).max() > 1e-9:
        raise SceneError(f"{what} {tuple(float(x) for x in vector)} is not a combination "
                         f"of the gradients {', '.join(names)} of the node (its section's "
                         "frame); choose an axis in it")
    dofs = model.node_dofs(node)
    dim = vector.size
    mapping = np.zeros((dim, dofs.size))
    for k, name in enumerate(names):
        start = model.node_vectors(node).index(name) * dim
        mapping[:, start:start + dim] += combination[k] * np.eye(dim)
    return dofs, mapping


@dataclass(frozen=True)
class Spherical(Joint):
    """Shared position, free relative rotation (a ball joint in 3D, a hinge in 2D)."""

    type: ClassVar[str] = "spherical"


@dataclass(frozen=True)
class Revolute(Joint):
    """A hinge: shared position, free relative rotation about z (2D) or about ``axis``
    (3D, default z): the axis a = G_A c as a fixed combination of the first node's gradients
    stays normal to two vectors b_k = G_B d_k of the second's, normal to it at the
    reference (two quadratic rows a . b_k = 0, bilinear in the nodes' coordinates;
    ``runtime.model.holonomic``)."""

    type: ClassVar[str] = "revolute"
    axis: tuple[float, ...] | None = key(_axis_key, None,
                                         only_3d="a 2D revolute joint turns about z")

    def resolved(self, context: Context) -> Revolute:
        if context.dim == 3 and self.axis is None:
            return dataclasses.replace(self, axis=(0.0, 0.0, 1.0))
        return self

    def rows(self, dim: int, per_node: int) -> int:
        return dim if dim == 2 else dim + 2

    def apply(self, model: ModelView, built: Built) -> None:
        super().apply(model, built)
        if model.dim == 2:
            return
        a, b = (model.node_index(n) for n in self.nodes)
        axis = np.asarray(self.axis, float)
        dofs_a, map_a = gradient_map(model, a, axis, "revolute: the axis")
        blocks = [gradient_map(model, b, normal, "revolute: the normal")
                  for normal in normals_of(axis)]
        dofs_b = blocks[0][0]
        joined = np.concatenate([dofs_a, dofs_b])
        n = dofs_a.size
        hessians = np.zeros((2, joined.size, joined.size))
        for k, (_, map_b) in enumerate(blocks):
            coupling = map_a.T @ map_b              # a . b_k = q_A^T (A^T B_k) q_B
            hessians[k, :n, n:] = coupling
            hessians[k, n:, :n] = coupling.T
        built.blocks.append(QuadraticBlock("revolute", joined, hessians,
                                           np.zeros((2, joined.size)), np.zeros(2)))


@dataclass(frozen=True)
class Weld(Joint):
    """A rigid connection: shared position, and the sections of the two nodes turn together.

    With G_A, G_B the (dim, dim) matrices of the nodes' reference gradients (columns r_x,
    r_y(, r_z)), the current gradients satisfy [r_B,x r_B,y ...] = [r_A,x r_A,y ...] C with
    the constant C = G_A^-1 G_B: both nodes share one deformation gradient F (r_k = F G[:, k]).
    In the reference this is r_B,k = R r_A,k with R = G_B G_A^-1 the fixed rotation between
    the two frames (an L-frame's corner: 90 degrees about z), and unlike R r_A,k it stays
    true when the welded assembly turns as a whole (rigid rotations leave it satisfied).
    Linear rows: dim for the position, dim per gradient (per_node rows in all).  This is the
    slope-discontinuity joint of Shabana & Mikkola (J. Mech. Des. 125, 2003); sharing F also
    ties the strains of the two end sections (stiffer than a beam-theory rigid joint by
    O(h^2 / (L l_element)), e.g. 0.1 % for the L-frame of scenes/l_frame.toml).
    """

    type: ClassVar[str] = "weld"

    def rows(self, dim: int, per_node: int) -> int:
        return per_node

    def apply(self, model: ModelView, built: Built) -> None:
        super().apply(model, built)
        dim = model.dim
        a, b = (model.node_index(n) for n in self.nodes)
        gradients = [name for name in model.node_vectors(a) if is_first_gradient(name)]

        def coordinates(node: int) -> np.ndarray:   # (gradients, dim) global indices
            return np.array([model.node_dofs(node, name) for name in gradients])

        ia, ib = coordinates(a), coordinates(b)
        ga, gb = model.reference[ia].T, model.reference[ib].T
        coupling = np.linalg.solve(ga, gb)
        coupling[np.abs(coupling) < WELD_ZERO] = 0.0
        for k in range(len(gradients)):
            for c in range(dim):
                row = {int(ia[m, c]): float(coupling[m, k]) for m in range(len(gradients))
                       if coupling[m, k] != 0.0}
                row[int(ib[k, c])] = -1.0
                built.rows.append(row)
