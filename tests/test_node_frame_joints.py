"""Prismatic, cylindrical and universal joints between two ANCF nodes (``nodes``,
docs/multibody.md): the rows vanish at t = 0 and under any rigid motion of the pair, match
finite differences, leave exactly the joint's relative motion free (small and finite), a
prismatic slide under gravity along its axis follows g t^2 / 2, each joint on a node that
a hub turns equals the rigid-body joint on a carrier turned the same way, both engines
agree, and bad input names its key."""

from __future__ import annotations

import dataclasses
import tomllib

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from test_multibody import _finite_difference_check, run, scene_of

from runtime import run_scene
from runtime.model.errors import SceneError
from runtime.model.model import Model
from runtime.model.scene import parse_scene
from runtime.model.schema import NodeRef
from runtime.solve.modal import modal

#: the direction of both beams, the prismatic and cylindrical axis
ALONG = np.array([0.6, 0.8, 0.0])
#: the end of beam a, where b starts for a universal joint (b starts 0.1 m further on
#: along ALONG for the prismatic and cylindrical joints)
TIP = 0.5 * ALONG


def _beams(gap: float, element: str = "beam3d", first: str = "beam3d") -> str:
    """Beam a from the origin to TIP, beam b from ``gap`` m further along ALONG, 0.6 m."""
    start = [float(x) for x in TIP + gap * ALONG]
    end = [float(x) for x in TIP + (gap + 0.6) * ALONG]
    return f"""
[material.steel]
E = 2.1e11
nu = 0.0
rho = 7800.0
[[body]]
name = "a"
element = "{first}"
material = "steel"
section = {{height = 0.02, width = 0.02}}
elements = 2
start = [0, 0, 0]
end = [{float(TIP[0])!r}, {float(TIP[1])!r}, 0]
[[body]]
name = "b"
element = "{element}"
material = "steel"
section = {{height = 0.02, width = 0.02}}
elements = 2
start = [{start[0]!r}, {start[1]!r}, 0]
end = [{end[0]!r}, {end[1]!r}, 0]
"""


PRISMATIC = 'type = "prismatic"\nnodes = ["a:-1", "b:0"]\naxis = [0.6, 0.8, 0.0]\n'
CYLINDRICAL = 'type = "cylindrical"\nnodes = ["a:-1", "b:0"]\naxis = [0.6, 0.8, 0.0]\n'
UNIVERSAL = ('type = "universal"\nnodes = ["a:-1", "b:0"]\naxis = [0, 0, 1]\n'
             'other_axis = [-0.8, 0.6, 0.0]\n')
CROSS = np.array([-0.8, 0.6, 0.0])
Z = np.array([0.0, 0.0, 1.0])

#: joint table, the gap of b, b's free motions relative to a (rigid_field arguments, small
#: rigid motions of b about points on its line), a forbidden one
JOINTS = {
    "prismatic": (PRISMATIC, 0.1, [{"translation": ALONG}], {"rotation": ALONG, "about": TIP}),
    "cylindrical": (CYLINDRICAL, 0.1, [{"translation": ALONG},
                                       {"rotation": ALONG, "about": TIP}],
                    {"rotation": Z, "about": TIP}),
    "universal": (UNIVERSAL, 0.0, [{"rotation": Z, "about": TIP},
                                   {"rotation": CROSS, "about": TIP}],
                  {"rotation": ALONG, "about": TIP}),
}


def _model(name: str, extra: str = "") -> Model:
    """The beams joined by the joint ``name``, after the tables ``extra``."""
    table, gap, _, _ = JOINTS[name]
    return Model(scene_of(f"{_beams(gap)}{extra}[[constraint]]\n{table}"))


def _rows(model: Model, q: np.ndarray) -> np.ndarray:
    """The joint's rows at q: the linear ones (A q - b) and the quadratic ones."""
    return np.concatenate([model.joints @ q - model.joint_offsets,
                           model.holonomic.value(q)])


def _jacobian(model: Model) -> np.ndarray:
    return np.vstack([model.joints.toarray(),
                      model.holonomic.jacobian(model.reference).toarray()])


