"""Scenes: the public Python API of the scene schema, read from and written to TOML
(DESIGN.md section 7).

Units SI: lengths in m, forces in N, moments in N m, velocities in m/s, angular velocities in
rad/s, accelerations in m/s^2, E in Pa, rho in kg/m^3, angles in degrees where the key says
``_deg`` and in rad in time laws, times in s.

A ``Scene`` is built from the dataclasses of this module and the typed records of
``runtime.model.items.constraints``, ``runtime.model.items.loads`` and
``runtime.model.items.sensors``, in Python or from a TOML
file (``load_scene``).  There is one validation path: a scene built in Python is written as
its TOML table (``Scene.to_dict``) and read by the parser of TOML files, so both raise the same
``SceneError`` whose message starts with the key path of the culprit (``body[1].sectoin:
unknown key; expected one of ...``) and says what was expected and what was found; the
validated scene holds the parsed values (node references ``"BODY:INDEX"`` resolved to
``NodeRef`` with a non-negative index, which keeps a negative index as written for
``to_toml``, so "BODY:-1" stays the last node when the body is remeshed; numbers as floats,
vectors as tuples).
``Scene.to_toml()`` writes a scene that ``load_scene`` reads back equal.

Beyond the types, a scene is checked for what it would do wrong:

* constraints: at most one clamp, pin or prescribed rotation per node (a clamp already holds
  what a pin holds; a clamp and a prescribed rotation contradict each other); joints join two
  distinct nodes at the same place in the reference, each pair once, and never two nodes whose
  positions are already held or already tied by other joints (the multipliers would be
  singular); a point force acts on a node whose position is free, a point moment on a node
  whose section can turn; some coordinate stays free;
* times: ``t_end`` and ``output_every`` are integer multiples of ``step`` (relative tolerance
  1e-9 on the ratio; the message suggests the nearest valid values);
* sizes, estimated before anything is built (``LIMITS``): memory of the model (element
  matrices, assembly, factorisation) and of a dense modal analysis with joints within 24 GiB;
  at most 1e8 time steps or load increments and 1e10 element-steps (about a day at the
  measured ~9 us per element and step); at most 1e8 values in the time series; at most 1000
  Newton iterations, 1000 modes (and no more than the degrees of freedom), 1000 sensors and
  Gauss orders up to 64; a relative Newton tolerance in [1e-15, 1e-2];
* names: sensor names are file names (at most 64 characters, unique ignoring case, none
  reserved: ``runtime.model.items.sensors``); body and material names printable, at most 64
  characters;
* files (``read_scene_file``): UTF-8 (a byte order mark is skipped), at most 16 MiB, a
  regular file, not empty; errors name the file (and the byte offset or the line).
"""

from __future__ import annotations

import dataclasses
import math
import re
import tomllib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from runtime.catalog import (
    BACKENDS,
    DEFAULT_LAW,
    ENGINES,
    INTEGRATORS,
    METHODS,
    NEWTON_MODES,
    generated_kinds,
    material_laws,
)
from runtime.kernels.kind import element_kind
from runtime.model import mesh as meshing
from runtime.model.items.constraints import CONSTRAINTS, Constraint, Joint, NodeConstraint, Weld
from runtime.model.items.loads import LOADS, Load
from runtime.model.items.sensors import SENSORS, Sensor
from runtime.model.schema import (
    NAME_LENGTH,
    Context,
    NodeRef,
    Nodes,
    boolean,
    choice,
    keys,
    number,
    parse_record,
    plain,
    rotation_vector,
    same,
    string,
    table,
    vector,
)
from runtime.model.time_laws import SceneError, _show

__all__ = [
    "Arc",
    "Body",
    "Dynamic",
    "Material",
    "Modal",
    "NodeRef",
    "Output",
    "Rectangle",
    "Scene",
    "SceneError",
    "Solver",
    "Spin",
    "Static",
    "load_scene",
    "parse_scene",
    "read_scene_file",
    "toml_text",
]

MODAL_ABOUT = ("reference", "static")
TITLE_LENGTH = 200
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
    "quadrature": 64,                    # Gauss order per direction (runtime.element.element)
    "scene_bytes": 16 * 2**20,           # size of a scene file
}
# two node constraints on one node: why not (by their types; one type: the same twice)
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


# --------------------------------------------------------------------------- dataclasses

