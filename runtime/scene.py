"""Scenes: a TOML file (DESIGN.md section 7) -> a validated, typed ``Scene``.

Units SI: lengths in m, forces in N, accelerations in m/s^2, E in Pa, rho in kg/m^3, angles
in degrees where the key says ``_deg`` and in rad in time laws, times in s.

Every error is a ``SceneError`` whose message starts with the key path of the culprit
(``body[1].sectoin: unknown key; expected one of ...``) and says what was expected and what
was found.  Node references ``"BODY:INDEX"`` are resolved: ``NodeRef.index`` is always the
non-negative node index (0 .. elements).

Beyond the types, a scene is checked for what it would do wrong:

* constraints: at most one clamp, pin or prescribed rotation per node (a clamp already holds
  what a pin holds; a clamp and a prescribed rotation contradict each other); joints join two
  distinct nodes at the same place in the reference, each pair once, and never two nodes whose
  positions are already held or already tied by other joints (the multipliers would be
  singular); a point force acts on a node whose position is free; some coordinate stays free;
* times: ``t_end`` and ``output_every`` are integer multiples of ``step`` (relative tolerance
  1e-9 on the ratio; the message suggests the nearest valid values);
* sizes, estimated before anything is built (``LIMITS``): memory of the model (element
  matrices, assembly, factorisation) and of a dense modal analysis with joints within 24 GiB;
  at most 1e8 time steps or load increments and 1e10 element-steps (about a day at the
  measured ~9 us per element and step); at most 1e8 values in the time series; at most 1000
  Newton iterations, 1000 modes (and no more than the degrees of freedom), 1000 sensors and
  Gauss orders up to 64; a relative Newton tolerance in [1e-15, 1e-2];
* names: sensor names are file names (``SENSOR_NAME``, at most 64 characters, unique ignoring
  case, none reserved); body and material names printable, at most 64 characters;
* files (``read_scene_file``): UTF-8 (a byte order mark is skipped), at most 16 MiB, a
  regular file, not empty; errors name the file (and the byte offset or the line).
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
from runtime.laws import Constant, Law, SceneError, _is_finite, _show, parse_law

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
MATERIAL_LAWS = ("svk", "ecm")
MODAL_ABOUT = ("reference", "static")
# names of sensors become CSV columns and PNG file names: ASCII letters, digits, "_", "." and
# "-", not starting with "." or "-", at most NAME_LENGTH characters, unique ignoring case (file
# systems that ignore case); "t" is the time column, "energies" the energy plot, the others
# are device names on Windows
SENSOR_NAME = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.\-]*")
RESERVED_SENSOR_NAMES = ("t", "energies", "con", "prn", "aux", "nul",
                         *(f"com{i}" for i in range(1, 10)), *(f"lpt{i}" for i in range(1, 10)))
NAME_LENGTH = 64
TITLE_LENGTH = 200
# a node index: ASCII digits, an optional "-", no "+", blanks, "_" or leading zeros
NODE_INDEX = re.compile(r"0|-?[1-9][0-9]*")
# relative tolerance on t_end / step and output_every / step being integers
MULTIPLE_TOLERANCE = 1e-9
# a relative Newton tolerance outside this range is never met or accepts unconverged steps
TOLERANCE_RANGE = (1e-15, 1e-2)
LIMITS = {
    "memory_bytes": 24 * 2**30,          # this machine
    "bytes_per_matrix_entry": 256,       # per entry of the element matrices (ndof^2 each):
                                         # measured ~160 B for build + static solve, + margin
    "steps": 10**8,                      # time steps, load increments
    "element_steps": 10**10,             # elements x steps: ~9 us each -> about a day
    "output_values": 10**8,              # rows x columns of timeseries.csv (read back to plot)
    "iterations": 1000,                  # Newton iterations per step
    "modes": 1000,
    "sensors": 1000,                     # one CSV column and one PNG each
    "quadrature": 64,                    # Gauss order per direction (runtime.element)
    "scene_bytes": 16 * 2**20,           # size of a scene file
}
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
    """Elastic material: E (Pa) > 0, -1 < nu < 0.5, rho (kg/m^3) > 0.

    law: ``svk`` (St. Venant-Kirchhoff) or ``ecm`` (elastic continuum mechanics with a shear
    correction); shear_correction: the ecm shear correction factor (> 0), None for the default
    (always None with svk); damping: Kelvin-Voigt coefficient alpha (s) >= 0, 0 for none.
    """

    name: str
    E: float
    nu: float
    rho: float
    law: str = "svk"
    shear_correction: float | None = None
    damping: float = 0.0


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
    ``spherical`` / ``revolute`` (2D only) join the two ``nodes``, coincident in the reference.
    ``angle``: the law of the prescribed rotation (rad); ``axis``: its unit rotation axis (3,)
    in 3D (default +z), None in 2D and for the other types."""

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
    """Dynamic analysis from 0 to ``t_end`` (s) with time step ``step`` (s), ``t_end`` an integer
    multiple of ``step``; outputs every ``output_every`` s (a multiple of ``step``; None: every
    step); ``rho_inf`` in [0, 1] for generalized-alpha; ``newton``: ``full`` (a new Jacobian
    at every iteration) or ``modified`` (Jacobian reused)."""

    t_end: float
    step: float
    integrator: str = "trapezoidal"
    output_every: float | None = None
    rho_inf: float = 0.8
    tolerance: float = 1e-10
    max_iterations: int = 20
    frequency_of: str | None = None    # sensor whose oscillation frequency is measured ...
    frequency_after: float = 0.0       # ... from this time (s) to t_end
    newton: str = "full"