def _moved(model: Model, rotation: Rotation, about: np.ndarray, translation: np.ndarray,
           bodies: tuple[str, ...] = ("a", "b")) -> np.ndarray:
    """The reference with the ``bodies`` turned by the finite ``rotation`` about the point
    ``about`` and moved by ``translation`` (m): positions and gradients."""
    q = model.reference.copy()
    matrix = rotation.as_matrix()
    for name in bodies:
        mesh = model.bodies[name]
        vectors = mesh.reference.reshape(mesh.nodes, len(mesh.kind.vectors), 3) @ matrix.T
        r = mesh.kind.vectors.index("r")
        vectors[:, r] += about - matrix @ about + translation
        q[mesh.coordinates] = vectors.ravel()
    return q


def test_the_rows_count_as_the_docs_say():
    assert [_rows(_model(name), _model(name).reference).size for name in JOINTS] == [5, 4, 4]


@pytest.mark.parametrize("name", JOINTS)
def test_rows_vanish_at_the_reference_and_match_finite_differences(name):
    model = _model(name)
    assert np.abs(_rows(model, model.reference)).max() <= 1e-15
    blocks = model.holonomic.blocks
    assert blocks
    rng = np.random.default_rng(5)
    for block in blocks:
        _finite_difference_check(block, rng)


@pytest.mark.parametrize("name", JOINTS)
def test_the_rows_leave_exactly_the_joints_small_relative_motion(name):
    """In the 12 small rigid motions of the two beams apart, the rows' null space is the
    6 common motions and the joint's free relative motions, no more."""
    _, _, free, _ = JOINTS[name]
    model = _model(name)
    jacobian = _jacobian(model)
    for motion in free:
        assert np.abs(jacobian @ model.rigid_field(**motion, body="b")).max() <= 1e-14
    motions = np.array([model.rigid_field(**{what: e}, body=body) for body in ("a", "b")
                        for what in ("translation", "rotation") for e in np.eye(3)]).T
    rank = np.linalg.matrix_rank(jacobian @ motions, tol=1e-10)
    assert 12 - rank == 6 + len(free)


@pytest.mark.parametrize("name", JOINTS)
def test_finite_rigid_and_free_motions_keep_the_rows_zero_a_forbidden_one_not(name):
    _, _, free, forbidden = JOINTS[name]
    model = _model(name)
    rng = np.random.default_rng(8)
    for _ in range(3):       # the pair turned and moved as a whole
        turn = Rotation.from_rotvec(rng.normal(size=3))
        q = _moved(model, turn, rng.normal(size=3), rng.normal(size=3))
        assert np.abs(_rows(model, q)).max() <= 1e-14
    for motion in free:      # b alone, a finite slide or turn
        if "translation" in motion:
            q = _moved(model, Rotation.identity(), TIP, 0.3 * motion["translation"], ("b",))
        else:
            q = _moved(model, Rotation.from_rotvec(1.2 * motion["rotation"]),
                       motion["about"], np.zeros(3), ("b",))
        assert np.abs(_rows(model, q)).max() <= 1e-14
    q = _moved(model, Rotation.from_rotvec(0.3 * forbidden["rotation"]), forbidden["about"],
               np.zeros(3), ("b",))
    assert np.abs(_rows(model, q)).max() > 1e-2
    q = _moved(model, Rotation.identity(), TIP, 0.01 * Z, ("b",))     # a slide across
    assert np.abs(_rows(model, q)).max() >= 0.01 - 1e-15


#: beam a clamped at its start, gravity along the axis, a short run
SLIDE = f"""
[[constraint]]
type = "clamp"
node = "a:0"
[[load]]
type = "gravity"
acceleration = [{float(6.0 * ALONG[0])!r}, {float(6.0 * ALONG[1])!r}, 0.0]
[analysis.dynamic]
t_end = 0.05
step = 1e-3
"""


@pytest.mark.parametrize("integrator", ["trapezoidal", "generalized_alpha"])
def test_a_prismatic_slide_under_gravity_along_its_axis_follows_g_t2_over_2(integrator):
    """b slides freely: its nodes move as a rigid body by g t^2 / 2 along the axis (the
    clamped a only stretches along it, which leaves its line in place)."""
    model = _model("prismatic", SLIDE)
    times, q, _, _ = run(model.scene, "compiled", integrator=integrator)
    b = model.bodies["b"]
    positions = q[:, b.coordinates].reshape(len(times), b.nodes, len(b.kind.vectors), 3)
    reference = b.reference.reshape(b.nodes, len(b.kind.vectors), 3)
    slide = reference[None, :, 0] + 3.0 * times[:, None, None] ** 2 * ALONG
    assert np.abs(positions[:, :, 0] - slide).max() <= 1e-11
    assert np.abs(positions[:, :, 1:] - reference[None, :, 1:]).max() <= 1e-11
    assert 3.0 * times[-1] ** 2 > 7e-3                                  # 7.5 mm