@dataclass(frozen=True)
class Material:
    """Elastic material ``name``: E (Pa) > 0, -1 < nu < 0.5, rho (kg/m^3) > 0.

    law: ``svk`` (St. Venant-Kirchhoff) or ``ecm`` (elastic continuum mechanics with a shear
    correction); shear_correction: the ecm shear correction factor (> 0), None for the default
    (always None with svk); damping: Kelvin-Voigt coefficient alpha (s) >= 0, 0 for none.
    In TOML the name is the key of the table ``[material.NAME]``.
    """

    name: str
    E: float
    nu: float
    rho: float
    law: str = "svk"
    shear_correction: float | None = None
    damping: float = 0.0

    def to_dict(self) -> dict[str, Any]:
        """The TOML table ``[material.NAME]`` (without the name)."""
        return table(self, skip=("name",))


@dataclass(frozen=True)
class Arc:
    """Circular arc in the x-y plane (at the centre's z in 3D): centre (dim,) in m, radius (m),
    start angle and opening angle (deg, counter-clockwise about +z when positive)."""

    center: tuple[float, ...]
    radius: float
    start_angle_deg: float
    angle_deg: float

    def to_dict(self) -> dict[str, Any]:
        """The TOML table ``arc = {...}``."""
        return table(self)


@dataclass(frozen=True)
class Spin:
    """A rigid rotation at the angular velocity ``omega`` (rad/s: a number, about +z, in 2D;
    a vector (3,) in 3D) about the point ``about`` (dim,) in m."""

    omega: float | tuple[float, ...]
    about: tuple[float, ...]

    def to_dict(self) -> dict[str, Any]:
        """The TOML table ``initial_angular_velocity = {...}``."""
        return table(self)


@dataclass(frozen=True)
class Rectangle:
    """A flat rectangle in the plane z = corner[2]: ``corner`` (3,) in m, ``size`` (a, b) in m
    along +x and +y, meshed by ``grid`` (nx, ny) elements of size a / nx by b / ny."""

    corner: tuple[float, ...]
    size: tuple[float, float]
    grid: tuple[int, int]

    def to_dict(self) -> dict[str, Any]:
        """The TOML table ``rectangle = {...}``."""
        return table(self)


@dataclass(frozen=True)
class Body:
    """A mesh of elements of kind ``element`` sharing nodes (numbered by the kind's node layout:
    ``n_nodes`` of them, see ``runtime.element.reference.structured_mesh``).

    Beam kinds (a line of ``elements`` elements): section ``height`` and ``width`` (m; TOML
    ``section = {height, width}``), either ``start``/``end`` (dim,) in m (straight) or
    ``arc``.  Plate kinds: ``rectangle`` (its grid sets ``elements``) and ``thickness`` (m;
    TOML ``section = {thickness}``).  material: the name of a material of the scene;
    quadrature: Gauss orders (dim,) or None for the kind's default.  Initial conditions
    (velocities at t = 0, zero where absent): ``initial_velocity`` (dim,) in m/s, a uniform
    translation, plus ``initial_angular_velocity``, a rigid ``Spin``.
    """

    name: str
    element: str
    material: str
    height: float | None = None
    width: float | None = None
    elements: int | None = None
    start: tuple[float, ...] | None = None
    end: tuple[float, ...] | None = None
    arc: Arc | None = None
    quadrature: tuple[int, ...] | None = None
    initial_velocity: tuple[float, ...] | None = None
    initial_angular_velocity: Spin | None = None
    rectangle: Rectangle | None = None
    thickness: float | None = None

    @property
    def dim(self) -> int:
        """Spatial dimension of the element kind (2 or 3)."""
        return element_kind(self.element).dim

    @property
    def counts(self) -> tuple[int, ...]:
        """Elements along each meshed axis: (elements,) for a line, the grid for a rectangle."""
        return tuple(self.rectangle.grid) if self.rectangle is not None else (self.elements,)

    @property
    def grid_shape(self) -> tuple[int, ...]:
        """Node points along each meshed axis: (nodes,) for a line, (columns along x, rows
        along y) for a rectangle."""
        return meshing.grid_shape(element_kind(self.element), self.counts)

    @property
    def n_nodes(self) -> int:
        """Number of nodes: elements + 1 for 2-node beams, 2 elements + 1 for 3-node beams,
        (nx + 1)(ny + 1) for 4-node plates."""
        return meshing.node_count(element_kind(self.element), self.counts)

    @property
    def geometry(self) -> tuple[float, float, float]:
        """The element's (length, height, width) as ``runtime.Element`` takes them: the
        element's sides a, b and the thickness for a plate."""
        if self.rectangle is not None:
            (a, b), (nx, ny) = self.rectangle.size, self.rectangle.grid
            return a / nx, b / ny, self.thickness
        if self.arc is not None:
            length = self.arc.radius * math.radians(abs(self.arc.angle_deg)) / self.elements
        else:
            length = math.dist(self.start, self.end) / self.elements
        return length, self.height, self.width

    def to_dict(self) -> dict[str, Any]:
        """The TOML table ``[[body]]``."""
        section = ({"thickness": self.thickness} if self.rectangle is not None
                   else {"height": self.height, "width": self.width})
        head = {"name": self.name, "element": self.element, "material": self.material,
                "section": {k: v for k, v in section.items() if v is not None}}
        # a rectangle's grid sets its elements (written only when they disagree: an error)
        grid = getattr(self.rectangle, "grid", None)
        if self.rectangle is None or (self.elements is not None
                                      and (grid is None or self.elements != math.prod(grid))):
            head["elements"] = self.elements
        return {**plain(head),
                **table(self, skip=(*head, "height", "width", "thickness", "elements"))}


