"""Rigid bodies and point masses of scenes (``[[body]]`` tables with a ``type``): a typed
registry, ``RIGID_BODIES`` (docs/multibody.md; the coordinates: docs/design.md,
"Multibody").

A rigid body (``type = "rigid"``) is described in the natural coordinates of García de
Jalón and Bayo: its origin r0 (the point ``position``) and its three unit axes u, v, w
(the columns of its rotation matrix), 12 coordinates q = [r0, u, v, w].  A point of the body
at body coordinates x (3,) is at ``r0 + x_1 u + x_2 v + x_3 w``, linear in q, so the mass
matrix is constant: ``M = M4 (x) I_3`` with ``M4 = [[m, m s^T], [m s, J]]``, s the centre of
mass and ``J = int x x^T dm = 1/2 tr(I_c) 1 - I_c + m s s^T`` (I_c the inertia tensor about
the centre of mass, body axes).  Six quadratic constraints keep u, v, w orthonormal.

In a 2D scene a rigid body has the planar natural coordinates q = [r0, u] (4): its origin
and its unit x axis; its y axis v = perp(u) = [-u_2, u_1] is linear in u, so a body point
x (2,) is at ``r0 + x_1 u + x_2 perp(u)``, linear in q, the mass matrix is constant
(``M = [[m I, m X(s)], [m X(s)^T, J_o I]]`` with X(x) = x_1 I + x_2 P, P the rotation by
+90 degrees, J_o the moment of inertia about the origin) and one quadratic row keeps
u . u = 1.

A point mass (``type = "point_mass"``) is a mass on a node of a meshed body (it adds to the
node's position mass) or a particle at a free point (dim coordinates of its own).
Each class declares its TOML keys as fields (``runtime.model.schema.Record``).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from runtime.model.errors import SceneError, show
from runtime.model.holonomic import QuadraticBlock
from runtime.model.schema import (
    Context,
    NodeRef,
    Record,
    checked_name,
    key,
    keys,
    node_key,
    number,
    registry,
    rotation_vector,
    vector,
)

__all__ = ["PERP", "RIGID_BODIES", "PointMass", "RigidBody", "RigidItem", "natural_map",
           "planar_defaults", "planar_frame", "rigid_key"]

#: a rotation matrix is orthonormal to this (its columns' products against the identity)
ORTHONORMAL = 1e-9
#: the rotation by +90 degrees about z: perp(u) = PERP @ u = [-u_2, u_1]
PERP = np.array([[0.0, -1.0], [1.0, 0.0]])


def natural_map(point: np.ndarray) -> np.ndarray:
    """The map from natural coordinates to the position of the body point at body
    coordinates ``point``: in 3D (point (3,)) the map (3, 12) [I, x_1 I, x_2 I, x_3 I] on
    [r0, u, v, w]; in 2D (point (2,)) the map (2, 4) [I, x_1 I + x_2 PERP] on [r0, u]."""
    point = np.asarray(point, float)
    if point.size == 2:
        return np.hstack([np.eye(2), point[0] * np.eye(2) + point[1] * PERP])
    return np.kron(np.concatenate([[1.0], point])[None, :], np.eye(3))


def planar_frame(angle: float) -> np.ndarray:
    """The rotation matrix (2, 2) by ``angle`` (rad) about z."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s], [s, c]])


def _name_key(value: Any, path: str, context: Context) -> str:
    name = checked_name(value, path, "a body name")
    if ":" in name:
        raise SceneError(f'{path}: expected a name without ":", got {show(name)}')
    return name


def planar_defaults(record: Record, context: Context, names: tuple[str, ...]) -> Record:
    """``record`` with the 3D defaults (3,) of its fields ``names`` (points, axes) cut to
    their x, y in a 2D scene (a value read in 2D has two components already)."""
    if context.dim == 3:
        return record
    return dataclasses.replace(record, **{name: getattr(record, name)[:2] for name in names
                                          if len(getattr(record, name)) == 3})


def rigid_key(value: Any, path: str, context: Context) -> str:
    """The name of a rigid body or point mass of the scene."""
    if not isinstance(value, str) or value not in context.rigid:
        names = ", ".join(context.rigid) or "none"
        raise SceneError(f"{path}: expected the name of a rigid body ([[body]] with type = "
                         f"\"rigid\" or \"point_mass\"), got {show(value)}; rigid bodies: "
                         f"{names}")
    return value