def test_a_free_prismatic_slide_carries_no_force():
    """The joint's reaction on b (its multipliers) is zero to the Newton tolerance (1e-10
    of the forces): below 1e-9 of the force of gravity on b (generalized-alpha; the
    trapezoidal rule's multipliers wander, to 2e-8 of it here)."""
    sensors = "".join(f'[[sensor]]\ntype = "reaction"\nname = "{quantity}"\nnode = "b:0"\n'
                      f'quantity = "{quantity}"\n' for quantity in ("force", "moment"))
    scene = _model("prismatic", SLIDE + sensors).scene
    result = run_scene(dataclasses.replace(scene, dynamic=dataclasses.replace(
        scene.dynamic, integrator="generalized_alpha")), progress=False)
    weight = 7800.0 * 0.02**2 * 0.6 * 6.0                                # N, along the axis
    assert np.abs(result.sensors["force"]).max() <= 1e-9 * weight
    assert np.abs(result.sensors["moment"]).max() <= 1e-9 * weight * 0.6


#: a's both ends clamped (its tip: b's slide on the ground), b driven along the axis
DRIVEN = """
[[constraint]]
type = "clamp"
node = "a:0"
[[constraint]]
type = "clamp"
node = "a:-1"
[analysis.dynamic]
t_end = 0.05
step = 1e-3
"""
LAW = 'displacement = {type = "cosine_ramp", duration = 0.04, value = 0.02}\n'


def test_a_driven_prismatic_slide_follows_its_law_in_both_engines():
    """With a displacement law d(t) = 0.01 (1 - cos(pi t / 0.04)) (m, then 0.02 m), b's
    first node moves by d(t) along the axis and not across it (to the Newton tolerance),
    its frame does not turn, and the engines agree."""
    model = Model(scene_of(f"{_beams(0.1)}{DRIVEN}[[constraint]]\n{PRISMATIC}{LAW}"))
    node = model.node_index(NodeRef("b", 0))
    root = model.node_dofs(node, "r")
    runs = [run(model.scene, engine) for engine in ("python", "compiled")]
    for times, q, _, _ in runs:
        travel = 0.01 * (1.0 - np.cos(np.pi * np.minimum(times, 0.04) / 0.04))
        assert np.abs(q[:, root] - model.reference[root] - travel[:, None] * ALONG).max() \
            <= 1e-12
        assert travel[-1] == pytest.approx(0.02)
        frame = np.array([model.node_frame(x, node) for x in q])
        assert np.abs(frame - frame[0]).max() <= 1e-12
    assert np.abs(runs[0][1] - runs[1][1]).max() <= 1e-10


#: a beam clamped at its start, under gravity across the axis, for a short run
DYNAMIC = """
[[constraint]]
type = "clamp"
node = "a:0"
[[load]]
type = "gravity"
acceleration = [0, 3.0, -9.81]
[analysis.dynamic]
t_end = 0.01
step = 1e-3
"""


@pytest.mark.parametrize("name", JOINTS)
def test_engines_agree_on_the_node_joints(name):
    model = _model(name, DYNAMIC)
    python = run(model.scene, "python")
    compiled = run(model.scene, "compiled")
    b = model.bodies["b"].coordinates
    assert np.ptp(python[1][:, b], axis=0).max() > 1e-5                 # b moves
    assert np.abs(python[1] - compiled[1]).max() <= 1e-10
    assert np.abs(python[2] - compiled[2]).max() <= 1e-8


