"""The registry of every ``[[constraint]]`` type, ``CONSTRAINTS``: the node constraints and
joints between ANCF nodes (``runtime.model.items.constraints``, ``node_frame_joints``) and
the joints of rigid bodies, which build on them (``runtime.model.items.body_joints``,
``axis_joints``).  A new constraint class is one entry here."""

from __future__ import annotations

from runtime.model.items.axis_joints import BodyCylindrical, BodyUniversal
from runtime.model.items.body_joints import BodyPrismatic, BodyRevolute, BodySpherical, BodyWeld
from runtime.model.items.constraints import (
    Clamp,
    Constraint,
    Hub,
    Pin,
    Revolute,
    Spherical,
    Weld,
)
from runtime.model.items.node_frame_joints import Cylindrical, Prismatic, Universal
from runtime.model.items.sliding import Sliding
from runtime.model.items.symmetry import Fix, Symmetry
from runtime.model.schema import registry

CONSTRAINTS: dict[str, type[Constraint]] = registry(Clamp, Pin, Symmetry, Fix, Hub, Spherical,
                                                    Revolute, Weld, Prismatic, Cylindrical,
                                                    Universal, BodySpherical,
                                                    BodyRevolute, BodyPrismatic, BodyWeld,
                                                    BodyCylindrical, BodyUniversal, Sliding)
