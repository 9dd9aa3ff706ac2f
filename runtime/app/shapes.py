"""Deformed shapes of a model: beams' centre lines, plates' mid-surfaces, ParaView files, an
animation.

An element's position field is ``r(p) = S(p) e`` at local points ``p`` of its reference
domain, with the shape functions ``S`` of the element kind (the generated ``shape_values``
kernel of its invariants family).  :class:`Shape` samples it on a small grid per element over
the axes the kind's mesh tiles (``ElementKind.mesh_axes``), at the middle of the other axes: the
centre line ``r(x, 0[, 0])`` of a beam, the mid-surface ``r(x, y, 0)`` of a plate or shell, the
volume of a solid.  The grid
holds the element's nodes, so every model node is a sample point.  Displacements, velocities
and mode shapes (all linear in the coordinates) are sampled the same way.

Writers (all atomic, a write error is :class:`runtime.app.writers.OutputError`):

* :func:`write_vtu` - one VTU file (meshio): line cells for beams, quad cells for plates and
  shells, hexahedra for solids, point data ``displacement`` (m), ``velocity`` (m/s), strain
  and stress (:meth:`Shape.fields`), or any arrays given (points at the reference
  configuration: Warp By Vector applies the displacement once);
* :func:`write_pvd` - a ParaView collection of VTU files with their times;
* :class:`VtkSeries` - a run observer writing ``vtk/dynamic_NNNNNN.vtu`` at every output time
  and ``vtk/dynamic.pvd``, plus ``vtk/static.vtu`` and ``vtk/mode_K.vtu`` / ``vtk/modes.pvd``;
* :class:`Frames` (a run observer) and :func:`write_animation` - a GIF of the deformed shape
  projected on a plane; :func:`write_snapshot` - a PNG of one state against the reference.
  Both draw the element edges (:attr:`Shape.outline`): a beam's centre line, the wireframe
  of a plate's or a solid's elements.
"""

from __future__ import annotations

import os
import textwrap
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from runtime.app import writers as output
from runtime.app.result import Modes, Observer
from runtime.kernels.kind import ElementKind
from runtime.kernels.loader import kernel_family
from runtime.model.items import material_points as material
from runtime.model.items.rigid import natural_map
from runtime.model.model import BodyMesh, Model
from runtime.progress import Bar

__all__ = ["PLANES", "Frames", "Shape", "VtkSeries", "magnification", "write_animation",
           "write_pvd", "write_snapshot", "write_vtu"]

#: sample intervals per element along each meshed axis (more where nodes fall between them)
PER_ELEMENT = 4
#: projections of the animation and snapshot: plane name -> (horizontal, vertical) axes
PLANES = {"xy": (0, 1), "xz": (0, 2), "yz": (1, 2)}
#: frames of an animation at most (output times are subsampled evenly beyond)
MAX_FRAMES = 100
#: VTK cell of a sample grid by the number of meshed axes (beams 1, plates 2, bricks 3)
CELL_TYPES = {1: "line", 2: "quad", 3: "hexahedron"}
#: the edges of a box of corners numbered as ``RigidBody.extent`` (VTK hexahedron order), as
#: one polyline through every edge (some twice)
_BOX_EDGES = np.array([0, 1, 2, 3, 0, 4, 5, 6, 7, 4, 5, 1, 2, 6, 7, 3])
#: sample points are matched on a grid of 2**-20 element units (as meshing.structured_mesh)
_KEY = 2**20