#: a hub (the first node of a short beam, turned by a spin-up law about ``axis``) and a
#: beam b near it; or the hub as a rigid carrier turned by a driven revolute joint (the
#: hub node's frame at t = 0: the global axes)
HUB = """
[material.steel]
E = 2.1e11
nu = 0.0
rho = 7800.0
[[body]]
name = "b"
element = "beam3d"
material = "steel"
section = {{height = 0.02, width = 0.02}}
elements = 2
start = [{start}, 0, 0]
end = [{end}, 0, 0]
[[load]]
type = "gravity"
acceleration = [0, 0, -9.81]
[analysis.dynamic]
t_end = 0.05
step = 1e-3
"""
ON_HUB = """
[[body]]
name = "hub"
element = "beam3d"
material = "steel"
section = {{height = 0.02, width = 0.02}}
elements = 1
start = [0, 0, 0]
end = [0.1, 0, 0]
[[constraint]]
type = "prescribed_rotation"
node = "hub:0"
axis = {axis}
angle = {{type = "spin_up", omega = 20.0, t_ramp = 0.05}}
"""
ON_CARRIER = """
[[body]]
type = "rigid"
name = "carrier"
mass = 1.0
inertia = [0.1, 0.1, 0.1]
[[constraint]]
type = "body_revolute"
body = "carrier"
axis = {axis}
angle = {{type = "spin_up", omega = 20.0, t_ramp = 0.05}}
"""

#: (b's start and end, the hub's axis, the node joint, the carrier's joint)
HUB_JOINTS = {
    "prismatic": ((0.2, 0.8), [0, 0, 1],
                  'type = "prismatic"\nnodes = ["b:0", "hub:0"]\naxis = [1, 0, 0]\n',
                  'type = "body_prismatic"\nbody = "carrier"\nnode = "b:0"\naxis = [1, 0, 0]\n'),
    "cylindrical": ((0.2, 0.8), [0, 0, 1],
                    'type = "cylindrical"\nnodes = ["hub:0", "b:0"]\naxis = [1, 0, 0]\n',
                    'type = "body_cylindrical"\nbody = "carrier"\nnode = "b:0"\n'
                    'axis = [1, 0, 0]\n'),
    "universal": ((0.0, 0.6), [1, 0, 0],
                  'type = "universal"\nnodes = ["hub:0", "b:0"]\naxis = [0, 0, 1]\n'
                  'other_axis = [0, 1, 0]\n',
                  'type = "body_universal"\nbody = "carrier"\nnode = "b:0"\n'
                  'axis = [0, 0, 1]\nother_axis = [0, 1, 0]\n'),
}


@pytest.mark.parametrize("name", HUB_JOINTS)
def test_a_joint_on_a_hub_node_equals_the_rigid_body_joint_on_a_turned_carrier(name):
    """The frame of a node that a hub turns is a rigid frame: b moves as when joined by
    the joint of a rigid body to a carrier at the hub, with the hub node's frame at t = 0,
    turned by the same law (the rows are the same functions of b's coordinates), to
    round-off with generalized-alpha."""
    (start, end), axis, node_joint, body_joint = HUB_JOINTS[name]
    base = HUB.format(start=start, end=end)
    on_hub = scene_of(f"{base}{ON_HUB.format(axis=axis)}[[constraint]]\n{node_joint}")
    on_carrier = scene_of(f"{base}{ON_CARRIER.format(axis=axis)}[[constraint]]\n{body_joint}")
    hub = run(on_hub, "compiled", integrator="generalized_alpha")
    carrier = run(on_carrier, "compiled", integrator="generalized_alpha")
    b_hub = Model(on_hub).bodies["b"].coordinates
    b_carrier = Model(on_carrier).bodies["b"].coordinates
    assert np.ptp(hub[1][:, b_hub], axis=0).max() > 1e-3               # b moves
    assert np.abs(hub[1][:, b_hub] - carrier[1][:, b_carrier]).max() <= 1e-9
    assert np.abs(hub[2][:, b_hub] - carrier[2][:, b_carrier]).max() <= 1e-7


def test_a_prismatic_joint_between_beam2d_nodes_holds_the_slide_and_the_angle():
    """In 2D: one row across the axis and one on the relative angle."""
    text = _beams(0.1, "beam2d", "beam2d").replace(", 0]", "]")
    model = Model(scene_of(f'{text}[[constraint]]\ntype = "prismatic"\n'
                           'nodes = ["a:-1", "b:0"]\naxis = [0.6, 0.8]\n'))
    assert np.abs(_rows(model, model.reference)).max() <= 1e-15
    jacobian = _jacobian(model)
    assert jacobian.shape[0] == 2
    _finite_difference_check(model.holonomic.blocks[0], np.random.default_rng(3))
    motions = np.array([model.rigid_field(translation=e, body=body) for body in ("a", "b")
                        for e in np.eye(2)]
                       + [model.rigid_field(rotation=1.0, about=TIP[:2], body=body)
                          for body in ("a", "b")]).T
    assert np.abs(jacobian @ model.rigid_field(translation=ALONG[:2], body="b")).max() \
        <= 1e-14
    assert 6 - np.linalg.matrix_rank(jacobian @ motions, tol=1e-10) == 3 + 1


