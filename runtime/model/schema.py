"""The scene schema's building blocks: value checkers, node references and ``Record``, the base
of the typed registries of constraints, loads and sensors (``runtime.model.items.constraints``,
``runtime.model.items.loads``, ``runtime.model.items.sensors``), modelled on the time laws of
``runtime.model.time_laws``.

A record is a frozen dataclass whose fields are the keys of its TOML table
``{type = "...", key = value, ...}``: each field says how its value is checked
(``key(parse)``), ``Record.parse`` reads a table with the messages of every scene error (key
path first), ``Record.to_dict`` writes the table back.  Adding a constraint, load or sensor is
one subclass with a ``type`` and its fields, added to its module's registry.
"""

from __future__ import annotations

import dataclasses
import math
import re
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar, Protocol

import numpy as np

from runtime.element.element import MAGNITUDE
from runtime.model.errors import SceneError, is_finite, show
from runtime.model.mesh import Mesh
from runtime.model.time_laws import Law, parse_law

# what a missing required key should hold, for error messages
HINTS = {
    "E": "Young's modulus in Pa",
    "nu": "Poisson's ratio",
    "rho": "the density in kg/m^3",
    "name": "a name",
    "element": "an element kind",
    "material": "the NAME of a [material.NAME] table",
    "section": "{height = H, width = W} in m",
    "height": "the section height in m",
    "width": "the section width in m",
    "elements": "the number of elements",
    "center": "the centre of the arc in m",
    "radius": "the radius of the arc in m",
    "angle_deg": "the opening angle of the arc in degrees",
    "node": 'a node reference "BODY:INDEX"',
    "nodes": 'two node references ["A:INDEX", "B:INDEX"]',
    "angle": 'a time law of the angle in rad, e.g. {type = "spin_up", omega = 4.0, t_ramp = 15.0}',
    "force": "the force vector in N",
    "moment": "the moment in N m (a number, about z, in 2D; a vector in 3D)",
    "acceleration": "the acceleration vector in m/s^2",
    "component": "x, y, z or norm",
    "omega": "the angular velocity in rad/s (a number, about z, in 2D; a vector in 3D)",
    "about": "the point (m) the body spins about",
    "t_end": "the end time in s",
    "step": "the time step in s",
}
# longest name of a body, material or sensor (characters)
NAME_LENGTH = 64
# a node index: ASCII digits, an optional "-", no "+", blanks, "_" or leading zeros
NODE_INDEX = re.compile(r"0|-?[1-9][0-9]*")


@dataclass(frozen=True)
class NodeRef:
    """Node ``index`` of body ``body`` (in a validated scene: 0 .. nodes - 1; as input,
    negative indices count from the end, and a rectangle body's nodes may be named by grid
    index ``"BODY:I,J"``).  ``str`` gives ``"BODY:INDEX"`` with that index; ``written`` keeps
    the index as the scene wrote it when it differs (not compared), so that the scene's TOML
    (``spelled``) still names the last node (or grid point) after its body is remeshed."""

    body: str
    index: int
    written: str | None = dataclasses.field(default=None, compare=False, repr=False)

    def __str__(self) -> str:
        return f"{self.body}:{self.index}"

    def spelled(self) -> str:
        """``"BODY:INDEX"`` as the scene wrote it."""
        return f"{self.body}:{self.index if self.written is None else self.written}"


@dataclass(frozen=True)
class EdgeRef:
    """The grid line ``axis = line`` of a rectangle body (``"BODY:x=0"``: the nodes of grid
    column 0, the edge at the rectangle's corner; ``"BODY:y=-1"``: the last grid row), or the
    lattice plane of a box body (a face: ``"BODY:z=0"`` its bottom), with
    ``line`` non-negative in a validated scene; or the named node set ``set`` of a body meshed
    from a file (``"BODY:NAME"``; axis "" and line 0).  ``nodes`` are the body's node indices
    on it (from x = 0 to the end along the other axis; a set's in node order; not compared);
    ``written`` as for NodeRef."""

    body: str
    axis: str
    line: int
    nodes: tuple[int, ...] = dataclasses.field(default=(), compare=False, repr=False)
    written: str | None = dataclasses.field(default=None, compare=False, repr=False)
    set: str | None = None

    def __str__(self) -> str:
        if self.set is not None:
            return f"{self.body}:{self.set}"
        return f"{self.body}:{self.axis}={self.line}"

    def spelled(self) -> str:
        """``"BODY:AXIS=LINE"`` (or ``"BODY:NAME"``) as the scene wrote it."""
        if self.set is not None:
            return str(self)
        return f"{self.body}:{self.axis}={self.line if self.written is None else self.written}"

    def refs(self) -> list[NodeRef]:
        """The nodes on the edge, as node references."""
        return [NodeRef(self.body, i) for i in self.nodes]