@dataclass(frozen=True)
class Static:
    """Static analysis: Newton-Raphson, at most ``max_iterations`` per load increment,
    convergence ``tolerance`` (relative), loads applied in ``load_steps`` equal increments."""

    max_iterations: int = 50
    tolerance: float = 1e-10
    load_steps: int = 1

    def to_dict(self) -> dict[str, Any]:
        """The TOML table ``[analysis.static]``."""
        return table(self)


@dataclass(frozen=True)
class Modal:
    """Modal analysis: the ``modes`` lowest frequencies about the reference configuration or
    the static solution."""

    modes: int = 4
    about: str = "reference"

    def to_dict(self) -> dict[str, Any]:
        """The TOML table ``[analysis.modal]``."""
        return table(self)


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

    def to_dict(self) -> dict[str, Any]:
        """The TOML table ``[analysis.dynamic]``."""
        return table(self)


@dataclass(frozen=True)
class Solver:
    """Elastic force method (gram | cij | quadrature), kernel backend (c | numpy) and engine
    (compiled | python; None: compiled when a C compiler is present and the backend is c, else
    python)."""

    method: str = "gram"
    backend: str = "c"
    engine: str | None = None

    def to_dict(self) -> dict[str, Any]:
        """The TOML table ``[solver]``."""
        return table(self)


@dataclass(frozen=True)
class Output:
    """What a run writes beyond the summary and time series: ``vtk`` (VTU/PVD files of the
    deformed bodies), ``animation`` (a GIF), ``states`` (keep the nodal states in memory)."""

    vtk: bool = False
    animation: bool = False
    states: bool = False

    def to_dict(self) -> dict[str, Any]:
        """The TOML table ``[output]``."""
        return table(self)


@dataclass(frozen=True, kw_only=True)
class Scene:
    """A validated scene.  Built in Python, the arguments are checked as the TOML file
    ``to_toml()`` would be (``SceneError`` naming the key path) and replaced by their parsed
    values.  ``materials``: Material objects (a sequence, or {name: Material}); node references
    may be ``NodeRef`` or ``"BODY:INDEX"``; vectors sequences of numbers; ``source`` is the
    file the scene came from (or ``"<scene>"``; not compared).

    Example::

        Scene(materials=[Material("steel", E=2.1e11, nu=0.3, rho=7800.0)],
              bodies=[Body("beam", "beam2d", "steel", 0.1, 0.1, 8, (0, 0), (1, 0))],
              constraints=[Clamp("beam:0")], loads=[PointForce("beam:-1", (0, -100))],
              sensors=[Displacement("tip_y", "beam:-1", "y")], static=Static())
    """

    title: str = "untitled"
    materials: dict[str, Material]
    bodies: tuple[Body, ...]
    constraints: tuple[Constraint, ...] = ()
    loads: tuple[Load, ...] = ()
    sensors: tuple[Sensor, ...] = ()
    static: Static | None = None
    modal: Modal | None = None
    dynamic: Dynamic | None = None
    solver: Solver = Solver()
    output: Output = Output()
    source: str = dataclasses.field(default="<scene>", compare=False)

    def __post_init__(self) -> None:
        parsed = parse_scene(self.to_dict(), self.source)
        for f in dataclasses.fields(self):
            object.__setattr__(self, f.name, getattr(parsed, f.name))

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

    def to_dict(self) -> dict[str, Any]:
        """The scene as the table a TOML file holds (what ``tomllib`` would return)."""
        data: dict[str, Any] = {"title": self.title,
                                "material": _materials_table(self.materials),
                                "body": plain(self.bodies)}
        for name, items in (("constraint", self.constraints), ("load", self.loads),
                            ("sensor", self.sensors)):
            if items:
                data[name] = plain(items)
        analysis = {name: plain(value) for name, value in (
            ("static", self.static), ("modal", self.modal), ("dynamic", self.dynamic))
            if value is not None}
        if analysis:
            data["analysis"] = analysis
        for name, value, default in (("solver", self.solver, Solver()),
                                     ("output", self.output, Output())):
            if not same(value, default):
                data[name] = plain(value)
        return data

    def to_toml(self) -> str:
        """The scene as TOML text (``load_scene`` of it gives an equal scene)."""
        return toml_text(self.to_dict())


