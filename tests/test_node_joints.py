"""ANCF nodes as the other side of the prismatic, cylindrical and universal joints of rigid
bodies and of the bushing (``node = "BODY:INDEX"``, docs/multibody.md): the rows vanish at
t = 0 and match finite differences, they leave exactly the expected relative motion of the
body and the node's frame free (the bushing's deflection reads the relative motion), both
engines agree, and a joint on a node that a hub turns equals the same joint on a rigid
body driven through the same rotation (its code path does not touch the node's); the bad
inputs name their keys."""

from __future__ import annotations

import tomllib

import numpy as np
import pytest
from test_multibody import _finite_difference_check, run, scene_of

from runtime.model.errors import SceneError
from runtime.model.model import Model
from runtime.model.scene import parse_scene

#: a free beam3d along (0.6, 0.8, 0) (its tip node's frame turned about z) and a turned
#: rigid body b near its tip
BASE = """
[material.steel]
E = 2.1e11
nu = 0.0
rho = 7800.0
[[body]]
name = "beam"
element = "beam3d"
material = "steel"
section = {height = 0.02, width = 0.02}
elements = 2
start = [0, 0, 0]
end = [0.6, 0.8, 0]
[[body]]
type = "rigid"
name = "b"
mass = 2.0
inertia = [0.3, 0.2, 0.4]
centre_of_mass = [0.05, 0.0, 0.0]
position = [0.7, 0.8, 0.1]
rotation = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
"""
#: where the point [0, 0.1, -0.1] of b (the universal joint's and the bushing's) is at
#: t = 0: at the beam's tip node
PLACE = np.array([0.6, 0.8, 0.0])
AXIS = np.array([0.0, 0.6, 0.8])

PRISMATIC = ('type = "body_prismatic"\nbody = "b"\nnode = "beam:-1"\n'
             'axis = [0.0, 0.6, 0.8]\n')
CYLINDRICAL = ('type = "body_cylindrical"\nbody = "b"\nnode = "beam:-1"\n'
               'axis = [0.6, 0.8, 0.0]\n')
UNIVERSAL = ('type = "body_universal"\nbody = "b"\nnode = "beam:-1"\n'
             'point = [0.0, 0.1, -0.1]\naxis = [0, 0, 1]\nother_axis = [1, 0, 0]\n')
BUSHING = ('type = "bushing"\nbody = "b"\nnode = "beam:-1"\npoint = [0.0, 0.1, -0.1]\n'
           'stiffness = [2e4, 3e4, 4e4, 50.0, 60.0, 70.0]\n'
           'damping = [5.0, 6.0, 7.0, 0.1, 0.2, 0.3]\n')


def _spin(about: np.ndarray, axis: np.ndarray) -> dict:
    return {"rotation": axis, "about": about}


#: joint tables and the relative motions of b they leave free (rigid_field arguments, in
#: global axes at t = 0): a prismatic slides along its axis; a cylindrical (its axis body
#: coordinates, (-0.8, 0.6, 0) in global axes; the point b's origin) also turns about it; a
#: universal turns about both pins through its point
JOINTS = {
    "prismatic": (PRISMATIC, [{"translation": AXIS}]),
    "driven prismatic": (PRISMATIC + 'displacement = {type = "cosine_ramp", duration = 0.5}\n',
                         []),
    "cylindrical": (CYLINDRICAL, [{"translation": np.array([-0.8, 0.6, 0.0])},
                                  _spin(np.array([0.7, 0.8, 0.1]), np.array([-0.8, 0.6, 0.0]))]),
    "universal": (UNIVERSAL, [_spin(PLACE, np.array([0.0, 0.0, 1.0])),
                              _spin(PLACE, np.array([0.6, 0.8, 0.0]))]),
}


def _model(table: str, kind: str = "constraint", base: str = BASE) -> Model:
    return Model(scene_of(f"{base}[[{kind}]]\n{table}"))


def _joint_blocks(model: Model) -> list:
    """The joint's blocks (not the rigid body's orthonormality rows)."""
    return [block for block in model.holonomic.blocks if block.owner.startswith("body_")]