# --------------------------------------------------------------------------- checkers

def keys(data: Any, path: str, required: tuple[str, ...], optional: tuple[str, ...],
         what: str = "a table") -> dict:
    """Check that ``data`` is a table holding all ``required`` keys and no unknown key."""
    if not isinstance(data, dict):
        raise SceneError(f"{path}: expected {what}, got {show(data)}")
    allowed = (*required, *optional)
    prefix = f"{path}." if path else ""
    for key_ in data:
        if key_ not in allowed:
            raise SceneError(f"{prefix}{key_}: unknown key; expected one of {', '.join(allowed)}")
    for key_ in required:
        if key_ not in data:
            hint = f"; expected {HINTS[key_]}" if key_ in HINTS else ""
            raise SceneError(f"{prefix}{key_}: missing required key{hint}")
    return data


def number(value: Any, path: str, positive: bool = False) -> float:
    """A finite number (a positive one if asked) as a float."""
    if not is_finite(value):
        raise SceneError(f"{path}: expected a {'positive' if positive else 'finite'} number, "
                         f"got {show(value)}")
    if positive and value <= 0:
        raise SceneError(f"{path}: expected a positive number, got {show(value)}")
    return float(value)


def in_range(value: float, path: str, what: str, hint: str = "") -> float:
    """``value`` (a positive number: a size in m, a modulus in Pa, a density in kg/m^3)
    within [1 / MAGNITUDE, MAGNITUDE], the range ``runtime.Element`` takes (``hint``: how to
    fix it)."""
    if not 1 / MAGNITUDE <= value <= MAGNITUDE:
        raise SceneError(f"{path}: expected {what} between {1 / MAGNITUDE:g} and "
                         f"{MAGNITUDE:g}{hint}, got {show(value)}")
    return value


def size(value: Any, path: str, what: str) -> float:
    """A positive finite number within the range of :func:`in_range` (``what`` it is, with
    its unit, e.g. "a section height in m")."""
    return in_range(number(value, path, positive=True), path, what)


def string(value: Any, path: str) -> str:
    """A non-empty string."""
    if not isinstance(value, str) or not value:
        raise SceneError(f"{path}: expected a non-empty string, got {show(value)}")
    return value


def choice(value: Any, path: str, choices: tuple[str, ...], what: str = "value") -> str:
    """One of ``choices``."""
    if not isinstance(value, str) or value not in choices:
        raise SceneError(f"{path}: unknown {what} {show(value)}; expected one of "
                         f"{', '.join(choices)}")
    return value


def boolean(value: Any, path: str) -> bool:
    """true or false."""
    if not isinstance(value, bool):
        raise SceneError(f"{path}: expected true or false, got {show(value)}")
    return value


def vector(value: Any, path: str, dim: int, why: str) -> tuple[float, ...]:
    """A list of ``dim`` finite numbers (``why`` says where ``dim`` comes from)."""
    if not isinstance(value, list) or len(value) != dim or not all(map(is_finite, value)):
        raise SceneError(f"{path}: expected a list of {dim} numbers ({why}), got {show(value)}")
    return tuple(float(x) for x in value)


def rotation_vector(value: Any, path: str, dim: int, what: str) -> float | tuple[float, ...]:
    """A pseudo-vector (moment, angular velocity): a number about z in 2D, a 3-vector in 3D."""
    if dim == 3:
        return vector(value, path, 3, "the scene is 3D")
    if not is_finite(value):
        raise SceneError(f"{path}: expected a number ({what} about z; the scene is 2D), got "
                         f"{show(value)}")
    return float(value)


class MeshedBody(Protocol):
    """What node references are resolved against: a body's name, element kind, node lattice
    and mesh (``runtime.model.bodies.Body``)."""

    name: str
    element: str

    @property
    def grid_shape(self) -> tuple[int, ...]: ...

    @property
    def n_nodes(self) -> int: ...

    @property
    def mesh(self) -> Mesh: ...

    @property
    def node_sets(self) -> dict[str, np.ndarray]: ...