class Shape:
    """The sampled shape of every body of ``model``: a grid of at least ``per_element``
    intervals per element along each meshed axis, refined to hold the element's nodes
    (a 3-node beam with ``per_element`` 3 samples x / l = 0, 1/3, 1/2, 2/3, 1).

    ``points``: number of sample points (bodies one after the other; within a body a point
    shared by elements is one point, numbered along x, then y); ``cells``: ``[(type,
    (cells, corners) point indices)]`` per VTK cell type (``CELL_TYPES``), as meshio takes
    them; ``node_points`` (nodes,): the sample point at each model node, in node order;
    ``outline`` (k,): point indices of the element edges as polylines separated by -1 (a
    beam body's centre line is one polyline, each plate element a closed loop).
    """

    def __init__(self, model: Model, per_element: int = PER_ELEMENT) -> None:
        self.dim = model.dim
        # per body: element dofs (m, ndof), shape values (samples, n_shape), sample points
        # (m, samples)
        self._bodies = []
        # per body: the body, the local sample coordinates (samples, dim) in m, sample points
        self._fields: list[tuple[BodyMesh, np.ndarray, np.ndarray]] = []
        cells: dict[str, list[np.ndarray]] = {}
        outline, node_points, first = [], [], 0
        for body in model.bodies.values():
            kind = body.kind
            axes = kind.mesh_axes
            if len(axes) not in CELL_TYPES:
                raise ValueError(f"shape: cannot draw {kind.name}, meshed over {len(axes)} "
                                 f"axes (meshes over 1 to 3 axes are drawn)")
            fractions = _sample_fractions(kind, axes, per_element)
            local = _grid(fractions)                                # (samples, axes)
            coordinates = _local_points(body, axes, local)
            values = _shape_values(body, coordinates)
            count, points, nodes = (_sample_points(body, axes, local) if body.mesh.lattice.size
                                    or not len(body.mesh.points)
                                    else _matched_points(body, values))
            self._bodies.append((body.element_dofs, values, first + points))
            self._fields.append((body, coordinates, first + points))
            corners = _grid_cells(fractions)                        # (cells, corners)
            cells.setdefault(CELL_TYPES[len(axes)], []).append(
                (first + points[:, corners]).reshape(-1, corners.shape[1]))
            outline += _polylines(first + points[:, _grid_loop(fractions)])
            node_points.append(first + nodes)
            first += count
        # per 2D rigid body: its coordinates (k,), the maps (corners, 2, k) of its corners
        # (``natural_map``: v = perp(u) is no coordinate, so no weights), their points
        self._planar: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
        for rigid in model.rigid.values():    # rigid bodies: their box (hexahedron; a
            if not hasattr(rigid.item, "extent"):                   # rectangle in 2D)
                continue
            corners = rigid.item.extent()                # (8, 3) | (4, 2) body coordinates
            points = first + np.arange(len(corners))[None, :]
            if model.dim == 3:
                values = np.column_stack([np.ones(8), corners])     # natural_map's weights
                self._bodies.append((rigid.dofs[None, :], values, points))
                outline += _polylines(points[:, _BOX_EDGES])
            else:
                self._planar.append((rigid.dofs, np.array([natural_map(c) for c in corners]),
                                     points[0]))
                outline += _polylines(points[:, [0, 1, 2, 3, 0]])
            cells.setdefault(CELL_TYPES[model.dim], []).append(points)
            first += len(corners)
        self.points = first
        self.cells = [(name, np.concatenate(blocks)) for name, blocks in cells.items()]
        self.node_points = np.concatenate(node_points) if node_points else np.zeros(0, int)
        self.outline = np.concatenate([np.append(line, -1) for line in outline])[:-1]

    def sample(self, q: np.ndarray) -> np.ndarray:
        """(points, 3) sampled vectors of coordinates ``q`` (size,): positions (m) for
        positions, velocities (m/s) for velocities (z = 0 in 2D)."""
        result = np.zeros((self.points, 3))
        for dofs, values, points in self._bodies:
            e = q[dofs].reshape(dofs.shape[0], values.shape[1], self.dim)
            samples = np.einsum("pk,mkd->mpd", values, e)       # (elements, samples, dim)
            result[points.ravel(), :self.dim] = samples.reshape(-1, self.dim)
        for dofs, maps, points in self._planar:
            result[points, :2] = maps @ q[dofs]
        return result

    def fields(self, q: np.ndarray) -> dict[str, np.ndarray]:
        """Strain and stress at the sample points for coordinates ``q`` (size,)
        (``runtime.model.items.material_points``; a point shared by elements takes their
        mean): ``green_lagrange_strain`` in the reference local frame and ``cauchy_stress``
        (Pa) in the current local frame, (points, 6) symmetric tensors in ParaView's order
        xx, yy, zz, xy, yz, xz (zz, yz, xz zero in 2D), and ``von_mises_stress`` (points,)
        (Pa; 2D plane stress)."""
        rows, cols = (0, 1, 2, 0, 1, 0), (0, 1, 2, 1, 2, 2)
        strain, stress = np.zeros((self.points, 6)), np.zeros((self.points, 6))
        mises, count = np.zeros(self.points), np.zeros(self.points)
        for body, coordinates, points in self._fields:
            found = material.strain_stress(body, np.arange(body.elements), coordinates,
                                           q[None, :])
            where = points.ravel()
            for target, tensor in ((strain, found.strain[0]), (stress, found.cauchy[0])):
                full = np.zeros((*tensor.shape[:2], 3, 3))
                full[..., :self.dim, :self.dim] = tensor
                np.add.at(target, where, full[..., rows, cols].reshape(-1, 6))
            np.add.at(mises, where, material.von_mises(found.cauchy[0]).ravel())
            np.add.at(count, where, 1.0)
        count = np.maximum(count, 1.0)     # rigid bodies' points: no strain
        return {"green_lagrange_strain": strain / count[:, None],
                "cauchy_stress": stress / count[:, None], "von_mises_stress": mises / count}

    @property
    def surface(self) -> bool:
        """True if some body is a surface (plate elements, quad cells)."""
        return any(kind == "quad" for kind, _ in self.cells)

    def projected(self, vectors: np.ndarray,
                  view: str | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Horizontal and vertical coordinates (k,) of the outline of ``vectors`` (points, 3)
        on ``view``: a plane (a key of ``PLANES``) or a (2, 3) projection matrix; NaN between
        polylines (matplotlib breaks lines there)."""
        drawn = vectors[self.outline] @ _matrix(view).T
        drawn[self.outline < 0] = np.nan
        return drawn[:, 0], drawn[:, 1]


def _matrix(view: str | np.ndarray) -> np.ndarray:
    """The (2, 3) projection of ``view``: a key of ``PLANES`` or already a matrix."""
    if not isinstance(view, str):
        return np.asarray(view, dtype=float)
    matrix = np.zeros((2, 3))
    matrix[[0, 1], list(PLANES[view])] = 1.0
    return matrix


def _sample_fractions(kind: ElementKind, axes: list[int], per_element: int) -> list[np.ndarray]:
    """Sample fractions of the element along each meshed axis: ``per_element`` equal
    intervals of [0, 1] and the nodes' fractions."""
    nodes = kind.node_fractions[:, axes]
    even = np.linspace(0.0, 1.0, per_element + 1)
    return [np.unique(np.round(np.concatenate([even, nodes[:, a]]) * _KEY)) / _KEY
            for a in range(len(axes))]


def _grid(fractions: list[np.ndarray]) -> np.ndarray:
    """(samples, axes) points of the tensor grid of ``fractions`` per axis, x fastest."""
    mesh = np.meshgrid(*fractions[::-1], indexing="ij")
    return np.stack(mesh[::-1], axis=-1).reshape(-1, len(fractions))


def _indices(fractions: list[np.ndarray]) -> np.ndarray:
    """Sample index of each grid point of ``_grid(fractions)``, shaped (ny, nx) or (nx,)."""
    shape = tuple(len(f) for f in fractions[::-1])
    return np.arange(int(np.prod(shape))).reshape(shape)


def _grid_cells(fractions: list[np.ndarray]) -> np.ndarray:
    """Local cells (cells, corners) of the sample grid: segments along a line, quads
    (counter-clockwise in the local x-y plane) over a surface, hexahedra in a volume (the
    bottom quad, then the top one: VTK's corner order)."""
    index = _indices(fractions)
    if index.ndim == 1:
        return np.column_stack([index[:-1], index[1:]])
    if index.ndim == 2:
        return np.stack([index[:-1, :-1], index[:-1, 1:], index[1:, 1:], index[1:, :-1]],
                        axis=-1).reshape(-1, 4)
    low, high = index[:-1], index[1:]              # z layers (index is (nz, ny, nx))
    return np.stack([layer[:, a, b] for layer in (low, high) for a, b in (
        (np.s_[:-1], np.s_[:-1]), (np.s_[:-1], np.s_[1:]), (np.s_[1:], np.s_[1:]),
        (np.s_[1:], np.s_[:-1]))], axis=-1).reshape(-1, 8)


def _grid_loop(fractions: list[np.ndarray]) -> np.ndarray:
    """Local sample indices along the element's edges: the line itself; a surface's
    boundary as a closed loop (y = 0, x = 1, y = 1, x = 0); a volume's twelve edges as one
    path (the bottom loop, then up each vertical edge and along the top, three verticals
    drawn twice)."""
    index = _indices(fractions)
    if index.ndim == 1:
        return index
    if index.ndim == 2:
        return _loop(index)
    bottom, top = _loop(index[0]), _loop(index[-1])
    corners = [0, len(fractions[0]) - 1, len(fractions[0]) + len(fractions[1]) - 2,
               2 * len(fractions[0]) + len(fractions[1]) - 3]   # loop positions of the corners
    vertical = [index[:, 0, 0], index[:, 0, -1], index[:, -1, -1], index[:, -1, 0]]
    path = [bottom, vertical[0][1:]]
    for k in range(4):     # along the top to corner k + 1, down its vertical and back up
        stop = corners[k + 1] if k < 3 else len(top) - 1
        path.append(top[corners[k] + 1:stop + 1])
        if k < 3:
            path += [vertical[k + 1][-2::-1], vertical[k + 1][1:]]
    return np.concatenate(path)


def _loop(index: np.ndarray) -> np.ndarray:
    """The boundary of a (ny, nx) sample grid as a closed loop (y = 0, x = 1, y = 1, x = 0)."""
    return np.concatenate([index[0, :-1], index[:-1, -1], index[-1, :0:-1], index[::-1, 0]])


def _polylines(lines: np.ndarray) -> list[np.ndarray]:
    """The element polylines ``lines`` (elements, k) of point indices as a list, chained
    where one ends at the next's start (the elements of a beam body make one line)."""
    out = [lines[0]]
    for line in lines[1:]:
        if out[-1][-1] == line[0]:
            out[-1] = np.concatenate([out[-1], line[1:]])
        else:
            out.append(line)
    return out


def _local_points(body: BodyMesh, axes: list[int], local: np.ndarray) -> np.ndarray:
    """Local coordinates (samples, dim) in m of the sample fractions ``local`` (samples,
    axes) of the meshed axes, at the middle of the other axes (a beam's centre line, a
    plate's mid-surface)."""
    element = body.element
    points = np.zeros((len(local), element.kind.dim))
    for a, (low, high) in enumerate(element.kind.domain.bounds(element.geometry)):
        points[:, a] = (low + local[:, axes.index(a)] * (high - low) if a in axes
                        else (low + high) / 2)
    return points


def _shape_values(body: BodyMesh, points: np.ndarray) -> np.ndarray:
    """Shape function values (samples, n_shape) at local coordinates ``points`` (samples,
    dim)."""
    element = body.element
    family = kernel_family(element.kind.name, "invariants", element.backend)
    return family("shape_values", {"point": points,
                                   "geometry": np.asarray(element.geometry)})["values"]


def _sample_points(body: BodyMesh, axes: list[int],
                   local: np.ndarray) -> tuple[int, np.ndarray, np.ndarray]:
    """Where the samples of ``body`` go: the number of its distinct sample points (numbered
    along x, then y), the point of each element sample (elements, samples) and the point of
    each node (nodes,)."""
    mesh = body.mesh
    corner = mesh.points[mesh.connectivity[:, 0]] - body.kind.node_fractions[0, axes]
    samples = np.round((corner[:, None, :] + local[None, :, :]) * _KEY).astype(np.int64)
    keys, inverse = np.unique(samples.reshape(-1, len(axes))[:, ::-1], axis=0,
                              return_inverse=True)
    where = {tuple(key): i for i, key in enumerate(keys)}
    nodes = np.round(mesh.points[:, ::-1] * _KEY).astype(np.int64)
    return (len(keys), inverse.reshape(samples.shape[:2]),
            np.array([where[tuple(key)] for key in nodes]))


def _matched_points(body: BodyMesh, values: np.ndarray) -> tuple[int, np.ndarray, np.ndarray]:
    """``_sample_points`` of a mesh read from a file (no node lattice): samples at the same
    reference position (within 1e-9 of the body's size) are one point, numbered in order of
    first appearance; each node is the point at its position."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    kind = body.kind
    e0 = body.element_e0.reshape(body.elements, kind.n_shape, kind.dim)
    samples = np.einsum("pk,mkd->mpd", values, e0).reshape(-1, kind.dim)
    tolerance = 1e-9 * max(float(np.ptp(samples, axis=0).max()), 1e-300)
    tree = cKDTree(samples)
    pairs = tree.query_pairs(tolerance, output_type="ndarray")
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])),
                       shape=(len(samples), len(samples)))
    _, labels = connected_components(graph, directed=False)
    _, first, inverse = np.unique(labels, return_index=True, return_inverse=True)
    order = np.argsort(np.argsort(first))          # points in order of first appearance
    points = order[inverse]
    _, nearest = tree.query(np.asarray(body.mesh.points, float))
    return len(first), points.reshape(body.elements, -1), points[nearest]


def write_vtu(path: str | Path, shape: Shape, q: np.ndarray,
              vectors: dict[str, np.ndarray]) -> Path:
    """The shape at coordinates ``q`` (size,; the reference configuration for a state, as
    :class:`VtkSeries` writes them) into the VTU file ``path`` (points in m, the cells of
    ``shape``), with point data ``{name: (points,) or (points, components)}`` (e.g.
    displacement in m, velocity in m/s, the strain and stress of :meth:`Shape.fields`)."""
    import meshio

    mesh = meshio.Mesh(shape.sample(q), shape.cells, point_data=vectors)
    path = Path(path)
    with output.atomic_path(path) as tmp:
        meshio.write(tmp, mesh, file_format="vtu")
    return path


def write_pvd(path: str | Path, entries: Sequence[tuple[float, str]]) -> Path:
    """A ParaView collection ``path`` of (time, file name relative to it) entries."""
    lines = ['<?xml version="1.0"?>',
             '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">',
             "  <Collection>"]
    lines += [f'    <DataSet timestep="{t!r}" group="" part="0" file={quoteattr(name)}/>'
              for t, name in entries]
    lines += ["  </Collection>", "</VTKFile>", ""]
    path = Path(path)
    try:
        with output.atomic_file(path, "w") as f:
            f.write("\n".join(lines))
    except OSError as error:
        raise output.OutputError(f"{path}: cannot write ({error.strerror or error})") from None
    return path


class VtkSeries(Observer):
    """Writes a run's shapes into ``folder`` (``vtk/`` of the run folder) as they are
    computed, the finite-element way: points at the reference configuration, the motion as
    point data (ParaView's Warp By Vector on ``displacement`` shows the deformed shape).
    ``static.vtu`` and ``dynamic_NNNNNN.vtu`` at every output time carry ``displacement``
    (m), ``velocity`` (m/s) and the strain and stress fields of :meth:`Shape.fields`, with
    ``dynamic.pvd`` (written when the dynamic analysis ends, however it ends);
    ``mode_K.vtu`` (points at the linearisation point, point data ``mode``, the mode shape
    normalised to a largest nodal displacement of 1) with ``modes.pvd`` (time = mode
    number).  ``files``: the static file and the collections written, as
    ``<folder name>/<file>``.  Each run it observes starts a fresh series: the files of the
    previous one are removed."""

    def __init__(self, folder: str | Path) -> None:
        if not isinstance(folder, str | os.PathLike):
            raise TypeError(f"folder: expected the path of the output folder (str or "
                            f"pathlib.Path), got {type(folder).__name__} {folder!r}")
        self.folder = Path(folder)
        self.files: list[str] = []
        self._entries: list[tuple[float, str]] = []
        self._written: list[str] = []   # every file of the current series

    def begin(self, model: Model) -> None:
        self.shape = Shape(model)
        self.reference = model.reference
        self.zero = np.zeros((self.shape.points, 3))
        try:
            self.folder.mkdir(exist_ok=True)
            for name in self._written:   # a second run: a fresh series
                (self.folder / name).unlink(missing_ok=True)
        except OSError as error:
            raise output.OutputError(f"{self.folder}: cannot prepare the folder "
                                     f"({error.strerror or error})") from None
        self.files, self._entries, self._written = [], [], []

    def _write(self, name: str, q: np.ndarray, vectors: dict[str, np.ndarray]) -> None:
        write_vtu(self.folder / name, self.shape, q, vectors)
        self._written.append(name)

    def _collection(self, name: str, entries: list[tuple[float, str]]) -> None:
        write_pvd(self.folder / name, entries)
        self._written.append(name)
        self.files.append(f"{self.folder.name}/{name}")

    def _state(self, name: str, q: np.ndarray, v: np.ndarray | None) -> None:
        """The state ``q``, ``v`` as ``name``: reference points, displacement, velocity."""
        self._write(name, self.reference, {
            "displacement": self.shape.sample(q - self.reference),
            "velocity": self.zero if v is None else self.shape.sample(v),
            **self.shape.fields(q)})

    def static(self, q: np.ndarray) -> None:
        self._state("static.vtu", q, None)
        self.files.append(f"{self.folder.name}/static.vtu")

    def modal(self, modes: Modes) -> None:
        entries = []
        for k, shape in enumerate(modes.shapes, start=1):
            name = f"mode_{k}.vtu"
            self._write(name, modes.about, {"mode": self.shape.sample(shape)})
            entries.append((float(k), name))
        self._collection("modes.pvd", entries)

    def sample(self, t: float, q: np.ndarray, v: np.ndarray, values: dict[str, float]) -> None:
        name = f"dynamic_{len(self._entries):06d}.vtu"
        self._state(name, q, v)
        self._entries.append((t, name))

    def dynamic_end(self) -> None:
        if self._entries:
            self._collection("dynamic.pvd", self._entries)


class Frames(Observer):
    """Keeps the sampled shape (points, 3) at the output times of the dynamic analysis, for
    :func:`write_animation`: ``shape`` (a :class:`Shape`), ``times``, ``frames`` and the
    ``reference`` samples.  Memory stays
    bounded: beyond ``2 * MAX_FRAMES`` frames every other one is dropped (evenly spaced
    output times are kept, and always the latest)."""

    def __init__(self) -> None:
        self.times: list[float] = []
        self.frames: list[np.ndarray] = []
        self._outputs: list[int] = []   # output number of each frame kept
        self._stride = 1                # frames kept: every stride-th output, and the latest
        self._count = 0

    def begin(self, model: Model) -> None:
        self.shape = Shape(model)
        self.reference = self.shape.sample(model.reference)

    def sample(self, t: float, q: np.ndarray, v: np.ndarray, values: dict[str, float]) -> None:
        if self._outputs and self._outputs[-1] % self._stride:  # the latest, not on stride
            self._drop(len(self._outputs) - 1)
        self.times.append(t)
        self.frames.append(self.shape.sample(q))
        self._outputs.append(self._count)
        self._count += 1
        if len(self.frames) > 2 * MAX_FRAMES:
            self._stride *= 2
            for k in reversed(range(len(self._outputs) - 1)):
                if self._outputs[k] % self._stride:
                    self._drop(k)

    def _drop(self, k: int) -> None:
        del self.times[k], self.frames[k], self._outputs[k]


def magnification(reference: np.ndarray, states: Sequence[np.ndarray],
                  fill: float = 0.1) -> float:
    """Scale of the displacements drawn: 1 when the largest displacement of ``states``
    (each (points, 3), like ``reference``) is at least 5 % of the model's extent, else the
    1-2-5 factor that shows it as about ``fill`` of it, at most (a small static deflection
    stays visible)."""
    extent = float(np.ptp(reference, axis=0).max()) or 1.0
    largest = max((float(np.abs(s - reference).max()) for s in states), default=0.0)
    if largest == 0.0 or largest >= 0.05 * extent:
        return 1.0
    wanted = fill * extent / largest
    power = 10.0 ** np.floor(np.log10(wanted))
    return float(max(m * power for m in (1, 2, 5) if m * power <= wanted))


#: the plane argument that lets :func:`view_plane` choose from the shapes drawn
AUTO_PLANE = "auto"


def view_plane(reference: np.ndarray, states: Sequence[np.ndarray]) -> str:
    """The projection that shows ``states`` (each (points, 3)) best against ``reference``:
    the axis of the model's largest extent across, and of the remaining axes the one the
    samples move most along (the larger extent without motion), as a key of ``PLANES``
    (a cantilever in x bending along y: "xy"; a plate in x-y bending along z: "xz")."""
    extent = np.ptp(reference, axis=0)
    across = int(np.argmax(extent))
    motion = np.max([np.abs(s - reference).max(axis=0) for s in states], axis=0) \
        if len(states) else np.zeros(3)
    others = [a for a in range(3) if a != across]
    up = max(others, key=lambda a: (motion[a] > 0, motion[a], extent[a], -a))
    pair = tuple(sorted((across, up)))
    return next(name for name, axes in PLANES.items() if axes == pair)


#: the drawn motion fills about this fraction of the model's extent (a 1-2-5 magnification)
FILL = 0.25
#: width of the drawings (inches); their height follows the drawn box within HEIGHTS
WIDTH = 6.4
HEIGHTS = (2.4, 4.8)
#: inches of a drawing taken by its title, labels and ticks, across and up
_DECOR = (0.9, 1.3)
#: angle of the receding axis of an oblique view
OBLIQUE_DEG = 30.0


@dataclass(frozen=True)
class _View:
    """A projection of the drawings: ``matrix`` (2, 3), axis labels and what the heading
    says about it ('' for a plane)."""

    matrix: np.ndarray
    labels: tuple[str, str]
    note: str = ""


def _view(plane: str, shape: Shape, reference: np.ndarray,
          states: Sequence[np.ndarray]) -> _View:
    """``plane`` as a :class:`_View`; ``AUTO_PLANE`` is the plane :func:`view_plane`
    chooses, seen obliquely for a surface in 3D (the third axis drawn receding at
    ``OBLIQUE_DEG``: a plate bending out of its plane is not seen edge-on)."""
    if plane != AUTO_PLANE and plane not in PLANES:
        raise ValueError(f"plane: expected {AUTO_PLANE} or one of {', '.join(PLANES)}, got "
                         f"{plane!r}")
    chosen = view_plane(reference, states) if plane == AUTO_PLANE else plane
    matrix = _matrix(chosen)
    if plane != AUTO_PLANE or not shape.surface or shape.dim != 3:
        return _View(matrix, (chosen[0], chosen[1]))
    depth = ({"x", "y", "z"} - set(chosen)).pop()
    angle = np.radians(OBLIQUE_DEG)
    matrix[:, "xyz".index(depth)] = np.cos(angle), np.sin(angle)
    return _View(matrix, (chosen[0], chosen[1]),
                 f"oblique view, {depth} drawn at {OBLIQUE_DEG:g} degrees")


def _drawing(shape: Shape, view: _View, reference: np.ndarray,
             shown: Sequence[np.ndarray], scale: float):
    """A figure and its axes holding every sample (points, 3) of ``reference`` and
    ``shown`` (displacements magnified ``scale`` times, which the vertical label says) at
    equal scales, the figure's height fitted to the drawn box (a slender beam is not a
    strip in a white page), the outline of ``reference`` dashed."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    drawn = np.concatenate([reference, *shown]) @ view.matrix.T
    low, high = drawn.min(axis=0), drawn.max(axis=0)
    margin = 0.05 * float(max(high - low) or 1.0)
    low, high = low - margin, high + margin
    across, up = high - low
    height = (WIDTH - _DECOR[0]) * up / across + _DECOR[1]
    fig = Figure(figsize=(WIDTH, float(np.clip(height, *HEIGHTS))), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ax.set_xlim(low[0], high[0])
    ax.set_ylim(low[1], high[1])
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel(f"{view.labels[0]} (m)")
    ax.set_ylabel(f"{view.labels[1]} (m)" if scale == 1 else
                  f"{view.labels[1]} (m, displacements x{scale:g})")
    ax.grid(True, alpha=0.3)
    ax.plot(*shape.projected(reference, view.matrix), "--", color="0.6", lw=1,
            label="reference")
    return fig, ax


def _heading(title: str, what: str, scale: float, view: _View) -> str:
    """The scene title (wrapped on at most two lines), then what is drawn, the
    magnification and the view."""
    lines = textwrap.wrap(title, 90, max_lines=2, placeholder=" ...")
    said = [what] + ([f"displacements x{scale:g}"] if scale != 1 else []) \
        + ([view.note] if view.note else [])
    return "\n".join([*lines, ", ".join(said)])


def write_snapshot(path: str | Path, shape: Shape, reference: np.ndarray, q: np.ndarray,
                   title: str, what: str = "static state", plane: str = AUTO_PLANE) -> Path:
    """PNG of the outline of ``shape`` (centre lines, plate element edges) at ``q`` over the
    reference ``reference`` (both coordinates, (size,)) projected on ``plane`` (a key of
    ``PLANES``, or ``AUTO_PLANE``: :func:`view_plane`, obliquely for plates), titled
    ``title`` and ``what``; displacements magnified as :func:`magnification` says (to
    ``FILL``), the figure fitted to the drawing."""
    base, state = shape.sample(reference), shape.sample(q)
    view = _view(plane, shape, base, [state])
    scale = magnification(base, [state], FILL)
    shown = base + scale * (state - base)
    fig, ax = _drawing(shape, view, base, [shown], scale)
    ax.plot(*shape.projected(shown, view.matrix), lw=2, color="C0", label="deformed")
    ax.set_title(_heading(title, what, scale, view), fontsize=9)
    ax.legend(fontsize=8)
    path = Path(path)
    with output.atomic_file(path) as f:
        fig.savefig(f, format="png", dpi=100)
    return path


def write_animation(path: str | Path, frames: Frames, title: str, plane: str = AUTO_PLANE,
                    fps: int = 10) -> Path:
    """GIF of the outlines of ``frames`` (centre lines, plate element edges) projected on
    ``plane`` (as for :func:`write_snapshot`; at most ``MAX_FRAMES`` frames, evenly chosen,
    the last included), with the reference dashed and the time in a corner; displacements
    magnified as :func:`magnification` says (to ``FILL``), the figure fitted to the motion."""
    from matplotlib.animation import FuncAnimation, PillowWriter

    if not frames.frames:
        raise ValueError("animation: no output time to draw")
    view = _view(plane, frames.shape, frames.reference, frames.frames)
    count = len(frames.frames)
    chosen = np.unique(np.linspace(0, count - 1, min(count, MAX_FRAMES)).round().astype(int))
    base = frames.reference
    scale = magnification(base, [frames.frames[k] for k in chosen], FILL)
    shown = [base + scale * (frames.frames[k] - base) for k in chosen]
    shape = frames.shape
    fig, ax = _drawing(shape, view, base, shown, scale)
    (curve,) = ax.plot(*shape.projected(shown[0], view.matrix), lw=2, color="C0")
    ax.set_title(_heading(title, "dynamic analysis", scale, view), fontsize=9)
    clock = fig.text(0.99, 0.01, "", ha="right", va="bottom", fontsize=9)
    fig.canvas.draw()               # lay out once: the frames keep that layout (fast)
    fig.set_layout_engine("none")

    def draw(n: int):
        curve.set_data(*shape.projected(shown[n], view.matrix))
        clock.set_text(f"t = {frames.times[chosen[n]]:.4g} s")
        return curve, clock

    animation = FuncAnimation(fig, draw, frames=len(shown), blit=False)
    path = Path(path)
    with output.atomic_path(path) as tmp, Bar("animation", len(shown), "frames") as bar:
        animation.save(tmp, writer=PillowWriter(fps=fps), dpi=80,
                       progress_callback=lambda done, total: bar.update(done + 1))
    return path