def _motions(model: Model) -> np.ndarray:
    """The small rigid motions (size, 12) of the body b and of the whole beam apart:
    translations along and rotations about the global axes (about the origin)."""
    return np.array([model.rigid_field(**{what: e}, body=body) for body in ("b", "beam")
                     for what in ("translation", "rotation") for e in np.eye(3)]).T


@pytest.mark.parametrize("name", JOINTS)
def test_node_joint_rows_vanish_and_match_finite_differences(name):
    model = _model(JOINTS[name][0])
    blocks = _joint_blocks(model)
    assert blocks
    assert np.abs(model.holonomic.value(model.reference)).max() <= 1e-15
    rng = np.random.default_rng(11)
    for block in blocks:
        _finite_difference_check(block, rng)


@pytest.mark.parametrize("name", JOINTS)
def test_node_joints_leave_exactly_the_expected_relative_motion(name):
    """In the 12 small rigid motions of the body and the beam, the rows' null space is
    the 6 common motions and the joint's free relative motions, no more."""
    table, free = JOINTS[name]
    model = _model(table)
    jacobian = model.holonomic.jacobian(model.reference).toarray()[6:]   # the joint's rows
    common = [model.rigid_field(translation=e) for e in np.eye(3)] + \
             [model.rigid_field(rotation=e, about=(0.3, -0.2, 0.5)) for e in np.eye(3)]
    relative = [model.rigid_field(**motion, body="b") for motion in free]
    for motion in common + relative:
        assert np.abs(jacobian @ motion).max() <= 1e-14
    rank = np.linalg.matrix_rank(jacobian @ _motions(model), tol=1e-10)
    assert 12 - rank == 6 + len(free)


def test_a_bushing_on_a_node_reads_the_relative_motion_in_the_bodys_axes():
    """The deflection's rate under small motions: 0 for the common rigid motions, the
    relative translation of the body point and the relative rotation in the body's axes at
    t = 0 for a motion of the body alone; its Jacobians match finite differences."""
    model = _model(BUSHING, "load")
    element = model.scene.loads[0].state_force(model)
    forms, dofs = element.forms, element.forms.dofs
    assert np.abs(forms.value(model.reference[dofs])).max() <= 1e-15
    slope = forms.jacobian(model.reference[dofs])
    axes = np.array(model.scene.rigid_bodies[0].frame)          # columns: b's axes at t = 0
    for e in np.eye(3):
        assert np.abs(slope @ model.rigid_field(translation=e)[dofs]).max() <= 1e-14
        rotation = model.rigid_field(rotation=e, about=(0.3, -0.2, 0.5))
        assert np.abs(slope @ rotation[dofs]).max() <= 1e-14
        moved = slope @ model.rigid_field(translation=e, body="b")[dofs]
        assert moved == pytest.approx(np.concatenate([axes.T @ e, np.zeros(3)]), abs=1e-14)
        turned = slope @ model.rigid_field(rotation=e, about=PLACE, body="b")[dofs]
        assert turned == pytest.approx(np.concatenate([np.zeros(3), axes.T @ e]), abs=1e-14)
    rng = np.random.default_rng(4)
    _finite_difference_check(forms, rng)
    q = model.reference + 0.05 * rng.normal(size=model.size)
    v = rng.normal(size=model.size)
    patch = element(q, True, v)
    for which, numeric in (("q", lambda s, e: element(q + s * e, False, v)),
                           ("v", lambda s, e: element(q, False, v + s * e))):
        expected = patch.jacobian[0] if which == "q" else patch.jacobian_dot[0]
        columns = []
        for dof in dofs:
            e = np.zeros(model.size)
            e[dof] = 1.0
            columns.append((numeric(1e-6, e).force[0] - numeric(-1e-6, e).force[0]) / 2e-6)
        assert np.abs(expected - np.array(columns).T).max() <= 1e-5 * np.abs(expected).max()


#: BASE with the beam clamped at its start, under gravity, for a short run
DYNAMIC = BASE + """
[[constraint]]
type = "clamp"
node = "beam:0"
[[load]]
type = "gravity"
acceleration = [0, 0, -9.81]
[analysis.dynamic]
t_end = 0.01
step = 1e-3
"""

