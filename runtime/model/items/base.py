"""The narrow interface between the items of a scene (constraints, loads, sensors) and the model
they contribute to.  Items receive a ``ModelView`` and ask it only what is declared here
(node indices and coordinates, frames, the reference, mass, energies); ``runtime.model.model``
implements it.  Items never import the model.
"""

from __future__ import annotations

from typing import Any, Protocol

import numpy as np
import scipy.sparse

from runtime.element.element import Element
from runtime.kernels.kind import ElementKind
from runtime.model.mesh import Mesh
from runtime.model.schema import NodeRef


class BodyView(Protocol):
    """One meshed body of the model: its kind, its element group, its mesh, and per element
    the reference coordinates ``element_e0`` (elements, ndof) and global coordinate indices
    ``element_dofs`` (elements, ndof)."""

    element: Element
    mesh: Mesh
    element_e0: np.ndarray
    element_dofs: np.ndarray

    @property
    def kind(self) -> ElementKind: ...


class ModelView(Protocol):
    """What an item may ask of the model: sizes (``dim``, ``size`` coordinates), the reference
    coordinates (size,), the indices of the ``free`` coordinates (neither fixed nor
    prescribed), the mass matrix (size, size) in kg, the joint rows ``A`` of ``A q = b``
    (rows, size), the bodies by name, the scene it was built from, and the queries below.
    Units SI."""

    dim: int
    size: int
    reference: np.ndarray
    free: np.ndarray
    mass: scipy.sparse.csr_matrix
    joints: scipy.sparse.csr_matrix
    #: b of the joint rows A q = b (rows,)
    joint_offsets: np.ndarray
    #: the quadratic constraint rows Phi(q) = 0 (``runtime.model.holonomic``)
    holonomic: Any
    #: per scene constraint, the indices of its multipliers in [joints; quadratic rows]
    constraint_multipliers: list
    bodies: dict[str, BodyView]
    scene: Any
    dissipated_energy: float
    #: the torsional springs' joint angles (rad, turns counted) by scene load index, or None
    spring_angles: np.ndarray | None
    #: the rigid bodies and point masses (``RigidCoordinates``: ``item``, ``dofs``) by name
    rigid: dict[str, Any]

    def rigid_point(self, name: str, point: tuple[float, ...]) -> tuple[np.ndarray, np.ndarray]:
        """(coordinates (k,), map (dim, k)) of the position of a rigid item's body point."""

    def node_index(self, ref: NodeRef) -> int:
        """Global node index of a scene node reference."""

    def node_vectors(self, node: int) -> tuple[str, ...]:
        """Names of the nodal vectors of a global node (``("r", "r_x", ...)``)."""

    def node_dofs(self, node: int, vector: str | None = None) -> np.ndarray:
        """Coordinates of a node (all, or one nodal vector such as "r")."""

    def held_dofs(self, node: int) -> np.ndarray:
        """Coordinates of a node that a clamp holds (``ElementKind.held_vectors``)."""

    def node_frame(self, q: np.ndarray, node: int) -> np.ndarray:
        """Orthonormal frame (dim, dim) of a node's gradients at coordinates ``q``."""

    def rigid_field(self, translation=None, rotation=None, about=None) -> np.ndarray:
        """Coordinates (size,) of a rigid motion field (see ``Model.rigid_field``)."""

    def strain_energy(self, q: np.ndarray, body: str | None = None) -> float:
        """Strain energy (J) of the model (or of one body) at ``q``."""

    def kinetic_energy(self, v: np.ndarray, body: str | None = None) -> float:
        """Kinetic energy (J) of the model (or of one body) at velocities ``v``."""

    def gravity_potential(self, q: np.ndarray, t: float | None = 0.0) -> float:
        """Potential energy (J) of the gravity loads at ``q`` and time ``t``."""

    def spring_energy(self, q: np.ndarray, t: float | None = 0.0,
                      angles: np.ndarray | None = None) -> float:
        """Energy (J) stored in the springs of the force elements (spring-dampers, torsional
        springs, bushings) at ``q`` and time ``t``, the torsional springs' angles near
        ``angles`` (turns counted)."""