@dataclass(frozen=True)
class Solver:
    """Elastic force method (gram | cij | quadrature), kernel backend (c | numpy) and engine
    (compiled | python; None: compiled when a C compiler is present and the backend is c, else
    python)."""

    method: str = "gram"
    backend: str = "c"
    engine: str | None = None


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
    if not _is_finite(value):
        raise SceneError(f"{path}: expected a {'positive' if positive else 'finite'} number, "
                         f"got {_show(value)}")
    if positive and value <= 0:
        raise SceneError(f"{path}: expected a positive number, got {_show(value)}")
    return float(value)


def _count(value: Any, path: str, maximum: int | None = None, why: str = "") -> int:
    """A positive integer (TOML integer: a float such as 1e20 or 10.0 is not one), at most
    ``maximum`` (``why`` says where the limit comes from)."""
    if isinstance(value, float):
        hint = f"; write {int(value)}" if value.is_integer() and abs(value) < 1e15 else ""
        raise SceneError(f"{path}: expected an integer, got {_show(value)} (a float{hint})")
    if isinstance(value, bool) or not isinstance(value, int) or value <= 0:
        raise SceneError(f"{path}: expected a positive integer, got {_show(value)}")
    if maximum is not None and value > maximum:
        raise SceneError(f"{path}: expected at most {maximum}{why}, got {_show(value)}")
    return value


def _string(value: Any, path: str) -> str:
    if not isinstance(value, str) or not value:
        raise SceneError(f"{path}: expected a non-empty string, got {_show(value)}")
    return value


def _name(value: Any, path: str, what: str = "a name") -> str:
    """A non-empty printable name of at most NAME_LENGTH characters, without blanks around."""
    name = _string(value, path)
    if len(name) > NAME_LENGTH:
        raise SceneError(f"{path}: expected {what} of at most {NAME_LENGTH} characters, got "
                         f"{len(name)} characters {_show(name)}")
    if not name.isprintable() or name != name.strip():
        raise SceneError(f"{path}: expected {what} of printable characters without blanks at "
                         f"either end, got {_show(name)}")
    return name


def _choice(value: Any, path: str, choices: tuple[str, ...], what: str = "value") -> str:
    if not isinstance(value, str) or value not in choices:
        raise SceneError(f"{path}: unknown {what} {_show(value)}; expected one of "
                         f"{', '.join(choices)}")
    return value


def _vector(value: Any, path: str, dim: int, why: str) -> tuple[float, ...]:
    if not isinstance(value, list) or len(value) != dim or not all(map(_is_finite, value)):
        raise SceneError(f"{path}: expected a list of {dim} numbers ({why}), got {_show(value)}")
    return tuple(float(x) for x in value)


def _array_of_tables(data: dict, key: str) -> list:
    value = data.get(key, [])
    if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
        raise SceneError(f"{key}: expected an array of tables ([[{key}]]), got {_show(value)}")
    return value


