"""Scenes: the public Python API of the scene schema, read from and written to TOML
(docs/design.md, "Scenes").

Units SI: lengths in m, forces in N, moments in N m, velocities in m/s, angular velocities in
rad/s, accelerations in m/s^2, E in Pa, rho in kg/m^3, angles in degrees where the key says
``_deg`` and in rad in time laws, times in s.

A ``Scene`` is built from the dataclasses of ``runtime.model.bodies``,
``runtime.model.placements`` and ``runtime.model.settings`` and the typed records of
``runtime.model.items``, in Python or from a TOML file (``load_scene``).  There is one
validation path: a scene built in Python is written as its TOML table (``Scene.to_dict``) and
read by the parser of TOML files (``runtime.model.parse``), so both raise the same
``SceneError`` whose message starts with the key path of the culprit (``body[1].sectoin:
unknown key; expected one of ...``) and says what was expected and what was found; the
validated scene holds the parsed values (node references ``"BODY:INDEX"`` resolved to
``NodeRef`` with a non-negative index, which keeps a negative index as written for
``to_toml``, so "BODY:-1" stays the last node when the body is remeshed; numbers as floats,
vectors as tuples).  ``Scene.to_toml()`` writes a scene that ``load_scene`` reads back equal.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from runtime.model import parse
from runtime.model.bodies import Body, Material
from runtime.model.errors import SceneError, show
from runtime.model.items.constraints import Constraint
from runtime.model.items.loads import Load
from runtime.model.items.rigid import RigidItem
from runtime.model.items.sensors import Sensor
from runtime.model.schema import plain, same
from runtime.model.settings import Dynamic, Modal, Output, Solver, Static
from runtime.model.toml_io import read_scene_file, toml_text


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
    rigid_bodies: tuple[RigidItem, ...] = ()
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
        """Spatial dimension shared by every body (2 or 3; a scene of rigid items only has
        theirs: ``runtime.model.parse.rigid_dimension``)."""
        if self.bodies:
            return self.bodies[0].dim
        return len(self.rigid_bodies[0].position) if self.rigid_bodies else 3

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
                                "body": plain(self.bodies) + plain(self.rigid_bodies)}
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
                                 f"{show(material.name)}; expected the same name")
        return plain(materials)
    if not isinstance(materials, list | tuple):
        return plain(materials)
    out: dict[str, Any] = {}
    for i, material in enumerate(materials):
        if not isinstance(material, Material):
            raise SceneError(f"material: expected Material objects, got {show(material)} at "
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


def parse_scene(data: dict, source: str = "<scene>") -> Scene:
    """Validate the parsed TOML ``data`` of a scene; ``source`` names it (a file path).

    Raises SceneError (message: key path, what was expected, what was found).
    """
    return _validated_scene(**parse.scene_fields(data, source))


def load_scene(path: str | Path) -> Scene:
    """Read and validate the TOML scene file ``path`` (SceneError for any problem)."""
    return parse_scene(read_scene_file(path), str(path))