def _materials_table(materials: Any) -> Any:
    """``[material.NAME]`` tables of Material objects (a sequence or {name: Material})."""
    if isinstance(materials, dict):
        for name, material in materials.items():
            if isinstance(material, Material) and material.name != name:
                raise SceneError(f"material.{name}: the material under this key is called "
                                 f"{_show(material.name)}; expected the same name")
        return plain(materials)
    if not isinstance(materials, list | tuple):
        return plain(materials)
    out: dict[str, Any] = {}
    for i, material in enumerate(materials):
        if not isinstance(material, Material):
            raise SceneError(f"material: expected Material objects, got {_show(material)} at "
                             f"position {i}")
        if material.name in out:
            raise SceneError(f"material.{material.name}: duplicate material name")
        out[material.name] = material.to_dict()
    return out


def _validated_scene(**values: Any) -> Scene:
    """A Scene of already validated values (the parser's result: not validated again)."""
    scene = object.__new__(Scene)
    for name, value in values.items():
        object.__setattr__(scene, name, value)
    return scene


# --------------------------------------------------------------------------- checkers

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


def _name(value: Any, path: str, what: str = "a name") -> str:
    """A non-empty printable name of at most NAME_LENGTH characters, without blanks around."""
    name = string(value, path)
    if len(name) > NAME_LENGTH:
        raise SceneError(f"{path}: expected {what} of at most {NAME_LENGTH} characters, got "
                         f"{len(name)} characters {_show(name)}")
    if not name.isprintable() or name != name.strip():
        raise SceneError(f"{path}: expected {what} of printable characters without blanks at "
                         f"either end, got {_show(name)}")
    return name


def _array_of_tables(data: dict, key: str) -> list:
    value = data.get(key, [])
    if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
        raise SceneError(f"{key}: expected an array of tables ([[{key}]]), got {_show(value)}")
    return value


# --------------------------------------------------------------------------- parsers

def _material(name: str, data: Any) -> Material:
    path = f"material.{name}" if name else 'material.""'
    _name(name, path, "a material name")
    keys(data, path, ("E", "nu", "rho"), ("law", "shear_correction", "damping"))
    E = number(data["E"], f"{path}.E", positive=True)
    nu = number(data["nu"], f"{path}.nu")
    if not -1.0 < nu < 0.5:
        raise SceneError(f"{path}.nu: expected a Poisson ratio in (-1, 0.5), got {_show(nu)}")
    rho = number(data["rho"], f"{path}.rho", positive=True)
    law = choice(data.get("law", DEFAULT_LAW), f"{path}.law", material_laws(), "material law")
    shear = None
    if "shear_correction" in data:
        shear = number(data["shear_correction"], f"{path}.shear_correction", positive=True)
        if law != "ecm":
            raise SceneError(f'{path}.shear_correction: only meaningful with law = "ecm", got '
                             f'law = "{law}"; remove it or set law = "ecm"')
    damping = number(data.get("damping", 0.0), f"{path}.damping")
    if damping < 0:
        raise SceneError(f"{path}.damping: expected a Kelvin-Voigt coefficient alpha >= 0 (s), "
                         f"got {_show(data['damping'])}")
    return Material(name, E, nu, rho, law, shear, damping)