# --------------------------------------------------------------------------- parsers

def _material(name: str, data: Any) -> Material:
    path = f"material.{name}" if name else 'material.""'
    _name(name, path, "a material name")
    _keys(data, path, ("E", "nu", "rho"), ("law", "shear_correction", "damping"))
    E = _number(data["E"], f"{path}.E", positive=True)
    nu = _number(data["nu"], f"{path}.nu")
    if not -1.0 < nu < 0.5:
        raise SceneError(f"{path}.nu: expected a Poisson ratio in (-1, 0.5), got {_show(nu)}")
    rho = _number(data["rho"], f"{path}.rho", positive=True)
    law = _choice(data.get("law", "svk"), f"{path}.law", MATERIAL_LAWS, "material law")
    shear = None
    if "shear_correction" in data:
        shear = _number(data["shear_correction"], f"{path}.shear_correction", positive=True)
        if law != "ecm":
            raise SceneError(f'{path}.shear_correction: only meaningful with law = "ecm", got '
                             f'law = "{law}"; remove it or set law = "ecm"')
    damping = _number(data.get("damping", 0.0), f"{path}.damping")
    if damping < 0:
        raise SceneError(f"{path}.damping: expected a Kelvin-Voigt coefficient alpha >= 0 (s), "
                         f"got {_show(data['damping'])}")
    return Material(name, E, nu, rho, law, shear, damping)


def _body(i: int, data: dict, materials: dict[str, Material]) -> Body:
    path = f"body[{i}]"
    _keys(data, path, ("name", "element", "material", "section", "elements"),
          ("start", "end", "arc", "quadrature"))
    name = _name(data["name"], f"{path}.name", "a body name")
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
        if not math.isfinite(sum((b - a) * (b - a) for a, b in zip(start, end, strict=True))):
            raise SceneError(f"{path}.end: expected a body of finite length, got start = "
                             f"{_show(data['start'])} and end = {_show(data['end'])}")
    elif "arc" in data:
        apath = f"{path}.arc"
        a = _keys(data["arc"], apath, ("center", "radius", "angle_deg"), ("start_angle_deg",),
                  "a table {center = [...], radius = R, angle_deg = A}")
        center = _vector(a["center"], f"{apath}.center", dim, why)
        radius = _number(a["radius"], f"{apath}.radius", positive=True)
        extent = radius + max(abs(x) for x in center)
        if not math.isfinite(extent * extent):
            raise SceneError(f"{apath}.radius: expected an arc of finite extent, got radius "
                             f"{_show(a['radius'])} about centre {_show(a['center'])}")
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
        top = LIMITS["quadrature"]
        if (not isinstance(q, list) or len(q) != dim or not all(
                isinstance(n, int) and not isinstance(n, bool) and 0 < n <= top for n in q)):
            raise SceneError(f"{path}.quadrature: expected a list of {dim} positive integers "
                             f"of at most {top} (Gauss orders; {why}), got {_show(q)}")
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
        if not NODE_INDEX.fullmatch(index_text):
            raise SceneError(f'{path}: expected an integer node index after ":" (ASCII digits '
                             f'and an optional leading "-"; no "+", blanks, "_" or leading '
                             f'zeros, "-0" neither: 0 is the first node, -1 the last), got '
                             f"{_show(value)}")
        n = self.bodies[name].n_nodes
        index = int(index_text) if len(index_text) <= 20 else None
        if index is None or not -n <= index < n:
            shown = index_text if index is not None else f"{index_text[:20]}..."
            raise SceneError(f"{path}: node index {shown} out of range for body {_show(name)} "
                             f"with {n} nodes (0..{n - 1} or -{n}..-1)")
        return NodeRef(name, index % n)


def _axis(value: Any, path: str) -> tuple[float, ...]:
    axis = _vector(value, path, 3, "an axis is 3D")
    norm = math.hypot(*axis)
    if norm == 0.0:
        raise SceneError(f"{path}: expected a non-zero axis, got {_show(value)}")
    return tuple(x / norm for x in axis)


