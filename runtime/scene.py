"""Scenes: a TOML file (DESIGN.md section 7) -> a validated, typed ``Scene``.

Units SI: lengths in m, forces in N, accelerations in m/s^2, E in Pa, rho in kg/m^3, angles
in degrees where the key says ``_deg`` and in rad in time laws, times in s.

Every error is a ``SceneError`` whose message starts with the key path of the culprit
(``body[1].sectoin: unknown key; expected one of ...``) and says what was expected and what
was found.  Node references ``"BODY:INDEX"`` are resolved: ``NodeRef.index`` is always the
non-negative node index (0 .. elements).
"""

from __future__ import annotations

import math
import re
import tomllib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from runtime.catalog import ENGINES, NEWTON_MODES
from runtime.element import METHODS
from runtime.kernels import BACKENDS, element_kind, known_kinds
from runtime.laws import Constant, Law, SceneError, _is_number, _show, parse_law

__all__ = [
    "Arc",
    "Body",
    "Constraint",
    "Dynamic",
    "Load",
    "Material",
    "Modal",
    "NodeRef",
    "Scene",
    "SceneError",
    "Sensor",
    "Solver",
    "Static",
    "load_scene",
    "parse_scene",
]

CONSTRAINT_TYPES = ("clamp", "pin", "prescribed_rotation", "spherical", "revolute")
LOAD_TYPES = ("point_force", "gravity")
SENSOR_TYPES = ("displacement", "position", "strain_energy", "kinetic_energy",
                "potential_energy", "total_energy", "constraint_violation")
INTEGRATORS = ("trapezoidal", "generalized_alpha")

MODAL_ABOUT = ("reference", "static")
# names of sensors become CSV columns and PNG file names; "t" is the time column and
# "energies" the energy plot
SENSOR_NAME = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.\-]*")
RESERVED_SENSOR_NAMES = ("t", "energies")
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
    "acceleration": "the acceleration vector in m/s^2",
    "component": "x, y, z or norm",
    "t_end": "the end time in s",
    "step": "the time step in s",
}


# --------------------------------------------------------------------------- dataclasses

@dataclass(frozen=True)
class NodeRef:
    """Node ``index`` (0-based, resolved: 0 .. elements) of body ``body``."""

    body: str
    index: int

    def __str__(self) -> str:
        return f"{self.body}:{self.index}"


@dataclass(frozen=True)
class Material:
    """St. Venant-Kirchhoff material: E (Pa) > 0, -1 < nu < 0.5, rho (kg/m^3) > 0."""

    name: str
    E: float
    nu: float
    rho: float


@dataclass(frozen=True)
class Arc:
    """Circular arc in the x-y plane (at the centre's z in 3D): centre (dim,) in m, radius (m),
    start angle and opening angle (deg, counter-clockwise about +z when positive)."""

    center: tuple[float, ...]
    radius: float
    start_angle_deg: float
    angle_deg: float


@dataclass(frozen=True)
class Body:
    """A mesh of ``elements`` elements of kind ``element`` (``elements + 1`` nodes).

    material: the name of a material of ``Scene.materials``; height, width: section (m);
    either ``start``/``end`` (dim,) in m (straight) or ``arc``; quadrature: Gauss orders
    (dim,) or None for the kind's default.
    """

    name: str
    element: str
    material: str
    height: float
    width: float
    elements: int
    start: tuple[float, ...] | None
    end: tuple[float, ...] | None
    arc: Arc | None
    quadrature: tuple[int, ...] | None

    @property
    def dim(self) -> int:
        """Spatial dimension of the element kind (2 or 3)."""
        return element_kind(self.element).dim

    @property
    def n_nodes(self) -> int:
        """Number of nodes, ``elements + 1``."""
        return self.elements + 1


@dataclass(frozen=True)
class Constraint:
    """A constraint: ``clamp`` / ``pin`` / ``prescribed_rotation`` act on ``node``;
    ``spherical`` / ``revolute`` join the two ``nodes``.  ``angle``: the law of the prescribed
    rotation (rad); ``axis``: unit rotation axis (3,) in 3D (default +z), None in 2D."""

    type: str
    node: NodeRef | None
    nodes: tuple[NodeRef, NodeRef] | None
    angle: Law | None
    axis: tuple[float, ...] | None


