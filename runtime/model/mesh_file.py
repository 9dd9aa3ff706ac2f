"""Bodies whose mesh is read from a file through meshio: ``mesh = { file = "part.msh" }`` in
a ``[[body]]`` table (the path relative to the scene file).  docs/design.md, section 9,
"Meshes from files", says what the file must hold.

* **Cells**: those of the kind's meshed dimension (lines for beams and cables, surfaces for
  plates and shells, volumes for bricks: boxes of one common frame) make the body, all of one
  type, the type whose nodes are the kind's node layout (``CELL_NODES``: ``line`` for
  2-node beams, ``line3`` for 3-node beams, ``quad`` for plate3d, ``quad8`` for the 8-node
  shells; ``hexahedron`` for a solid kind with a corner layout).  Cells of other dimensions
  only name sets.  Each cell's nodes are reordered from meshio's (VTK's) order to the kind's
  (line3's middle node comes last in meshio, second in a 3-node beam).
* **Nodes**: the file's points that the body's cells use, in the file's order (node k of the
  body is the k-th such point; every point used: the file's own numbering).
* **Sets** (targets ``"BODY:NAME"``): meshio cell sets; gmsh physical groups (cell data
  ``gmsh:physical`` with their names in ``field_data``); point data and cell data arrays of
  0 and 1 (one value per point or cell, 1 marking the members: VTU).  A set of cells names
  the nodes of its cells.
* **Normals**: a point data array ``normal`` (points, 3) gives the shells' r_z at the nodes
  (normalised), instead of the surface's own (``runtime.model.mesh_geometry``).

The reference configuration is computed once per file, kind and modification time.
"""

from __future__ import annotations

import contextlib
import functools
import io
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from runtime.element.element import MAGNITUDE
from runtime.kernels.kind import ElementKind, element_kind
from runtime.model import mesh_geometry as geometry
from runtime.model.errors import SceneError, show
from runtime.model.mesh import Mesh
from runtime.model.placements import Placement
from runtime.model.schema import in_range, keys, string

#: meshio cell types by topological dimension and their nodes' local coordinates (fractions
#: of the element's extent along the meshed axes, in meshio's node order)
CELL_NODES: dict[str, tuple[tuple[float, ...], ...]] = {
    "line": ((0,), (1,)),
    "line3": ((0,), (1,), (0.5,)),
    "quad": ((0, 0), (1, 0), (1, 1), (0, 1)),
    "quad8": ((0, 0), (1, 0), (1, 1), (0, 1), (0.5, 0), (1, 0.5), (0.5, 1), (0, 0.5)),
    "quad9": ((0, 0), (1, 0), (1, 1), (0, 1), (0.5, 0), (1, 0.5), (0.5, 1), (0, 0.5),
              (0.5, 0.5)),
    "hexahedron": ((0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1),
                   (1, 1, 1), (0, 1, 1)),
}
#: topological dimension of meshio's cell types (those not listed are ignored)
CELL_DIMENSION = {"vertex": 0, "line": 1, "line3": 1, "line4": 1, "triangle": 2,
                  "triangle6": 2, "triangle7": 2, "quad": 2, "quad8": 2, "quad9": 2,
                  "polygon": 2, "tetra": 3, "tetra10": 3, "hexahedron": 3,
                  "hexahedron20": 3, "hexahedron27": 3, "wedge": 3, "pyramid": 3}
#: the point data array that gives shell normals
NORMAL_ARRAY = "normal"


@dataclass(frozen=True)
class MeshData:
    """A mesh file read for one kind: node ``positions`` (nodes, dim) in m, the structured
    ``mesh`` (connectivity in the kind's node order), the element references ``e0s``
    (elements, ndof), element ``sides`` (elements, mesh axes) in m, ``shapes`` (elements,)
    the index of each element's shape (``mesh_geometry.shape_groups``), the node sets and
    element sets by name (node and element indices of the body), the ``cell_type`` read."""

    positions: np.ndarray
    mesh: Mesh
    e0s: np.ndarray
    sides: np.ndarray
    shapes: np.ndarray
    node_sets: dict[str, np.ndarray]
    element_sets: dict[str, np.ndarray]
    cell_type: str


