"""The bodies and materials of a scene: ``[material.NAME]`` and ``[[body]]`` tables as frozen
dataclasses.  A body is a mesh of elements of one kind, placed in space by its placement
(``runtime.model.placements``); it writes its TOML table back (``to_dict``)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from runtime.kernels.kind import element_kind
from runtime.model import mesh as meshing
from runtime.model.mesh_file import FileMesh
from runtime.model.placements import Arc, Box, Line, Placement, Rectangle
from runtime.model.schema import plain, table


@dataclass(frozen=True)
class Material:
    """Elastic material ``name``: E (Pa) > 0, -1 < nu < 0.5, rho (kg/m^3) > 0.

    law: ``svk`` (St. Venant-Kirchhoff) or another law of docs/laws.md (``ecm``, elastic
    continuum mechanics with a shear correction; ``svk_sri`` for plates and shells, ...);
    shear_correction: the ecm shear correction factor (> 0), None for the default (always
    None with svk and svk_sri); damping: Kelvin-Voigt coefficient alpha (s) >= 0, 0 for none.
    In TOML the name is the key of the table ``[material.NAME]``.
    """

    name: str
    E: float
    nu: float
    rho: float
    law: str = "svk"
    shear_correction: float | None = None
    damping: float = 0.0

    def to_dict(self) -> dict[str, Any]:
        """The TOML table ``[material.NAME]`` (without the name)."""
        return table(self, skip=("name",))


@dataclass(frozen=True)
class Spin:
    """A rigid rotation at the angular velocity ``omega`` (rad/s: a number, about +z, in 2D;
    a vector (3,) in 3D) about the point ``about`` (dim,) in m."""

    omega: float | tuple[float, ...]
    about: tuple[float, ...]

    def to_dict(self) -> dict[str, Any]:
        """The TOML table ``initial_angular_velocity = {...}``."""
        return table(self)


@dataclass(frozen=True)
class Body:
    """A mesh of elements of kind ``element`` sharing nodes (placed and numbered by the kind's
    node layout: ``n_nodes`` of them, see ``runtime.model.mesh``).

    Beam kinds (a line of ``elements`` elements): section ``height`` and ``width`` (m; TOML
    ``section = {height, width}``), either ``start``/``end`` (dim,) in m (straight) or
    ``arc``.  Plate kinds: ``rectangle`` (its grid sets ``elements``) and ``thickness`` (m;
    TOML ``section = {thickness}``).  Solid kinds (meshing three axes): ``box`` (its grid sets
    ``elements``; no section).  Beam and plate kinds may instead be meshed from a file,
    ``mesh_file`` (TOML ``mesh = {file = "part.msh"}``, in Python the path or a
    ``FileMesh``: ``runtime.model.mesh_file``; its cells set ``elements``).  material: the
    name of a material of the scene; quadrature: Gauss orders (dim,) or None for the kind's
    default.  Initial conditions (velocities at t = 0, zero where absent):
    ``initial_velocity`` (dim,) in m/s, a uniform translation, plus
    ``initial_angular_velocity``, a rigid ``Spin``.
    """

    name: str
    element: str
    material: str
    height: float | None = None
    width: float | None = None
    elements: int | None = None
    start: tuple[float, ...] | None = None
    end: tuple[float, ...] | None = None
    arc: Arc | None = None
    quadrature: tuple[int, ...] | None = None
    initial_velocity: tuple[float, ...] | None = None
    initial_angular_velocity: Spin | None = None
    rectangle: Rectangle | None = None
    thickness: float | None = None
    box: Box | None = None
    mesh_file: FileMesh | str | None = None

    @property
    def dim(self) -> int:
        """Spatial dimension of the element kind (2 or 3)."""
        return element_kind(self.element).dim

    @property
    def placement(self) -> Placement:
        """Where the body lies: its rectangle, its box, its arc, or the line from start to end
        (the one place that tells them apart), or the mesh file."""
        if self.mesh_file is not None:
            return self.mesh_file
        if self.rectangle is not None:
            return self.rectangle
        if self.box is not None:
            return self.box
        return self.arc if self.arc is not None else Line(self.start, self.end)

    @property
    def counts(self) -> tuple[int, ...]:
        """Elements along each meshed axis: (elements,) for a line, the grid for a rectangle."""
        return self.placement.counts(self.elements)

    @property
    def grid_shape(self) -> tuple[int, ...]:
        """Points of the node lattice along each meshed axis (``runtime.model.mesh``): (nodes,)
        for a line, (columns along x, rows along y) for a rectangle; with mid-side nodes the
        lattice has two steps per element; none for a mesh from a file."""
        if self.mesh_file is not None:
            return ()
        return meshing.lattice_shape(element_kind(self.element), self.counts)

    @property
    def n_nodes(self) -> int:
        """Number of nodes: elements + 1 for 2-node beams, 2 elements + 1 for 3-node beams,
        (nx + 1)(ny + 1) for 4-node plates, what the layout places for others (computed
        without meshing; those a mesh file's cells use)."""
        if self.mesh_file is not None:
            return len(self.mesh_file.data.positions)
        return meshing.node_count(element_kind(self.element), self.counts)

    @property
    def mesh(self) -> meshing.Mesh:
        """The body's mesh: structured (built once per kind and counts) or read from its file
        (``points`` are then the node positions in m, with no lattice)."""
        if self.mesh_file is not None:
            return self.mesh_file.data.mesh
        return meshing.structured_mesh(element_kind(self.element), self.counts)

    @property
    def solid(self) -> bool:
        """Whether the body's kind meshes every axis (a brick: a box or a file of boxes)."""
        return len(element_kind(self.element).mesh_axes) == 3

    @property
    def section(self) -> tuple[float, ...]:
        """The section sizes (m) across the meshed axes: (height, width) of a beam, the
        thickness of a plate, none for a solid (its elements' sides are the geometry)."""
        if self.box is not None or self.solid:
            return ()
        return (self.thickness,) if self.thickness is not None else (self.height, self.width)

    @property
    def geometry(self) -> tuple[float, float, float]:
        """The element's (length, height, width) as ``runtime.Element`` takes them: the
        element's sides a, b and the thickness for a plate."""
        return (*self.placement.element_sides(self.counts), *self.section)

    @property
    def shapes(self) -> np.ndarray:
        """The shape of each element (elements,): elements of one index are rigid placements
        of one another and share one set of invariants (all 0 but in a mesh file's body)."""
        if self.mesh_file is not None:
            return self.mesh_file.data.shapes
        return np.zeros(math.prod(self.counts), np.int64)

    @property
    def node_sets(self) -> dict:
        """The named node sets of a mesh file, {name: node indices}; none otherwise."""
        return self.mesh_file.data.node_sets if self.mesh_file is not None else {}

    def node_position(self, index: int) -> tuple[float, ...]:
        """Reference position (m) of node ``index``, as the model meshes the body."""
        return self.placement.node_position(tuple(self.mesh.points[index]), self.counts)

    def to_dict(self) -> dict[str, Any]:
        """The TOML table ``[[body]]``: what the body was given, so that the parser rejects
        what does not fit its kind (a plate's height, a beam's thickness, a plate's
        elements beside its grid)."""
        section = {"height": self.height, "width": self.width, "thickness": self.thickness}
        given = {k: v for k, v in section.items() if v is not None}
        head = {"name": self.name, "element": self.element, "material": self.material,
                **({"section": given} if given or not (self.box or self.solid) else {})}
        # a grid sets its elements (written only when they disagree: an error)
        grid = getattr(self.rectangle or self.box, "grid", None)
        if self.elements is not None and (grid is None or self.elements != math.prod(grid)) \
                and self.mesh_file is None:
            head["elements"] = self.elements
        if self.mesh_file is not None:   # a path given in Python: its table
            head["mesh"] = (self.mesh_file.to_dict() if isinstance(self.mesh_file, FileMesh)
                            else {"file": self.mesh_file})
        return {**plain(head),
                **table(self, skip=(*head, *section, "elements", "mesh_file"))}