def _constraint(i: int, data: dict, node: _Nodes, dim: int) -> Constraint:
    path = f"constraint[{i}]"
    if "type" not in data:
        raise SceneError(f"{path}.type: missing required key; expected one of "
                         f"{', '.join(CONSTRAINT_TYPES)}")
    kind = _choice(data["type"], f"{path}.type", CONSTRAINT_TYPES, "constraint type")
    if kind in ("clamp", "pin"):
        _keys(data, path, ("type", "node"), ())
        return Constraint(kind, node(data["node"], f"{path}.node"), None, None, None)
    if kind == "prescribed_rotation":
        if dim == 2 and "axis" in data:
            raise SceneError(f"{path}.axis: only allowed in 3D scenes (a 2D rotation is about z)")
        _keys(data, path, ("type", "node", "angle"), ("axis",) if dim == 3 else ())
        ref = node(data["node"], f"{path}.node")
        angle = parse_law(data["angle"], f"{path}.angle")
        axis = _axis(data.get("axis", [0.0, 0.0, 1.0]), f"{path}.axis") if dim == 3 else None
        return Constraint(kind, ref, None, angle, axis)
    # spherical, revolute: two nodes
    if kind == "revolute" and dim == 3:
        raise SceneError(f'{path}.type: a revolute joint is planar (2D scenes only); use '
                         f'"spherical" in 3D')
    _keys(data, path, ("type", "nodes"), ())
    refs = data["nodes"]
    if not isinstance(refs, list) or len(refs) != 2:
        raise SceneError(f'{path}.nodes: expected two node references ["A:-1", "B:0"], got '
                         f"{_show(refs)}")
    a, b = node(refs[0], f"{path}.nodes[0]"), node(refs[1], f"{path}.nodes[1]")
    if a == b:
        raise SceneError(f"{path}.nodes: expected two different nodes, got {a} twice "
                         f"({_show(refs[0])} and {_show(refs[1])})")
    return Constraint(kind, None, (a, b), None, None)


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
    if not SENSOR_NAME.fullmatch(name) or len(name) > NAME_LENGTH:
        raise SceneError(f"{path}.name: expected letters, digits, _ . and - starting with a "
                         f"letter, digit or _, at most {NAME_LENGTH} characters (it names a "
                         f"CSV column and a PNG file), got {_show(name)}")
    if name.split(".")[0].lower() in RESERVED_SENSOR_NAMES:
        raise SceneError(f"{path}.name: expected a name other than the reserved "
                         f"{', '.join(RESERVED_SENSOR_NAMES)} (in any case, also before a "
                         f'"."), got {_show(name)}')
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


def _iterations(value: Any, path: str) -> int:
    return _count(value, path, LIMITS["iterations"], " Newton iterations")


def _tolerance(value: Any, path: str) -> float:
    low, high = TOLERANCE_RANGE
    tolerance = _number(value, path, positive=True)
    if not low <= tolerance <= high:
        raise SceneError(f"{path}: expected a relative Newton tolerance in [{low:g}, {high:g}] "
                         f"(below, rounding never lets Newton meet it; above, unconverged "
                         f"steps pass), got {_show(value)}")
    return tolerance


def _static(data: Any) -> Static:
    return Static(**_table_fields(data, "analysis.static", {
        "max_iterations": _iterations, "tolerance": _tolerance,
        "load_steps": lambda v, p: _count(v, p, LIMITS["steps"], " load increments")}))


def _modal(data: Any) -> Modal:
    return Modal(**_table_fields(data, "analysis.modal", {
        "modes": lambda v, p: _count(v, p, LIMITS["modes"], " modes"),
        "about": lambda v, p: _choice(v, p, MODAL_ABOUT)}))


def _g(x: float) -> str:
    return f"{x:.12g}"


def _multiple(value: float, step: float, path: str, key: str) -> None:
    """``value`` (at key ``key``) must be an integer multiple of the time step."""
    ratio = value / step
    if not math.isfinite(ratio):
        raise SceneError(f"{path}.{key}: {key} / step = {ratio} overflows; expected a {key} "
                         f"of at most t_end, got {_g(value)} s for step = {_g(step)} s")
    n = round(ratio)
    if abs(ratio - n) <= MULTIPLE_TOLERANCE * ratio:
        return
    low, high = math.floor(ratio), math.ceil(ratio)
    values = " or ".join(_g(k * step) for k in (low, high) if k >= 1)
    text = (f"{path}.{key}: expected an integer multiple of {path}.step = {_g(step)} s, got "
            f"{key} = {_g(value)} s ({key} / step = {_g(ratio)}")
    if key == "t_end":
        steps = " or ".join(_g(value / k) for k in (high, low))
        raise SceneError(f"{text}: the run would stop at {_g(n * step)} s); nearest valid: "
                         f"t_end = {values} s, or step = {steps} s")
    raise SceneError(f"{text}); nearest valid: {key} = {values} s")