@dataclass(frozen=True)
class FileMesh(Placement):
    """A mesh read from ``file`` (as the scene writes it, relative to the scene's folder) for
    elements of ``kind``; ``data`` holds what was read (not compared: two bodies of one file
    are equal)."""

    keys: ClassVar[tuple[str, ...]] = ("mesh",)
    count_key: ClassVar[str] = "mesh"

    file: str
    kind: str = field(compare=False)
    data: MeshData = field(compare=False, repr=False)

    @classmethod
    def parse(cls, value: Any, path: str, kind: str, folder: str | None) -> FileMesh:
        """The mesh of the table ``mesh = {file = "..."}`` ``value`` at ``path``, read for
        ``kind`` (``folder``: the scene file's folder, None for the working directory)."""
        table = keys(value, path, ("file",), (), 'a table {file = "part.msh"}')
        name = string(table["file"], f"{path}.file")
        resolved = (Path(folder) if folder else Path.cwd()) / name
        if not resolved.is_file():
            raise SceneError(f"{path}.file: no mesh file {show(name)} (looked for "
                             f"{resolved}); expected a path relative to the scene file")
        stat = resolved.stat()
        try:
            data = _read(str(resolved.resolve()), stat.st_mtime_ns, stat.st_size, kind)
        except SceneError as error:
            raise SceneError(f"{path}.file: {show(name)}: {error}") from None
        return cls(name, kind, data)

    def to_dict(self) -> dict[str, Any]:
        """The TOML table ``mesh = {...}``."""
        return {"file": self.file}

    def counts(self, elements: int | None) -> tuple[int, ...]:
        return (len(self.data.e0s),)

    def element_sides(self, counts: tuple[int, ...]) -> tuple[float, ...]:
        """The elements' common parameter extents (m): those of every element where the
        kind's nodes carry gradients along the mesh (``check_shapes`` makes them congruent);
        else the mean sides (the interpolated geometry does not depend on them)."""
        return tuple(float(s) for s in self.data.sides.mean(axis=0))

    def check_counts(self, counts: tuple[int, ...], path: str) -> None:
        """Element sizes are checked when the file is read."""

    def node_position(self, point: tuple[float, ...], counts: tuple[int, ...]
                      ) -> tuple[float, ...]:
        return tuple(float(x) for x in point)

    def extent(self) -> float:
        return float(np.abs(self.data.positions).max())

    def element_references(self, kind: ElementKind, counts: tuple[int, ...]) -> np.ndarray:
        return self.data.e0s


class _Problem(SceneError):
    """A fault of the file's content (the caller prefixes the key path and file name)."""


def _load(path: str):
    """The meshio mesh of ``path``; _Problem when meshio cannot read it (its own messages
    on stderr are kept out of the run's)."""
    import meshio

    captured = io.StringIO()
    try:
        with contextlib.redirect_stderr(captured), contextlib.redirect_stdout(captured):
            return meshio.read(path)
    except (Exception, SystemExit) as error:   # meshio's VTU reader exits on bad XML
        said = str(error) if not isinstance(error, SystemExit) else ""
        said = said or captured.getvalue().strip().splitlines()[-1:] or [type(error).__name__]
        said = said if isinstance(said, str) else said[0]
        if "not found" in said and Path(path).is_file():
            said = f"unknown mesh format {Path(path).suffix!r}"
        raise _Problem(f"cannot read the mesh ({said}); expected a mesh file meshio reads "
                       "(gmsh .msh, VTK .vtu/.vtk, Abaqus .inp, ...)") from None


def fitting_cell(kind: ElementKind) -> str | None:
    """The meshio cell type whose nodes are the kind's node layout (None if none is)."""
    axes = kind.mesh_axes
    points = {tuple(round(float(f), 9) for f in row) for row in kind.node_fractions[:, axes]}
    for name, nodes in CELL_NODES.items():
        if len(nodes[0]) == len(axes) and {tuple(map(float, p)) for p in nodes} == points:
            return name
    return None