@dataclass(frozen=True)
class Load:
    """``point_force`` at ``node`` (vector: force, N) or ``gravity`` on every body (vector:
    acceleration, m/s^2, node None); the vector (dim,) is scaled by ``law.value(t)``."""

    type: str
    node: NodeRef | None
    vector: tuple[float, ...]
    law: Law


@dataclass(frozen=True)
class Sensor:
    """A named output: ``displacement`` / ``position`` (m) of ``node``, ``component`` x|y|z|norm,
    in the frame of node ``frame`` when given; ``strain_energy`` / ``kinetic_energy`` (J) of
    ``body`` (None: the whole model); ``potential_energy`` (J, of gravity) and
    ``total_energy`` (J, strain + kinetic + potential) of the whole model;
    ``constraint_violation`` (norm of the constraints)."""

    name: str
    type: str
    node: NodeRef | None
    component: str | None
    frame: NodeRef | None
    body: str | None


@dataclass(frozen=True)
class Static:
    """Static analysis: Newton-Raphson, at most ``max_iterations`` per load increment,
    convergence ``tolerance`` (relative), loads applied in ``load_steps`` equal increments."""

    max_iterations: int = 50
    tolerance: float = 1e-10
    load_steps: int = 1


@dataclass(frozen=True)
class Modal:
    """Modal analysis: the ``modes`` lowest frequencies about the reference configuration or
    the static solution."""

    modes: int = 4
    about: str = "reference"


@dataclass(frozen=True)
class Dynamic:
    """Dynamic analysis from 0 to ``t_end`` (s) with time step ``step`` (s); outputs every
    ``output_every`` s (None: every step); ``rho_inf`` in [0, 1] for generalized-alpha."""

    t_end: float
    step: float
    integrator: str = "trapezoidal"
    output_every: float | None = None
    rho_inf: float = 0.8
    tolerance: float = 1e-10
    max_iterations: int = 20
    frequency_of: str | None = None    # sensor whose oscillation frequency is measured ...
    frequency_after: float = 0.0       # ... from this time (s) to t_end
    newton: str = "full"               # full | modified (Jacobian kept while it converges)


@dataclass(frozen=True)
class Solver:
    """Elastic force method (gram | cij | quadrature) and kernel backend (c | numpy)."""

    method: str = "gram"
    backend: str = "c"
    engine: str | None = None          # compiled | python; None: compiled with backend c


@dataclass(frozen=True)
class Scene:
    """A validated scene; ``source`` is the file it came from (or ``"<scene>"``)."""

    title: str
    materials: dict[str, Material]
    bodies: tuple[Body, ...]
    constraints: tuple[Constraint, ...]
    loads: tuple[Load, ...]
    sensors: tuple[Sensor, ...]
    static: Static | None
    modal: Modal | None
    dynamic: Dynamic | None
    solver: Solver
    source: str

    @property
    def dim(self) -> int:
        """Spatial dimension shared by every body (2 or 3)."""
        return self.bodies[0].dim

    def body(self, name: str) -> Body:
        """The body called ``name`` (KeyError otherwise)."""
        for body in self.bodies:
            if body.name == name:
                return body
        raise KeyError(name)

    def material_of(self, body: Body | str) -> Material:
        """The material of a body (or of the body called so)."""
        b = self.body(body) if isinstance(body, str) else body
        return self.materials[b.material]


# --------------------------------------------------------------------------- checkers

def _keys(data: Any, path: str, required: tuple[str, ...], optional: tuple[str, ...],
          what: str = "a table") -> dict:
    """Check that ``data`` is a table holding all ``required`` keys and no unknown key."""
    if not isinstance(data, dict):
        raise SceneError(f"{path}: expected {what}, got {_show(data)}")
    allowed = (*required, *optional)
    prefix = f"{path}." if path else ""
    for key in data:
        if key not in allowed:
            raise SceneError(f"{prefix}{key}: unknown key; expected one of {', '.join(allowed)}")
    for key in required:
        if key not in data:
            hint = f"; expected {HINTS[key]}" if key in HINTS else ""
            raise SceneError(f"{prefix}{key}: missing required key{hint}")
    return data


def _number(value: Any, path: str, positive: bool = False) -> float:
    if not _is_number(value) or not math.isfinite(value):
        raise SceneError(f"{path}: expected a {'positive ' if positive else ''}number, "
                         f"got {_show(value)}")
    if positive and value <= 0:
        raise SceneError(f"{path}: expected a positive number, got {_show(value)}")
    return float(value)


