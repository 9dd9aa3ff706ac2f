"""Reference coordinates e0 of elements placed in space (straight segments, arcs, flat
rectangles, bent panels) and node frames, for any element kind: node points and nodal vectors
come from element.json (``runtime.kernels.kind``)."""

from __future__ import annotations

import numpy as np

from runtime.kernels.kind import ElementKind, is_first_gradient, vector_axes

#: The axes of the second derivative along the local x, r_xx: the curvature vector of a
#: line (a quintic cable's nodal vector), which the curved placements compute.
CURVATURE_AXES = (0, 0)


def frame_reference(kind: ElementKind, positions: np.ndarray, frames: np.ndarray,
                    curvatures: np.ndarray | None = None) -> np.ndarray:
    """e0 (ndof,) from node positions (nodes, dim), node frames (nodes, dim, dim) and, for a
    placement curved along its local x, the curvature vectors (nodes, dim).

    frames[i][:, a] is the gradient dr0/dx_a at node i (a unit-speed parameterisation has
    orthonormal frames); curvatures[i] is d^2 r0 / dx^2 at node i (1/m; -(1/R) times the
    radial unit vector on an arc of radius R), the r_xx a kind may carry (zero when None: a
    straight axis).  Nodal vectors are taken in the kind's storage order; other higher
    derivatives (r_zz, r_xy, ...) are zero: the reference is linear across the section or the
    thickness (straight fibres: ``curved_reference_check``).
    """
    e0 = []
    zero = np.zeros(kind.dim)
    for i, (position, frame) in enumerate(zip(positions, frames, strict=True)):
        for name in kind.vectors:
            axes = vector_axes(name)
            if not axes:
                e0.extend(position)
            elif len(axes) == 1:
                e0.extend(frame[:, axes[0]])
            elif axes == CURVATURE_AXES and curvatures is not None:
                e0.extend(curvatures[i])
            else:
                e0.extend(zero)
    return np.array(e0, dtype=float)


def curved_reference_check(kind: ElementKind, what: str, curvature: bool = False) -> None:
    """Raise ValueError if ``kind`` carries a higher derivative along a meshed axis (r_xx,
    r_xz of a beam or shell) that the placement does not compute: on a reference curved
    along that axis it is not zero.  A placement that computes the curvature of its local x
    (``curvature``: arcs, bent elements) gives r_xx.  Derivatives across the section or the
    thickness only (r_zz of a shell) are zero on them: their fibres are straight."""
    computed = {CURVATURE_AXES} if curvature else set()
    curved = [name for name in kind.vectors if len(vector_axes(name)) > 1
              and set(vector_axes(name)) & set(kind.mesh_axes)
              and vector_axes(name) not in computed]
    if curved:
        raise ValueError(f"{what} element: {kind.name} carries {', '.join(curved)}, "
                         "derivatives along the curved axis that this placement does not "
                         "compute; expected a straight or flat placement")


def gradient_frame(gradients: dict[str, np.ndarray], dim: int) -> np.ndarray:
    """Orthonormal frame (dim, dim) from a node's gradient vectors {"r_x": (dim,), ...}:
    orthonormalised with r_x kept as the first axis.  A missing gradient (r_x of a 3-node
    beam) is completed from the others: r_x = r_y x r_z in 3D, r_y turned by -90 degrees in
    2D (so the frame stays right-handed).  Gradients of shape (k, dim) give k frames
    (k, dim, dim)."""
    axes = "xyz"[:dim]
    columns = {name[-1]: np.asarray(value, float) for name, value in gradients.items()
               if is_first_gradient(name)}
    missing = [a for a in axes if a not in columns]
    if len(missing) > 1:
        raise ValueError(f"frame: a node with gradients {sorted(gradients)} has too few to "
                         f"define a frame in {dim}D")
    if missing and dim == 3:
        i = axes.index(missing[0])
        columns[missing[0]] = np.cross(columns[axes[(i + 1) % 3]], columns[axes[(i + 2) % 3]])
    elif missing:
        other = columns["y" if missing[0] == "x" else "x"]
        sign = 1.0 if missing[0] == "x" else -1.0
        columns[missing[0]] = sign * np.stack([other[..., 1], -other[..., 0]], axis=-1)
    # modified Gram-Schmidt, vectorised over a block (a QR factorisation with a positive
    # diagonal: np.linalg.qr of many small matrices costs microseconds each)
    basis: list[np.ndarray] = []
    for a in axes:
        column = columns[a]
        for unit in basis:
            column = column - np.sum(column * unit, axis=-1, keepdims=True) * unit
        basis.append(column / np.linalg.norm(column, axis=-1, keepdims=True))
    return np.stack(basis, axis=-1)