ENGINE_CASES = {name: ("constraint", table) for name, (table, _) in JOINTS.items()}
ENGINE_CASES["bushing"] = ("load", BUSHING)


@pytest.mark.parametrize("name", ENGINE_CASES)
def test_engines_agree_on_node_joints(name):
    kind, table = ENGINE_CASES[name]
    scene = scene_of(f"{DYNAMIC}[[{kind}]]\n{table}")
    python = run(scene, "python")
    compiled = run(scene, "compiled")
    assert np.ptp(python[1][:, -12:], axis=0).max() > 1e-5          # b moves
    assert np.abs(python[1] - compiled[1]).max() <= 1e-10
    assert np.abs(python[2] - compiled[2]).max() <= 1e-8


#: a beam whose first node is a hub turned about z, and b near it; or the same hub as a
#: rigid carrier (the node's frame at t = 0) turned by a driven revolute joint
HUB = """
[material.steel]
E = 2.1e11
nu = 0.0
rho = 7800.0
[[body]]
type = "rigid"
name = "b"
mass = 2.0
inertia = [0.3, 0.2, 0.4]
centre_of_mass = [0.05, 0.0, 0.0]
position = [0.1, 0.0, 0.1]
rotation = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
[[load]]
type = "gravity"
acceleration = [0, 0, -9.81]
[analysis.dynamic]
t_end = 0.05
step = 1e-3
"""
ON_NODE = """
[[body]]
name = "beam"
element = "beam3d"
material = "steel"
section = {height = 0.02, width = 0.02}
elements = 1
start = [0, 0, 0]
end = [0.6, 0.8, 0]
[[constraint]]
type = "prescribed_rotation"
node = "beam:0"
angle = {type = "spin_up", omega = 20.0, t_ramp = 0.05}
"""
ON_CARRIER = """
[[body]]
type = "rigid"
name = "carrier"
mass = 1.0
inertia = [0.1, 0.1, 0.1]
rotation = [[0.6, -0.8, 0.0], [0.8, 0.6, 0.0], [0.0, 0.0, 1.0]]
[[constraint]]
type = "body_revolute"
body = "carrier"
angle = {type = "spin_up", omega = 20.0, t_ramp = 0.05}
"""

HUB_JOINTS = {
    "prismatic": ("constraint", 'type = "body_prismatic"\nbody = "b"\naxis = [0.6, 0.8, 0.0]\n'),
    "cylindrical": ("constraint", 'type = "body_cylindrical"\nbody = "b"\n'
                                  'axis = [0.6, 0.8, 0.0]\npoint = [0.0, 0.0, 0.0]\n'),
    "universal": ("constraint", 'type = "body_universal"\nbody = "b"\npoint = [-0.1, 0.1, -0.1]\n'
                                'axis = [0, 0, 1]\nother_axis = [0, 1, 0]\n'),
    "bushing": ("load", 'type = "bushing"\nbody = "b"\npoint = [-0.1, 0.1, -0.1]\n'
                        'stiffness = [2e3, 3e3, 4e3, 50.0, 60.0, 70.0]\n'),
}


@pytest.mark.parametrize("name", HUB_JOINTS)
def test_a_joint_on_a_turned_node_equals_the_joint_on_a_turned_rigid_body(name):
    """The node's frame turned by a hub is a rigid frame: b moves as on a rigid carrier at
    the node, with the node's frame at t = 0, turned by the same law, to round-off with
    generalized-alpha.  (Not so the integrators' own view of the two drives: the trapezoidal
    rule's positions of b differ by O(h^3), 5e-8 m at this step, and generalized-alpha
    gives the hub the law's velocities but the driven carrier velocities 4e-3 m/s off
    them, which a bushing's damping reads: the bushing here is undamped.)"""
    kind, table = HUB_JOINTS[name]
    on_node = scene_of(f"{HUB}{ON_NODE}[[{kind}]]\n{table}node = \"beam:0\"\n")
    on_carrier = scene_of(f"{HUB}{ON_CARRIER}[[{kind}]]\n{table}other = \"carrier\"\n")
    node = run(on_node, "compiled", integrator="generalized_alpha")
    carrier = run(on_carrier, "compiled", integrator="generalized_alpha")
    b_node = Model(on_node).rigid["b"].dofs
    b_carrier = Model(on_carrier).rigid["b"].dofs
    assert np.ptp(node[1][:, b_node], axis=0).max() > 1e-3           # b moves
    assert np.abs(node[1][:, b_node] - carrier[1][:, b_carrier]).max() <= 1e-9
    assert np.abs(node[2][:, b_node] - carrier[2][:, b_carrier]).max() <= 1e-7