def _dynamic(data: Any) -> Dynamic:
    path = "analysis.dynamic"
    positive = lambda v, p: _number(v, p, positive=True)  # noqa: E731
    fields = _table_fields(data, path, {
        "t_end": positive, "step": positive,
        "integrator": lambda v, p: _choice(v, p, INTEGRATORS, "integrator"),
        "output_every": positive, "rho_inf": _number, "tolerance": _tolerance,
        "max_iterations": _iterations, "frequency_of": _string,
        "frequency_after": lambda v, p: _number(v, p),
        "newton": lambda v, p: _choice(v, p, NEWTON_MODES, "Newton iteration")},
        required=("t_end", "step"))
    t_end, step = fields["t_end"], fields["step"]
    if not 0.0 <= fields.get("frequency_after", 0.0) < t_end:
        raise SceneError(f"{path}.frequency_after: expected a time in [0, t_end), got "
                         f"{fields['frequency_after']!r}")
    if step > t_end:
        raise SceneError(f"{path}.step: expected a step of at most t_end = {t_end!r} s, got "
                         f"{step!r}")
    top = LIMITS["steps"]
    if t_end / step > top:
        raise SceneError(f"{path}.step: t_end / step = {t_end / step:.3g} time steps exceed "
                         f"the limit of {top:.0e}; expected step >= {_g(t_end / top)} s for "
                         f"t_end = {_g(t_end)} s")
    _multiple(t_end, step, path, "t_end")
    if "output_every" in fields:
        if fields["output_every"] < step:
            raise SceneError(f"{path}.output_every: expected an interval of at least step = "
                             f"{step!r} s, got {fields['output_every']!r}")
        _multiple(fields["output_every"], step, path, "output_every")
    if "rho_inf" in fields and not 0.0 <= fields["rho_inf"] <= 1.0:
        raise SceneError(f"{path}.rho_inf: expected a number in [0, 1], got "
                         f"{fields['rho_inf']!r}")
    return Dynamic(**fields)


def _solver(data: Any) -> Solver:
    return Solver(**_table_fields(data, "solver", {
        "method": lambda v, p: _choice(v, p, METHODS, "method"),
        "backend": lambda v, p: _choice(v, p, BACKENDS, "backend"),
        "engine": lambda v, p: _choice(v, p, ENGINES, "engine")}))


def _node_position(body: Body, index: int) -> tuple[float, ...]:
    """Reference position (m) of node ``index`` (0 .. elements) of a body, as the model
    meshes it."""
    if body.arc is None:
        f = index / body.elements
        return tuple(a + (b - a) * f for a, b in zip(body.start, body.end, strict=True))
    arc = body.arc
    step = math.radians(arc.angle_deg) / body.elements
    theta = math.radians(arc.start_angle_deg) + index * step
    x, y = arc.center[0], arc.center[1]
    return (x + arc.radius * math.cos(theta), y + arc.radius * math.sin(theta), *arc.center[2:])


def _extent(body: Body) -> float:
    """Largest coordinate magnitude of a body (m): the length scale of its positions."""
    if body.arc is None:
        return max(abs(x) for x in (*body.start, *body.end))
    return max(abs(x) for x in body.arc.center) + body.arc.radius