def straight_reference(kind: ElementKind, start, end) -> np.ndarray:
    """e0 of a straight line element from ``start`` to ``end`` (m); its nodes at their
    fractions of the length (0, 1 for 2-node beams; 0, 1/2, 1 for 3-node beams); local y lies
    in the x-y plane (perpendicular to the axis: +y for an element along +x), local z
    completes a right-handed frame (+z for an element along +x)."""
    if kind.mesh_axes != [0]:
        raise ValueError(f"straight element: {kind.name} is not a line element (use "
                         "rectangle_reference)")
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
    fractions = kind.node_fractions[:, 0]
    positions = start[None, :] + fractions[:, None] * axis[None, :]
    return frame_reference(kind, positions, np.stack([frame] * kind.n_nodes))


def rectangle_reference(kind: ElementKind, origin, side_x, side_y) -> np.ndarray:
    """e0 of a flat rectangular (plate) element: corner ``origin`` (m), local x along the
    vector ``side_x`` (its length is the side a), local y along ``side_y`` (side b,
    perpendicular to side_x), local z their unit normal; nodes at their fractions of a, b."""
    if kind.mesh_axes != [0, 1]:
        raise ValueError(f"rectangle element: {kind.name} is not a plate element")
    origin, side_x, side_y = (np.asarray(v, float) for v in (origin, side_x, side_y))
    a, b = np.linalg.norm(side_x), np.linalg.norm(side_y)
    if a == 0 or b == 0 or abs(side_x @ side_y) > 1e-12 * a * b:
        raise ValueError("rectangle element: expected two nonzero perpendicular sides")
    normal = np.cross(side_x, side_y)
    frame = np.column_stack([side_x / a, side_y / b, normal / np.linalg.norm(normal)])
    fractions = kind.node_fractions
    positions = origin + fractions[:, :1] * side_x + fractions[:, 1:2] * side_y
    return frame_reference(kind, positions, np.stack([frame] * kind.n_nodes))


def bent_reference(kind: ElementKind, geometry, radius: float) -> np.ndarray:
    """e0 of one element of ``geometry`` (length, height, width) bent along its local x onto
    a circle of ``radius`` (x is arc length): beams and solids in the x-y plane from the
    origin towards +y (r_y pointing to the centre; a solid's z kept); plates into a
    cylindrical panel about an axis parallel to y, towards +z (r_z the outward normal of
    the flat panel turned with it)."""
    curved_reference_check(kind, "bent", curvature=True)
    points = kind.node_points(*geometry)
    positions, frames, curvatures = [], [], []
    plate = kind.mesh_axes == [0, 1]
    for p in points:
        t = p[0] / radius
        c, s = np.cos(t), np.sin(t)
        if plate:
            positions.append([radius * s, p[1], radius * (1 - c)])
            frames.append(np.column_stack([[c, 0, s], [0, 1, 0], [-s, 0, c]]))
            curvatures.append(np.array([-s, 0.0, c]) / radius)
        else:
            position = radius * np.array([s, 1 - c, 0.0]) + p[1] * np.array([-s, c, 0.0])
            if len(p) > 2:      # a solid's nodes off the x-y plane keep their z
                position[2] += p[2]
            frame = np.column_stack([[c, s, 0], [-s, c, 0], [0, 0, 1]])
            # d^2/dx^2 of the position: (1/R) (1 - y/R) towards the centre (0, R)
            curvature = (1 - p[1] / radius) / radius * np.array([-s, c, 0.0])
            positions.append(position[: kind.dim])
            frames.append(frame[: kind.dim, : kind.dim])
            curvatures.append(curvature[: kind.dim])
    return frame_reference(kind, np.array(positions, float), np.array(frames, float),
                           np.array(curvatures, float))


def arc_reference(kind: ElementKind, center, radius: float, start_angle: float,
                  angle: float) -> np.ndarray:
    """e0 of one element on a circular arc in the x-y plane (angles in rad, radius in m).

    The local x is the arc length (element length = radius * |angle|), counter-clockwise for
    angle > 0; local y points to the centre for angle > 0 (away from it for angle < 0) so the
    frame stays right-handed; local z is the plane normal.
    """
    if kind.mesh_axes != [0]:
        raise ValueError(f"arc element: {kind.name} is not a line element")
    curved_reference_check(kind, "arc", curvature=True)
    center = np.asarray(center, float)[: kind.dim]
    positions, frames = [], []
    sign = 1.0 if angle > 0 else -1.0
    thetas = start_angle + angle * kind.node_fractions[:, 0]
    for theta in thetas:
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
    # d^2 r / ds^2 = -(1/R) times the radial unit vector, whichever way the arc turns
    radial = np.column_stack([np.cos(thetas), np.sin(thetas), np.zeros_like(thetas)])
    return frame_reference(kind, np.stack(positions), np.stack(frames),
                           -radial[:, : kind.dim] / radius)