def _body(i: int, data: dict, materials: dict[str, Material]) -> Body:
    path = f"body[{i}]"
    keys(data, path, ("name", "element", "material", "section"),
         ("elements", "start", "end", "arc", "rectangle", "quadrature", "initial_velocity",
          "initial_angular_velocity"))
    name = _name(data["name"], f"{path}.name", "a body name")
    if ":" in name:
        raise SceneError(f'{path}.name: expected a name without ":", got {_show(name)}')
    kind = choice(data["element"], f"{path}.element", tuple(generated_kinds()), "element kind")
    meta = element_kind(kind)
    dim = meta.dim
    why = f"{kind} is {dim}D"
    material = string(data["material"], f"{path}.material")
    if material not in materials:
        defined = ", ".join(materials) or "none"
        raise SceneError(f"{path}.material: material {_show(material)} is not defined; "
                         f"defined materials: {defined}")
    law = materials[material].law
    if (why := meta.law_not_applicable(law)) is not None:
        raise SceneError(f"{path}.material: material {_show(material)} has law = "
                         f"{_show(law)}, which does not apply to {kind} elements ({why}); "
                         f"expected a material with one of the laws "
                         f"{', '.join(meta.laws)}")
    plate = len(meta.mesh_axes) == 2
    shape = _plate_shape if plate else _line_shape
    height, width, thickness, elements, start, end, arc, rectangle = shape(data, path, kind, dim)

    quadrature = None
    if "quadrature" in data:
        q = data["quadrature"]
        top = LIMITS["quadrature"]
        if (not isinstance(q, list) or len(q) != dim or not all(
                isinstance(n, int) and not isinstance(n, bool) and 0 < n <= top for n in q)):
            raise SceneError(f"{path}.quadrature: expected a list of {dim} positive integers "
                             f"of at most {top} (Gauss orders; {why}), got {_show(q)}")
        quadrature = tuple(q)
    velocity = None
    if "initial_velocity" in data:
        velocity = vector(data["initial_velocity"], f"{path}.initial_velocity", dim,
                          f"a velocity in m/s; {why}")
    spin = None
    if "initial_angular_velocity" in data:
        spath = f"{path}.initial_angular_velocity"
        s = keys(data["initial_angular_velocity"], spath, ("omega", "about"), (),
                 "a table {omega = ..., about = [...]}")
        spin = Spin(rotation_vector(s["omega"], f"{spath}.omega", dim, "the angular velocity "
                                    "in rad/s"),
                    vector(s["about"], f"{spath}.about", dim, f"a point in m; {why}"))
    return Body(name, kind, material, height, width, elements, start, end, arc, quadrature,
                velocity, spin, rectangle, thickness)


def _line_shape(data: dict, path: str, kind: str, dim: int) -> tuple:
    """Section, element count and placement of a line body (beam kinds)."""
    why = f"{kind} is {dim}D"
    if "rectangle" in data:
        raise SceneError(f"{path}.rectangle: {kind} is a beam element; a beam body is a line "
                         "(start and end) or an arc; rectangles are for plate elements")
    if "elements" not in data:
        raise SceneError(f"{path}.elements: missing required key; expected the number of "
                         f"elements along the body")
    section = keys(data["section"], f"{path}.section", ("height", "width"), (),
                   "a table {height = H, width = W}")
    height = number(section["height"], f"{path}.section.height", positive=True)
    width = number(section["width"], f"{path}.section.width", positive=True)
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
        start = vector(data["start"], f"{path}.start", dim, why)
        end = vector(data["end"], f"{path}.end", dim, why)
        if start == end:
            raise SceneError(f"{path}.end: expected a point different from start, got "
                             f"{_show(data['end'])}")
        if not math.isfinite(sum((b - a) * (b - a) for a, b in zip(start, end, strict=True))):
            raise SceneError(f"{path}.end: expected a body of finite length, got start = "
                             f"{_show(data['start'])} and end = {_show(data['end'])}")
    elif "arc" in data:
        arc = _arc(data["arc"], f"{path}.arc", dim, why)
    else:
        raise SceneError(f"{path}: expected start and end (straight) or arc, got neither")
    return height, width, None, elements, start, end, arc, None


def _plate_shape(data: dict, path: str, kind: str, dim: int) -> tuple:
    """Section, element count and placement of a rectangle body (plate kinds)."""
    for key in ("start", "end", "arc"):
        if key in data:
            raise SceneError(f"{path}.{key}: {kind} is a plate element; a plate body is a "
                             f"rectangle = {{corner = [x, y, z], size = [a, b], grid = "
                             f"[nx, ny]}}")
    if "elements" in data:
        raise SceneError(f"{path}.elements: the rectangle's grid sets the elements of a plate "
                         f"body; remove elements")
    if "rectangle" not in data:
        raise SceneError(f"{path}.rectangle: missing required key; expected {{corner = "
                         f"[x, y, z], size = [a, b], grid = [nx, ny]}} ({kind} is a plate "
                         f"element)")
    section = keys(data["section"], f"{path}.section", ("thickness",), (),
                   "a table {thickness = T}")
    thickness = number(section["thickness"], f"{path}.section.thickness", positive=True)
    rpath = f"{path}.rectangle"
    r = keys(data["rectangle"], rpath, ("corner", "size", "grid"), (),
             "a table {corner = [x, y, z], size = [a, b], grid = [nx, ny]}")
    corner = vector(r["corner"], f"{rpath}.corner", dim, f"{kind} is {dim}D")
    size = vector(r["size"], f"{rpath}.size", 2, "the sides a along x and b along y, in m")
    extent = size[0] + size[1] + max(map(abs, corner))
    if min(size) <= 0 or not math.isfinite(extent * extent):
        raise SceneError(f"{rpath}.size: expected two positive finite sides in m, got "
                         f"{_show(r['size'])}")
    grid = r["grid"]
    if not isinstance(grid, list) or len(grid) != 2:
        raise SceneError(f"{rpath}.grid: expected [nx, ny], two positive integers (elements "
                         f"along x and y), got {_show(grid)}")
    grid = tuple(_count(n, f"{rpath}.grid[{k}]") for k, n in enumerate(grid))
    return (None, None, thickness, grid[0] * grid[1], None, None, None,
            Rectangle(corner, size, grid))


