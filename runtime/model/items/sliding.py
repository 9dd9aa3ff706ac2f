"""The sliding joint (``[[constraint]] type = "sliding"``): a point - a ``node`` of another
meshed body, or the point ``point`` (body coordinates) of a rigid body or point mass ``body``
- held on the centre line of the line body ``beam`` (any cable or beam kind), free to slide
along it across its elements, without friction.  The point's curve parameter is eliminated
(the closest point of the line), the rows are the offset's components normal to the
tangent (``runtime.model.sliding_rows``): one in 2D, two in 3D, along e x t and e for the
joint's ``normal`` e (a fixed direction the tangent must never turn to: by default the
normal of the plane of a curved line, or for a straight line the direction normal to it
closest to z, or to y for a line along z).  The point must be on the line at t = 0."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from runtime.model.errors import SceneError, show
from runtime.model.items.base import ModelView
from runtime.model.items.constraints import Built, Constraint, NodeSide
from runtime.model.items.load_points import shape_tables
from runtime.model.items.rigid import planar_defaults, rigid_key
from runtime.model.schema import Context, NodeRef, Record, key, node_key, unit_axis, vector
from runtime.model.sliding_rows import CentreLine, Normal, SlideError, SlidingBlock

__all__ = ["Sliding"]

#: the point must be this close to the line at t = 0, relative to the body's length
ON_LINE = 1e-6
#: samples per element of the search for the point's closest element at t = 0
SEARCH_SAMPLES = 9
#: the 3D rows' normal must make at least this sine with the tangent at t = 0
NORMAL_ANGLE = 0.1


def _line_body_key(value: Any, path: str, context: Context) -> str:
    bodies = context.node.bodies
    if not isinstance(value, str) or value not in bodies:
        raise SceneError(f"{path}: expected the name of a meshed body, got {show(value)}; "
                         f"bodies: {', '.join(bodies) or 'none'}")
    body = bodies[value]
    if len(body.grid_shape) != 1:
        raise SceneError(f"{path}: a point slides along a line body (a cable or beam "
                         f"kind); body {show(value)} is a {body.element} body")
    return value


def _point_key(value: Any, path: str, context: Context) -> tuple[float, ...]:
    return vector(value, path, context.dim, f"a point in body coordinates, m, {context.dim}D")


def _normal_key(value: Any, path: str, context: Context) -> tuple[float, ...]:
    return unit_axis(value, path)


@dataclass(frozen=True)
class Sliding(NodeSide, Constraint):
    """A point held on the centre line of the line body ``beam`` (module docstring)."""

    type: ClassVar[str] = "sliding"
    beam: str = key(_line_body_key)
    node: NodeRef | str | None = key(node_key, None)
    body: str | None = key(rigid_key, None)
    point: tuple[float, ...] = key(_point_key, (0.0, 0.0, 0.0))
    normal: tuple[float, ...] | None = key(_normal_key, None,
                                           only_3d="2D rows need no normal")

    @classmethod
    def parse(cls, data: dict, path: str, context: Context) -> Record:
        if ("node" in data) == ("body" in data):
            raise SceneError(f"{path}: expected the sliding point as node = \"BODY:INDEX\" "
                             f"or as body = \"NAME\" (a rigid body or point mass, with its "
                             f"point), got {'both' if 'node' in data else 'neither'}")
        if "point" in data and "body" not in data:
            raise SceneError(f"{path}.point: a point in body coordinates needs body")
        joint = super().parse(data, path, context)
        if joint.node is not None and joint.node.body == joint.beam:
            raise SceneError(f"{path}.node: expected a node of another body than the beam "
                             f"{show(joint.beam)}")
        carrier = getattr(context.rigid.get(joint.body), "node", None)
        if carrier is not None and carrier.body == joint.beam:
            raise SceneError(f"{path}.body: the point mass {show(joint.body)} sits on a node "
                             f"of the beam {show(joint.beam)} itself; expected a point off it")
        return joint

    def resolved(self, context: Context) -> Record:
        return self if self.body is None else planar_defaults(self, context, ("point",))

    @property
    def target_key(self) -> str:
        return "node"

    def _point(self, model: ModelView) -> tuple[np.ndarray, np.ndarray]:
        """(coordinates (p,), position map (dim, p)) of the sliding point."""
        if self.node is not None:
            return model.node_dofs(model.node_index(self.node), "r"), np.eye(model.dim)
        return model.rigid_point(self.body, self.point)

    def apply(self, model: ModelView, built: Built) -> None:
        body = model.bodies[self.beam]
        kind = body.kind

        def values(xi: np.ndarray) -> np.ndarray:
            points = np.zeros((xi.size, kind.dim))
            points[:, 0] = xi
            return shape_tables(body, points)[0]

        line = CentreLine(kind, body.element, body.element_dofs, values)
        point_dofs, point_map = self._point(model)
        coordinates = np.unique(body.element_dofs)
        dofs = np.concatenate([point_dofs, coordinates])
        columns = point_dofs.size + np.searchsorted(coordinates, body.element_dofs)
        reference = model.reference
        start = self._start(line, reference[body.element_dofs], point_map @
                            reference[point_dofs])
        side = f"node {self.node.spelled()}" if self.node is not None else self.body
        owner = f"sliding joint of {side} on {self.beam}"
        normals = self._normals(model.dim, line, reference[body.element_dofs], start)
        block = SlidingBlock(owner, dofs, point_dofs.size, point_map, line, columns, normals,
                             start)
        x = reference[dofs]
        try:
            block.local(x)
        except SlideError as error:
            raise SceneError(f"beam: the point is not on the centre line of {show(self.beam)} "
                             f"at t = 0 ({error})") from None
        element, xi = block.start_found
        nearest = line.derivatives(xi)[0] @ reference[body.element_dofs[element]]
        offset = float(np.linalg.norm(point_map @ reference[point_dofs] - nearest))
        if offset > ON_LINE * line.elements * line.length:
            raise SceneError(f"{'node' if self.node else 'point'}: the sliding point must be "
                             f"on the centre line of {show(self.beam)} at t = 0 (within "
                             f"{ON_LINE:g} of its length); it is {offset:.3g} m from it, the "
                             f"nearest point of the line is "
                             f"{tuple(round(float(c), 9) for c in nearest)}")
        built.blocks.append(block)

    @staticmethod
    def _start(line: CentreLine, elements: np.ndarray, point: np.ndarray
               ) -> tuple[int, float]:
        """The element and xi of the sample of the line nearest to ``point`` at t = 0
        (``elements`` (elements, ndof) reference coordinates)."""
        best, where = np.inf, (0, 0.0)
        for e in range(line.elements):
            for xi in np.linspace(0.0, line.length, SEARCH_SAMPLES):
                distance = np.linalg.norm(point - line.derivatives(xi)[0] @ elements[e])
                if distance < best:
                    best, where = distance, (e, float(xi))
        return where

    def _normals(self, dim: int, line: CentreLine, elements: np.ndarray,
                 start: tuple[int, float]) -> tuple[Normal, ...]:
        """The rows' directions: the tangent turned by 90 degrees (2D); e x t and e (3D)."""
        if dim == 2:
            return (Normal(np.array([[0.0, -1.0], [1.0, 0.0]]), 1, np.zeros(2)),)
        e = np.asarray(self.normal, float) if self.normal is not None else \
            _default_normal(line, elements, start)
        tangent = line.derivatives(start[1])[1] @ elements[start[0]]
        if np.linalg.norm(np.cross(e, tangent)) < NORMAL_ANGLE * np.linalg.norm(tangent):
            raise SceneError(f"normal: expected a direction across the line, got "
                             f"{show(self.normal)} along its tangent "
                             f"{tuple(round(float(c), 6) for c in tangent)} at the point")
        cross = np.array([[0.0, -e[2], e[1]], [e[2], 0.0, -e[0]], [-e[1], e[0], 0.0]])
        return Normal(cross, 1, np.zeros(3)), Normal(np.zeros((3, 3)), 1, e)


def _default_normal(line: CentreLine, elements: np.ndarray, start: tuple[int, float]
                    ) -> np.ndarray:
    """The normal of the plane of a curved reference line (its tangents at the nodes span
    it), else (a straight line) the unit vector normal to it closest to z (y for a line
    along z)."""
    tangents = np.array([line.derivatives(xi)[1] @ q for q in elements
                         for xi in (0.0, line.length / 2, line.length)])
    tangents /= np.linalg.norm(tangents, axis=1)[:, None]
    _, singular, axes = np.linalg.svd(tangents)
    if singular[1] > 1e-6 * singular[0]:
        return axes[2]
    t = tangents[0]
    helper = np.array([0.0, 1.0, 0.0]) if abs(t[2]) > 0.9 else np.array([0.0, 0.0, 1.0])
    e = helper - (helper @ t) * t
    return e / np.linalg.norm(e)
