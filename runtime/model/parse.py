"""Reading a scene's TOML table into its validated parts: materials, bodies, items
(constraints, loads, sensors through their registries), analyses, solver and output settings,
each checked with an error naming its key path (``SceneError``), then the cross-checks
(``runtime.model.checks``) and the size estimates (``runtime.model.sizes``).

Names: body and material names printable, at most 64 characters; sensor names are file names
(at most 64 characters, unique ignoring case, none reserved: ``runtime.model.items.sensors``).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from runtime.catalog import (
    BACKENDS,
    DEFAULT_LAW,
    ENGINES,
    INTEGRATORS,
    LINEAR_SOLVERS,
    METHODS,
    NEWTON_MODES,
    STATIC_METHODS,
    generated_kinds,
    material_laws,
)
from runtime.element.invariants import is_straight
from runtime.kernels.kind import element_kind
from runtime.model.bodies import Body, Material, Spin
from runtime.model.checks import check_constraints, check_frequency, check_loads
from runtime.model.errors import SceneError, number_text, show
from runtime.model.items.constraint_types import CONSTRAINTS
from runtime.model.items.loads import LOADS
from runtime.model.items.rigid import RIGID_BODIES, RigidItem
from runtime.model.items.sensors import (
    SENSORS,
    MaterialPointSensor,
    SectionForce,
    Sensor,
    Slide,
    SpringAngle,
    check_reactions,
)
from runtime.model.mesh_file import FileMesh, check_shapes
from runtime.model.placements import PLACEMENTS, Arc, Box, Line, Rectangle
from runtime.model.schema import (
    HINTS,
    Context,
    Nodes,
    boolean,
    checked_name,
    choice,
    count,
    keys,
    number,
    parse_record,
    rotation_vector,
    size,
    string,
    vector,
)
from runtime.model.settings import (
    MULTIPLE_TOLERANCE,
    Dynamic,
    Modal,
    Output,
    Solver,
    Static,
)
from runtime.model.sizes import LIMITS, check_model_size, check_sizes

MODAL_ABOUT = ("reference", "static")


TITLE_LENGTH = 200


# a shear correction factor is of order 1 (5/6 for a rectangle); far outside, the shear
# stiffness k G dwarfs or vanishes beside E and the results are meaningless
SHEAR_CORRECTION_RANGE = (1e-2, 1e2)
# largest kinetic energy (J) of a body's initial motion: beyond it, the energies, their sums
# and the squares Newton's norms form overflow double precision (2e308)
KINETIC_ENERGY_LIMIT = 1e100

# a relative Newton tolerance outside this range is never met or accepts unconverged steps
TOLERANCE_RANGE = (1e-15, 1e-2)


def _array_of_tables(data: dict, key: str) -> list:
    value = data.get(key, [])
    if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
        raise SceneError(f"{key}: expected an array of tables ([[{key}]]), got {show(value)}")
    return value


def _material(name: str, data: Any) -> Material:
    path = f"material.{name}" if name else 'material.""'
    checked_name(name, path, "a material name")
    keys(data, path, ("E", "nu", "rho"), ("law", "shear_correction", "damping"))
    E = size(data["E"], f"{path}.E", "Young's modulus in Pa")
    nu = number(data["nu"], f"{path}.nu")
    if not -1.0 < nu < 0.5:
        raise SceneError(f"{path}.nu: expected a Poisson ratio in (-1, 0.5), got {show(nu)}")
    rho = size(data["rho"], f"{path}.rho", "a density in kg/m^3")
    law = choice(data.get("law", DEFAULT_LAW), f"{path}.law", material_laws(), "material law")
    shear = None
    if "shear_correction" in data:
        shear = number(data["shear_correction"], f"{path}.shear_correction", positive=True)
        low, high = SHEAR_CORRECTION_RANGE
        if not low <= shear <= high:
            raise SceneError(f"{path}.shear_correction: expected a shear correction factor in "
                             f"[{low:g}, {high:g}] (of order 1: 5/6 for a rectangular "
                             f"section), got {show(data['shear_correction'])}")
        if law != "ecm":
            raise SceneError(f'{path}.shear_correction: only meaningful with law = "ecm", got '
                             f'law = "{law}"; remove it or set law = "ecm"')
    damping = number(data.get("damping", 0.0), f"{path}.damping")
    if damping < 0:
        raise SceneError(f"{path}.damping: expected a Kelvin-Voigt coefficient alpha >= 0 (s), "
                         f"got {show(data['damping'])}")
    return Material(name, E, nu, rho, law, shear, damping)


def _body(i: int, data: dict, materials: dict[str, Material], folder: str | None) -> Body:
    path = f"body[{i}]"
    keys(data, path, ("name", "element", "material"),
         ("section", "elements", *(key for placement in PLACEMENTS for key in placement.keys),
          *FileMesh.keys, "quadrature", "initial_velocity", "initial_angular_velocity"))
    name = checked_name(data["name"], f"{path}.name", "a body name")
    if ":" in name:
        raise SceneError(f'{path}.name: expected a name without ":", got {show(name)}')
    kind = choice(data["element"], f"{path}.element", tuple(generated_kinds()), "element kind")
    meta = element_kind(kind)
    dim = meta.dim
    why = f"{kind} is {dim}D"
    material = string(data["material"], f"{path}.material")
    if material not in materials:
        defined = ", ".join(materials) or "none"
        raise SceneError(f"{path}.material: material {show(material)} is not defined; "
                         f"defined materials: {defined}")
    law = materials[material].law
    why = meta.law_not_applicable(law)
    if why is None and law not in meta.laws:  # e.g. a cable law on a continuum kind
        why = f"a law the {meta.energy.name} energy of {kind} has not"
    if why is not None:
        raise SceneError(f"{path}.material: material {show(material)} has law = "
                         f"{show(law)}, which does not apply to {kind} elements ({why}); "
                         f"expected a material with one of the laws "
                         f"{', '.join(meta.laws)}")
    shape = (_line_shape, _plate_shape, _box_shape)[len(meta.mesh_axes) - 1]
    if shape is not _box_shape:
        if "box" in data:
            raise SceneError(f"{path}.box: {kind} is not a solid element; boxes are for "
                             f"elements meshing three axes (bricks)")
        if "section" not in data:
            raise SceneError(f"{path}.section: missing required key; expected "
                             f"{HINTS['section']}")
    mesh_file = None
    if "mesh" in data:
        height, width, thickness, elements, mesh_file = _file_shape(data, path, kind, folder)
        start = end = arc = rectangle = box = None
    else:
        height, width, thickness, elements, start, end, arc, rectangle, box = shape(
            data, path, kind, dim)
    if arc is not None and "general" not in meta.laws[law].variants:
        raise SceneError(f"{path}.arc: {kind} with law = {show(law)} takes straight references "
                         f"only: {meta.laws[law].curved}; expected start and end (a straight "
                         "body)")
    if mesh_file is not None and "general" not in meta.laws[law].variants and not all(
            is_straight(meta, e0, (*mesh_file.element_sides(()), *(
                (thickness,) if height is None else (height, width))))
            for e0 in mesh_file.data.e0s[np.unique(mesh_file.data.shapes, return_index=True)[1]]):
        raise SceneError(f"{path}.mesh: {kind} with law = {show(law)} takes straight references "
                         f"only: {meta.laws[law].curved}; expected a straight mesh")

    quadrature = None
    if "quadrature" in data:
        q = data["quadrature"]
        top = LIMITS["quadrature"]
        if (not isinstance(q, list) or len(q) != dim or not all(
                isinstance(n, int) and not isinstance(n, bool) and 0 < n <= top for n in q)):
            raise SceneError(f"{path}.quadrature: expected a list of {dim} positive integers "
                             f"of at most {top} (Gauss orders; {why}), got {show(q)}")
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
                velocity, spin, rectangle, thickness, box, mesh_file)


def _check_initial_motion(body: Body, path: str, rho: float) -> None:
    """SceneError when the initial velocity or spin of ``body`` (at ``path``) gives it a
    kinetic energy beyond KINETIC_ENERGY_LIMIT: a bound on its speed from its mass."""
    mass = rho * math.prod(body.geometry) * math.prod(body.counts)
    fastest = math.sqrt(2 * KINETIC_ENERGY_LIMIT / mass)
    speeds = []
    if body.initial_velocity is not None:
        speeds.append(("initial_velocity", math.hypot(*body.initial_velocity)))
    if body.initial_angular_velocity is not None:
        spin = body.initial_angular_velocity
        reach = math.dist(spin.about, (0.0,) * len(spin.about)) + \
            math.sqrt(len(spin.about)) * body.placement.extent()
        speeds.append(("initial_angular_velocity.omega", math.hypot(*np.atleast_1d(
            spin.omega)) * reach))
    for key, speed in speeds:
        if speed > fastest:
            raise SceneError(f"{path}.{key}: expected a motion of body {show(body.name)} "
                             f"({mass:.3g} kg) at speeds of at most {fastest:.3g} m/s (a "
                             f"kinetic energy of at most {KINETIC_ENERGY_LIMIT:g} J, what double "
                             f"precision carries through a run), got speeds up to {speed:.3g} "
                             f"m/s")


def _file_shape(data: dict, path: str, kind: str, folder: str | None) -> tuple:
    """Section, element count and mesh (a ``FileMesh``) of a body meshed from a file (beam,
    plate and solid kinds)."""
    meta = element_kind(kind)
    for key in ("elements", *Line.keys, *Arc.keys, *Rectangle.keys, *Box.keys):
        if key in data:
            what = "elements" if key == "elements" else "placement"
            raise SceneError(f"{path}.{key}: the mesh file sets the body's {what}; "
                             f"expected either mesh = {{file = ...}} or {key}, got both")
    mesh = FileMesh.parse(data["mesh"], f"{path}.mesh", kind, folder)
    check_shapes(mesh, f"{path}.mesh")
    if len(meta.mesh_axes) == 3:   # a solid: its elements' sides are its geometry
        if "section" in data:
            raise SceneError(f"{path}.section: {kind} is a solid element; its elements' "
                             "sides come from the mesh file (no section)")
        return None, None, None, len(mesh.data.e0s), mesh
    if len(meta.mesh_axes) == 1:
        section = keys(data["section"], f"{path}.section", ("height", "width"), (),
                       "a table {height = H, width = W}")
        height = size(section["height"], f"{path}.section.height", "a section height in m")
        width = size(section["width"], f"{path}.section.width", "a section width in m")
        return height, width, None, len(mesh.data.e0s), mesh
    section = keys(data["section"], f"{path}.section", ("thickness",), (),
                   "a table {thickness = T}")
    thickness = size(section["thickness"], f"{path}.section.thickness", "a thickness in m")
    return None, None, thickness, len(mesh.data.e0s), mesh


def _line_shape(data: dict, path: str, kind: str, dim: int) -> tuple:
    """Section, element count and placement (a ``Line`` or an ``Arc``) of a line body (beam
    kinds)."""
    why = f"{kind} is {dim}D"
    if "rectangle" in data:
        raise SceneError(f"{path}.rectangle: {kind} is a beam element; a beam body is a line "
                         "(start and end) or an arc; rectangles are for plate elements")
    if "elements" not in data:
        raise SceneError(f"{path}.elements: missing required key; expected the number of "
                         f"elements along the body")
    section = keys(data["section"], f"{path}.section", ("height", "width"), (),
                   "a table {height = H, width = W}")
    height = size(section["height"], f"{path}.section.height", "a section height in m")
    width = size(section["width"], f"{path}.section.width", "a section width in m")
    elements = count(data["elements"], f"{path}.elements")
    straight = any(key in data for key in Line.keys)
    if straight and "arc" in data:
        raise SceneError(f"{path}: expected either start and end or arc, got both")
    if straight:
        line = Line.parse(data, path, dim, why)
        return height, width, None, elements, line.start, line.end, None, None, None
    if "arc" in data:
        arc = Arc.parse(data["arc"], f"{path}.arc", dim, why)
        return height, width, None, elements, None, None, arc, None, None
    raise SceneError(f"{path}: expected start and end (straight) or arc, got neither")


def _plate_shape(data: dict, path: str, kind: str, dim: int) -> tuple:
    """Section, element count and placement (a ``Rectangle``) of a plate body."""
    for key in (*Line.keys, *Arc.keys):
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
    thickness = size(section["thickness"], f"{path}.section.thickness", "a thickness in m")
    rectangle = Rectangle.parse(data["rectangle"], f"{path}.rectangle", dim, f"{kind} is {dim}D")
    return (None, None, thickness, math.prod(rectangle.grid), None, None, None, rectangle, None)


def _box_shape(data: dict, path: str, kind: str, dim: int) -> tuple:
    """Element count and placement (a ``Box``) of a solid body (kinds meshing three axes)."""
    for key in ("section", *Line.keys, *Arc.keys, *Rectangle.keys):
        if key in data:
            raise SceneError(f"{path}.{key}: {kind} is a solid element; a solid body is a "
                             f"box = {{corner = [x, y, z], size = [a, b, c], grid = "
                             f"[nx, ny, nz]}} (its elements' sides are its geometry)")
    if "elements" in data:
        raise SceneError(f"{path}.elements: the box's grid sets the elements of a solid "
                         f"body; remove elements")
    if "box" not in data:
        raise SceneError(f"{path}.box: missing required key; expected {{corner = [x, y, z], "
                         f"size = [a, b, c], grid = [nx, ny, nz]}} ({kind} is a solid element)")
    box = Box.parse(data["box"], f"{path}.box", dim, f"{kind} is {dim}D")
    return (None, None, None, math.prod(box.grid), None, None, None, None, box)


def _table_fields(data: Any, path: str, spec: dict[str, Callable[[Any, str], Any]],
                  required: tuple[str, ...] = ()) -> dict:
    optional = tuple(k for k in spec if k not in required)
    keys(data, path, required, optional)
    return {key: check(data[key], f"{path}.{key}") for key, check in spec.items() if key in data}


def _iterations(value: Any, path: str) -> int:
    return count(value, path, LIMITS["iterations"], " Newton iterations")


def _tolerance(value: Any, path: str) -> float:
    low, high = TOLERANCE_RANGE
    tolerance = number(value, path, positive=True)
    if not low <= tolerance <= high:
        raise SceneError(f"{path}: expected a relative Newton tolerance in [{low:g}, {high:g}] "
                         f"(below, rounding never lets Newton meet it; above, unconverged "
                         f"steps pass), got {show(value)}")
    return tolerance


def _static(data: Any, sensors: list[Sensor]) -> Static:
    path = "analysis.static"
    fields = _table_fields(data, path, {
        "max_iterations": _iterations, "tolerance": _tolerance,
        "load_steps": lambda v, p: count(v, p, LIMITS["steps"], " load increments"),
        "method": lambda v, p: choice(v, p, STATIC_METHODS, "static method"),
        "arc_length": lambda v, p: number(v, p, positive=True),
        "max_steps": lambda v, p: count(v, p, LIMITS["steps"], " path points"),
        "max_load_factor": lambda v, p: number(v, p, positive=True),
        "stop_sensor": string, "stop_value": number})
    arc_keys = sorted(set(fields) & {"arc_length", "max_steps", "max_load_factor",
                                     "stop_sensor", "stop_value"})
    if arc_keys and fields.get("method") != "arc_length":
        raise SceneError(f'{path}.{arc_keys[0]}: only meaningful with method = "arc_length"; '
                         f'add it or remove {arc_keys[0]}')
    if ("stop_sensor" in fields) != ("stop_value" in fields):
        given, missing = (("stop_sensor", "stop_value") if "stop_sensor" in fields
                          else ("stop_value", "stop_sensor"))
        raise SceneError(f"{path}.{missing}: expected with {given} (the path stops when "
                         f"sensor stop_sensor passes stop_value)")
    names = [s.name for s in sensors]
    if "stop_sensor" in fields and fields["stop_sensor"] not in names:
        expected = f"one of {', '.join(names)}" if names else "a [[sensor]] name (none defined)"
        raise SceneError(f"{path}.stop_sensor: no sensor called {show(fields['stop_sensor'])}; "
                         f"expected {expected}")
    return Static(**fields)


def _modal(data: Any) -> Modal:
    return Modal(**_table_fields(data, "analysis.modal", {
        "modes": lambda v, p: count(v, p, LIMITS["modes"], " modes"),
        "about": lambda v, p: choice(v, p, MODAL_ABOUT)}))


def _multiple(value: float, step: float, path: str, key: str) -> None:
    """``value`` (at key ``key``) must be an integer multiple of the time step."""
    ratio = value / step
    if not math.isfinite(ratio):
        raise SceneError(f"{path}.{key}: {key} / step = {ratio} overflows; expected a {key} "
                         f"of at most t_end, got {number_text(value)} s for step = "
                         f"{number_text(step)} s")
    n = round(ratio)
    if abs(ratio - n) <= MULTIPLE_TOLERANCE * ratio:
        return
    low, high = math.floor(ratio), math.ceil(ratio)
    values = " or ".join(number_text(k * step) for k in (low, high) if k >= 1)
    text = (f"{path}.{key}: expected an integer multiple of {path}.step = "
            f"{number_text(step)} s, got {key} = {number_text(value)} s ({key} / step = "
            f"{number_text(ratio)}")
    if key == "t_end":
        steps = " or ".join(number_text(value / k) for k in (high, low))
        raise SceneError(f"{text}: the run would stop at {number_text(n * step)} s); nearest "
                         f"valid: t_end = {values} s, or step = {steps} s")
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
                         f"the limit of {top:.0e}; expected step >= "
                         f"{number_text(t_end / top)} s for t_end = {number_text(t_end)} s")
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
        "engine": lambda v, p: choice(v, p, ENGINES, "engine"),
        "linear_solver": lambda v, p: choice(v, p, LINEAR_SOLVERS, "linear solver"),
        "threads": lambda v, p: count(v, p, LIMITS["threads"], " threads")}))


def _output(data: Any) -> Output:
    return Output(**_table_fields(data, "output", dict.fromkeys(
        (f.name for f in dataclasses.fields(Output)), boolean)))


def rigid_dimension(tables: list[tuple[int, dict]]) -> int:
    """The dimension of a scene of rigid items only (``tables``: (index in [[body]],
    table)): 2 when one of them has a ``position`` of two numbers, else 3."""
    planar = any(isinstance(raw.get("position"), list) and len(raw["position"]) == 2
                 for _, raw in tables)
    return 2 if planar else 3


def _rigid_bodies(tables: list[tuple[int, dict]], bodies: list[Body],
                  context: Context) -> tuple[RigidItem, ...]:
    """The rigid items (rigid bodies, point masses) of the ``[[body]]`` tables with a
    ``type`` (``tables``: (index in [[body]], table)), their names unique among all bodies."""
    items: list[RigidItem] = []
    names = {b.name for b in bodies}
    for i, raw in tables:
        item = parse_record(RIGID_BODIES, "body", raw, f"body[{i}]", context)
        if item.name in names:
            raise SceneError(f"body[{i}].name: duplicate body name {show(item.name)}")
        names.add(item.name)
        items.append(item)
    return tuple(items)


def _check_material_points(sensors: list[Sensor], bodies: list[Body],
                           materials: dict[str, Material]) -> None:
    """SceneError for a strain, stress or section sensor on a body whose law is a structural
    energy of the centre line (``elastic_line``: no Green strain at material points, and its
    section forces are not built)."""
    by_name = {body.name: body for body in bodies}
    for i, sensor in enumerate(sensors):
        if not isinstance(sensor, MaterialPointSensor | SectionForce):
            continue
        body = by_name[sensor.body]
        law = materials[body.material].law
        info = element_kind(body.element).laws.get(law)
        if info is not None and info.structural:
            raise SceneError(f"sensor[{i}].type: body {show(body.name)} has the {law} law "
                             f"of material {show(body.material)}, a structural energy of "
                             f"the centre line: its {sensor.type} sensors are not built "
                             f"(no strains at material points); expected a displacement, "
                             f"position, velocity or energy sensor for this body, or a "
                             f"continuum law (ecm, ecm_sri)")


def scene_fields(data: dict, source: str = "<scene>") -> dict[str, Any]:
    """The validated fields of the ``Scene`` of the parsed TOML ``data`` (``source`` names
    it: a file path).

    Raises SceneError (message: key path, what was expected, what was found).
    """
    if not isinstance(data, dict):
        raise SceneError(f"{source}: expected a table of scene keys, got {show(data)}")
    # [study] declares a work-precision sweep: read and validated by `ancf study
    # error-vs-time` (runtime/studies/error_vs_time.py), ignored by runs
    keys(data, "", (), ("title", "material", "body", "constraint", "load", "sensor",
                        "analysis", "solver", "output", "study"))
    default_title = Path(source).stem if source != "<scene>" else "untitled"
    title = string(data.get("title", default_title), "title")
    if len(title) > TITLE_LENGTH or not title.isprintable():
        raise SceneError(f"title: expected one line of printable text of at most "
                         f"{TITLE_LENGTH} characters, got {show(title)}")

    raw_materials = data.get("material", {})
    if not isinstance(raw_materials, dict):
        raise SceneError(f"material: expected tables [material.NAME], got {show(raw_materials)}")
    materials = {name: _material(name, m) for name, m in raw_materials.items()}

    raw_bodies = _array_of_tables(data, "body")
    if not raw_bodies:
        raise SceneError("body: a scene needs at least one [[body]], got none")
    bodies: list[Body] = []
    rigid_tables = [(i, raw) for i, raw in enumerate(raw_bodies)
                    if isinstance(raw, dict) and "type" in raw]
    for i, raw in enumerate(raw_bodies):
        if isinstance(raw, dict) and "type" in raw:
            continue
        body = _body(i, raw, materials, None if source == "<scene>"
                     else str(Path(source).resolve().parent))
        if any(b.name == body.name for b in bodies):
            raise SceneError(f"body[{i}].name: duplicate body name {show(body.name)}")
        if bodies and body.dim != bodies[0].dim:
            raise SceneError(f"body[{i}].element: expected a {bodies[0].dim}D element kind like "
                             f"body[0], got {body.element} ({body.dim}D)")
        bodies.append(body)
    check_model_size(tuple(bodies))
    for i, body in enumerate(bodies):   # element sizes once the counts are known to fit
        body.placement.check_counts(body.counts, f"body[{i}]")
        _check_initial_motion(body, f"body[{i}]", materials[body.material].rho)
    context = Context(bodies[0].dim if bodies else rigid_dimension(rigid_tables),
                      Nodes(tuple(bodies)),
                      None if source == "<scene>" else str(Path(source).resolve().parent))
    rigid_bodies = _rigid_bodies(rigid_tables, bodies, context)
    context = dataclasses.replace(context, rigid={r.name: r for r in rigid_bodies})

    constraints = tuple(parse_record(CONSTRAINTS, "constraint", c, f"constraint[{i}]", context)
                        for i, c in enumerate(_array_of_tables(data, "constraint")))
    check_constraints(constraints, tuple(bodies))
    loads = tuple(parse_record(LOADS, "load", x, f"load[{i}]", context)
                  for i, x in enumerate(_array_of_tables(data, "load")))
    check_loads(loads, constraints, tuple(bodies))
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
                f" (as {show(same_name[0])}, ignoring case)"
            raise SceneError(f"sensor[{i}].name: duplicate sensor name {show(sensor.name)}"
                             f"{case}; sensor names name files, unique ignoring case")
        sensors.append(sensor)
    check_reactions(tuple(sensors), constraints)
    _check_material_points(sensors, bodies, materials)
    for i, sensor in enumerate(sensors):
        spring = getattr(sensor, "load", None)
        if isinstance(sensor, SpringAngle) and (spring >= len(loads)
                                                or loads[spring].type != "torsional_spring"):
            raise SceneError(f"sensor[{i}].load: expected the index of a torsional_spring "
                             f"among the {len(loads)} [[load]] tables, got {spring}")
        index = getattr(sensor, "constraint", None)
        if isinstance(sensor, Slide):
            if index >= len(constraints) or constraints[index].type != "sliding":
                raise SceneError(f"sensor[{i}].constraint: expected the index of a sliding "
                                 f"joint among the {len(constraints)} [[constraint]] tables, "
                                 f"got {index}")
            continue
        if index is not None and (index >= len(constraints) or sensor.body not in (
                getattr(constraints[index], "body", None),
                getattr(constraints[index], "other", None))):
            raise SceneError(f"sensor[{i}].constraint: expected the index of a joint of body "
                             f"{show(sensor.body)} among the {len(constraints)} "
                             f"[[constraint]] tables, got {index}")

    analysis = keys(data.get("analysis", {}), "analysis", (), ("static", "modal", "dynamic"))
    static = _static(analysis["static"], sensors) if "static" in analysis else None
    modal = _modal(analysis["modal"]) if "modal" in analysis else None
    dynamic = _dynamic(analysis["dynamic"]) if "dynamic" in analysis else None
    if dynamic is not None and dynamic.frequency_of is not None:
        check_frequency(dynamic, sensors)
    solver = _solver(data.get("solver", {}))
    output = _output(data.get("output", {}))
    check_sizes(tuple(bodies), constraints, sensors, static, modal, dynamic,
                sum(r.coordinates for r in rigid_bodies))
    return dict(title=title, materials=materials, bodies=tuple(bodies),
                rigid_bodies=rigid_bodies,
                constraints=constraints, loads=loads, sensors=tuple(sensors), static=static,
                modal=modal, dynamic=dynamic, solver=solver, output=output, source=source)
