"""Cross-checks of a parsed scene, for what it would do wrong:

* constraints: at most one kind of clamp, pin or prescribed rotation per node (a clamp
  already holds what a pin holds; a clamp and a prescribed rotation contradict each other;
  two clamps or two pins of one node, as at the corner of two clamped edges, are merged;
  two prescribed rotations are refused); a symmetry or fix (which hold parts of a node)
  contradicts a prescribed rotation (beside a clamp or pin it holds what they leave free,
  as at the corner of a clamped edge and a symmetry edge); joints join two
  distinct nodes, each pair once; those that share a position (all but prismatic and
  cylindrical) join nodes at the same place in the reference, never two nodes whose
  positions are already held or already tied by other joints (the multipliers would be
  singular); a weld joins nodes that carry every gradient;
* loads: a point force acts on a node whose position is free, a point moment on a node whose
  section can turn, a line force on a grid line of a rectangle or a node set of a mesh file
  (not on a box's face; a line moment not on a set);
* the frequency estimate of a dynamic analysis has a sensor and enough output samples.
"""

from __future__ import annotations

import math

import numpy as np

from runtime.kernels.kind import element_kind
from runtime.model.bodies import Body
from runtime.model.errors import SceneError, number_text, show
from runtime.model.items.constraints import (
    Constraint,
    Hub,
    Joint,
    NodeConstraint,
    NodePair,
    Weld,
)
from runtime.model.items.loads import Load
from runtime.model.items.sensors import Sensor
from runtime.model.schema import NodeRef
from runtime.model.settings import MULTIPLE_TOLERANCE, Dynamic

# a constraint holding parts of a node (symmetry, fix) beside one of these on the node: why not
PARTIAL_CONFLICTS = {
    "prescribed_rotation": "contradictory: the prescribed rotation drives the node's "
                           "coordinates",
}

# two node constraints on one node: why not (by their types; one type listed: refused twice)
CONFLICTS = {
    frozenset({"clamp", "pin"}): "redundant: the clamp holds every coordinate of the node, the "
                                 "pin only its position; keep the clamp",
    frozenset({"clamp", "prescribed_rotation"}): "contradictory: the clamp holds the node's "
                                                 "gradients, the prescribed rotation turns them",
    frozenset({"pin", "prescribed_rotation"}): "redundant: the prescribed rotation already "
                                               "holds the node's position (a rigid hub); "
                                               "remove the pin",
    frozenset({"prescribed_rotation"}): "a node has at most one prescribed_rotation",
}