def node_order(kind: ElementKind, cell: str) -> np.ndarray:
    """For each node of the kind (its order), the index of the cell's node at the same
    local point (meshio's order): line3 -> a 3-node beam is [0, 2, 1]."""
    nodes = np.array(CELL_NODES[cell], float)
    fractions = kind.node_fractions[:, kind.mesh_axes]
    return np.array([int(np.flatnonzero(np.all(np.isclose(nodes, f), axis=1))[0])
                     for f in fractions])


@functools.lru_cache(maxsize=16)
def _read(path: str, mtime: int, size: int, kind_name: str) -> MeshData:
    """The mesh file ``path`` (its modification time and size key the cache) read for
    ``kind_name``; _Problem naming what is wrong with its content."""
    kind = element_kind(kind_name)
    mesh = _load(path)
    dimension = len(kind.mesh_axes)
    fit = fitting_cell(kind)
    blocks = [(i, b) for i, b in enumerate(mesh.cells)
              if CELL_DIMENSION.get(b.type) == dimension and len(b.data)]
    types = sorted({b.type for _, b in blocks})
    at = ", ".join("(" + ", ".join(f"{c:g}" for c in p) + ")" for p in CELL_NODES.get(fit, ()))
    wanted = (f"{kind.name} takes {fit} cells (its {kind.n_nodes} nodes at {at} of the cell, "
              "in meshio's order)" if fit else
              f"no meshio cell type has the node layout of {kind.name}")
    if not types:
        found = ", ".join(sorted({b.type for b in mesh.cells})) or "none"
        raise _Problem(f"no cells of a usable type: {wanted}; the file has cells {found}")
    if len(types) > 1:
        raise _Problem(f"mixed cell types {', '.join(types)}; a body is one kind of element: "
                       f"{wanted} (one body per cell type)")
    if types[0] != fit:
        raise _Problem(f"{types[0]} cells do not fit {kind.name}: {wanted}")
    order = node_order(kind, fit)
    cells = np.concatenate([b.data[:, order] for _, b in blocks]).astype(np.int64)
    used, connectivity = np.unique(cells, return_inverse=True)
    connectivity = connectivity.reshape(cells.shape)
    points = np.asarray(mesh.points, float)
    if points.shape[1] < kind.dim or not np.isfinite(points).all():
        raise _Problem(f"expected finite points with {kind.dim} coordinates, got an array "
                       f"of shape {points.shape}")
    extra = points[used, kind.dim:]
    if extra.size and np.abs(extra).max() > 0:
        raise _Problem(f"{kind.name} is {kind.dim}D; expected points at z = 0, got z up to "
                       f"{np.abs(extra).max():.3g} m")
    positions = points[used, :kind.dim]
    if np.abs(positions).max() > MAGNITUDE:
        raise _Problem(f"expected coordinates of at most {MAGNITUDE:g} m in magnitude")
    normals = _normals(mesh, used, kind)
    try:
        if dimension == 1:
            connectivity, e0s, lengths = geometry.line_references(kind, positions,
                                                                  connectivity)
            sides = lengths[:, None]
        elif dimension == 2:
            e0s, sides = geometry.surface_references(kind, positions, connectivity, normals)
        else:
            e0s, sides = geometry.solid_references(kind, positions, connectivity)
    except geometry.MeshGeometryError as error:
        raise _Problem(str(error)) from None
    for side in sides.ravel():
        in_range(float(side), "element sides", "element sides in m")
    node_sets, element_sets = _sets(mesh, used, blocks, len(cells))
    structured = Mesh(positions, np.zeros((len(positions), 0), np.int64), connectivity)
    for array in (structured.points, structured.connectivity, e0s, sides):
        array.flags.writeable = False
    return MeshData(positions, structured, e0s, sides, geometry.shape_groups(kind, e0s),
                    node_sets, element_sets, fit)