class Nodes:
    """Resolves node references ``"BODY:INDEX"`` (``"BODY:I,J"`` on rectangle bodies: the node
    at point (I, J) of the node lattice, ``runtime.model.mesh``) and edges ``"BODY:x=I"`` /
    ``"BODY:y=J"`` (the nodes on that lattice line) against the bodies of a scene; on a body
    meshed from a file, ``"BODY:NAME"`` names one of its node sets (a node where the set
    holds one node)."""

    def __init__(self, bodies: tuple[MeshedBody, ...]) -> None:
        self.bodies = {b.name: b for b in bodies}

    def _body(self, value: Any, path: str, form: str) -> tuple[MeshedBody, str]:
        if not isinstance(value, str) or value.count(":") != 1:
            raise SceneError(f"{path}: expected {form}, got {show(value)}")
        name, rest = value.split(":")
        if name not in self.bodies:
            raise SceneError(f"{path}: unknown body {show(name)} in {show(value)}; bodies: "
                             f"{', '.join(self.bodies)}")
        return self.bodies[name], rest

    def __call__(self, value: Any, path: str) -> NodeRef:
        body, text = self._body(value, path, 'a node reference "BODY:INDEX"')
        shape = body.grid_shape
        if not shape and not NODE_INDEX.fullmatch(text):
            nodes = self._set(body, text, path, value)
            if len(nodes) != 1:
                raise SceneError(f"{path}: set {show(text)} of body {show(body.name)} holds "
                                 f"{len(nodes)} nodes; a node reference names one (sets of "
                                 f"several nodes go where an edge is taken, e.g. the edge of "
                                 f"a clamp), got {show(value)}")
            return NodeRef(body.name, int(nodes[0]), text)
        if "," in text and len(shape) >= 2:
            parts = text.split(",")
            if len(parts) != len(shape):
                form, count_ = (("I,J", "two") if len(shape) == 2 else ("I,J,K", "three"))
                raise SceneError(f'{path}: expected a grid index "BODY:{form}" ({count_} '
                                 f"integers), got {show(value)}")
            grid = tuple(_index(part, n, path, value, f"grid index {axis}",
                                f"body {show(body.name)} with {n} node {what}")
                         for part, n, axis, what in zip(parts, shape, "IJK",
                                                        ("columns", "rows", "layers"),
                                                        strict=False))
            index = body.mesh.node_at(grid)
            if index is None:
                point = ",".join(map(str, grid))
                near = ", ".join(f'"{body.name}:{",".join(map(str, body.mesh.lattice[k]))}" '
                                 f"(node {k})" for k in body.mesh.nearest(grid))
                raise SceneError(f"{path}: no node at grid point {point} of body "
                                 f"{show(body.name)} ({body.element} elements place nodes on "
                                 f"part of its {' x '.join(map(str, shape))} node lattice); "
                                 f"nearest nodes: {near}")
            return NodeRef(body.name, index, None if text == str(index) else text)
        n = body.n_nodes
        index = _index(text, n, path, value, "node index",
                       f"body {show(body.name)} with {n} nodes", grid=len(shape) >= 2)
        return NodeRef(body.name, index, None if text == str(index) else text)

    def edge(self, value: Any, path: str) -> EdgeRef:
        """An edge (a node lattice line) ``"BODY:x=I"`` or ``"BODY:y=J"`` of a rectangle
        body, or a face (a lattice plane, also ``"BODY:z=K"``) of a box body: the nodes on it,
        in node order (along the line; x fastest, then y, on a face)."""
        form = 'an edge "BODY:x=I" or "BODY:y=J" (a grid line of a rectangle body)'
        body, text = self._body(value, path, form)
        shape = body.grid_shape
        if not shape:
            nodes = self._set(body, text, path, value)
            return EdgeRef(body.name, "", 0, tuple(int(i) for i in nodes), set=text)
        if len(shape) == 1:
            raise SceneError(f"{path}: body {show(body.name)} is a line of {body.element} "
                             f"elements; edges are grid lines of rectangle bodies (use node "
                             f'"{body.name}:INDEX"), got {show(value)}')
        if len(shape) == 3:
            form = ('a face "BODY:x=I", "BODY:y=J" or "BODY:z=K" (a lattice plane of a box '
                    'body)')
        if text[:2] not in tuple(f"{axis}=" for axis in "xyz"[:len(shape)]):
            raise SceneError(f"{path}: expected {form}, got {show(value)}")
        axis = text[0]
        a = "xyz".index(axis)
        n = shape[a]
        line = _index(text[2:], n, path, value, f"grid line {axis}",
                      f"body {show(body.name)} with {n} node "
                      f"{('columns', 'rows', 'layers')[a]}")
        nodes = tuple(int(i) for i in body.mesh.on_line(a, line))
        return EdgeRef(body.name, axis, line, nodes, None if text[2:] == str(line) else text[2:])


    @staticmethod
    def _set(body: MeshedBody, name: str, path: str, value: str) -> np.ndarray:
        """The nodes of set ``name`` of a body meshed from a file (SceneError at ``path``
        listing its sets when it has none of that name, or when the set holds none of the
        body's nodes)."""
        sets = body.node_sets
        if name not in sets:
            known = ", ".join(sorted(sets)) or "none"
            raise SceneError(f"{path}: body {show(body.name)} (meshed from a file) has no node "
                             f"set {show(name)} in {show(value)}; expected a node index or "
                             f"one of its sets: {known}")
        if not len(sets[name]):
            raise SceneError(f"{path}: set {show(name)} of body {show(body.name)} names no "
                             f"node of the body (it is empty, or its points lie on none of "
                             f"the body's cells); expected a set of the body's nodes, got "
                             f"{show(value)}")
        return sets[name]