def check_constraints(constraints: tuple[Constraint, ...], bodies: tuple[Body, ...]) -> None:
    """Reject constraints that contradict or repeat each other (see the module docstring)."""
    holds: dict[NodeRef, int] = {}   # node -> the constraint holding its position
    for i, c in enumerate(constraints):
        if not isinstance(c, NodeConstraint) or not c.holds_position:
            continue
        for node in c.targets():
            j = holds.setdefault(node, i)
            if j == i:
                continue
            first = constraints[j]
            if first.type == c.type and frozenset({c.type}) not in CONFLICTS:
                continue   # held twice the same way (two clamped edges' corner): merged
            why = CONFLICTS.get(frozenset({first.type, c.type}), "a node has at most one of them")
            where = c.target_key
            raise SceneError(f"constraint[{i}].{where}: constraint[{j}] ({first.type}) and "
                             f"constraint[{i}] ({c.type}) on node {node}: {why}")

    for i, c in enumerate(constraints):
        if not isinstance(c, NodeConstraint) or c.holds_position:
            continue
        for node in c.targets():
            j = holds.get(node)
            if j is not None and constraints[j].type in PARTIAL_CONFLICTS:
                raise SceneError(f"constraint[{i}].{c.target_key}: constraint[{j}] "
                                 f"({constraints[j].type}) and constraint[{i}] ({c.type}) on "
                                 f"node {node}: {PARTIAL_CONFLICTS[constraints[j].type]}")

    by_name = {b.name: b for b in bodies}
    for i, c in enumerate(constraints):
        if isinstance(c, Hub):
            check_hub_axis(f"constraint[{i}].axis", c, by_name[c.node.body])
    scale = max((b.placement.extent() for b in bodies), default=1.0)
    # joints tie node positions together; held nodes are tied to the ground (None)
    parent: dict[NodeRef | None, NodeRef | None] = {}
    ties: dict[NodeRef | None, list[int]] = {}

    def root(node: NodeRef | None) -> NodeRef | None:
        while parent.get(node, node) != node:
            node = parent[node]
        return node

    for node, i in holds.items():
        parent[node] = None
        ties.setdefault(None, []).append(i)
    joined: dict[frozenset, int] = {}
    for i, c in enumerate(constraints):
        if not isinstance(c, NodePair):
            continue
        a, b = c.nodes
        path = f"constraint[{i}].nodes"
        j = joined.setdefault(frozenset(c.nodes), i)
        if j != i:
            raise SceneError(f"{path}: the same joint as constraint[{j}] (nodes {a} and {b}); "
                             f"expected each pair of nodes joined once")
        if not isinstance(c, Joint):      # a prismatic or cylindrical: the nodes apart
            continue
        if isinstance(c, Weld):
            check_weld(path, by_name[a.body], by_name[b.body])
        pa = by_name[a.body].node_position(a.index)
        pb = by_name[b.body].node_position(b.index)
        gap = math.dist(pa, pb)
        if gap > 1e-9 * scale:
            show = lambda p: "(" + ", ".join(number_text(x) for x in p) + ")"  # noqa: E731
            raise SceneError(f"{path}: the nodes of a joint share their position, expected "
                             f"two nodes at the same place in the reference, got {a} at "
                             f"{show(pa)} and {b} at {show(pb)}, {gap:.3g} m apart")
        if a in holds and b in holds:
            raise SceneError(f"{path}: redundant joint: both positions are already held, {a} "
                             f"by constraint[{holds[a]}] ({constraints[holds[a]].type}) and {b} "
                             f"by constraint[{holds[b]}] ({constraints[holds[b]].type})")
        ra, rb = root(a), root(b)
        if ra == rb:
            through = ", ".join(f"constraint[{k}]" for k in sorted(ties[ra]))
            what = "held in place" if ra is None else "tied together"
            raise SceneError(f"{path}: redundant joint: {a} and {b} are already {what} "
                             f"through {through}")
        if ra is None:
            ra, rb = rb, ra
        parent[ra] = rb
        ties[rb] = [*ties.get(rb, []), *ties.pop(ra, []), i]


def check_hub_axis(path: str, hub: Hub, body: Body) -> None:
    """A prescribed rotation of a 3D node that carries one gradient (``ElementKind.frame_gap``:
    a cable's r_x, a shell's r_z) about the direction of that gradient would turn nothing:
    the node stays clamped.  Refused, naming the line's axis or the surface's normal."""
    kind = element_kind(body.element)
    gradients = kind.first_gradients
    if kind.dim != 3 or len(gradients) != 1:
        return
    element, local = np.argwhere(body.mesh.connectivity == hub.node.index)[0]
    e0 = body.placement.element_references(kind, body.counts)[element]
    along = e0.reshape(kind.n_shape, 3)[local * len(kind.vectors)
                                        + kind.vectors.index(gradients[0])]
    axis = np.asarray(hub.axis or (0.0, 0.0, 1.0))
    if np.linalg.norm(np.cross(axis, along)) <= 1e-9 * np.linalg.norm(axis) * np.linalg.norm(
            along):
        what, turn = (("axis", "no section, no torsion") if kind.frame_gap().count("tangent")
                      else ("normal", "no turn about the normal"))
        raise SceneError(f"{path}: a rotation about the {what} of body {body.name!r} "
                         f"({kind.name}, its nodes carry only {', '.join(kind.vectors)}: {turn}) "
                         f"turns none of its coordinates; expected an axis not parallel to the "
                         f"{'cable' if what == 'axis' else 'normal'}, or a clamp")


