"""Line forces on plates: the consistent load of a grid line is f times the line's length,
acting at the line, whether the line is a boundary or an interior one (an interior line is
the side of two elements and is integrated once)."""

from __future__ import annotations

import numpy as np
import pytest

from runtime import Body, Clamp, LineForce, Material, Rectangle, Scene, Static
from runtime.catalog import generated_kinds
from runtime.kernels.kind import element_kind
from runtime.model.model import Model

PLATE_KINDS = [k for k in generated_kinds() if len(element_kind(k).mesh_axes) == 2]
SIZE, GRID = (1.6, 0.3), (8, 3)
STEEL = Material("steel", E=2.1e11, nu=0.0, rho=7850.0)


def _model(kind: str, line: str, force=(0.0, 0.0, -100.0)) -> Model:
    plate = Body("plate", kind, "steel", thickness=0.01,
                 rectangle=Rectangle(corner=(0.0, 0.0, 0.0), size=SIZE, grid=GRID))
    return Model(Scene(materials=[STEEL], bodies=[plate],
                       constraints=[Clamp(edge="plate:x=0")],
                       loads=[LineForce(edge=line, force_per_length=force)], static=Static()))


# lattice lines x = I (length b, at x = I a / (nx sx)) and y = J (length a, at y = J b / (ny sy)),
# sx, sy lattice steps per element (2 with mid-side nodes: odd lines cross elements' middles)
LINES = [("x", i) for i in (1, 4, -1)] + [("y", j) for j in (0, 1, 2, -1)]


@pytest.mark.parametrize("kind", PLATE_KINDS)
@pytest.mark.parametrize("axis, index", LINES)
def test_line_force_resultant_and_moment_on_boundary_and_interior_lines(kind, axis, index):
    model = _model(kind, f"plate:{axis}={index}")
    load = model.nominal_load()
    positions = model.reference[model.position_dofs()]
    forces = load[model.position_dofs()]
    a, b = SIZE
    along = "xy".index(axis)
    length = b if axis == "x" else a
    lines = GRID[along] * element_kind(kind).lattice_steps[along]   # lattice steps across
    place = (index % (lines + 1)) * SIZE[along] / lines
    # resultant: f times the line's length
    np.testing.assert_allclose(forces.sum(axis=0), [0.0, 0.0, -100.0 * length], rtol=1e-12,
                               atol=1e-9)
    # first moments of the z forces: the line's place across it, the middle along it
    total = forces[:, 2].sum()
    centre = (forces[:, 2] @ positions[:, :2]) / total
    expected = [place, b / 2] if axis == "x" else [a / 2, place]
    np.testing.assert_allclose(centre, expected, rtol=1e-12, atol=1e-12)