def _index(text: str, n: int, path: str, value: str, noun: str, owner: str,
           grid: bool = False) -> int:
    """A ``noun`` ("node index") in -n .. n - 1 of ``owner`` ('body "b" with 11 nodes'),
    written as ASCII digits (NODE_INDEX), made non-negative."""
    if not NODE_INDEX.fullmatch(text):
        also = ' or a grid index "I,J"' if grid else ""
        raise SceneError(f'{path}: expected an integer {noun} after ":" (ASCII digits and an '
                         f'optional leading "-"; no "+", blanks, "_" or leading zeros, "-0" '
                         f'neither: 0 is the first, -1 the last){also}, got {show(value)}')
    index = int(text) if len(text) <= 20 else None
    if index is None or not -n <= index < n:
        shown = text if index is not None else f"{text[:20]}..."
        raise SceneError(f"{path}: {noun} {shown} out of range for {owner} (0..{n - 1} or "
                         f"-{n}..-1)")
    return index % n


@dataclass(frozen=True)
class Context:
    """What a record's values are checked against: the scene's dimension and bodies, and
    the folder of its file (``None`` for a scene built in Python), where the modules of
    Python functions are looked for first."""

    dim: int
    node: Nodes
    folder: str | None = None
    #: the rigid bodies and point masses by name (``runtime.model.items.rigid``)
    rigid: dict = dataclasses.field(default_factory=dict)

    @property
    def body_names(self) -> tuple[str, ...]:
        """Names of the scene's bodies, in order."""
        return tuple(self.node.bodies)


# --------------------------------------------------------------------------- TOML values