def _check_constraints(constraints: tuple[Constraint, ...], bodies: tuple[Body, ...]) -> None:
    """Reject constraints that contradict or repeat each other (see the module docstring)."""
    holds: dict[NodeRef, int] = {}   # node -> the constraint holding its position
    for i, c in enumerate(constraints):
        if c.node is None:
            continue
        j = holds.setdefault(c.node, i)
        if j == i:
            continue
        first = constraints[j]
        pair = {first.type, c.type}
        both = f"constraint[{j}] ({first.type}) and constraint[{i}] ({c.type}) on node {c.node}"
        if len(pair) == 1:
            why = (f"a node has at most one {c.type}" if c.type == "prescribed_rotation"
                   else "the same constraint twice")
        elif pair == {"clamp", "pin"}:
            why = "redundant: the clamp holds every coordinate of the node, the pin only its " \
                  "position; keep the clamp"
        elif pair == {"clamp", "prescribed_rotation"}:
            why = "contradictory: the clamp holds the node's gradients, the prescribed " \
                  "rotation turns them"
        else:
            why = "redundant: the prescribed rotation already holds the node's position " \
                  "(a rigid hub); remove the pin"
        raise SceneError(f"constraint[{i}].node: {both}: {why}")

    by_name = {b.name: b for b in bodies}
    scale = max(_extent(b) for b in bodies)
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
        if c.nodes is None:
            continue
        a, b = c.nodes
        path = f"constraint[{i}].nodes"
        j = joined.setdefault(frozenset(c.nodes), i)
        if j != i:
            raise SceneError(f"{path}: the same joint as constraint[{j}] (nodes {a} and {b}); "
                             f"expected each pair of nodes joined once")
        pa = _node_position(by_name[a.body], a.index)
        pb = _node_position(by_name[b.body], b.index)
        gap = math.dist(pa, pb)
        if gap > 1e-9 * scale:
            show = lambda p: "(" + ", ".join(_g(x) for x in p) + ")"  # noqa: E731
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


def _check_loads(loads: tuple[Load, ...], constraints: tuple[Constraint, ...]) -> None:
    held = {c.node: i for i, c in enumerate(constraints) if c.node is not None}
    for i, load in enumerate(loads):
        if load.node in held:
            j = held[load.node]
            raise SceneError(f"load[{i}].node: the position of {load.node} is held by "
                             f"constraint[{j}] ({constraints[j].type}): a force there does "
                             f"nothing; expected a node that can move")


def _big(n: int) -> str:
    return str(n) if n < 10**15 else f"~1e{int(n.bit_length() * math.log10(2))}"


def _gib(n: int) -> str:
    return f"{n / 2**30:.3g} GiB" if n < 10**300 else f"{_big(n // 2**30)} GiB"


def _model_bytes(bodies: tuple[Body, ...]) -> int:
    """Estimated peak memory (bytes) of building and solving the model of the bodies."""
    return LIMITS["bytes_per_matrix_entry"] * sum(
        b.elements * element_kind(b.element).ndof ** 2 for b in bodies)