def _arc(data: Any, path: str, dim: int, why: str) -> Arc:
    a = keys(data, path, ("center", "radius", "angle_deg"), ("start_angle_deg",),
             "a table {center = [...], radius = R, angle_deg = A}")
    center = vector(a["center"], f"{path}.center", dim, why)
    radius = number(a["radius"], f"{path}.radius", positive=True)
    extent = radius + max(abs(x) for x in center)
    if not math.isfinite(extent * extent):
        raise SceneError(f"{path}.radius: expected an arc of finite extent, got radius "
                         f"{_show(a['radius'])} about centre {_show(a['center'])}")
    start_angle = number(a.get("start_angle_deg", 0.0), f"{path}.start_angle_deg")
    angle = number(a["angle_deg"], f"{path}.angle_deg")
    if angle == 0.0 or abs(angle) > 360.0:
        raise SceneError(f"{path}.angle_deg: expected a non-zero angle of at most 360 "
                         f"degrees in magnitude, got {_show(a['angle_deg'])}")
    return Arc(center, radius, start_angle, angle)


def _table_fields(data: Any, path: str, spec: dict[str, Callable[[Any, str], Any]],
                  required: tuple[str, ...] = ()) -> dict:
    optional = tuple(k for k in spec if k not in required)
    keys(data, path, required, optional)
    return {key: check(data[key], f"{path}.{key}") for key, check in spec.items() if key in data}


def _iterations(value: Any, path: str) -> int:
    return _count(value, path, LIMITS["iterations"], " Newton iterations")


def _tolerance(value: Any, path: str) -> float:
    low, high = TOLERANCE_RANGE
    tolerance = number(value, path, positive=True)
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
        "about": lambda v, p: choice(v, p, MODAL_ABOUT)}))


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
    positive = lambda v, p: number(v, p, positive=True)  # noqa: E731
    fields = _table_fields(data, path, {
        "t_end": positive, "step": positive,
        "integrator": lambda v, p: choice(v, p, INTEGRATORS, "integrator"),
        "output_every": positive, "rho_inf": number, "tolerance": _tolerance,
        "max_iterations": _iterations, "frequency_of": string,
        "frequency_after": lambda v, p: number(v, p),
        "newton": lambda v, p: choice(v, p, NEWTON_MODES, "Newton iteration")},
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
        "method": lambda v, p: choice(v, p, METHODS, "method"),
        "backend": lambda v, p: choice(v, p, BACKENDS, "backend"),
        "engine": lambda v, p: choice(v, p, ENGINES, "engine")}))


def _output(data: Any) -> Output:
    return Output(**_table_fields(data, "output", dict.fromkeys(
        (f.name for f in dataclasses.fields(Output)), boolean)))


# --------------------------------------------------------------------------- scene checks

def _node_position(body: Body, index: int) -> tuple[float, ...]:
    """Reference position (m) of node ``index`` of a body, as the model meshes it (nodes
    evenly spaced along a line or arc, on the grid of a rectangle)."""
    shape = body.grid_shape
    if body.rectangle is not None:
        r = body.rectangle
        i, j = index % shape[0], index // shape[0]
        x, y = (i / (shape[0] - 1)) * r.size[0], (j / (shape[1] - 1)) * r.size[1]
        return (r.corner[0] + x, r.corner[1] + y, r.corner[2])
    f = index / (shape[0] - 1)
    if body.arc is None:
        return tuple(a + (b - a) * f for a, b in zip(body.start, body.end, strict=True))
    arc = body.arc
    theta = math.radians(arc.start_angle_deg) + f * math.radians(arc.angle_deg)
    x, y = arc.center[0], arc.center[1]
    return (x + arc.radius * math.cos(theta), y + arc.radius * math.sin(theta), *arc.center[2:])


def _extent(body: Body) -> float:
    """Largest coordinate magnitude of a body (m): the length scale of its positions."""
    if body.rectangle is not None:
        r = body.rectangle
        return max(abs(x) for x in r.corner) + r.size[0] + r.size[1]
    if body.arc is None:
        return max(abs(x) for x in (*body.start, *body.end))
    return max(abs(x) for x in body.arc.center) + body.arc.radius