def check_weld(path: str, a: Body, b: Body) -> None:
    """A weld shares the deformation gradient of two nodes: both must carry every first
    gradient (r_x, r_y[, r_z]) to define it, and nothing else (a higher derivative, r_zz,
    would need the second derivatives of the map between the two nodes' frames)."""
    for body in (a, b):
        kind = element_kind(body.element)
        if len(kind.first_gradients) != kind.dim or len(kind.vectors) != kind.dim + 1:
            frame = ", ".join(f"r_{a}" for a in "xyz"[:kind.dim])
            raise SceneError(f"{path}: a weld ties the full frames ({frame}) of its nodes; "
                             f"{body.element} nodes of body {show(body.name)} carry "
                             f"{', '.join(kind.vectors)}; expected nodes of an element with "
                             f"every first gradient and no higher derivative, or a spherical "
                             f"joint")


def check_loads(loads: tuple[Load, ...], constraints: tuple[Constraint, ...],
                bodies: tuple[Body, ...]) -> None:
    """A load must act on coordinates that its nodes' constraints leave free (on one node of
    an edge at least); a line force acts along a grid line of a rectangle body, not on the
    face of a box body, and a face force on such a face only."""
    boxes = {b.name for b in bodies if b.box is not None}
    for i, load in enumerate(loads):
        edge = getattr(load, "edge", None)
        if edge is not None and edge.set is not None and load.on_gradients:
            raise SceneError(f"load[{i}].edge: {edge} is a node set of a mesh file; a "
                             f"{load.noun} acts along a grid line of a rectangle body (along "
                             f"the sides of a file's cells it is not built yet; a line force "
                             f"is)")
        if edge is not None and edge.body in boxes:
            raise SceneError(f"load[{i}].edge: {edge} is a face of the box body "
                             f"{show(edge.body)}; a {load.noun} acts along a grid line of a "
                             f"rectangle body (on a face: a face_force)")
        face = getattr(load, "face", None)
        if face is not None and face.body not in boxes:
            raise SceneError(f"load[{i}].face: {face} is not a face of a box body; a "
                             f"{load.noun} acts on a lattice plane \"BODY:x=I\", \"BODY:y=J\" "
                             f"or \"BODY:z=K\" of a box body")
    held = {node: i for i, c in enumerate(constraints)
            if isinstance(c, NodeConstraint) and c.holds_position for node in c.targets()}
    for i, load in enumerate(loads):
        targets = load.targets()
        blocked = [held[node] for node in targets if node in held and not (
            load.on_gradients and not constraints[held[node]].holds_gradients)]
        if not targets or len(blocked) < len(targets):
            continue
        j = blocked[0]
        what, can = ("section", "turn") if load.on_gradients else ("position", "move")
        where = load.target_key
        nodes = f"{targets[0]}" if len(targets) == 1 else \
            f"every node of {getattr(load, where)}"
        raise SceneError(f"load[{i}].{where}: the {what} of {nodes} is held by "
                         f"constraint[{j}] ({constraints[j].type}): a {load.noun} there does "
                         f"nothing; expected a node whose {what} can {can}")


def check_frequency(dynamic: Dynamic, sensors: list[Sensor]) -> None:
    path = "analysis.dynamic"
    names = [s.name for s in sensors]
    if dynamic.frequency_of not in names:
        expected = f"one of {', '.join(names)}" if names else "a [[sensor]] name (none defined)"
        raise SceneError(f"{path}.frequency_of: no sensor called {show(dynamic.frequency_of)}; "
                         f"expected {expected}")
    # outputs at multiples of output_every and at t_end
    every = dynamic.output_every or dynamic.step
    first = math.ceil(dynamic.frequency_after / every * (1 - MULTIPLE_TOLERANCE))
    last = dynamic.t_end / every
    samples = math.floor(last * (1 + MULTIPLE_TOLERANCE)) - first + 1
    samples += abs(last - round(last)) > MULTIPLE_TOLERANCE * last
    if samples < 8:
        raise SceneError(f"{path}.frequency_after: the frequency estimate needs at least 8 "
                         f"output samples from frequency_after = "
                         f"{number_text(dynamic.frequency_after)} s to t_end = "
                         f"{number_text(dynamic.t_end)} s, got {samples} (every "
                         f"{number_text(every)} s); expected a smaller frequency_after or "
                         f"output_every")