def _point_key(value: Any, path: str, context: Context) -> tuple[float, ...]:
    return vector(value, path, context.dim, f"a point or vector in {context.dim}D")


def _positive_key(value: Any, path: str, context: Context) -> float:
    return number(value, path, positive=True)


def _matrix(value: Any, path: str, n: int = 3) -> np.ndarray:
    if (not isinstance(value, list) or len(value) != n
            or not all(isinstance(row, list) for row in value)):
        raise SceneError(f"{path}: expected a {n} x {n} matrix "
                         f"[{', '.join(['[..]'] * n)}], got {show(value)}")
    return np.array([vector(row, f"{path}[{i}]", n, f"a row of a {n} x {n} matrix")
                     for i, row in enumerate(value)])


def _inertia_key(value: Any, path: str,
                 context: Context) -> tuple[tuple[float, ...], ...] | float:
    """An inertia tensor (kg m^2) about the centre of mass in body axes: a symmetric,
    positive definite 3 x 3 matrix whose principal moments satisfy the triangle inequality
    strictly (those of a body with volume), or its three principal moments; in 2D the
    moment of inertia about z (a positive number)."""
    if context.dim == 2:
        if isinstance(value, list):
            raise SceneError(f"{path}: expected a number (the moment of inertia about z in "
                             f"kg m^2; the scene is 2D), got {show(value)}")
        return number(value, path, positive=True)
    if isinstance(value, list) and len(value) == 3 and not isinstance(value[0], list):
        tensor = np.diag(vector(value, path, 3, "principal moments of inertia in kg m^2"))
    else:
        tensor = _matrix(value, path)
    if not np.allclose(tensor, tensor.T, rtol=1e-12, atol=0.0):
        raise SceneError(f"{path}: expected a symmetric inertia tensor, got {show(value)}")
    moments = np.linalg.eigvalsh(tensor)
    if moments[0] <= 0:
        raise SceneError(f"{path}: expected a positive definite inertia tensor (kg m^2), got "
                         f"principal moments {', '.join(f'{x:.6g}' for x in moments)}")
    if moments[0] + moments[1] <= moments[2] * (1 + 1e-12):
        raise SceneError(f"{path}: principal moments {', '.join(f'{x:.6g}' for x in moments)}"
                         " break the triangle inequality I_1 + I_2 > I_3 (no body with volume "
                         "has them; a rod or a disc needs a thickness)")
    return tuple(tuple(float(x) for x in row) for row in tensor)


def _rotation_key(value: Any, path: str, context: Context) -> tuple[tuple[float, ...], ...]:
    """A rotation matrix (its columns: the body axes in the global frame; dim x dim)."""
    matrix = _matrix(value, path, context.dim)
    error = np.abs(matrix.T @ matrix - np.eye(context.dim)).max()
    if error > ORTHONORMAL or np.linalg.det(matrix) <= 0:
        raise SceneError(f"{path}: expected a rotation matrix (orthonormal columns to "
                         f"{ORTHONORMAL:g}, determinant +1), got {show(value)} (columns off "
                         f"orthonormal by {error:.3g}, determinant "
                         f"{np.linalg.det(matrix):.6g})")
    return tuple(tuple(float(x) for x in row) for row in matrix)


def _angle_key(value: Any, path: str, context: Context) -> float:
    """The angle (rad) of a 2D body's x axis from the global x axis at t = 0."""
    if context.dim == 3:
        raise SceneError(f"{path}: an angle gives a 2D body's pose; a 3D body takes rotation "
                         "= [[..], [..], [..]] (its axes as columns)")
    return number(value, path)


def _angular_velocity_key(value: Any, path: str,
                          context: Context) -> tuple[float, ...] | float:
    return rotation_vector(value, path, context.dim, "the angular velocity in rad/s")


def _shape_key(spec: tuple[str, ...], what: str):
    def parse(value: Any, path: str, context: Context) -> dict[str, Any]:
        data = keys(value, path, spec, (), f"a table {{{', '.join(spec)}}} ({what})")
        out: dict[str, Any] = {}
        for name in spec:
            if name == "size":
                sides = vector(data[name], f"{path}.size", 3, "the box's sides in m")
                if min(sides) <= 0:
                    raise SceneError(f"{path}.size: expected positive sides (m), got "
                                     f"{show(data[name])}")
                out[name] = list(sides)
            else:
                out[name] = number(data[name], f"{path}.{name}", positive=True)
        return out
    return parse