def _check_constraints(constraints: tuple[Constraint, ...], bodies: tuple[Body, ...]) -> None:
    """Reject constraints that contradict or repeat each other (see the module docstring)."""
    holds: dict[NodeRef, int] = {}   # node -> the constraint holding its position
    for i, c in enumerate(constraints):
        if not isinstance(c, NodeConstraint):
            continue
        for node in c.targets():
            j = holds.setdefault(node, i)
            if j == i:
                continue
            first = constraints[j]
            why = CONFLICTS.get(frozenset({first.type, c.type}),
                                "the same constraint twice" if first.type == c.type else
                                "a node has at most one of them")
            where = c.target_key
            raise SceneError(f"constraint[{i}].{where}: constraint[{j}] ({first.type}) and "
                             f"constraint[{i}] ({c.type}) on node {node}: {why}")

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
        if not isinstance(c, Joint):
            continue
        a, b = c.nodes
        path = f"constraint[{i}].nodes"
        if isinstance(c, Weld):
            _check_weld(path, by_name[a.body], by_name[b.body])
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


def _check_weld(path: str, a: Body, b: Body) -> None:
    """A weld shares the deformation gradient of two nodes: both must carry every gradient
    (r_x, r_y[, r_z]) to define it."""
    for body in (a, b):
        kind = element_kind(body.element)
        if len(kind.vectors) != kind.dim + 1:
            frame = ", ".join(f"r_{a}" for a in "xyz"[:kind.dim])
            raise SceneError(f"{path}: a weld ties the full frames ({frame}) of its nodes; "
                             f"{body.element} nodes of body {_show(body.name)} carry "
                             f"{', '.join(kind.vectors)}; expected nodes of an element with "
                             f"every gradient, or a spherical joint")


def _check_loads(loads: tuple[Load, ...], constraints: tuple[Constraint, ...]) -> None:
    """A load must act on coordinates that its nodes' constraints leave free (on one node of
    an edge at least)."""
    held = {node: i for i, c in enumerate(constraints) if isinstance(c, NodeConstraint)
            for node in c.targets()}
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


def _big(n: int) -> str:
    return str(n) if n < 10**15 else f"~1e{int(n.bit_length() * math.log10(2))}"


def _gib(n: int) -> str:
    return f"{n / 2**30:.3g} GiB" if n < 10**300 else f"{_big(n // 2**30)} GiB"


def _model_bytes(bodies: tuple[Body, ...]) -> int:
    """Estimated peak memory (bytes) of building and solving the model of the bodies."""
    return LIMITS["bytes_per_matrix_entry"] * sum(
        b.elements * element_kind(b.element).ndof ** 2 for b in bodies)


def _coordinates(bodies: tuple[Body, ...]) -> int:
    """Number of coordinates of the model of the bodies (nodes times coordinates per node)."""
    return sum(b.n_nodes * element_kind(b.element).per_node for b in bodies)