def _check_model_size(bodies: tuple[Body, ...]) -> None:
    """Refuse a mesh whose model cannot fit the memory of this machine (``LIMITS``)."""
    memory = LIMITS["memory_bytes"]
    per_entry = LIMITS["bytes_per_matrix_entry"]
    ndof = {b.name: element_kind(b.element).ndof for b in bodies}
    entries = [b.elements * ndof[b.name] ** 2 for b in bodies]
    elements = sum(b.elements for b in bodies)
    coordinates = sum(b.n_nodes for b in bodies) * (ndof[bodies[0].name] // 2)
    model_bytes = _model_bytes(bodies)
    if model_bytes > memory:
        i = max(range(len(bodies)), key=entries.__getitem__)
        n = ndof[bodies[i].name]
        most = memory // (per_entry * n * n)
        raise SceneError(f"body[{i}].elements: {_big(elements)} elements ({_big(coordinates)} "
                         f"coordinates) need about {_gib(model_bytes)} of memory (estimate: "
                         f"{per_entry} B per entry of the {n}x{n} element matrices), over the "
                         f"limit of {_gib(memory)}; expected at most about {most} "
                         f"{bodies[i].element} elements in the scene")


def _check_sizes(bodies: tuple[Body, ...], constraints: tuple[Constraint, ...],
                 sensors: list[Sensor], static: Static | None, modal: Modal | None,
                 dynamic: Dynamic | None) -> None:
    """Refuse what cannot run on this machine in a sane time (``LIMITS``), before building;
    the mesh itself passed ``_check_model_size``."""
    memory = LIMITS["memory_bytes"]
    elements = sum(b.elements for b in bodies)
    per_node = element_kind(bodies[0].element).ndof // 2
    dim = bodies[0].dim
    coordinates = sum(b.n_nodes for b in bodies) * per_node
    model_bytes = _model_bytes(bodies)
    held = sum(per_node if c.type in ("clamp", "prescribed_rotation") else dim
               for c in constraints if c.node is not None)
    free = coordinates - held
    joints = sum(1 for c in constraints if c.nodes is not None)
    dofs = free - dim * joints
    if dofs <= 0:
        raise SceneError(f"constraint: the constraints hold all {coordinates} coordinates of "
                         f"the model; expected at least one free coordinate")
    if modal is not None:
        if modal.modes > dofs:
            raise SceneError(f"analysis.modal.modes: expected at most the {dofs} degrees of "
                             f"freedom of the model, got {modal.modes}")
        dense = 24 * free**2 if joints else 0
        if model_bytes + dense > memory:
            raise SceneError(f"analysis.modal: with joints, a modal analysis works on dense "
                             f"{free}x{free} matrices: about {_gib(model_bytes + dense)} with "
                             f"the model, over the limit of {_gib(memory)}; expected fewer "
                             f"elements, no joints or no modal analysis")

    work = LIMITS["element_steps"]
    if static is not None and static.load_steps * elements > work:
        raise SceneError(f"analysis.static.load_steps: {static.load_steps} load increments of "
                         f"{elements} elements exceed the limit of {work:.0e} element-steps "
                         f"(about a day); expected at most {work // elements} increments")
    if dynamic is not None:
        steps = round(dynamic.t_end / dynamic.step)
        if steps * elements > work:
            raise SceneError(f"analysis.dynamic.step: {steps} time steps of {elements} elements "
                             f"exceed the limit of {work:.0e} element-steps (about a day at "
                             f"~9 us per element and step); expected step >= "
                             f"{_g(dynamic.t_end * elements / work)} s, a shorter t_end or "
                             f"fewer elements")
        every = dynamic.output_every or dynamic.step
        rows = round(dynamic.t_end / every) + 2
        columns = len(sensors) + 1
        if rows * columns > LIMITS["output_values"]:
            what = "output_every" if dynamic.output_every else "output_every (absent: every step)"
            least = dynamic.t_end * columns / LIMITS["output_values"]
            raise SceneError(f"analysis.dynamic.{what}: {rows} rows of {columns} columns in "
                             f"timeseries.csv exceed the limit of {LIMITS['output_values']:.0e} "
                             f"values (the file is read back whole for the plots); expected "
                             f"output_every >= {_g(least)} s (a multiple of step)")


def _check_frequency(dynamic: Dynamic, sensors: list[Sensor]) -> None:
    path = "analysis.dynamic"
    names = [s.name for s in sensors]
    if dynamic.frequency_of not in names:
        expected = f"one of {', '.join(names)}" if names else "a [[sensor]] name (none defined)"
        raise SceneError(f"{path}.frequency_of: no sensor called {_show(dynamic.frequency_of)}; "
                         f"expected {expected}")
    # outputs at multiples of output_every and at t_end
    every = dynamic.output_every or dynamic.step
    first = math.ceil(dynamic.frequency_after / every * (1 - MULTIPLE_TOLERANCE))
    last = dynamic.t_end / every
    samples = math.floor(last * (1 + MULTIPLE_TOLERANCE)) - first + 1
    samples += abs(last - round(last)) > MULTIPLE_TOLERANCE * last
    if samples < 8:
        raise SceneError(f"{path}.frequency_after: the frequency estimate needs at least 8 "
                         f"output samples from frequency_after = {_g(dynamic.frequency_after)} "
                         f"s to t_end = {_g(dynamic.t_end)} s, got {samples} (every "
                         f"{_g(every)} s); expected a smaller frequency_after or output_every")


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
    if len(title) > TITLE_LENGTH or not title.isprintable():
        raise SceneError(f"title: expected one line of printable text of at most "
                         f"{TITLE_LENGTH} characters, got {_show(title)}")

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
    _check_model_size(tuple(bodies))
    dim = bodies[0].dim
    node = _Nodes(tuple(bodies))

    constraints = tuple(_constraint(i, c, node, dim)
                        for i, c in enumerate(_array_of_tables(data, "constraint")))
    _check_constraints(constraints, tuple(bodies))
    loads = tuple(_load(i, x, node, dim) for i, x in enumerate(_array_of_tables(data, "load")))
    _check_loads(loads, constraints)
    raw_sensors = _array_of_tables(data, "sensor")
    if len(raw_sensors) > LIMITS["sensors"]:
        raise SceneError(f"sensor: expected at most {LIMITS['sensors']} sensors (one CSV "
                         f"column and one PNG plot each), got {len(raw_sensors)}")
    sensors: list[Sensor] = []
    for i, raw in enumerate(raw_sensors):
        sensor = _sensor(i, raw, node, dim)
        same = [s.name for s in sensors if s.name.lower() == sensor.name.lower()]
        if same:
            case = "" if same[0] == sensor.name else f" (as {_show(same[0])}, ignoring case)"
            raise SceneError(f"sensor[{i}].name: duplicate sensor name {_show(sensor.name)}"
                             f"{case}; sensor names name files, unique ignoring case")
        sensors.append(sensor)

    analysis = _keys(data.get("analysis", {}), "analysis", (), ("static", "modal", "dynamic"))
    static = _static(analysis["static"]) if "static" in analysis else None
    modal = _modal(analysis["modal"]) if "modal" in analysis else None
    dynamic = _dynamic(analysis["dynamic"]) if "dynamic" in analysis else None
    if dynamic is not None and dynamic.frequency_of is not None:
        _check_frequency(dynamic, sensors)
    solver = _solver(data.get("solver", {}))
    _check_sizes(tuple(bodies), constraints, sensors, static, modal, dynamic)
    return Scene(title, materials, tuple(bodies), constraints, loads, tuple(sensors), static,
                 modal, dynamic, solver, source)


def read_scene_file(path: str | Path) -> dict:
    """The TOML table of a scene file, unvalidated.

    SceneError naming the file for a missing, unreadable or oversized file, a directory,
    bytes that are not UTF-8 (with the byte offset, line and column), invalid TOML (with the
    line) and an empty scene.  A UTF-8 byte order mark is skipped.
    """
    path = Path(path)
    limit = LIMITS["scene_bytes"]
    try:
        if path.is_dir():
            raise SceneError(f"{path}: is a directory; expected a scene file (TOML)")
        if path.exists() and not path.is_file():
            raise SceneError(f"{path}: not a regular file; expected a scene file (TOML)")
        with path.open("rb") as f:
            raw = f.read(limit + 1)
    except OSError as exc:
        raise SceneError(f"{path}: cannot read the scene file ({exc.strerror or exc})") from None
    if len(raw) > limit:
        raise SceneError(f"{path}: expected a scene file of at most {limit // 2**20} MiB, got "
                         f"a larger file")
    bom = 3 if raw.startswith(b"\xef\xbb\xbf") else 0
    if raw.startswith((b"\xff\xfe", b"\xfe\xff")):
        raise SceneError(f"{path}: UTF-16 text (byte order mark at offset 0); expected UTF-8: "
                         f"save the scene as UTF-8")
    try:
        text = raw[bom:].decode("utf-8")
    except UnicodeDecodeError as exc:
        offset = bom + exc.start
        line = raw.count(b"\n", 0, offset) + 1
        column = offset - (raw.rfind(b"\n", 0, offset) + 1) + 1
        raise SceneError(f"{path}: not UTF-8 text: byte 0x{raw[offset]:02x} at offset {offset} "
                         f"(line {line}, column {column}); expected a UTF-8 TOML file") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(f"{path}: TOML syntax error: {exc}") from None
    except RecursionError:
        raise SceneError(f"{path}: TOML error: arrays or tables nested too deeply") from None
    except ValueError:          # an integer of more than 4300 digits
        raise SceneError(f"{path}: TOML error: an integer with too many digits (at most 4300 "
                         f"are read)") from None
    if not data:
        raise SceneError(f"{path}: the scene file is empty (no keys); expected a TOML scene "
                         f"with at least one [[body]]")
    return data


def load_scene(path: str | Path) -> Scene:
    """Read and validate the TOML scene file ``path`` (SceneError for any problem)."""
    return parse_scene(read_scene_file(path), str(path))