@dataclass(frozen=True)
class RigidItem(Record):
    """Base of the rigid items of ``[[body]]``: a ``name`` and what the model needs."""

    name: str = key(_name_key)

    @property
    def coordinates(self) -> int:
        """Coordinates of its own (appended after those of the meshed bodies)."""
        raise NotImplementedError

    def initial_coordinates(self) -> np.ndarray:
        """Its coordinates at t = 0 (coordinates,)."""
        raise NotImplementedError

    def initial_velocities(self) -> np.ndarray:
        """Its velocities at t = 0 (coordinates,)."""
        raise NotImplementedError

    def mass_matrix(self) -> np.ndarray:
        """Its constant mass matrix (coordinates, coordinates) in kg (and kg m, kg m^2)."""
        raise NotImplementedError

    def constraint_block(self, first: int, owner: str) -> QuadraticBlock | None:
        """Its own constraint rows on its coordinates from ``first`` (None: none)."""
        return None

    def point_map(self, point: tuple[float, ...]) -> np.ndarray:
        """The map (dim, coordinates) from its coordinates to the position of its
        ``point``."""
        raise NotImplementedError


@dataclass(frozen=True)
class RigidBody(RigidItem):
    """A rigid body in natural coordinates (module docstring): ``mass`` (kg) and ``inertia``
    (kg m^2, about the centre of mass, body axes; in 2D the moment about z), or a ``box =
    {size = [a, b, c]}`` or a ``cylinder = {radius, length}`` (axis along body z; in 2D c
    and the length are the thickness normal to the plane) centred on the centre of mass with
    a ``density`` (kg/m^3); ``centre_of_mass`` (dim,) in body coordinates (m, default the
    origin); the pose at t = 0: ``position`` (dim,) of the origin (m) and ``rotation``
    (dim x dim, columns the body axes in the global frame) or, in 2D, its ``angle`` (rad);
    ``velocity`` (dim,) of the origin (m/s) and ``angular_velocity`` (rad/s, global axes;
    in 2D a number about z) at t = 0."""

    type: ClassVar[str] = "rigid"
    mass: float | None = key(_positive_key, None)
    inertia: tuple[tuple[float, ...], ...] | float | None = key(_inertia_key, None)
    box: dict | None = key(_shape_key(("size",), "a box of sides size (m)"), None)
    cylinder: dict | None = key(_shape_key(("radius", "length"),
                                           "a cylinder along body z (m)"), None)
    density: float | None = key(_positive_key, None)
    centre_of_mass: tuple[float, ...] = key(_point_key, (0.0, 0.0, 0.0))
    position: tuple[float, ...] = key(_point_key, (0.0, 0.0, 0.0))
    rotation: tuple[tuple[float, ...], ...] = key(
        _rotation_key, ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)))
    angle: float | None = key(_angle_key, None)
    velocity: tuple[float, ...] | None = key(_point_key, None)
    angular_velocity: tuple[float, ...] | float | None = key(_angular_velocity_key, None)

    @classmethod
    def parse(cls, data: dict, path: str, context: Context) -> Record:
        shapes = [name for name in ("box", "cylinder") if name in data]
        given = [name for name in ("mass", "inertia") if name in data]
        if len(shapes) > 1:
            raise SceneError(f"{path}.{shapes[1]}: expected one shape, got box and cylinder")
        if shapes and (given or "density" not in data):
            culprit = given[0] if given else "density"
            raise SceneError(f"{path}.{culprit}: a {shapes[0]} takes a density (kg/m^3) and "
                             "gives the mass and inertia; "
                             + (f"remove {culprit}" if given else "add density"))
        if not shapes:
            if "density" in data:
                raise SceneError(f"{path}.density: a density needs a box or a cylinder")
            for name in ("mass", "inertia"):
                if name not in data:
                    raise SceneError(f"{path}.{name}: missing required key; expected mass "
                                     "(kg) and inertia (kg m^2), or a box or a cylinder with "
                                     "a density")
        if "angle" in data and "rotation" in data:
            raise SceneError(f"{path}.angle: expected an angle or a rotation, got both")
        return super().parse(data, path, context)

    def resolved(self, context: Context) -> RigidBody:
        """In 2D: the 2D defaults of the centre of mass, position and rotation, and the
        rotation of an ``angle`` (which it replaces)."""
        if context.dim == 3:
            return self
        body = planar_defaults(self, context, ("centre_of_mass", "position"))
        if self.angle is not None or len(self.rotation) == 3:
            body = dataclasses.replace(body, rotation=tuple(
                tuple(float(x) for x in row) for row in planar_frame(self.angle or 0.0)))
        return dataclasses.replace(body, angle=None)

    @property
    def dim(self) -> int:
        """Its space's dimension (2 or 3)."""
        return len(self.position)

    def mass_properties(self) -> tuple[float, np.ndarray | float]:
        """(mass (kg), inertia about the centre of mass in kg m^2: the tensor (3, 3) in 3D,
        the moment about z in 2D)."""
        if self.box is not None:
            a, b, c = self.box["size"]
            mass = self.density * a * b * c
            tensor = mass / 12 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
        elif self.cylinder is not None:
            r, length = self.cylinder["radius"], self.cylinder["length"]
            mass = self.density * math.pi * r * r * length
            side = mass * (3 * r * r + length * length) / 12
            tensor = np.diag([side, side, mass * r * r / 2])
        elif self.dim == 2:
            return self.mass, float(self.inertia)
        else:
            return self.mass, np.array(self.inertia)
        return mass, (tensor if self.dim == 3 else float(tensor[2, 2]))

    @property
    def coordinates(self) -> int:
        return 12 if self.dim == 3 else 4

    @property
    def frame(self) -> np.ndarray:
        """The rotation matrix (dim, dim) at t = 0."""
        return np.array(self.rotation)

    def initial_coordinates(self) -> np.ndarray:
        axes = self.frame.T if self.dim == 3 else self.frame.T[:1]     # [u, v, w] or [u]
        return np.concatenate([self.position, *axes])

    def initial_velocities(self) -> np.ndarray:
        origin = np.zeros(self.dim) if self.velocity is None else np.array(self.velocity)
        if self.dim == 2:                  # du/dt = omega perp(u)
            omega = 0.0 if self.angular_velocity is None else float(self.angular_velocity)
            return np.concatenate([origin, omega * PERP @ self.frame[:, 0]])
        omega = np.zeros(3) if self.angular_velocity is None else np.array(
            self.angular_velocity)
        return np.concatenate([origin, *np.cross(omega, self.frame.T)])

    def mass_matrix(self) -> np.ndarray:
        mass, inertia = self.mass_properties()
        s = np.array(self.centre_of_mass)
        if self.dim == 2:       # J_o = I_z + m |s|^2, X(s) = s_1 I + s_2 PERP
            coupling = mass * (s[0] * np.eye(2) + s[1] * PERP)
            polar = (inertia + mass * s @ s) * np.eye(2)
            return np.block([[mass * np.eye(2), coupling], [coupling.T, polar]])
        second = 0.5 * np.trace(inertia) * np.eye(3) - inertia + mass * np.outer(s, s)
        m4 = np.block([[np.array([[mass]]), mass * s[None, :]], [mass * s[:, None], second]])
        return np.kron(m4, np.eye(3))

    def constraint_block(self, first: int, owner: str) -> QuadraticBlock:
        """u.u = v.v = w.w = 1, u.v = v.w = w.u = 0 (Hessians on the 9 axis coordinates);
        in 2D u.u = 1 alone."""
        if self.dim == 2:
            hessian = np.zeros((1, 4, 4))
            hessian[0, 2:, 2:] = 2 * np.eye(2)
            return QuadraticBlock(owner, np.arange(first, first + 4), hessian,
                                  np.zeros((1, 4)), -np.ones(1))
        hessians = np.zeros((6, 12, 12))
        pairs = [(1, 1), (2, 2), (3, 3), (1, 2), (2, 3), (3, 1)]
        for row, (a, b) in enumerate(pairs):
            block = np.zeros((4, 4))
            block[a, b] += 1.0
            block[b, a] += 1.0
            hessians[row] = np.kron(block, np.eye(3))
        constant = np.array([-1.0, -1.0, -1.0, 0.0, 0.0, 0.0])
        return QuadraticBlock(owner, np.arange(first, first + 12), hessians,
                              np.zeros((6, 12)), constant)

    def point_map(self, point: tuple[float, ...]) -> np.ndarray:
        return natural_map(np.asarray(point, float))

    def axes(self, q: np.ndarray) -> np.ndarray:
        """Its axes (k, dim, dim), rows u, v (, w), at its coordinates q (k, coordinates)."""
        if self.dim == 2:
            u = q[:, 2:4]
            return np.stack([u, u @ PERP.T], axis=1)
        return q[:, 3:].reshape(-1, 3, 3)

    def extent(self) -> np.ndarray:
        """The corners (8, 3) in body coordinates (m) of the box it is drawn as (VTK
        hexahedron order): its box, the box around its cylinder, or the box of its mass
        and inertia (sides a^2 = 6 (I2 + I3 - I1) / m, ...), centred on the centre of mass;
        in 2D the corners (4, 2) of the rectangle of its box's a, b, the square around its
        cylinder or the square of its moment (a^2 = 6 I / m), anticlockwise."""
        if self.dim == 2:
            if self.box is not None:
                sides = np.array(self.box["size"][:2], float)
            elif self.cylinder is not None:
                sides = np.full(2, 2 * self.cylinder["radius"])
            else:
                mass, inertia = self.mass_properties()
                sides = np.full(2, math.sqrt(6 * inertia / mass))
            unit = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float) - 0.5
            return unit * sides + np.asarray(self.centre_of_mass)
        if self.box is not None:
            sides = np.array(self.box["size"], float)
        elif self.cylinder is not None:
            diameter = 2 * self.cylinder["radius"]
            sides = np.array([diameter, diameter, self.cylinder["length"]])
        else:
            mass, inertia = self.mass_properties()
            moments = np.diag(inertia)
            sides = np.sqrt(np.maximum(6 * (moments.sum() - 2 * moments) / mass, 0.0))
        unit = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],
                         [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], float) - 0.5
        return unit * sides + np.asarray(self.centre_of_mass)