@pytest.mark.parametrize(("text", "message"), [
    (_beams(0.1, "cable3d") + f"[[constraint]]\n{PRISMATIC}",
     "constraint[0].nodes[1]: a prismatic joint holds the node's frame, which needs its three "
     'gradients r_x, r_y, r_z (a beam3d or plate3d node); node "b:0" of body "b" (cable3d)'),
    (_beams(0.1, "cable3d") + f"[[constraint]]\n{CYLINDRICAL}",
     "constraint[0].nodes[1]: a cylindrical joint's line and the normals of its axis turn "
     "with the node's frame"),
    (_beams(0.1) + f"[[constraint]]\n{PRISMATIC.replace('0.6, 0.8, 0.0', '0.8, 0.6, 0.0')}",
     'constraint[0].nodes: the second node must lie on the axis through the first at t = 0'),
    (_beams(0.0) + f"[[constraint]]\n{UNIVERSAL.replace('-0.8, 0.6', '0.6, 0.8')}".replace(
        "axis = [0, 0, 1]", "axis = [0, 0.6, 0.8]"),
     "constraint[0].other_axis: expected an axis normal to axis at t = 0 (the cross of the "
     "joint), got an angle of 61.3"),
    (_beams(0.1) + f"[[constraint]]\n{UNIVERSAL}",
     "constraint[0].nodes: the nodes of a joint share their position"),
    (_beams(0.1) + f"[[constraint]]\n{PRISMATIC}[[constraint]]\n{CYLINDRICAL}",
     "constraint[1].nodes: the same joint as constraint[0] (nodes a:2 and b:0)"),
])
def test_bad_node_joints_are_scene_errors_naming_the_key(text, message):
    with pytest.raises(SceneError) as error:
        scene_of(text)
    assert str(error.value).startswith(message), str(error.value)


@pytest.mark.parametrize(("table", "message"), [
    (CYLINDRICAL.replace('"a:-1", "b:0"', '"b:0", "a:-1"').replace("0.6, 0.8, 0.0", "0, 0, 1"),
     "constraint[0]: cylindrical: axis (0.0, 0.0, 1.0) is not a combination of the "
     "gradients r_x of the node"),
    (UNIVERSAL, "constraint[0]: universal: other_axis (-0.8, 0.6, 0.0) is not a "
                "combination of the gradients r_x of the node"),
])
def test_an_axis_out_of_a_cable_nodes_span_fails_when_the_model_is_built(table, message):
    """b is a cable (at a's tip): its r_x spans its tangent only (known with the model)."""
    scene = scene_of(f"{_beams(0.0, 'cable3d')}[[constraint]]\n{table}")
    with pytest.raises(SceneError) as error:
        Model(scene)
    assert str(error.value).startswith(message), str(error.value)


@pytest.mark.parametrize("name", [*JOINTS, "driven prismatic"])
def test_node_joints_round_trip_through_toml(name):
    table, gap, _, _ = JOINTS[name.split()[-1]]
    scene = scene_of(f"{_beams(gap)}[[constraint]]\n{table}{LAW if 'driven' in name else ''}")
    assert parse_scene(tomllib.loads(scene.to_toml())) == scene


@pytest.mark.parametrize("name", JOINTS)
def test_the_modes_of_the_pair_show_the_joints_free_motions_at_zero_frequency(name):
    """a clamped at its start, b on the joint, unloaded: one zero frequency per free
    relative motion (the slide, the turn about the axis, the pins), then b's elastic
    modes."""
    _, _, free, _ = JOINTS[name]
    model = _model(name, '[[constraint]]\ntype = "clamp"\nnode = "a:0"\n')
    omega = modal(model, model.reference, len(free) + 1)
    # zero to the round-off of the eigenvalues, sqrt(eps lambda_max) ~ 1e-2 rad/s here
    assert np.abs(omega[:len(free)]).max() <= 1e-3 * omega[len(free)]
    assert omega[len(free)] > 70.0                                       # rad/s