def plain(value: Any) -> Any:
    """``value`` as TOML data (tables, lists, strings, numbers, booleans): scene objects by
    their ``to_dict``, node references as ``"BODY:INDEX"`` (as written), NumPy arrays and
    scalars as lists and Python numbers; anything else unchanged (the parser then says what
    is wrong)."""
    if hasattr(value, "to_dict"):
        return value.to_dict()
    if isinstance(value, NodeRef | EdgeRef):
        return value.spelled()
    if isinstance(value, dict):
        return {k: plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [plain(v) for v in value]
    if isinstance(value, np.ndarray):
        return plain(value.tolist())
    if isinstance(value, np.generic):
        return value.item()
    return value


def table(obj: Any, skip: tuple[str, ...] = ()) -> dict[str, Any]:
    """The TOML table of a dataclass: its fields (named as the TOML keys) as ``plain`` data,
    without ``skip`` and those left at None or at their default."""
    out: dict[str, Any] = {}
    for f in sorted(dataclasses.fields(obj), key=lambda f: f.kw_only):   # keyword-only last
        value = getattr(obj, f.name)
        if f.name in skip or value is None or (f.default is not dataclasses.MISSING
                                               and same(value, f.default)):
            continue
        out[f.name] = plain(value)
    return out


def same(value: Any, default: Any) -> bool:
    """``value == default`` for scene values of any type (False where == is not a bool)."""
    try:
        return type(value) is type(default) and bool(value == default)
    except (TypeError, ValueError):
        return False


# --------------------------------------------------------------------------- records

Parse = Callable[[Any, str, Context], Any]


def key(parse: Parse, default: Any = dataclasses.MISSING, only_3d: str = "",
        kw_only: bool = False) -> Any:
    """A record field read by ``parse(value, path, context)``; without ``default`` the TOML key
    is required; ``only_3d`` (why) makes it an error in 2D scenes; ``kw_only`` makes it a
    keyword-only argument (a base class field with a default)."""
    return dataclasses.field(default=default, kw_only=kw_only,
                             metadata={"parse": parse, "only_3d": only_3d})


def node_key(value: Any, path: str, context: Context) -> NodeRef:
    """A node reference "BODY:INDEX" (or "BODY:I,J" on a rectangle body)."""
    return context.node(value, path)


def edge_key(value: Any, path: str, context: Context) -> EdgeRef:
    """An edge "BODY:x=I" / "BODY:y=J" of a rectangle body."""
    return context.node.edge(value, path)


def law_key(value: Any, path: str, context: Context) -> Law:
    """A time law table."""
    return parse_law(value, path, context.folder)


@dataclass(frozen=True)
class Record:
    """Base of constraints, loads and sensors: ``type`` names the class in scenes, ``dims`` the
    scene dimensions it exists in (``dims_message`` says why not, at the ``type`` key)."""

    type: ClassVar[str] = ""
    dims: ClassVar[tuple[int, ...]] = (2, 3)
    dims_message: ClassVar[str] = ""

    @classmethod
    def parse(cls, data: dict, path: str, context: Context) -> Record:
        """The record of the TOML table ``data`` (its ``type`` already read) at ``path``."""
        if context.dim not in cls.dims:
            raise SceneError(f"{path}.type: {cls.dims_message}")
        fields = [f for f in dataclasses.fields(cls) if "parse" in f.metadata]
        for f in fields:
            if f.metadata["only_3d"] and context.dim == 2 and f.name in data:
                raise SceneError(f"{path}.{f.name}: only allowed in 3D scenes "
                                 f"({f.metadata['only_3d']})")
        present = [f for f in fields if context.dim == 3 or not f.metadata["only_3d"]]
        required = tuple(f.name for f in present if f.default is dataclasses.MISSING)
        optional = tuple(f.name for f in present if f.default is not dataclasses.MISSING)
        keys(data, path, ("type", *required), optional)
        values = {f.name: f.metadata["parse"](data[f.name], f"{path}.{f.name}", context)
                  for f in present if f.name in data}
        return cls(**values).resolved(context)

    def resolved(self, context: Context) -> Record:
        """This record with defaults that depend on the scene filled in (after ``parse``)."""
        return self

    def to_dict(self) -> dict[str, Any]:
        """The TOML table of this record (``parse`` of it gives the record back)."""
        return {"type": self.type, **table(self)}


def parse_record(registry: dict[str, type[Record]], what: str, data: dict, path: str,
                 context: Context) -> Record:
    """The record of one TOML table of an array ``[[what]]`` (``type`` chooses its class in
    ``registry``)."""
    if "type" not in data:
        raise SceneError(f"{path}.type: missing required key; expected one of "
                         f"{', '.join(registry)}")
    name = choice(data["type"], f"{path}.type", tuple(registry), f"{what} type")
    return registry[name].parse(data, path, context)


def registry(*classes: type[Record]) -> dict[str, type[Record]]:
    """{type: class} of record classes, in the order given."""
    return {cls.type: cls for cls in classes}


def unit_axis(value: Any, path: str, dim: int = 3) -> tuple[float, ...]:
    """A non-zero axis of ``dim`` components, normalised (an axis already of unit length to
    1e-12 is kept as it is, so that reading a written scene gives the same numbers)."""
    axis = vector(value, path, dim, f"an axis in {dim}D")
    norm = math.hypot(*axis)
    if norm == 0.0:
        raise SceneError(f"{path}: expected a non-zero axis, got {show(value)}")
    if abs(norm - 1.0) <= 1e-12:
        return axis
    return tuple(x / norm for x in axis)


def count(value: Any, path: str, maximum: int | None = None, why: str = "") -> int:
    """A positive integer (TOML integer: a float such as 1e20 or 10.0 is not one), at most
    ``maximum`` (``why`` says where the limit comes from)."""
    if isinstance(value, float):
        hint = f"; write {int(value)}" if value.is_integer() and abs(value) < 1e15 else ""
        raise SceneError(f"{path}: expected an integer, got {show(value)} (a float{hint})")
    if isinstance(value, bool) or not isinstance(value, int) or value <= 0:
        raise SceneError(f"{path}: expected a positive integer, got {show(value)}")
    if maximum is not None and value > maximum:
        raise SceneError(f"{path}: expected at most {maximum}{why}, got {show(value)}")
    return value


def checked_name(value: Any, path: str, what: str = "a name") -> str:
    """A non-empty printable name of at most NAME_LENGTH characters, without blanks around."""
    name = string(value, path)
    if len(name) > NAME_LENGTH:
        raise SceneError(f"{path}: expected {what} of at most {NAME_LENGTH} characters, got "
                         f"{len(name)} characters {show(name)}")
    if not name.isprintable() or name != name.strip():
        raise SceneError(f"{path}: expected {what} of printable characters without blanks at "
                         f"either end, got {show(name)}")
    return name
