"""A scene turned into a model: meshed bodies, global coordinates, assembly, constraints.

Each body is meshed by connectivity from its kind's node layout (``runtime.model.mesh``: a
line of beam elements, interior nodes included for 3-node beams; a grid of plate or shell
elements with exactly the nodes of the layout, corners and mid-sides); its nodes are numbered
along x, then y, and the bodies one after the other.  Coordinates are
node-major over the whole model: a node owns ``per_node`` consecutive coordinates (its
nodal vectors, e.g. r, r_x, r_y, r_z or r, r_y, r_z, each a dim-vector), the number of
its body's kind.  Coordinates are split into *free* ones (unknowns), *fixed* ones (clamp,
pin) and *prescribed* ones (driven by a hub rotation); joints between bodies are linear
constraints ``A q = 0`` with Lagrange multipliers.  Element quantities are evaluated for a
whole body in one batched kernel call and scattered with precomputed index maps.
"""

from __future__ import annotations

import dataclasses
import functools
import time
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse
import scipy.sparse.csgraph

from runtime.element import reference as geometry
from runtime.element.element import Element
from runtime.kernels.kind import ElementKind, element_kind
from runtime.model import mesh as meshing
from runtime.model.errors import SceneError
from runtime.model.holonomic import Driver, HolonomicConstraints
from runtime.model.items.constraints import Built, HeldNodes
from runtime.model.items.rigid import RigidItem
from runtime.model.scene import Scene
from runtime.model.schema import NodeRef
from runtime.model.sliding_rows import SlidingBlock


@dataclass
class BodyMesh:
    """One body: its element group (or groups: ``groups``), mesh, reference coordinates and
    index maps."""

    name: str
    element: Element
    mesh: meshing.Mesh
    first_node: int          # global index of the body's node 0
    first_coordinate: int    # global index of the body's first coordinate
    reference: np.ndarray    # (nodes * per_node,) reference coordinates of the body
    element_dofs: np.ndarray  # (elements, ndof) global coordinate indices
    element_e0: np.ndarray   # (elements, ndof) reference coordinates of every element

    _kernels: dict = field(default_factory=dict, repr=False)
    #: the body's element groups, one per element shape, each a BodyMesh of those elements
    #: with its own Element (``[self]`` when every element has one shape)
    groups: list = field(default_factory=list, repr=False)

    @property
    def kind(self) -> ElementKind:
        """The element kind of the body."""
        return self.element.kind

    @property
    def elements(self) -> int:
        return self.element_dofs.shape[0]

    @property
    def nodes(self) -> int:
        """Number of nodes of the body."""
        return len(self.mesh.points)

    @property
    def coordinates(self) -> slice:
        """The body's slice of the global coordinates."""
        return slice(self.first_coordinate, self.first_coordinate + self.reference.size)

    def kernel(self, name: str):
        """The group kernel ``name`` of this body's elements (bound once, then reused): an
        elastic kernel, or a damping one (damping_force, damped_force_jacobians)."""
        if name not in self._kernels:
            damping = name.startswith(("damping_", "damped_"))
            self._kernels[name] = (self.element.damping_group_kernel(name) if damping
                                   else self.element.group_kernel(name))
        return self._kernels[name]

    @property
    def damped(self) -> bool:
        """Whether the material has Kelvin-Voigt damping (forces depend on velocities)."""
        return self.element.damping > 0


@dataclass
class RigidCoordinates:
    """A rigid item of the model (``runtime.model.items.rigid``) and its first global
    coordinate."""

    item: RigidItem
    first: int

    @property
    def dofs(self) -> np.ndarray:
        """Its own global coordinates (none for a point mass on a node)."""
        return np.arange(self.first, self.first + self.item.coordinates)


def _entries(position: np.ndarray, dofs: np.ndarray):
    """(rows, cols, keep), each (sets * k * k,): the places among the unknowns (``position``
    (size,), -1 where not free) of every entry (i, j) of each coordinate set of ``dofs``
    (sets, k), set by set and row-major, and whether both coordinates are free."""
    k = dofs.shape[1]
    rows = position[np.repeat(dofs, k, axis=1)].ravel()
    cols = position[np.tile(dofs, (1, k))].ravel()
    return rows, cols, (rows >= 0) & (cols >= 0)


def node_references(kind: ElementKind, mesh: meshing.Mesh, e0s: np.ndarray) -> np.ndarray:
    """Reference coordinates (nodes * per_node,) of the mesh's nodes from its elements'
    references (elements, ndof) (a node shared by elements takes the last one's value)."""
    nodes = np.zeros((len(mesh.points), kind.per_node))
    nodes[mesh.connectivity.ravel()] = e0s.reshape(-1, kind.per_node)
    return nodes.ravel()


