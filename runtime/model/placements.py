"""Where a body's mesh lies in space: its placement, a registry (``PLACEMENTS``).

A placement reads its own keys of a ``[[body]]`` table, says how many elements tile each
meshed axis and how large they are, where each node of the structured mesh is, how far the
body reaches from the origin, and gives the reference coordinates of every element.  Line
kinds (beams) are placed on a straight ``Line`` (``start``/``end``) or an ``Arc``; plate and
shell kinds on a ``Rectangle``; solid kinds (meshing three axes, bricks) in a ``Box``.
``Body.placement`` is the one place that tells which one a body has.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from runtime.element import reference
from runtime.element.element import MAGNITUDE
from runtime.kernels.kind import ElementKind
from runtime.model.errors import SceneError, show
from runtime.model.schema import count, in_range, keys, number, table, vector


@dataclass(frozen=True)
class Placement:
    """Base of the placements.  ``keys``: the ``[[body]]`` keys it is written under;
    ``mesh_dims``: how many axes the meshes of the kinds it places tile; ``count_key``: the
    body key that sets the element counts (named by size errors)."""

    keys: ClassVar[tuple[str, ...]] = ()
    mesh_dims: ClassVar[int] = 1
    count_key: ClassVar[str] = "elements"

    def counts(self, elements: int | None) -> tuple[int, ...]:
        """Elements along each meshed axis (``elements``: the body's element count)."""
        return (elements,)

    def element_sides(self, counts: tuple[int, ...]) -> tuple[float, ...]:
        """Size (m) of one element along each meshed axis."""
        raise NotImplementedError

    def check_counts(self, counts: tuple[int, ...], path: str) -> None:
        """SceneError at the body's count key (``path.count_key``, per axis ``[k]`` on a
        grid) when so many elements make an element side shorter than ``runtime.Element``
        takes (1 / MAGNITUDE m)."""
        for k, (side, n) in enumerate(zip(self.element_sides(counts), counts, strict=True)):
            if side < 1 / MAGNITUDE:
                key = self.count_key + (f"[{k}]" if self.mesh_dims > 1 else "")
                most = max(1, math.floor(side * n * MAGNITUDE))
                raise SceneError(f"{path}.{key}: {n} elements make elements {side:.3g} m long; "
                                 f"expected elements of at least {1 / MAGNITUDE:g} m (at most "
                                 f"{most} elements), got {n}")

    def node_position(self, point: tuple[float, ...], counts: tuple[int, ...]
                      ) -> tuple[float, ...]:
        """Reference position (m) of the mesh point ``point`` (element units along each
        meshed axis, ``runtime.model.mesh.Mesh.points``) of a structured mesh of ``counts``
        elements: along a line or arc, on a rectangle."""
        raise NotImplementedError

    def extent(self) -> float:
        """Largest coordinate magnitude (m) the body reaches: the scale of its positions."""
        raise NotImplementedError

    def element_references(self, kind: ElementKind, counts: tuple[int, ...]) -> np.ndarray:
        """Reference coordinates (elements, ndof) of every element, in the element order of
        ``runtime.model.mesh.structured_mesh`` (along x, then y)."""
        raise NotImplementedError


@dataclass(frozen=True)
class Line(Placement):
    """A straight line from ``start`` to ``end`` (dim,) in m (body keys ``start``, ``end``)."""

    keys: ClassVar[tuple[str, ...]] = ("start", "end")

    start: tuple[float, ...]
    end: tuple[float, ...]

    @classmethod
    def parse(cls, data: dict, path: str, dim: int, why: str) -> Line:
        """The line of a ``[[body]]`` table ``data`` at ``path``."""
        for key in ("start", "end"):
            if key not in data:
                raise SceneError(f"{path}.{key}: missing required key; expected a point in m "
                                 "(a straight body needs start and end)")
        start = vector(data["start"], f"{path}.start", dim, why)
        end = vector(data["end"], f"{path}.end", dim, why)
        if start == end:
            raise SceneError(f"{path}.end: expected a point different from start, got "
                             f"{show(data['end'])}")
        if not math.isfinite(sum((b - a) * (b - a) for a, b in zip(start, end, strict=True))):
            raise SceneError(f"{path}.end: expected a body of finite length, got start = "
                             f"{show(data['start'])} and end = {show(data['end'])}")
        in_range(math.dist(start, end), f"{path}.end", "a body length |end - start| in m",
                 f" (start = {show(data['start'])})")
        return cls(start, end)

    def element_sides(self, counts: tuple[int, ...]) -> tuple[float, ...]:
        return (math.dist(self.start, self.end) / counts[0],)

    def node_position(self, point: tuple[float, ...], counts: tuple[int, ...]
                      ) -> tuple[float, ...]:
        f = point[0] / counts[0]
        return tuple(a + (b - a) * f for a, b in zip(self.start, self.end, strict=True))

    def extent(self) -> float:
        return max(abs(x) for x in (*self.start, *self.end))

    def element_references(self, kind: ElementKind, counts: tuple[int, ...]) -> np.ndarray:
        m = counts[0]
        start, end = np.asarray(self.start, float), np.asarray(self.end, float)
        points = [start + (end - start) * j / m for j in range(m + 1)]
        return np.array([reference.straight_reference(kind, points[j], points[j + 1])
                         for j in range(m)])


@dataclass(frozen=True)
class Arc(Placement):
    """Circular arc in the x-y plane (at the centre's z in 3D): centre (dim,) in m, radius (m),
    start angle and opening angle (deg, counter-clockwise about +z when positive)."""

    keys: ClassVar[tuple[str, ...]] = ("arc",)

    center: tuple[float, ...]
    radius: float
    start_angle_deg: float
    angle_deg: float

    @classmethod
    def parse(cls, data: Any, path: str, dim: int, why: str) -> Arc:
        """The arc of the table ``arc = {...}`` ``data`` at ``path``."""
        a = keys(data, path, ("center", "radius", "angle_deg"), ("start_angle_deg",),
                 "a table {center = [...], radius = R, angle_deg = A}")
        center = vector(a["center"], f"{path}.center", dim, why)
        radius = number(a["radius"], f"{path}.radius", positive=True)
        extent = radius + max(abs(x) for x in center)
        if not math.isfinite(extent * extent):
            raise SceneError(f"{path}.radius: expected an arc of finite extent, got radius "
                             f"{show(a['radius'])} about centre {show(a['center'])}")
        in_range(radius, f"{path}.radius", "an arc radius in m")
        start_angle = number(a.get("start_angle_deg", 0.0), f"{path}.start_angle_deg")
        angle = number(a["angle_deg"], f"{path}.angle_deg")
        if angle == 0.0 or abs(angle) > 360.0:
            raise SceneError(f"{path}.angle_deg: expected a non-zero angle of at most 360 "
                             f"degrees in magnitude, got {show(a['angle_deg'])}")
        in_range(radius * math.radians(abs(angle)), f"{path}.angle_deg",
                 "an arc length radius x angle in m", f" (radius = {show(a['radius'])} m)")
        return cls(center, radius, start_angle, angle)

    def to_dict(self) -> dict[str, Any]:
        """The TOML table ``arc = {...}``."""
        return table(self)

    def element_sides(self, counts: tuple[int, ...]) -> tuple[float, ...]:
        return (self.radius * math.radians(abs(self.angle_deg)) / counts[0],)

    def node_position(self, point: tuple[float, ...], counts: tuple[int, ...]
                      ) -> tuple[float, ...]:
        f = point[0] / counts[0]
        theta = math.radians(self.start_angle_deg) + f * math.radians(self.angle_deg)
        x, y = self.center[0], self.center[1]
        return (x + self.radius * math.cos(theta), y + self.radius * math.sin(theta),
                *self.center[2:])

    def extent(self) -> float:
        return max(abs(x) for x in self.center) + self.radius

    def element_references(self, kind: ElementKind, counts: tuple[int, ...]) -> np.ndarray:
        m = counts[0]
        step = np.radians(self.angle_deg) / m
        start = np.radians(self.start_angle_deg)
        return np.array([reference.arc_reference(kind, self.center, self.radius,
                                                 start + j * step, step) for j in range(m)])


@dataclass(frozen=True)
class Rectangle(Placement):
    """A flat rectangle in the plane z = corner[2]: ``corner`` (3,) in m, ``size`` (a, b) in m
    along +x and +y, meshed by ``grid`` (nx, ny) elements of size a / nx by b / ny."""

    keys: ClassVar[tuple[str, ...]] = ("rectangle",)
    mesh_dims: ClassVar[int] = 2
    count_key: ClassVar[str] = "rectangle.grid"

    corner: tuple[float, ...]
    size: tuple[float, float]
    grid: tuple[int, int]

    @classmethod
    def parse(cls, data: Any, path: str, dim: int, why: str) -> Rectangle:
        """The rectangle of the table ``rectangle = {...}`` ``data`` at ``path``."""
        r = keys(data, path, ("corner", "size", "grid"), (),
                 "a table {corner = [x, y, z], size = [a, b], grid = [nx, ny]}")
        corner = vector(r["corner"], f"{path}.corner", dim, why)
        if max(map(abs, corner)) > MAGNITUDE:
            raise SceneError(f"{path}.corner: expected a point with coordinates of at most "
                             f"{MAGNITUDE:g} m in magnitude, got {show(r['corner'])}")
        sides = vector(r["size"], f"{path}.size", 2, "the sides a along x and b along y, in m")
        if min(sides) <= 0 or not math.isfinite((sides[0] + sides[1]) ** 2):
            raise SceneError(f"{path}.size: expected two positive finite sides in m, got "
                             f"{show(r['size'])}")
        for side in sides:
            in_range(side, f"{path}.size", "sides in m")
        grid = r["grid"]
        if not isinstance(grid, list) or len(grid) != 2:
            raise SceneError(f"{path}.grid: expected [nx, ny], two positive integers "
                             f"(elements along x and y), got {show(grid)}")
        return cls(corner, sides,
                   tuple(count(n, f"{path}.grid[{k}]") for k, n in enumerate(grid)))

    def to_dict(self) -> dict[str, Any]:
        """The TOML table ``rectangle = {...}``."""
        return table(self)

    def counts(self, elements: int | None) -> tuple[int, ...]:
        return tuple(self.grid)

    def element_sides(self, counts: tuple[int, ...]) -> tuple[float, ...]:
        return tuple(side / n for side, n in zip(self.size, counts, strict=True))

    def node_position(self, point: tuple[float, ...], counts: tuple[int, ...]
                      ) -> tuple[float, ...]:
        x, y = (p / n * side for p, n, side in zip(point, counts, self.size, strict=True))
        return (self.corner[0] + x, self.corner[1] + y, self.corner[2])

    def extent(self) -> float:
        return max(abs(x) for x in self.corner) + self.size[0] + self.size[1]

    def element_references(self, kind: ElementKind, counts: tuple[int, ...]) -> np.ndarray:
        (a, b), (nx, ny) = self.size, counts
        side_x, side_y = np.array([a / nx, 0.0, 0.0]), np.array([0.0, b / ny, 0.0])
        corner = np.asarray(self.corner, float)
        return np.array([reference.rectangle_reference(kind, corner + i * side_x + j * side_y,
                                                       side_x, side_y)
                         for j in range(ny) for i in range(nx)])


@dataclass(frozen=True)
class Box(Placement):
    """An axis-aligned box: ``corner`` (3,) in m, ``size`` (a, b, c) in m along +x, +y and +z,
    meshed by ``grid`` (nx, ny, nz) elements of size a / nx by b / ny by c / nz (solid kinds,
    whose meshes tile all three axes)."""

    keys: ClassVar[tuple[str, ...]] = ("box",)
    mesh_dims: ClassVar[int] = 3
    count_key: ClassVar[str] = "box.grid"

    corner: tuple[float, ...]
    size: tuple[float, float, float]
    grid: tuple[int, int, int]

    @classmethod
    def parse(cls, data: Any, path: str, dim: int, why: str) -> Box:
        """The box of the table ``box = {...}`` ``data`` at ``path``."""
        r = keys(data, path, ("corner", "size", "grid"), (),
                 "a table {corner = [x, y, z], size = [a, b, c], grid = [nx, ny, nz]}")
        corner = vector(r["corner"], f"{path}.corner", dim, why)
        if max(map(abs, corner)) > MAGNITUDE:
            raise SceneError(f"{path}.corner: expected a point with coordinates of at most "
                             f"{MAGNITUDE:g} m in magnitude, got {show(r['corner'])}")
        sides = vector(r["size"], f"{path}.size", 3, "the sides a, b, c along x, y, z, in m")
        if min(sides) <= 0 or not math.isfinite(sum(sides) ** 2):
            raise SceneError(f"{path}.size: expected three positive finite sides in m, got "
                             f"{show(r['size'])}")
        for side in sides:
            in_range(side, f"{path}.size", "sides in m")
        grid = r["grid"]
        if not isinstance(grid, list) or len(grid) != 3:
            raise SceneError(f"{path}.grid: expected [nx, ny, nz], three positive integers "
                             f"(elements along x, y and z), got {show(grid)}")
        return cls(corner, sides,
                   tuple(count(n, f"{path}.grid[{k}]") for k, n in enumerate(grid)))

    def to_dict(self) -> dict[str, Any]:
        """The TOML table ``box = {...}``."""
        return table(self)

    def counts(self, elements: int | None) -> tuple[int, ...]:
        return tuple(self.grid)

    def element_sides(self, counts: tuple[int, ...]) -> tuple[float, ...]:
        return tuple(side / n for side, n in zip(self.size, counts, strict=True))

    def node_position(self, point: tuple[float, ...], counts: tuple[int, ...]
                      ) -> tuple[float, ...]:
        return tuple(c + p / n * side for c, p, n, side in zip(self.corner, point, counts,
                                                                self.size, strict=True))

    def extent(self) -> float:
        return max(abs(x) for x in self.corner) + sum(self.size)

    def element_references(self, kind: ElementKind, counts: tuple[int, ...]) -> np.ndarray:
        sides = np.array(self.element_sides(counts))
        fractions = kind.node_fractions
        frames = np.broadcast_to(np.eye(3), (kind.n_nodes, 3, 3))
        cells = [(i, j, k) for k in range(counts[2]) for j in range(counts[1])
                 for i in range(counts[0])]
        return np.array([reference.frame_reference(
            kind, np.asarray(self.corner) + (np.array(cell) + fractions) * sides, frames)
            for cell in cells])


#: Every placement, by the kinds of meshes it places (``Placement.mesh_dims``).
PLACEMENTS: tuple[type[Placement], ...] = (Line, Arc, Rectangle, Box)