def _normals(mesh, used: np.ndarray, kind: ElementKind) -> np.ndarray | None:
    """The unit normals (nodes, 3) of the point data array ``normal``, if the file has one."""
    if NORMAL_ARRAY not in mesh.point_data:
        return None
    normals = np.asarray(mesh.point_data[NORMAL_ARRAY], float)
    if len(kind.mesh_axes) != 2 or normals.shape != (len(mesh.points), 3):
        raise _Problem(f"point data {NORMAL_ARRAY!r}: expected the unit normals (points, 3) "
                       f"of a surface mesh, got an array of shape {normals.shape} for "
                       f"{kind.name}")
    normals = normals[used]
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    if not np.isfinite(normals).all() or length.min() == 0:
        raise _Problem(f"point data {NORMAL_ARRAY!r}: expected non-zero finite normals")
    return normals / length


def _flags(values: Any) -> np.ndarray | None:
    """The members (a boolean array) of an array of 0 and 1 (None for any other array)."""
    array = np.asarray(values)
    if array.ndim != 1 or array.dtype.kind not in "biu" or not array.size:
        return None
    if not np.isin(array, (0, 1)).all():
        return None
    return array.astype(bool)


def _sets(mesh, used: np.ndarray, blocks: list, elements: int
          ) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """Node sets and element sets by name (body node and element indices, sorted): see the
    module docstring for where they come from."""
    body_node = np.full(len(mesh.points), -1)
    body_node[used] = np.arange(len(used))
    first = {}   # the body element index of each body block's first cell
    count = 0
    for i, block in blocks:
        first[i] = count
        count += len(block.data)
    cells: dict[str, list[tuple[int, np.ndarray]]] = {}   # name -> (block, cell indices)
    for name, per_block in mesh.cell_sets.items():
        for i, members in enumerate(per_block):
            if members is not None and len(members):
                cells.setdefault(name, []).append((i, np.asarray(members, np.int64)))
    names = {int(tag): name for name, (tag, *_) in mesh.field_data.items()
             if np.ndim(mesh.field_data[name]) == 1}
    for array, per_block in mesh.cell_data.items():
        if array == "gmsh:physical":
            for i, tags in enumerate(per_block):
                for tag in np.unique(tags):
                    if int(tag) in names:
                        cells.setdefault(names[int(tag)], []).append(
                            (i, np.flatnonzero(tags == tag)))
            continue
        flags = [_flags(values) for values in per_block]
        if all(f is not None for f in flags):
            for i, f in enumerate(flags):
                if f.any():
                    cells.setdefault(array, []).append((i, np.flatnonzero(f)))
    node_sets: dict[str, np.ndarray] = {}
    element_sets: dict[str, np.ndarray] = {}
    for name, members in cells.items():
        points = np.concatenate([mesh.cells[i].data[m].ravel() for i, m in members])
        node_sets[name] = np.unique(body_node[points])
        own = [first[i] + m for i, m in members if i in first]
        if own:
            element_sets[name] = np.unique(np.concatenate(own))
    for name, values in mesh.point_data.items():
        flags = _flags(values)
        if flags is not None and name not in node_sets:
            node_sets[name] = np.unique(body_node[np.flatnonzero(flags)])
    return ({name: nodes[nodes >= 0] for name, nodes in node_sets.items()},
            element_sets)


def check_shapes(mesh: FileMesh, path: str) -> None:
    """SceneError unless the elements of a kind that carries gradients along the mesh (r_x
    of a 2-node beam or a cable, r_x and r_y of plate3d) all have one shape: their
    parameter extents must be the true lengths (unit r_x), one per body.  Kinds carrying
    only the position and gradients across (3-node beams, 8-node shells) take any shapes,
    one element group each."""
    kind = element_kind(mesh.kind)
    shapes = mesh.data.shapes
    if geometry.carries_in_plane_gradients(kind) and shapes.max() > 0:
        other = int(np.flatnonzero(shapes > 0)[0])
        raise SceneError(f"{path}.file: {show(mesh.file)}: its elements have {shapes.max() + 1} "
                         f"different shapes (element {other} is not a rigid placement of "
                         f"element 0); {kind.name} nodes carry "
                         f"{', '.join(kind.vectors[1:])}, derivatives along the mesh whose "
                         f"length follows the element's, so its elements must be congruent "
                         f"(equal lengths: a uniform line or arc, a flat grid of equal "
                         f"rectangles); for other meshes use a kind that carries the position "
                         f"only along the mesh (beam3d_3node, shell3d_8node, shell3d_3833)")
