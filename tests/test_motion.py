"""Initial conditions and rigid motions: initial velocities are the rigid velocity field of
each body (translation and spin about a point); a free spinning beam (scenes/
spinning_beam.toml) conserves energy and angular momentum to the second order of both
integrators; ``Model.free_motions`` names the rigid motions the constraints leave free, which
are exactly the null space of the constrained stiffness at the reference."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import scipy.linalg
from scenes_small import STEEL, body, scene, simulate

import scenes
from runtime import (
    Clamp,
    Dynamic,
    Hub,
    Pin,
    Spherical,
    Spin,
    SpinUp,
    Weld,
    load_scene,
)
from runtime.model.model import Model


def angular_momentum(model: Model, q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """int rho r x v dV about the origin (kg m^2/s): sum m_kl q_k x v_l with m the scalar
    mass matrix of the nodal vectors (M = m (x) I)."""
    mass = model.mass[0::model.dim, 0::model.dim]
    nodal_q, nodal_v = q.reshape(-1, model.dim), v.reshape(-1, model.dim)
    return np.cross(nodal_q, mass @ nodal_v).sum(axis=0)


def test_initial_velocities_are_the_rigid_field_of_each_body():
    model = Model(load_scene(scenes.path("spinning_beam")))
    velocity = model.initial_velocities()
    omega, shift = np.array([2.0, 3.0, 6.0]), np.array([1.0, 0.0, 0.0])
    for node in range(model.n_nodes):
        r = model.reference[model.node_dofs(node, "r")]
        assert np.allclose(velocity[model.node_dofs(node, "r")], shift + np.cross(omega, r))
        for name in ("r_x", "r_y", "r_z"):
            gradient = model.reference[model.node_dofs(node, name)]
            assert np.allclose(velocity[model.node_dofs(node, name)],
                               np.cross(omega, gradient))
    # rigid-body values: m = rho A L, I about the centre (rod of square section h)
    length, h = 1.0, 0.02
    mass = STEEL.rho * h * h * length
    inertia = np.diag([mass * 2 * h * h / 12] + [mass * (length**2 + h**2) / 12] * 2)
    kinetic = 0.5 * mass * shift @ shift + 0.5 * omega @ inertia @ omega
    assert model.kinetic_energy(velocity) == pytest.approx(kinetic, rel=1e-12)
    assert angular_momentum(model, model.reference, velocity) == pytest.approx(
        inertia @ omega, rel=1e-12)


def test_initial_velocities_in_2d_spin_about_a_point_and_spare_held_coordinates():
    bodies = [dataclasses.replace(body("a", elements=2), initial_velocity=(0.5, -1.0)),
              dataclasses.replace(body("b", elements=2, start=(1.0, 0.0), end=(2.0, 0.0)),
                                  initial_angular_velocity=Spin(3.0, (1.0, 0.0)))]
    model = Model(scene(bodies, [Pin("a:0"), Hub("b:-1", SpinUp(1.0, 1.0))]))
    velocity = model.initial_velocities()
    assert np.all(velocity[model.fixed] == 0) and np.all(velocity[model.prescribed] == 0)
    node = model.node_index(model.scene.constraints[0].node) + 1          # a:1
    assert np.allclose(velocity[model.node_dofs(node, "r")], (0.5, -1.0))
    assert np.allclose(velocity[model.node_dofs(node, "r_x")], 0.0)
    b1 = model.bodies["b"].first_node + 1                                  # at x = 1.5
    assert np.allclose(velocity[model.node_dofs(b1, "r")], (0.0, 1.5))
    assert np.allclose(velocity[model.node_dofs(b1, "r_x")], (0.0, 3.0))
    assert np.allclose(velocity[model.node_dofs(b1, "r_y")], (-3.0, 0.0))


@pytest.fixture(scope="module")
def spinning() -> dict:
    """(integrator, step) -> (relative energy drift, relative angular momentum drift) over
    the 0.5 s of the spinning beam."""
    base = load_scene(scenes.path("spinning_beam"))
    drifts = {}
    for integrator in ("trapezoidal", "generalized_alpha"):
        for step in (1e-3, 5e-4):
            dynamic = dataclasses.replace(base.dynamic, step=step, integrator=integrator)
            run = simulate(dataclasses.replace(base, dynamic=dynamic), keep_states=True)
            model = run.model
            energy = run["total_energy"]
            momentum = np.array([angular_momentum(model, q, v) for _, q, v in run.states])
            assert np.allclose(run.states[0][2], model.initial_velocities(), rtol=0,
                               atol=1e-12)
            drifts[integrator, step] = (
                np.abs(energy - energy[0]).max() / energy[0],
                np.linalg.norm(momentum - momentum[0], axis=1).max()
                / np.linalg.norm(momentum[0]))
            assert run["strain_energy"].max() > 1e-7 * energy[0]   # it does deform
    return drifts


@pytest.mark.parametrize("integrator", ["trapezoidal", "generalized_alpha"])
def test_spinning_free_beam_conserves_energy_and_angular_momentum(spinning, integrator):
    coarse, fine = spinning[integrator, 1e-3], spinning[integrator, 5e-4]
    for k in range(2):   # energy, angular momentum
        # second order: halving the step divides the drift by ~4 (measured 4.0 and 4.9)
        assert fine[k] < coarse[k] / 3.5
        assert fine[k] < 1e-5


def _nullity_of_constrained_stiffness(model: Model) -> int:
    """Dimension of {u : K u = 0, A u = 0} over the free coordinates at the reference."""
    _, data = model.internal_forces(model.reference)
    stiffness = model.jacobian_matrix(data).toarray()
    joints = model.joints_free.toarray()
    basis = scipy.linalg.null_space(joints) if joints.size else np.eye(model.free.size)
    reduced = basis.T @ stiffness @ basis
    values = np.abs(np.linalg.eigvalsh(0.5 * (reduced + reduced.T)))
    return int(np.sum(values < 1e-9 * values.max()))


Z = (0.0,)


@pytest.mark.parametrize("bodies, constraints, expected, nullity", [
    ([body()], [], ["body 'beam' is free to translate along x and y and to rotate about z"], 3),
    ([body()], [Pin("beam:0")], ["body 'beam' is free to rotate about z"], 1),
    ([body()], [Clamp("beam:0")], [], 0),
    ([body(element="beam3d", start=(0, 0, 0), end=(1, 0, 0))], [],
     ["body 'beam' is free to translate along x, y and z and to rotate about x, y and z"], 6),
    ([body(element="beam3d", start=(0, 0, 0), end=(1, 1, 0))], [Pin("beam:0"), Pin("beam:-1")],
     ["body 'beam' is free to rotate about (0.707, 0.707, 0)"], 1),
    ([body("a", element="beam3d", start=(0, 0, 0), end=(1, 0, 0)),
      body("b", element="beam3d", start=(1, 0, 0), end=(1, 1, 0))],
     [Pin("a:0"), Spherical(("a:-1", "b:0"))],
     # b translates (without turning) as a swings about the pin
     ["body 'a' is free to rotate about x, y and z",
      "body 'b' is free to translate along y and z and to rotate about x, y and z"], 6),
    ([body("a"), body("b", start=(1.0, 0.0), end=(1.0, 1.0))], [Weld(("a:-1", "b:0"))],
     ["body 'a' is free to translate along x and y and to rotate about z",
      "body 'b' is free to translate along x and y and to rotate about z"], 3),
    ([body("a"), body("b", start=(1.0, 0.0), end=(1.0, 1.0))],
     [Clamp("a:0"), Weld(("a:-1", "b:0"))], [], 0),
    ([body()], [Hub("beam:0", SpinUp(1.0, 1.0))], [], 0),
    # a 3D cable's spin about its own axis moves none of its coordinates (r, r_x): never a
    # free motion, at any inclination (a clamped diagonal cable was "free to rotate about
    # (0.707, 0.707, 0)", a pinned one along x "about (nan, nan, nan)")
    ([body(element="cable3d", start=(0, 0, 0), end=(1, 1, 0))], [Clamp("beam:0")], [], 0),
    ([body(element="cable3d", start=(0, 0, 0), end=(1, 0, 0))], [Pin("beam:0")],
     ["body 'beam' is free to rotate about y and z"], 2),
    ([body(element="cable3d", start=(0, 0, 0), end=(1, 1, 0))], [Pin("beam:0")],
     ["body 'beam' is free to rotate about (0, 0, 1) and (0.707, -0.707, 0)"], 2),
    ([body(element="cable3d", start=(0, 0, 0), end=(0, 1, 1))], [],
     ["body 'beam' is free to translate along x, y and z and to rotate about "
      "(0, 0.707, -0.707) and (1, 0, 0)"], 5),
])
def test_free_motions_name_the_null_space_of_the_constrained_stiffness(
        bodies, constraints, expected, nullity):
    model = Model(scene(bodies, constraints, dynamic=Dynamic(t_end=0.1, step=0.1)))
    assert model.free_motions() == expected
    assert _nullity_of_constrained_stiffness(model) == nullity


def test_static_analysis_of_a_free_body_names_the_body_and_motion(tmp_path):
    """Issue 10: an unrestrained body in static analysis was "Newton did not converge"
    without a cause; now it is an invalid scene (exit 2) naming the body and its motions."""
    from runtime.app.run import run
    from runtime.model.scene import parse_scene

    data = {"material": {"m": {"E": 2.1e11, "nu": 0.0, "rho": 7800.0}},
            "body": [{"name": "rod", "element": "beam2d", "material": "m", "elements": 2,
                      "section": {"height": 0.1, "width": 0.1}, "start": [0.0, 0.0],
                      "end": [1.0, 0.0]}],
            "load": [{"type": "point_force", "node": "rod:-1", "force": [0.0, -1.0]}],
            "analysis": {"static": {}}}
    summary, code = run(parse_scene(data), tmp_path / "out", quiet=True)
    assert code == 2 and summary["status"] == "failed"
    assert "body 'rod' is free to translate along x and y and to rotate about z" in \
        summary["message"]
    assert summary["message"].startswith("analysis.static:")