def _count(value: Any, path: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value <= 0:
        raise SceneError(f"{path}: expected a positive integer, got {_show(value)}")
    return value


def _string(value: Any, path: str) -> str:
    if not isinstance(value, str) or not value:
        raise SceneError(f"{path}: expected a non-empty string, got {_show(value)}")
    return value


def _choice(value: Any, path: str, choices: tuple[str, ...], what: str = "value") -> str:
    if not isinstance(value, str) or value not in choices:
        raise SceneError(f"{path}: unknown {what} {_show(value)}; expected one of "
                         f"{', '.join(choices)}")
    return value


def _vector(value: Any, path: str, dim: int, why: str) -> tuple[float, ...]:
    if (not isinstance(value, list) or len(value) != dim
            or not all(_is_number(x) and math.isfinite(x) for x in value)):
        raise SceneError(f"{path}: expected a list of {dim} numbers ({why}), got {_show(value)}")
    return tuple(float(x) for x in value)


def _array_of_tables(data: dict, key: str) -> list:
    value = data.get(key, [])
    if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
        raise SceneError(f"{key}: expected an array of tables ([[{key}]]), got {_show(value)}")
    return value


# --------------------------------------------------------------------------- parsers

def _material(name: str, data: Any) -> Material:
    path = f"material.{name}"
    _keys(data, path, ("E", "nu", "rho"), ())
    E = _number(data["E"], f"{path}.E", positive=True)
    nu = _number(data["nu"], f"{path}.nu")
    if not -1.0 < nu < 0.5:
        raise SceneError(f"{path}.nu: expected a Poisson ratio in (-1, 0.5), got {_show(nu)}")
    rho = _number(data["rho"], f"{path}.rho", positive=True)
    return Material(name, E, nu, rho)


def _body(i: int, data: dict, materials: dict[str, Material]) -> Body:
    path = f"body[{i}]"
    _keys(data, path, ("name", "element", "material", "section", "elements"),
          ("start", "end", "arc", "quadrature"))
    name = _string(data["name"], f"{path}.name")
    if ":" in name:
        raise SceneError(f'{path}.name: expected a name without ":", got {_show(name)}')
    kinds = tuple(known_kinds())
    kind = _choice(data["element"], f"{path}.element", kinds, "element kind")
    dim = element_kind(kind).dim
    why = f"{kind} is {dim}D"
    material = _string(data["material"], f"{path}.material")
    if material not in materials:
        defined = ", ".join(materials) or "none"
        raise SceneError(f"{path}.material: material {_show(material)} is not defined; "
                         f"defined materials: {defined}")
    section = _keys(data["section"], f"{path}.section", ("height", "width"), (),
                    "a table {height = H, width = W}")
    height = _number(section["height"], f"{path}.section.height", positive=True)
    width = _number(section["width"], f"{path}.section.width", positive=True)
    elements = _count(data["elements"], f"{path}.elements")

    straight = "start" in data or "end" in data
    if straight and "arc" in data:
        raise SceneError(f"{path}: expected either start and end or arc, got both")
    start = end = None
    arc = None
    if straight:
        for key in ("start", "end"):
            if key not in data:
                raise SceneError(f"{path}.{key}: missing required key; expected a point in m "
                                 "(a straight body needs start and end)")
        start = _vector(data["start"], f"{path}.start", dim, why)
        end = _vector(data["end"], f"{path}.end", dim, why)
        if start == end:
            raise SceneError(f"{path}.end: expected a point different from start, got "
                             f"{_show(data['end'])}")
    elif "arc" in data:
        apath = f"{path}.arc"
        a = _keys(data["arc"], apath, ("center", "radius", "angle_deg"), ("start_angle_deg",),
                  "a table {center = [...], radius = R, angle_deg = A}")
        center = _vector(a["center"], f"{apath}.center", dim, why)
        radius = _number(a["radius"], f"{apath}.radius", positive=True)
        start_angle = _number(a.get("start_angle_deg", 0.0), f"{apath}.start_angle_deg")
        angle = _number(a["angle_deg"], f"{apath}.angle_deg")
        if angle == 0.0 or abs(angle) > 360.0:
            raise SceneError(f"{apath}.angle_deg: expected a non-zero angle of at most 360 "
                             f"degrees in magnitude, got {_show(a['angle_deg'])}")
        arc = Arc(center, radius, start_angle, angle)
    else:
        raise SceneError(f"{path}: expected start and end (straight) or arc, got neither")

    quadrature = None
    if "quadrature" in data:
        q = data["quadrature"]
        if (not isinstance(q, list) or len(q) != dim
                or not all(isinstance(n, int) and not isinstance(n, bool) and n > 0 for n in q)):
            raise SceneError(f"{path}.quadrature: expected a list of {dim} positive integers "
                             f"({why}), got {_show(q)}")
        quadrature = tuple(q)
    return Body(name, kind, material, height, width, elements, start, end, arc, quadrature)


class _Nodes:
    """Resolves ``"BODY:INDEX"`` against the bodies of a scene."""

    def __init__(self, bodies: tuple[Body, ...]) -> None:
        self.bodies = {b.name: b for b in bodies}

    def __call__(self, value: Any, path: str) -> NodeRef:
        if not isinstance(value, str) or value.count(":") != 1:
            raise SceneError(f'{path}: expected a node reference "BODY:INDEX", got '
                             f"{_show(value)}")
        name, index_text = value.split(":")
        if name not in self.bodies:
            raise SceneError(f"{path}: unknown body {_show(name)} in {_show(value)}; bodies: "
                             f"{', '.join(self.bodies)}")
        try:
            index = int(index_text.strip())
        except ValueError:
            raise SceneError(f'{path}: expected an integer node index after ":", got '
                             f"{_show(value)}") from None
        n = self.bodies[name].n_nodes
        if not -n <= index < n:
            raise SceneError(f"{path}: node index {index} out of range for body {_show(name)} "
                             f"with {n} nodes (0..{n - 1} or -{n}..-1)")
        return NodeRef(name, index % n)


def _axis(value: Any, path: str) -> tuple[float, ...]:
    axis = _vector(value, path, 3, "an axis is 3D")
    norm = math.sqrt(sum(x * x for x in axis))
    if norm == 0.0:
        raise SceneError(f"{path}: expected a non-zero axis, got {_show(value)}")
    return tuple(x / norm for x in axis)


def _constraint(i: int, data: dict, node: _Nodes, dim: int) -> Constraint:
    path = f"constraint[{i}]"
    if "type" not in data:
        raise SceneError(f"{path}.type: missing required key; expected one of "
                         f"{', '.join(CONSTRAINT_TYPES)}")
    kind = _choice(data["type"], f"{path}.type", CONSTRAINT_TYPES, "constraint type")
    axis_key = ("axis",) if dim == 3 else ()
    if kind in ("clamp", "pin"):
        _keys(data, path, ("type", "node"), ())
        return Constraint(kind, node(data["node"], f"{path}.node"), None, None, None)
    if kind == "prescribed_rotation":
        if dim == 2 and "axis" in data:
            raise SceneError(f"{path}.axis: only allowed in 3D scenes (a 2D rotation is about z)")
        _keys(data, path, ("type", "node", "angle"), axis_key)
        ref = node(data["node"], f"{path}.node")
        angle = parse_law(data["angle"], f"{path}.angle")
        axis = _axis(data.get("axis", [0.0, 0.0, 1.0]), f"{path}.axis") if dim == 3 else None
        return Constraint(kind, ref, None, angle, axis)
    # spherical, revolute: two nodes
    if kind == "revolute" and dim == 2 and "axis" in data:
        raise SceneError(f"{path}.axis: only allowed in 3D scenes (a 2D joint turns about z)")
    _keys(data, path, ("type", "nodes"), axis_key if kind == "revolute" else ())
    refs = data["nodes"]
    if not isinstance(refs, list) or len(refs) != 2:
        raise SceneError(f'{path}.nodes: expected two node references ["A:-1", "B:0"], got '
                         f"{_show(refs)}")
    a, b = node(refs[0], f"{path}.nodes[0]"), node(refs[1], f"{path}.nodes[1]")
    if a == b:
        raise SceneError(f"{path}.nodes: expected two different nodes, got {a} twice")
    axis = None
    if kind == "revolute" and dim == 3:
        axis = _axis(data.get("axis", [0.0, 0.0, 1.0]), f"{path}.axis")
    return Constraint(kind, None, (a, b), None, axis)


def _load(i: int, data: dict, node: _Nodes, dim: int) -> Load:
    path = f"load[{i}]"
    if "type" not in data:
        raise SceneError(f"{path}.type: missing required key; expected one of "
                         f"{', '.join(LOAD_TYPES)}")
    kind = _choice(data["type"], f"{path}.type", LOAD_TYPES, "load type")
    why = f"the scene is {dim}D"
    if kind == "point_force":
        _keys(data, path, ("type", "node", "force"), ("time_law",))
        ref = node(data["node"], f"{path}.node")
        vector = _vector(data["force"], f"{path}.force", dim, why)
    else:
        _keys(data, path, ("type", "acceleration"), ("time_law",))
        ref = None
        vector = _vector(data["acceleration"], f"{path}.acceleration", dim, why)
    law = parse_law(data["time_law"], f"{path}.time_law") if "time_law" in data else Constant()
    return Load(kind, ref, vector, law)


def _sensor(i: int, data: dict, node: _Nodes, dim: int) -> Sensor:
    path = f"sensor[{i}]"
    for key in ("name", "type"):
        if key not in data:
            hint = "a name" if key == "name" else f"one of {', '.join(SENSOR_TYPES)}"
            raise SceneError(f"{path}.{key}: missing required key; expected {hint}")
    name = _string(data["name"], f"{path}.name")
    if not SENSOR_NAME.fullmatch(name):
        raise SceneError(f"{path}.name: expected letters, digits, _ . and - starting with a "
                         f"letter, digit or _, got {_show(name)}")
    if name in RESERVED_SENSOR_NAMES:
        raise SceneError(f"{path}.name: expected a name other than the reserved "
                         f"{' and '.join(RESERVED_SENSOR_NAMES)}, got {_show(name)}")
    kind = _choice(data["type"], f"{path}.type", SENSOR_TYPES, "sensor type")
    if kind in ("displacement", "position"):
        _keys(data, path, ("name", "type", "node", "component"), ("frame",))
        ref = node(data["node"], f"{path}.node")
        components = ("x", "y", "z", "norm") if dim == 3 else ("x", "y", "norm")
        component = _choice(data["component"], f"{path}.component", components, "component")
        frame = node(data["frame"], f"{path}.frame") if "frame" in data else None
        return Sensor(name, kind, ref, component, frame, None)
    if kind in ("strain_energy", "kinetic_energy"):
        _keys(data, path, ("name", "type"), ("body",))
        body = None
        if "body" in data:
            body = _choice(data["body"], f"{path}.body", tuple(node.bodies), "body")
        return Sensor(name, kind, None, None, None, body)
    _keys(data, path, ("name", "type"), ())
    return Sensor(name, kind, None, None, None, None)


def _table_fields(data: Any, path: str, spec: dict[str, Callable[[Any, str], Any]],
                  required: tuple[str, ...] = ()) -> dict:
    optional = tuple(k for k in spec if k not in required)
    _keys(data, path, required, optional)
    return {key: check(data[key], f"{path}.{key}") for key, check in spec.items() if key in data}


def _static(data: Any) -> Static:
    return Static(**_table_fields(data, "analysis.static", {
        "max_iterations": _count, "tolerance": lambda v, p: _number(v, p, positive=True),
        "load_steps": _count}))


def _modal(data: Any) -> Modal:
    return Modal(**_table_fields(data, "analysis.modal", {
        "modes": _count, "about": lambda v, p: _choice(v, p, MODAL_ABOUT)}))


def _dynamic(data: Any) -> Dynamic:
    path = "analysis.dynamic"
    positive = lambda v, p: _number(v, p, positive=True)  # noqa: E731
    fields = _table_fields(data, path, {
        "t_end": positive, "step": positive,
        "integrator": lambda v, p: _choice(v, p, INTEGRATORS, "integrator"),
        "output_every": positive, "rho_inf": _number, "tolerance": positive,
        "max_iterations": _count, "frequency_of": _string,
        "frequency_after": lambda v, p: _number(v, p),
        "newton": lambda v, p: _choice(v, p, NEWTON_MODES, "Newton mode")},
        required=("t_end", "step"))
    if not 0.0 <= fields.get("frequency_after", 0.0) < fields["t_end"]:
        raise SceneError(f"{path}.frequency_after: expected a time in [0, t_end), got "
                         f"{fields['frequency_after']!r}")
    if fields["step"] > fields["t_end"]:
        raise SceneError(f"{path}.step: expected a step of at most t_end = {fields['t_end']!r} "
                         f"s, got {fields['step']!r}")
    if "output_every" in fields and fields["output_every"] < fields["step"]:
        raise SceneError(f"{path}.output_every: expected an interval of at least step = "
                         f"{fields['step']!r} s, got {fields['output_every']!r}")
    if "rho_inf" in fields and not 0.0 <= fields["rho_inf"] <= 1.0:
        raise SceneError(f"{path}.rho_inf: expected a number in [0, 1], got "
                         f"{fields['rho_inf']!r}")
    return Dynamic(**fields)


def _solver(data: Any) -> Solver:
    return Solver(**_table_fields(data, "solver", {
        "method": lambda v, p: _choice(v, p, METHODS, "method"),
        "backend": lambda v, p: _choice(v, p, BACKENDS, "backend"),
        "engine": lambda v, p: _choice(v, p, ENGINES, "engine")}))


def parse_scene(data: dict, source: str = "<scene>") -> Scene:
    """Validate the parsed TOML ``data`` of a scene; ``source`` names it (a file path).

    Raises SceneError (message: key path, what was expected, what was found).
    """
    if not isinstance(data, dict):
        raise SceneError(f"{source}: expected a table of scene keys, got {_show(data)}")
    # [study] declares a work-precision sweep: read and validated by `ancf study
    # error-vs-time` (runtime/studies/error_vs_time.py), ignored by runs
    _keys(data, "", (), ("title", "material", "body", "constraint", "load", "sensor",
                         "analysis", "solver", "study"))
    default_title = Path(source).stem if source != "<scene>" else "untitled"
    title = _string(data.get("title", default_title), "title")

    raw_materials = data.get("material", {})
    if not isinstance(raw_materials, dict):
        raise SceneError(f"material: expected tables [material.NAME], got {_show(raw_materials)}")
    materials = {name: _material(name, m) for name, m in raw_materials.items()}

    raw_bodies = _array_of_tables(data, "body")
    if not raw_bodies:
        raise SceneError("body: a scene needs at least one [[body]], got none")
    bodies: list[Body] = []
    for i, raw in enumerate(raw_bodies):
        body = _body(i, raw, materials)
        if any(b.name == body.name for b in bodies):
            raise SceneError(f"body[{i}].name: duplicate body name {_show(body.name)}")
        if bodies and body.dim != bodies[0].dim:
            raise SceneError(f"body[{i}].element: expected a {bodies[0].dim}D element kind like "
                             f"body[0], got {body.element} ({body.dim}D)")
        bodies.append(body)
    dim = bodies[0].dim
    node = _Nodes(tuple(bodies))

    constraints = tuple(_constraint(i, c, node, dim)
                        for i, c in enumerate(_array_of_tables(data, "constraint")))
    loads = tuple(_load(i, x, node, dim) for i, x in enumerate(_array_of_tables(data, "load")))
    sensors: list[Sensor] = []
    for i, raw in enumerate(_array_of_tables(data, "sensor")):
        sensor = _sensor(i, raw, node, dim)
        if any(s.name == sensor.name for s in sensors):
            raise SceneError(f"sensor[{i}].name: duplicate sensor name {_show(sensor.name)}")
        sensors.append(sensor)

    analysis = _keys(data.get("analysis", {}), "analysis", (), ("static", "modal", "dynamic"))
    static = _static(analysis["static"]) if "static" in analysis else None
    modal = _modal(analysis["modal"]) if "modal" in analysis else None
    dynamic = _dynamic(analysis["dynamic"]) if "dynamic" in analysis else None
    if dynamic is not None and dynamic.frequency_of is not None and \
            dynamic.frequency_of not in {s.name for s in sensors}:
        raise SceneError(f"analysis.dynamic.frequency_of: no sensor called "
                         f"{_show(dynamic.frequency_of)}; expected one of the [[sensor]] names")
    solver = _solver(data.get("solver", {}))
    return Scene(title, materials, tuple(bodies), constraints, loads, tuple(sensors), static,
                 modal, dynamic, solver, source)


def read_scene_file(path: str | Path) -> dict:
    """The TOML table of a scene file, unvalidated (SceneError if unreadable or not TOML)."""
    path = Path(path)
    try:
        with path.open("rb") as f:
            return tomllib.load(f)
    except OSError as exc:
        raise SceneError(f"{path}: cannot read the scene file ({exc.strerror or exc})") from None
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(f"{path}: TOML syntax error: {exc}") from None


def load_scene(path: str | Path) -> Scene:
    """Read and validate the TOML scene file ``path`` (SceneError for any problem)."""
    return parse_scene(read_scene_file(path), str(path))