def _check_model_size(bodies: tuple[Body, ...]) -> None:
    """Refuse a mesh whose model cannot fit the memory of this machine (``LIMITS``)."""
    memory = LIMITS["memory_bytes"]
    per_entry = LIMITS["bytes_per_matrix_entry"]
    ndof = {b.name: element_kind(b.element).ndof for b in bodies}
    entries = [b.elements * ndof[b.name] ** 2 for b in bodies]
    elements = sum(b.elements for b in bodies)
    coordinates = _coordinates(bodies)
    model_bytes = _model_bytes(bodies)
    if model_bytes > memory:
        i = max(range(len(bodies)), key=entries.__getitem__)
        n = ndof[bodies[i].name]
        most = memory // (per_entry * n * n)
        key = "rectangle.grid" if bodies[i].rectangle is not None else "elements"
        raise SceneError(f"body[{i}].{key}: {_big(elements)} elements ({_big(coordinates)} "
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
    dim = bodies[0].dim
    per_node = {b.name: element_kind(b.element).per_node for b in bodies}
    coordinates = _coordinates(bodies)
    model_bytes = _model_bytes(bodies)
    held = sum(c.held(dim, per_node[node.body]) for c in constraints
               if isinstance(c, NodeConstraint) for node in c.targets())
    free = coordinates - held
    joints = [c for c in constraints if isinstance(c, Joint)]
    dofs = free - sum(c.rows(dim, per_node[c.nodes[0].body]) for c in joints)
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
    keys(data, "", (), ("title", "material", "body", "constraint", "load", "sensor",
                        "analysis", "solver", "output", "study"))
    default_title = Path(source).stem if source != "<scene>" else "untitled"
    title = string(data.get("title", default_title), "title")
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
    context = Context(bodies[0].dim, Nodes(tuple(bodies)))

    constraints = tuple(parse_record(CONSTRAINTS, "constraint", c, f"constraint[{i}]", context)
                        for i, c in enumerate(_array_of_tables(data, "constraint")))
    _check_constraints(constraints, tuple(bodies))
    loads = tuple(parse_record(LOADS, "load", x, f"load[{i}]", context)
                  for i, x in enumerate(_array_of_tables(data, "load")))
    _check_loads(loads, constraints)
    raw_sensors = _array_of_tables(data, "sensor")
    if len(raw_sensors) > LIMITS["sensors"]:
        raise SceneError(f"sensor: expected at most {LIMITS['sensors']} sensors (one CSV "
                         f"column and one PNG plot each), got {len(raw_sensors)}")
    sensors: list[Sensor] = []
    for i, raw in enumerate(raw_sensors):
        sensor = parse_record(SENSORS, "sensor", raw, f"sensor[{i}]", context)
        same_name = [s.name for s in sensors if s.name.lower() == sensor.name.lower()]
        if same_name:
            case = "" if same_name[0] == sensor.name else \
                f" (as {_show(same_name[0])}, ignoring case)"
            raise SceneError(f"sensor[{i}].name: duplicate sensor name {_show(sensor.name)}"
                             f"{case}; sensor names name files, unique ignoring case")
        sensors.append(sensor)

    analysis = keys(data.get("analysis", {}), "analysis", (), ("static", "modal", "dynamic"))
    static = _static(analysis["static"]) if "static" in analysis else None
    modal = _modal(analysis["modal"]) if "modal" in analysis else None
    dynamic = _dynamic(analysis["dynamic"]) if "dynamic" in analysis else None
    if dynamic is not None and dynamic.frequency_of is not None:
        _check_frequency(dynamic, sensors)
    solver = _solver(data.get("solver", {}))
    output = _output(data.get("output", {}))
    _check_sizes(tuple(bodies), constraints, sensors, static, modal, dynamic)
    return _validated_scene(title=title, materials=materials, bodies=tuple(bodies),
                            constraints=constraints, loads=loads, sensors=tuple(sensors),
                            static=static, modal=modal, dynamic=dynamic, solver=solver,
                            output=output, source=source)


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


# --------------------------------------------------------------------------- TOML writer

BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")
ESCAPES = {'"': '\\"', "\\": "\\\\", "\b": "\\b", "\t": "\\t", "\n": "\\n", "\f": "\\f",
           "\r": "\\r"}


def _toml_string(text: str) -> str:
    """A TOML basic string (control characters escaped)."""
    return '"' + "".join(ESCAPES.get(c) or (f"\\u{ord(c):04x}" if ord(c) < 0x20 or c == "\x7f"
                                            else c) for c in text) + '"'


def _toml_key(key: str) -> str:
    return key if BARE_KEY.fullmatch(key) else _toml_string(key)


def _toml_value(value: Any) -> str:
    """One TOML value on one line (tables inline)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int | float):
        return repr(value)      # floats: the shortest text that reads back the same float
    if isinstance(value, str):
        return _toml_string(value)
    if isinstance(value, list):
        return "[" + ", ".join(map(_toml_value, value)) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{_toml_key(k)} = {_toml_value(v)}" for k, v in value.items()) \
            + "}"
    raise TypeError(f"no TOML value for {value!r}")


def _is_table_array(value: Any) -> bool:
    return isinstance(value, list) and bool(value) and all(isinstance(v, dict) for v in value)


def _emit(data: dict, path: tuple[str, ...], lines: list[str]) -> None:
    inline = {k: v for k, v in data.items() if not isinstance(v, dict) and
              not _is_table_array(v)}
    header = ".".join(map(_toml_key, path))
    if path and (inline or len(inline) == len(data)):   # an empty table is written too
        lines.append(f"\n[{header}]")
    lines.extend(f"{_toml_key(k)} = {_toml_value(v)}" for k, v in inline.items())
    for k, value in data.items():
        if isinstance(value, dict):
            _emit(value, (*path, k), lines)
        elif _is_table_array(value):
            for item in value:   # items of arrays of tables: their tables are inline
                lines.append(f"\n[[{'.'.join(map(_toml_key, (*path, k)))}]]")
                lines.extend(f"{_toml_key(n)} = {_toml_value(v)}" for n, v in item.items())


def toml_text(data: dict) -> str:
    """TOML text of a table of TOML data (``tomllib.loads`` of it gives ``data`` back): tables
    as ``[a.b]``, arrays of tables as ``[[a]]`` with their own tables inline."""
    lines: list[str] = []
    _emit(data, (), lines)
    return "\n".join(lines).lstrip("\n") + "\n"