class Model:
    """Bodies, mass matrix, loads and constraints of a scene (see the module docstring)."""

    def __init__(self, scene: Scene, method: str | None = None, backend: str | None = None):
        self.scene = scene
        self.method = method or scene.solver.method
        self.backend = backend or scene.solver.backend
        self.timing = {"compile_s": 0.0, "preprocess_s": 0.0}
        self._free_motion_cache: dict[float, list[str]] = {}
        self.kernel_seconds = 0.0  # time inside element force/Jacobian kernels (s)
        # energy dissipated by damping since the start of the current dynamic run (J), set
        # by the engine at each output
        self.dissipated_energy = 0.0
        # the torsional springs' joint angles (rad, turns counted; by scene load index) at
        # the state the sensors see, set by the engine at each output (None: each within
        # half a turn of 0)
        self.spring_angles: np.ndarray | None = None
        start = time.perf_counter()
        self.bodies: dict[str, BodyMesh] = {}
        self.dim = scene.dim
        nodes = coordinates = 0
        for body in scene.bodies:
            material = scene.materials[body.material]
            kind = element_kind(body.element)
            e0s = np.ascontiguousarray(body.placement.element_references(kind, body.counts))
            groups = []   # (element rows, Element) per element shape of the body
            shapes = body.shapes
            for shape in range(int(shapes.max(initial=0)) + 1):
                rows = np.flatnonzero(shapes == shape)
                element = Element(kind.name, *body.geometry, material.E, material.nu,
                                  material.rho, e0=e0s[rows[0]], method=self.method,
                                  backend=self.backend, quadrature=body.quadrature,
                                  law=material.law, shear_correction=material.shear_correction,
                                  damping=material.damping)
                groups.append((rows, element))
                self.timing["compile_s"] += element.timing["compile_s"]
            mesh = body.mesh
            dofs = coordinates + mesh.dofs(kind)
            whole = BodyMesh(body.name, groups[0][1], mesh, nodes, coordinates,
                             node_references(kind, mesh, e0s), dofs, e0s)
            whole.groups = [whole] if len(groups) == 1 else [
                dataclasses.replace(whole, element=element, element_dofs=dofs[rows],
                                    element_e0=np.ascontiguousarray(e0s[rows]), _kernels={})
                for rows, element in groups]
            self.bodies[body.name] = whole
            nodes += len(mesh.points)
            coordinates += len(mesh.points) * kind.per_node
        #: the element groups of every body, one per element shape (a body placed
        #: structurally is one group; a mesh file's body one per shape of its elements):
        #: each shares one Element's invariants and kernels
        self.groups = [group for body in self.bodies.values() for group in body.groups]
        self.n_nodes = nodes
        self._body_list = list(self.bodies.values())
        self._first_nodes = np.array([b.first_node for b in self._body_list])
        #: the rigid bodies and point masses by name, with their first coordinate (their
        #: coordinates follow those of the meshed bodies)
        self.rigid: dict[str, RigidCoordinates] = {}
        for item in scene.rigid_bodies:
            self.rigid[item.name] = RigidCoordinates(item, coordinates)
            coordinates += item.coordinates
        #: the driver coordinates of the rheonomic joints (``runtime.model.holonomic``:
        #: prescribed, without mass) after the rigid items': (coordinate, Driver), and the
        #: coordinates of each scene constraint's drivers
        self.drivers: list[tuple[int, Driver]] = []
        self._constraint_drivers: list[np.ndarray] = []
        for constraint in scene.constraints:
            own = constraint.drivers()
            self._constraint_drivers.append(np.arange(coordinates, coordinates + len(own)))
            self.drivers += [(coordinates + k, driver) for k, driver in enumerate(own)]
            coordinates += len(own)
        self.size = coordinates
        self.reference = np.concatenate([b.reference for b in self.bodies.values()]
                                        + [r.item.initial_coordinates()
                                           for r in self.rigid.values()]
                                        + [driver.sample(0.0)[0]
                                           for _, driver in self.drivers])
        self._build_mass()
        self._build_constraints()
        self._build_maps()
        self.timing["preprocess_s"] = time.perf_counter() - start - self.timing["compile_s"]

    def length_scale(self) -> float:
        """A characteristic length (m) for convergence tests: the largest reference extent."""
        return float(max(np.ptp(self.reference), 1.0))

    # --- indexing ------------------------------------------------------------------------

    def node_index(self, ref: NodeRef) -> int:
        """Global node index of a scene node reference."""
        body = self.bodies[ref.body]
        index = ref.index if ref.index >= 0 else body.nodes + ref.index
        return body.first_node + index

    def body_of(self, node: int) -> BodyMesh:
        """The body that a global node belongs to."""
        return self._body_list[int(np.searchsorted(self._first_nodes, node, side="right")) - 1]

    def node_vectors(self, node: int) -> tuple[str, ...]:
        """Names of the nodal vectors of a global node (``("r", "r_x", ...)``)."""
        return self.body_of(node).kind.vectors

    def node_dofs(self, node: int, vector: str | None = None) -> np.ndarray:
        """Coordinates of a node (all, or one nodal vector such as "r")."""
        body = self.body_of(node)
        per_node = body.kind.per_node
        start = body.first_coordinate + (node - body.first_node) * per_node
        if vector is None:
            return np.arange(start, start + per_node)
        k = body.kind.vectors.index(vector)
        return np.arange(start + k * self.dim, start + (k + 1) * self.dim)

    def held_dofs(self, node: int) -> np.ndarray:
        """Coordinates of a node that a clamp or a prescribed rotation holds, in storage
        order: its ``ElementKind.held_vectors`` (position, first gradients; a cable's
        curvature r_xx stays free)."""
        return np.concatenate([self.node_dofs(node, vector)
                               for vector in self.body_of(node).kind.held_vectors])

    def position_dofs(self) -> np.ndarray:
        """Coordinates of the positions r of every node, (nodes, dim), in node order."""
        if not self.bodies:
            return np.zeros((0, self.dim), int)
        return np.concatenate([
            body.first_coordinate + (np.arange(body.nodes)[:, None] * body.kind.per_node
                                     + body.kind.vectors.index("r") * self.dim
                                     + np.arange(self.dim)[None, :])
            for body in self.bodies.values()])

    def coordinate_names(self) -> list[str]:
        """A name per coordinate: nodal vector and component (``"r_x.y"``), (size,)."""
        return [f"{vector}.{'xyz'[c]}" for body in self.bodies.values()
                for _ in range(body.nodes) for vector in body.kind.vectors
                for c in range(self.dim)]

    # --- mass, constraints, index maps -------------------------------------------------

    def _build_mass(self) -> None:
        rows, cols, vals = [], [], []
        for body in self.groups:
            mass = body.element.mass_matrix()
            ndof = mass.shape[0]
            dofs = body.element_dofs
            rows.append(np.repeat(dofs, ndof, axis=1).ravel())
            cols.append(np.tile(dofs, (1, ndof)).ravel())
            vals.append(np.broadcast_to(mass.ravel(), (dofs.shape[0], ndof * ndof)).ravel())
        for rigid in self.rigid.values():
            mass = rigid.item.mass_matrix()
            dofs = rigid.dofs if rigid.dofs.size else self.node_dofs(
                self.node_index(rigid.item.node), "r")
            rows.append(np.repeat(dofs, dofs.size))
            cols.append(np.tile(dofs, dofs.size))
            vals.append((mass if rigid.dofs.size else rigid.item.mass * np.eye(dofs.size)).ravel())
        self.mass = scipy.sparse.csr_matrix(
            (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
            shape=(self.size, self.size))
        self.mass.sum_duplicates()

    def _build_constraints(self) -> None:
        built = Built(np.zeros(self.size, bool))
        for name, rigid in self.rigid.items():
            block = rigid.item.constraint_block(rigid.first, f"body {name!r}")
            if block is not None:
                built.blocks.append(block)
        #: the multipliers of each scene constraint: indices into [joints; quadratic rows]
        multipliers: dict[int, tuple[list[int], list[int]]] = {}
        # the clamps and pins first (they add no rows): the rows of symmetry planes then see
        # every coordinate held on their nodes (``runtime.model.items.symmetry.hold_rows``)
        constraints = self.scene.constraints
        order = sorted(range(len(constraints)), key=lambda i: not (
            isinstance(constraints[i], HeldNodes) and constraints[i].holds_position))
        for index in order:
            constraint = constraints[index]
            rows = len(built.rows)
            quadratic = sum(block.rows for block in built.blocks)
            built.drivers = self._constraint_drivers[index]
            try:
                constraint.apply(self, built)
            except SceneError as error:   # what only the model can check (gradients' span)
                raise SceneError(f"constraint[{index}]: {error}") from None
            multipliers[index] = (
                list(range(rows, len(built.rows))),
                list(range(quadratic, sum(block.rows for block in built.blocks))))
        fixed = built.fixed
        self.hubs = built.hubs  # (node, angle law, axis (3,))
        prescribed = np.zeros(self.size, bool)
        for node, _, _ in self.hubs:
            prescribed[self.held_dofs(node)] = True
        prescribed[[coordinate for coordinate, _ in self.drivers]] = True
        fixed &= ~prescribed
        self.fixed = np.flatnonzero(fixed)
        self.prescribed = np.flatnonzero(prescribed)
        #: the sets of coordinates the Jacobian couples (``_coupled_groups``)
        self._coupled = self._coupled_groups(built.blocks)
        self.free = self._bandwidth_order(np.flatnonzero(~fixed & ~prescribed))
        rows = np.repeat(np.arange(len(built.rows)), [len(row) for row in built.rows])
        cols = [i for row in built.rows for i in row]
        vals = np.array([v for row in built.rows for v in row.values()], float)
        self.joints = scipy.sparse.csr_matrix((vals, (rows, cols)),     # A, with A q = b
                                              shape=(len(built.rows), self.size))
        #: b of the joint rows A q = b (rows,): 0 but for rows held at their reference
        #: value (``runtime.model.items.symmetry``), m or 1
        self.joint_offsets = np.zeros(len(built.rows))
        for row, offset in built.offsets.items():
            self.joint_offsets[row] = offset
        self.joints_free = self.joints[:, self.free]
        self.joints_prescribed = self.joints[:, self.prescribed]
        #: the quadratic constraint rows (rigid bodies' own, nonlinear joints)
        self.holonomic = HolonomicConstraints(built.blocks, self.size, self.free)
        joints = len(built.rows)
        self.constraint_multipliers = [
            multipliers[index][0] + [joints + r for r in multipliers[index][1]]
            for index in range(len(constraints))]
        self._check_independent()
        self.mass_ff = self.mass[self.free][:, self.free].tocsc()
        self.mass_fp = self.mass[self.free][:, self.prescribed].tocsr()

    def _check_independent(self) -> None:
        """SceneError naming the first constraint whose rows repeat what the rigid bodies'
        rows and the constraints before it already hold (their multipliers would be
        singular): [A; Phi_q] at t = 0 over the rows that touch the rigid items' coordinates
        (free columns), row by row: a row in the span of those before is redundant."""
        if not self.rigid or not self.holonomic:
            return
        rigid = np.concatenate([r.dofs for r in self.rigid.values()])
        matrix = scipy.sparse.vstack([self.joints, self.holonomic.jacobian(self.reference)],
                                     format="csr")
        free = np.zeros(self.size, bool)
        free[self.free] = True
        owners = np.full(matrix.shape[0], -1)
        for index, rows in enumerate(self.constraint_multipliers):
            owners[rows] = index
        touching = np.flatnonzero(np.asarray(abs(matrix[:, rigid]).sum(axis=1)).ravel() > 0)
        # the rigid bodies' own rows first, then the constraints' in order
        touching = touching[np.argsort(owners[touching], kind="stable")]
        dense = matrix[touching][:, free].toarray()
        basis: list[np.ndarray] = []     # orthonormal rows spanning those before
        for row, owner in zip(dense, owners[touching], strict=True):
            rest = row.copy()
            for _ in range(2):           # Gram-Schmidt, twice for round-off
                for unit in basis:
                    rest -= (unit @ rest) * unit
            size = float(np.linalg.norm(rest))
            if size > 1e-9 * max(float(np.linalg.norm(row)), 1e-300):
                basis.append(rest / size)
            elif owner >= 0:
                index = int(owner)
                raise SceneError(
                    f"constraint[{index}]: redundant: a row of this "
                    f"{self.scene.constraints[index].type} joint repeats what the rigid "
                    f"bodies and the constraints before it already hold (the multipliers "
                    f"would be singular); remove it or free what it repeats")

    def _coupled_groups(self, blocks: list) -> list[np.ndarray]:
        """The sets of coordinates that the Jacobian couples, each (sets, k) global indices:
        the element groups, then the coordinates of the rigid items (mass), of the quadratic
        constraint ``blocks`` (their geometric stiffness) and of force elements."""
        return [body.element_dofs for body in self.groups] + [
            rigid.dofs[None, :] for rigid in self.rigid.values() if rigid.dofs.size] + [
            block.coupled for block in blocks] + [
            load.coupled_dofs(self)[None, :] for load in self.scene.loads
            if hasattr(load, "coupled_dofs")]

    def _bandwidth_order(self, free: np.ndarray) -> np.ndarray:
        """The free coordinates ``free`` (nf,) in the order of the unknowns: their global
        order, or the reverse Cuthill-McKee order of the Jacobian's graph where that at
        least halves the bandwidth (rigid bodies, numbered after the meshes, joined to
        nodes far apart: a slider-crank's 119 becomes 23; a plate numbered along its long
        side).  Chains of beams keep their global order (already of least bandwidth)."""
        position = np.full(self.size, -1, np.int64)
        position[free] = np.arange(free.size)
        rows, cols = [], []
        for dofs in self._coupled:
            r, c, keep = _entries(position, dofs)
            rows.append(r[keep])
            cols.append(c[keep])
        rows, cols = np.concatenate(rows), np.concatenate(cols)
        if rows.size == 0:
            return free
        graph = scipy.sparse.csr_matrix((np.ones(rows.size), (rows, cols)),
                                        shape=(free.size, free.size))
        order = scipy.sparse.csgraph.reverse_cuthill_mckee(graph, symmetric_mode=True)
        rank = np.empty_like(order)
        rank[order] = np.arange(order.size)
        natural = int(np.abs(rows - cols).max())
        reordered = int(np.abs(rank[rows] - rank[cols]).max())
        return free[order] if 2 * reordered <= natural else free

    def _build_maps(self) -> None:
        """Scatter maps from element Jacobians to the free-free CSR matrix.

        Each element entry (i, j) with both coordinates free lands in one CSR slot; the
        slots come from one sort of all flat indices row * nf + col (canonical CSR order).
        """
        position = self.free_position
        nf = self.free.size
        keeps, flats = [], []
        for dofs in self._coupled:
            r, c, keep = _entries(position, dofs)
            keeps.append(keep)
            flats.append((r * nf + c)[keep])
        unique, slots = np.unique(np.concatenate(flats), return_inverse=True)
        self._pattern_keys = unique
        rows, cols = unique // nf, unique % nf
        indptr = np.concatenate([[0], np.cumsum(np.bincount(rows, minlength=nf))])
        self.pattern = scipy.sparse.csr_matrix(
            (np.ones(unique.size), cols.astype(np.int32), indptr.astype(np.int32)),
            shape=(nf, nf))
        bounds = np.cumsum([0] + [f.size for f in flats])
        self._jac_targets = [(keep, slots[bounds[i]:bounds[i + 1]])
                             for i, keep in enumerate(keeps)][:len(self.groups)]
        #: slots (k, k) of every quadratic block's geometric stiffness (-1: not free; -2
        #: outside the pattern: a sliding block's element pairs, where its Hessian is 0)
        self.holonomic_slots = [self.slots(block.dofs, isinstance(block, SlidingBlock))
                                for block in self.holonomic.blocks]
        # banded (upper) storage of LAPACK: entry (i, j), i <= j, at [u + i - j, j]
        self.bandwidth = int(np.abs(rows - cols).max(initial=0))
        upper = rows <= cols
        self._band_slots = np.flatnonzero(upper)
        self._band_index = (self.bandwidth + rows[upper] - cols[upper]) * nf + cols[upper]
        self.mass_banded = self.banded(self.mass_ff[rows, cols].A1)

    @functools.cached_property
    def free_position(self) -> np.ndarray:
        """(size,) the index of each coordinate among the free ones, -1 where it is not free
        (read only)."""
        position = np.full(self.size, -1, np.int64)
        position[self.free] = np.arange(self.free.size)
        position.flags.writeable = False
        return position

    def slots(self, dofs: np.ndarray, outside: bool = False) -> np.ndarray:
        """The positions (..., k, k) in ``pattern`` order of the entries (i, j) of the
        coordinates ``dofs`` (..., k), -1 where either is not free.  The pattern must hold
        the others (AssertionError), unless ``outside``: then -2 marks those it does not."""
        p = self.free_position[dofs]
        rows, cols = p[..., :, None], p[..., None, :]
        flat = rows * self.free.size + cols
        keys = self._pattern_keys
        found = np.minimum(np.searchsorted(keys, flat), max(keys.size - 1, 0))
        inside = (rows >= 0) & (cols >= 0)
        held = inside & (keys[found] == flat) if keys.size else np.zeros_like(inside)
        if not outside:
            assert np.array_equal(held, inside), "entries outside the Jacobian pattern"
        return np.where(held, found, np.where(inside, -2, -1))

    def constraint_rows(self, q: np.ndarray) -> scipy.sparse.csr_matrix:
        """[A_f; Phi_q,f(q)] (joint rows + quadratic rows, nf): the free columns of the joint
        rows and of the quadratic rows' Jacobian at the coordinates q (size,)."""
        if not self.holonomic:
            return scipy.sparse.csr_matrix(self.joints_free)
        return scipy.sparse.vstack([self.joints_free, self.holonomic.jacobian_free(q)],
                                   format="csr")

    def constraint_values(self, q: np.ndarray) -> np.ndarray:
        """[A q - b; Phi(q)] (joint rows + quadratic rows,) at the coordinates q (size,)."""
        linear = self.joints @ q - self.joint_offsets
        if not self.holonomic:
            return linear
        return np.concatenate([linear, self.holonomic.value(q)])

    def holonomic_stiffness(self, multipliers: np.ndarray, q: np.ndarray) -> np.ndarray:
        """The geometric stiffness (Phi_q^T lambda)_q of the quadratic constraint rows for
        their multipliers (rows,) at the coordinates q (size,; the driver coordinates of
        rheonomic rows scale their Hessians) as data in ``pattern`` order (nnz,)."""
        data = np.zeros(self.pattern.nnz)
        for slots, block in zip(self.holonomic_slots,
                                self.holonomic.stiffness_blocks(multipliers, q), strict=True):
            keep = slots >= 0
            data += np.bincount(slots[keep], block[keep], self.pattern.nnz)
        return data

    def banded(self, data: np.ndarray) -> np.ndarray:
        """Upper banded storage ((bandwidth + 1, nf), LAPACK layout) of a free-free matrix
        given by its data in ``pattern`` order (e.g. Jacobian data from internal_forces)."""
        nf = self.free.size
        band = np.zeros((self.bandwidth + 1) * nf)
        band[self._band_index] = data[self._band_slots]
        return band.reshape(self.bandwidth + 1, nf)

    # --- element quantities ------------------------------------------------------------

    def internal_forces(self, q: np.ndarray, jacobian: bool = True):
        """Elastic force (size,) and, if asked, the free-free Jacobian data in CSR order.

        One batched kernel call per body; results scattered with precomputed maps.  The
        time spent in the kernels themselves accumulates in ``kernel_seconds``.
        """
        force, data, _ = self.internal_forces_damped(q, None, jacobian)
        return force, data

    @property
    def damped(self) -> bool:
        """Whether any body has Kelvin-Voigt damping."""
        return any(body.damped for body in self.bodies.values())

    def internal_forces_damped(self, q: np.ndarray, v: np.ndarray | None,
                               jacobian: bool = True):
        """Elastic plus damping force (size,) at coordinates q and velocities v (size,; None:
        elastic only) and, if asked, the free-free Jacobian data with respect to q and to v
        (CSR order; d/dv None without v, zero for undamped bodies).  The Jacobian pass is one
        kernel per damped body (damped_force_jacobians); the force pass adds damping_force to
        the elastic force."""
        force = np.zeros(self.size)
        data = np.zeros(self.pattern.nnz) if jacobian else None
        data_dot = np.zeros(self.pattern.nnz) if jacobian and v is not None else None
        for body, (keep, slots) in zip(self.groups, self._jac_targets, strict=True):
            dofs = body.element_dofs
            damped = body.damped and v is not None
            inputs = {"e": np.ascontiguousarray(q[dofs]), "e0": body.element_e0}
            if damped:
                inputs["e_dot"] = np.ascontiguousarray(v[dofs])
            start = time.perf_counter()
            if jacobian and damped:
                out = body.kernel("damped_force_jacobians")(inputs)
            else:
                out = body.kernel("force_jacobian" if jacobian else "force")(inputs)
                if damped:
                    out = dict(out, force=out["force"]
                               + body.kernel("damping_force")(inputs)["force"])
            self.kernel_seconds += time.perf_counter() - start
            force += np.bincount(dofs.ravel(), out["force"].ravel(), self.size)
            if jacobian:
                data += np.bincount(slots, out["jacobian"].ravel()[keep], self.pattern.nnz)
                if damped:
                    data_dot += np.bincount(slots, out["jacobian_dot"].ravel()[keep],
                                            self.pattern.nnz)
        return force, data, data_dot

    def dissipation_power(self, q: np.ndarray, v: np.ndarray) -> float:
        """Power (W) dissipated by Kelvin-Voigt damping at coordinates q, velocities v
        (size,): -v . F_damping (>= 0)."""
        total = 0.0
        for body in self.groups:
            if body.damped:
                dofs = body.element_dofs
                force = body.kernel("damping_force")({
                    "e": np.ascontiguousarray(q[dofs]), "e0": body.element_e0,
                    "e_dot": np.ascontiguousarray(v[dofs])})["force"]
                total -= float(np.sum(force * v[dofs]))
        return total

    def jacobian_matrix(self, data: np.ndarray) -> scipy.sparse.csr_matrix:
        """Free-free elastic Jacobian from ``internal_forces`` data."""
        return scipy.sparse.csr_matrix((data, self.pattern.indices, self.pattern.indptr),
                                       shape=self.pattern.shape)

    def strain_energy(self, q: np.ndarray, body: str | None = None):
        """Strain energy (J) of one body or of the whole model at coordinates q: (size,)
        gives a float, a block (k, size) an array (k,) (one batched kernel call per body)."""
        rows = np.atleast_2d(q)
        total = np.zeros(rows.shape[0])
        for mesh in self.groups:
            if body is None or mesh.name == body:
                elements, ndof = mesh.element_dofs.shape
                e = np.ascontiguousarray(rows[:, mesh.element_dofs].reshape(-1, ndof))
                e0 = mesh.element_e0 if rows.shape[0] == 1 else \
                    np.tile(mesh.element_e0, (rows.shape[0], 1))
                out = mesh.kernel("energy")({"e": e, "e0": e0})
                total += out["energy"].reshape(rows.shape[0], elements).sum(axis=1)
        return float(total[0]) if q.ndim == 1 else total

    def kinetic_energy(self, v: np.ndarray, body: str | None = None):
        """Kinetic energy 1/2 v^T M v (J) of one body or of the whole model: velocities (size,)
        give a float, a block (k, size) an array (k,)."""
        if body is not None:
            mask = np.zeros(self.size)
            mask[self.bodies[body].coordinates] = 1.0
            v = v * mask
        if v.ndim == 1:
            return 0.5 * float(v @ (self.mass @ v))
        return 0.5 * np.einsum("ij,ij->i", v, (self.mass @ v.T).T)

    def nominal_loads(self) -> list[tuple[object, np.ndarray]]:
        """(time law, generalised force (size,) at unit law value) of every load."""
        if not hasattr(self, "_nominal_loads"):
            self._nominal_loads = [(load.time_law, load.nominal(self))
                                   for load in self.scene.loads]
        return self._nominal_loads

    def nominal_load(self) -> np.ndarray:
        """Every load at its nominal value, time laws not applied (static analysis), (size,)."""
        return sum((vector for _, vector in self.nominal_loads()), np.zeros(self.size))

    def external_forces(self, t: float) -> np.ndarray:
        """Loads at time t (N), (size,)."""
        force = np.zeros(self.size)
        for law, vector in self.nominal_loads():
            force += law.value(t) * vector
        return force

    def gravity_potential(self, q: np.ndarray, t=0.0):
        """Potential energy (J) of the gravity loads relative to the reference: -F_g . (q - q0),
        at time t (s), or at the loads' nominal value when t is None (static analysis).  A
        block q (k, size) with times t (k,) gives an array (k,)."""
        total = np.zeros(np.atleast_2d(q).shape[0])
        for load, (law, force) in zip(self.scene.loads, self.nominal_loads(), strict=True):
            if load.potential:
                scale = 1.0 if t is None else law.sample(np.atleast_1d(np.asarray(t, float)))[0]
                total -= scale * ((q - self.reference) @ force)
        return float(total[0]) if q.ndim == 1 else total

    def spring_energy(self, q: np.ndarray, t=0.0, angles: np.ndarray | None = None):
        """Energy (J) k/2 (L - L0)^2 stored in the springs of the spring-dampers and
        k/2 (phi - phi_0)^2 in the torsional ones (times their time law at t; the nominal
        value when t is None), at q (size,) or a block (k, size) with times t (k,); the
        torsional springs' phi near ``angles`` (loads,) or (k, loads) (rad, turns counted:
        ``Samples.spring_angles``; None: within half a turn of 0)."""
        rows = np.atleast_2d(q)
        total = np.zeros(rows.shape[0])
        near = None if angles is None else np.broadcast_to(
            np.atleast_2d(angles), (rows.shape[0], len(self.scene.loads)))
        for index, load in enumerate(self.scene.loads):
            if not hasattr(load, "coupled_dofs"):
                continue
            element = load.state_force(self)
            scale = 1.0 if t is None else load.time_law.sample(
                np.broadcast_to(np.atleast_1d(np.asarray(t, float)), total.shape))[0]
            if near is not None and hasattr(element, "turned"):
                energies = [element.energy(x, float(n)) for x, n in zip(rows, near[:, index],
                                                                       strict=True)]
            else:
                energies = [element.energy(x) for x in rows]
            total += scale * np.array(energies)
        return float(total[0]) if q.ndim == 1 else total

    # --- frames and rigid motions --------------------------------------------------------

    def node_frame(self, q: np.ndarray, node: int) -> np.ndarray:
        """Orthonormal frame (dim, dim) of a node at coordinates q (size,), or its frames
        (k, dim, dim) along a block q (k, size): its gradient vectors
        (``reference.gradient_frame``: r_x kept as the first axis, a gradient the node does not
        carry completed from the others; exact for a rigidly rotated node such as a hub)."""
        return geometry.gradient_frame({name: q[..., self.node_dofs(node, name)] for name in
                                        self.node_vectors(node) if name != "r"}, self.dim)

    def rigid_field(self, translation: Sequence[float] | None = None,
                    rotation: float | Sequence[float] | None = None,
                    about: Sequence[float] | None = None,
                    body: str | None = None) -> np.ndarray:
        """Coordinates (size,) of the small rigid motion of the reference by ``translation``
        (dim,) and ``rotation`` (a number about z in 2D, (3,) in 3D) about the point
        ``about`` (dim,; default the origin): positions u + w x (r - about), gradients w x r_k;
        zero outside ``body`` if given.  In velocities: m/s from m/s and rad/s."""
        field = np.zeros(self.size)
        for name, mesh in self.bodies.items():
            if body is not None and name != body:
                continue
            nodes = mesh.reference.reshape(mesh.nodes, len(mesh.kind.vectors), self.dim)
            part = np.zeros_like(nodes)
            k = mesh.kind.vectors.index("r")
            if translation is not None:
                part[:, k] += np.asarray(translation, float)
            if rotation is not None:
                arms = nodes.copy()
                arms[:, k] -= np.zeros(self.dim) if about is None else np.asarray(about, float)
                part += _cross(rotation, arms)
            field[mesh.coordinates] = part.ravel()
        for name, rigid in self.rigid.items():
            if (body is not None and name != body) or not rigid.dofs.size:
                continue
            vectors = self.reference[rigid.dofs].reshape(-1, self.dim)   # a point (, its axes)
            part = np.zeros_like(vectors)
            if translation is not None:
                part[0] += np.asarray(translation, float)
            if rotation is not None:
                arms = vectors.copy()
                arms[0] -= np.zeros(self.dim) if about is None else np.asarray(about, float)
                part += _cross(rotation, arms)
            field[rigid.dofs] = part.ravel()
        return field

    def initial_velocities(self) -> np.ndarray:
        """Velocities (size,) at t = 0 (m/s, per coordinate) from the bodies'
        ``initial_velocity`` and ``initial_angular_velocity``: positions v + w x (r - about),
        gradients w x r_k, in the reference; fixed and prescribed coordinates zero."""
        velocities = np.zeros(self.size)
        for body in self.scene.bodies:
            spin = body.initial_angular_velocity
            if body.initial_velocity is not None or spin is not None:
                velocities += self.rigid_field(body.initial_velocity, spin and spin.omega,
                                               spin and spin.about, body.name)
        for rigid in self.rigid.values():
            velocities[rigid.dofs] = rigid.item.initial_velocities()
        velocities[self.fixed] = 0.0
        velocities[self.prescribed] = 0.0
        return velocities

    def rigid_point(self, name: str, point: tuple[float, ...]) -> tuple[np.ndarray, np.ndarray]:
        """(coordinates (k,), map (dim, k)) of the position of the body point ``point`` (body
        coordinates, m) of the rigid item ``name``: a rigid body's natural coordinates, a
        particle's position, or the node of a point mass on a node."""
        rigid = self.rigid[name]
        if not rigid.dofs.size:
            return self.node_dofs(self.node_index(rigid.item.node), "r"), np.eye(self.dim)
        return rigid.dofs, rigid.item.point_map(point)

    def free_motions(self, tolerance: float = 1e-12) -> list[str]:
        """The rigid motions the constraints leave free (see ``_free_motions``), computed
        once per tolerance (the constraints of a model do not change)."""
        if tolerance not in self._free_motion_cache:
            self._free_motion_cache[tolerance] = self._free_motions(tolerance)
        return list(self._free_motion_cache[tolerance])

    def _free_motions(self, tolerance: float) -> list[str]:
        """One sentence per body that the constraints leave free to move rigidly, e.g.
        "body 'beam' is free to translate along x and y and to rotate about z" (empty when
        the model is held): the null space of the constrained stiffness at the reference.

        The elastic stiffness of a body at its reference vanishes exactly on its small rigid
        motions (and only there for elements without spurious zero-energy modes), so the
        null space is the set of rigid motions of the bodies (dim translations and 1 or 3
        rotations each) that keep fixed and prescribed coordinates at rest and satisfy the
        joints: computed in that small basis (columns normalised per body), with
        ``tolerance`` on the eigenvalues of its Gram matrix (relative to 1).
        """
        if not self.bodies:      # rigid items only: ``runtime.solve.static.check_held``
            return []
        rotations = 1 if self.dim == 2 else 3
        per_body = self.dim + rotations
        positions = self.reference[self.position_dofs()]
        columns, norms, absent = [], [], []
        for b, (name, mesh) in enumerate(self.bodies.items()):
            centre = positions[mesh.first_node:mesh.first_node + mesh.nodes].mean(axis=0)
            fields = np.column_stack([
                self.rigid_field(unit[:self.dim], unit[self.dim:] if rotations == 3
                                 else unit[self.dim], centre, name)
                for unit in np.eye(per_body)])
            scale = np.linalg.norm(fields, axis=0)
            scale[scale == 0] = 1.0
            unit_fields = fields / scale
            norms.extend(scale)
            columns.append(scipy.sparse.csc_matrix(unit_fields))
            # motions the coordinates do not carry (a 3D cable's spin about its own axis, at
            # any inclination: its nodes hold no section) move nothing: counted as held,
            # orthogonal to the others in the body's parameters (m and rad), so that the free
            # rotations named are those about axes perpendicular to the spin
            # (a normalised parameter vector u is the physical p = u / scale: p . (v / scale)
            # = 0 with v = vector / scale the physical spin)
            values, vectors = np.linalg.eigh(unit_fields.T @ unit_fields)
            for vector in vectors[:, values <= tolerance].T:
                row = np.zeros(per_body * len(self.bodies))
                row[b * per_body:(b + 1) * per_body] = vector / scale**2
                absent.append(row / np.linalg.norm(row))
        basis = scipy.sparse.hstack(columns).tocsr()
        held = np.concatenate([self.fixed, self.prescribed])
        rows = scipy.sparse.vstack([self.joints, self.holonomic.jacobian(self.reference)])
        constrained = scipy.sparse.vstack([basis[held], rows @ basis,
                                           scipy.sparse.csr_matrix(
                                               np.reshape(absent, (-1, basis.shape[1])))])
        values, vectors = np.linalg.eigh((constrained.T @ constrained).toarray())
        null = vectors[:, values <= tolerance]
        sentences = []
        for b, name in enumerate(self.bodies):
            rows = slice(b * per_body, (b + 1) * per_body)
            motions = _motions(null[rows], np.asarray(norms[rows]), self.dim)
            if motions:
                sentences.append(f"body {name!r} is free to {motions}")
        return sentences


def _cross(rotation: float | Sequence[float], arms: np.ndarray) -> np.ndarray:
    """rotation x arms for arms (..., dim): a number about z in 2D, a 3-vector in 3D."""
    if arms.shape[-1] == 2:
        return float(rotation) * np.stack([-arms[..., 1], arms[..., 0]], axis=-1)
    return np.cross(np.asarray(rotation, float), arms)


RANK_TOLERANCE = 1e-6   # singular values of unit null vectors' parts counted as zero


def _motions(null: np.ndarray, norms: np.ndarray, dim: int) -> str:
    """Words for the rigid motions of one body in the null vectors ``null`` (params, k):
    rows dim translations then the rotations, each column of the basis divided by ``norms``
    (the translations share one norm)."""
    translations, rotations = null[:dim], null[dim:]
    _, s, vt = np.linalg.svd(rotations, full_matrices=True)
    turning = int(np.sum(s > RANK_TOLERANCE))
    words = []
    moving, s_t, _ = np.linalg.svd(translations @ vt[turning:].T, full_matrices=False)
    sliding = int(np.sum(s_t > RANK_TOLERANCE))
    if sliding:
        words.append(f"translate along {_directions(moving[:, :sliding])}")
    if turning:
        axes = np.linalg.qr((rotations @ vt[:turning].T) / norms[dim:, None])[0]
        words.append(f"rotate about {_directions(axes) if dim == 3 else 'z'}")
    return " and to ".join(words)


def _directions(basis: np.ndarray) -> str:
    """Names of the span of orthonormal columns: coordinate axes ("x and y") when they span
    it, else the columns as vectors (parts of round-off size written as 0)."""
    names = "xyz"[:basis.shape[0]]
    inside = [names[i] for i in range(basis.shape[0])
              if np.sum(basis[i] ** 2) > 1.0 - RANK_TOLERANCE]
    if len(inside) != basis.shape[1]:   # vectors, each with its first non-zero part positive
        signs = [np.sign(column[np.argmax(np.abs(column) > RANK_TOLERANCE)]) for column in
                 basis.T]
        inside = ["(" + ", ".join(f"{x:.3g}" for x in
                            np.where(np.abs(column) > RANK_TOLERANCE, sign * column, 0.0) + 0.0)
                  + ")"
                  for sign, column in zip(signs, basis.T, strict=True)]
    return inside[0] if len(inside) == 1 else ", ".join(inside[:-1]) + " and " + inside[-1]
