"""Reference coordinates e0 of single elements placed in space: straight segments and arcs."""

from __future__ import annotations

import numpy as np

from runtime.kernels import ElementKind


def frame_reference(kind: ElementKind, positions: np.ndarray, frames: np.ndarray) -> np.ndarray:
    """e0 (ndof,) from node positions (nodes, dim) and node frames (nodes, dim, dim).

    frames[i][:, a] is the gradient dr0/dx_a at node i (a unit-speed parameterisation has
    orthonormal frames).  Nodal vectors are taken in the kind's storage order.
    """
    vectors = kind.meta["vectors"]
    e0 = []
    for position, frame in zip(positions, frames, strict=True):
        for name in vectors:
            e0.extend(position if name == "r" else frame[:, "xyz".index(name[-1])])
    return np.array(e0, dtype=float)


def straight_reference(kind: ElementKind, start, end) -> np.ndarray:
    """e0 of a straight element from ``start`` to ``end`` (m); local y lies in the x-y plane
    (perpendicular to the axis: +y for an element along +x), local z completes a right-handed
    frame (+z for an element along +x)."""
    start, end = np.asarray(start, float), np.asarray(end, float)
    axis = end - start
    length = float(np.linalg.norm(axis))
    if length == 0:
        raise ValueError("straight element: start and end coincide")
    tangent = axis / length
    if kind.dim == 2:
        frame = np.column_stack([tangent, [-tangent[1], tangent[0]]])
    else:
        # local y = z x tangent (in the x-y plane); for a near-vertical axis use x instead
        helper = np.array([0.0, 0.0, 1.0]) if abs(tangent[2]) < 0.9 else np.array([1.0, 0, 0])
        normal = np.cross(helper, tangent)
        normal /= np.linalg.norm(normal)
        frame = np.column_stack([tangent, normal, np.cross(tangent, normal)])
    return frame_reference(kind, np.stack([start, end]), np.stack([frame, frame]))


def arc_reference(kind: ElementKind, center, radius: float, start_angle: float,
                  angle: float) -> np.ndarray:
    """e0 of one element on a circular arc in the x-y plane (angles in rad, radius in m).

    The local x is the arc length (element length = radius * |angle|), counter-clockwise for
    angle > 0; local y points to the centre for angle > 0 (away from it for angle < 0) so the
    frame stays right-handed; local z is the plane normal.
    """
    center = np.asarray(center, float)[: kind.dim]
    positions, frames = [], []
    sign = 1.0 if angle > 0 else -1.0
    for theta in (start_angle, start_angle + angle):
        radial = np.array([np.cos(theta), np.sin(theta)])
        tangent = sign * np.array([-np.sin(theta), np.cos(theta)])
        normal = -sign * radial
        position = center[:2] + radius * radial
        if kind.dim == 2:
            positions.append(position)
            frames.append(np.column_stack([tangent, normal]))
        else:
            positions.append(np.append(position, center[2]))
            frames.append(np.column_stack([np.append(tangent, 0), np.append(normal, 0),
                                           [0.0, 0.0, 1.0]]))
    return frame_reference(kind, np.stack(positions), np.stack(frames))