def _node_key(value: Any, path: str, context: Context) -> NodeRef:
    return node_key(value, path, context)


@dataclass(frozen=True)
class PointMass(RigidItem):
    """A ``mass`` (kg) on a ``node`` of a meshed body ("BODY:INDEX": its position's mass
    grows by it; no coordinates of its own), or a particle at ``position`` (dim,) m with
    ``velocity`` (dim,) m/s at t = 0 (dim coordinates: its position)."""

    type: ClassVar[str] = "point_mass"
    mass: float = key(_positive_key)
    node: NodeRef | str | None = key(_node_key, None)
    position: tuple[float, ...] | None = key(_point_key, None)
    velocity: tuple[float, ...] | None = key(_point_key, None)

    @classmethod
    def parse(cls, data: dict, path: str, context: Context) -> Record:
        given = [name for name in ("node", "position") if name in data]
        if len(given) != 1:
            written = " and ".join(given) if given else "neither"
            raise SceneError(f"{path}: expected either node = \"BODY:INDEX\" or position = "
                             f"[{', '.join('xyz'[:context.dim])}], got {written}")
        if "node" in data and "velocity" in data:
            raise SceneError(f"{path}.velocity: a point mass on a node moves with the node; "
                             "give the body's initial_velocity instead")
        return super().parse(data, path, context)

    @property
    def coordinates(self) -> int:
        return 0 if self.node is not None else len(self.position)

    def initial_coordinates(self) -> np.ndarray:
        return np.zeros(0) if self.node is not None else np.array(self.position)

    def initial_velocities(self) -> np.ndarray:
        if self.node is not None:
            return np.zeros(0)
        return np.zeros(self.coordinates) if self.velocity is None else np.array(self.velocity)

    def mass_matrix(self) -> np.ndarray:
        return self.mass * np.eye(self.coordinates)

    def point_map(self, point: tuple[float, ...]) -> np.ndarray:
        return np.eye(self.coordinates)


RIGID_BODIES: dict[str, type[RigidItem]] = registry(RigidBody, PointMass)


def check_rigid_bodies(item, path: str, context: Context, needs: str) -> None:
    """SceneError unless ``item.body`` and, where the item has one, ``item.other`` (None: the
    ground) are rigid bodies, not point masses, and distinct; ``needs`` says what the item
    needs, as in "a bushing joins rigid bodies"."""
    for name in ("body", "other"):
        value = getattr(item, name, None)
        if value is not None and not isinstance(context.rigid[value], RigidBody):
            raise SceneError(f"{path}.{name}: {needs} (type = \"rigid\"), got the point mass "
                             f"{show(value)}")
    if getattr(item, "other", None) == item.body:
        raise SceneError(f"{path}.other: expected another body than {show(item.body)}")