CABLE = BASE.replace('element = "beam3d"', 'element = "cable3d"')


def test_a_universal_joint_takes_a_cable_node_whose_tangent_is_its_pin():
    """A 3D cable node carries r_x only: enough for the pin along its tangent."""
    model = _model(UNIVERSAL, base=CABLE)
    assert np.abs(model.holonomic.value(model.reference)).max() <= 1e-15
    _finite_difference_check(_joint_blocks(model)[0], np.random.default_rng(2))


@pytest.mark.parametrize(("kind", "table", "base", "message"), [
    ("constraint", PRISMATIC + 'other = "b"\n', BASE,
     "constraint[0].other: expected a node or another body (or neither: the ground), got both"),
    ("constraint", CYLINDRICAL + 'other = "b"\n', BASE,
     "constraint[0].other: expected a node or another body (or neither: the ground), got both"),
    ("load", BUSHING + 'other = "b"\n', BASE,
     "load[0].other: expected a node or another body (or neither: the ground), got both"),
    ("constraint", PRISMATIC, CABLE,
     "constraint[0].node: a body_prismatic holds the node's frame, which needs its three "
     'gradients r_x, r_y, r_z (a beam3d or plate3d node); node "beam:-1" of body "beam" '
     "(cable3d) carries only r, r_x: enough for an axis along a gradient (body_revolute, "
     "body_universal), not for a frame"),
    ("load", BUSHING, CABLE, "load[0].node: a bushing turns with the node's frame"),
])
def test_bad_node_sides_are_scene_errors_naming_the_key(kind, table, base, message):
    with pytest.raises(SceneError) as error:
        scene_of(f"{base}[[{kind}]]\n{table}")
    assert str(error.value).startswith(message)


@pytest.mark.parametrize(("table", "base", "message"), [
    (CYLINDRICAL + "point = [0.0, 0.1, -0.1]\n", CABLE,
     "constraint[0]: body_cylindrical of b: the normal of the axis (-0.0, 0.0, -1.0) is not "
     "a combination of the gradients r_x of the node"),
    (CYLINDRICAL, CABLE, "constraint[0]: body_cylindrical of b: the point: its offset from "
                         "the node (0.09999999999999998, 0.0, 0.1) is not a combination"),
    (UNIVERSAL.replace("other_axis = [1, 0, 0]", "other_axis = [0, 1, 0]"), CABLE,
     'constraint[0]: body_universal of b: other_axis: node "beam:-1" of body "beam" (cable3d) '
     "has only r_x of a frame: expected an axis along its local x, got (0.0, 1.0, 0.0)"),
    (UNIVERSAL.replace("other_axis = [1, 0, 0]", "other_axis = [0, 0, 1]"), BASE,
     "constraint[0]: body_universal of b: other_axis (the node's reference frame): expected "
     "an axis normal to the body's axis at t = 0"),
])
def test_node_sides_lacking_a_direction_fail_when_the_model_is_built(table, base, message):
    """What the node's frame must hold is known with the model: a cable node's r_x has no
    normals of its own axis, no pin across it, and a pin must be normal to the body's."""
    scene = scene_of(f"{base}[[constraint]]\n{table}")
    with pytest.raises(SceneError) as error:
        Model(scene)
    assert str(error.value).startswith(message)


@pytest.mark.parametrize("name", ENGINE_CASES)
def test_node_sides_round_trip_through_toml(name):
    kind, table = ENGINE_CASES[name]
    scene = scene_of(f"{BASE}[[{kind}]]\n{table}")
    assert parse_scene(tomllib.loads(scene.to_toml())) == scene
