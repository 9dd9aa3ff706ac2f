"""Python load functions: a callable time law against the built-in one it spells, a Python
load against the built-in load it spells (static and dynamic), a PD-controlled arm against
the closed-form response of the rigid arm, finite-difference Jacobians against exact ones,
both engines on a controller with velocity feedback, and the errors (bad module path,
missing function, wrong shape, NaN) each naming its scene key."""

from __future__ import annotations

import math
import subprocess
import sys
import textwrap

import numpy as np
import pytest
from scenes_small import scene

from runtime import (
    Body,
    Clamp,
    CosineRamp,
    Displacement,
    Dynamic,
    Material,
    Pin,
    PointForce,
    PointMoment,
    PythonLoad,
    SceneError,
    Static,
    load_scene,
    run_scene,
)
from runtime.model.dae import StateLoads
from runtime.model.model import Model

E, RHO, LENGTH, H = 2.1e11, 7800.0, 1.0, 0.05
STEEL = Material("m", E=E, nu=0.0, rho=RHO)
# node 0 of a beam2d arm: r (0, 1), r_x (2, 3), r_y (4, 5)
RY = slice(4, 6)


def _arm(elements: int = 4) -> Body:
    return Body("arm", "beam2d", "m", H, H, elements, (0.0, 0.0), (LENGTH, 0.0))


def _arm_scene(loads, **kwargs):
    return scene([_arm()], [Pin("arm:0")], loads,
                 [Displacement("tip_x", "arm:-1", component="x"),
                  Displacement("tip_y", "arm:-1", component="y")],
                 material=STEEL, **kwargs)


def _moment_on_hub(q: np.ndarray, moment: float) -> np.ndarray:
    """Generalised force (size,) of a moment about z on the hub's section: the virtual work
    M d theta with theta the angle of r_y, d theta = (r_y x d r_y) / |r_y|^2."""
    force = np.zeros(q.size)
    ry = q[RY]
    force[RY] = moment * np.array([-ry[1], ry[0]]) / (ry @ ry)
    return force


def _cosine(t: np.ndarray, duration: float = 0.01) -> np.ndarray:
    """The cosine ramp of eq. 42 (value 1), written out."""
    inside = 0.5 * (1.0 - np.cos(math.pi * np.minimum(t, duration) / duration))
    return np.where(t <= 0.0, 0.0, inside)


def test_callable_time_law_equals_the_cosine_ramp():
    runs = [run_scene(scene([_arm()], [Pin("arm:0")],
                            [PointForce("arm:-1", (0.0, -2e4), time_law=law)],
                            [Displacement("tip_y", "arm:-1", component="y")], material=STEEL,
                            dynamic=Dynamic(t_end=0.02, step=1e-3)), progress=False)
            for law in (CosineRamp(0.01), _cosine)]
    builtin, python = (run.sensors["tip_y"] for run in runs)
    assert np.abs(builtin).max() > 1e-4
    np.testing.assert_allclose(python, builtin, rtol=0, atol=1e-15)


def _pd(gain: float, rate_gain: float, target: float):
    """A PD torque on the hub's section angle theta (angle of r_y) toward ``target``."""
    def torque(t, q, v):
        ry, ry_dot = q[RY], v[RY]
        theta = math.atan2(-ry[0], ry[1])
        rate = (ry[0] * ry_dot[1] - ry[1] * ry_dot[0]) / (ry @ ry)
        return _moment_on_hub(q, gain * (target - theta) - rate_gain * rate)
    return torque


def _rigid_angle(t, gain, rate_gain, inertia, target):
    """Closed form of J theta'' + D theta' + K theta = K target from rest (underdamped)."""
    omega, zeta = math.sqrt(gain / inertia), rate_gain / (2 * math.sqrt(gain * inertia))
    damped = omega * math.sqrt(1 - zeta**2)
    return target * (1 - np.exp(-zeta * omega * t) * (np.cos(damped * t) + zeta * omega
                                                     / damped * np.sin(damped * t)))


def test_pd_controller_turns_a_stiff_arm_as_the_rigid_closed_form():
    """A steel arm pinned at its hub, turned 0.5 rad by a PD torque (closed loop 1 Hz,
    damping ratio 0.7; first bending mode about 40 Hz): the tip's angle follows the rigid
    rod's closed form, J = m (L^2 / 3 + h^2 / 12), finite rotation included."""
    mass = RHO * H * H * LENGTH
    inertia = mass * (LENGTH**2 / 3 + H**2 / 12)
    omega, zeta, target = 2 * math.pi, 0.7, 0.5
    gain, rate_gain = inertia * omega**2, 2 * zeta * omega * inertia
    data = _arm_scene([PythonLoad(_pd(gain, rate_gain, target), nodes=["arm:0"])],
                      dynamic=Dynamic(t_end=0.5, step=2e-3, output_every=0.01))
    result = run_scene(data, progress=False)
    t = result.sensors["t"]
    angle = np.arctan2(result.sensors["tip_y"], LENGTH + result.sensors["tip_x"])
    assert angle.max() > 0.4
    np.testing.assert_allclose(angle, _rigid_angle(t, gain, rate_gain, inertia, target),
                               rtol=0, atol=2e-3)


def test_python_load_equals_the_builtin_moment_static_and_dynamic():
    """A hub moment written as a Python function of the reference section (the fixed
    point_moment's generalised force) times a cosine ramp gives the built-in's results."""
    moment = 500.0

    def fixed(t, q, v):
        return _moment_on_hub(np.r_[np.zeros(4), 0.0, 1.0, np.zeros(q.size - 6)],
                              moment * float(_cosine(np.array([t]))[0]))

    ramp = CosineRamp(0.01)
    clamped = [PointForce("arm:-1", (0.0, -1e4))]
    runs = [run_scene(_arm_scene([load, *clamped], dynamic=Dynamic(t_end=0.02, step=1e-3)),
                      progress=False)
            for load in (PointMoment("arm:0", moment, time_law=ramp),
                         PythonLoad(fixed, nodes=["arm:0"]))]
    for name in ("tip_x", "tip_y"):
        builtin, python = (run.sensors[name] for run in runs)
        assert np.abs(builtin).max() > 1e-5
        np.testing.assert_allclose(python, builtin, rtol=0, atol=1e-13)
    # static: a clamped cantilever under a tip force, built-in and as a Python load
    statics = [run_scene(scene([_arm()], [Clamp("arm:0")], [load],
                               [Displacement("tip_y", "arm:-1", component="y")],
                               material=STEEL, static=Static()),
                         progress=False).summary["static"]["sensors"]["tip_y"]
               for load in (PointForce("arm:-1", (0.0, -2e3)),
                            PythonLoad(lambda t, q, v: _tip_force(q, -2e3), nodes=["arm:-1"]))]
    assert statics[1] == pytest.approx(statics[0], rel=1e-12)
    assert statics[0] < -1e-3


def _tip_force(q: np.ndarray, fy: float) -> np.ndarray:
    force = np.zeros(q.size)
    force[-5] = fy         # r_y component of the last node's position: (-6, -5)
    return force


def _spring_damper(t, q, v):
    """A nonlinear spring-damper on the hub section's r_y with a feedback of its rate."""
    force = np.zeros(q.size)
    ry, ry_dot = q[RY], v[RY]
    force[RY] = -3e3 * (ry - [0.0, 1.0]) * (ry @ ry) - 40.0 * ry_dot * (1 + ry[0] ** 2) \
        + 7.0 * math.sin(t)
    return force


def _spring_damper_jacobian(t, q, v):
    size = q.size
    d_q, d_v = np.zeros((size, size)), np.zeros((size, size))
    ry, ry_dot = q[RY], v[RY]
    d_q[RY, RY] = -3e3 * ((ry @ ry) * np.eye(2) + 2 * np.outer(ry - [0.0, 1.0], ry))
    d_q[RY, 4] += -40.0 * ry_dot * 2 * ry[0]
    d_v[RY, RY] = -40.0 * (1 + ry[0] ** 2) * np.eye(2)
    return d_q, d_v


def test_finite_difference_jacobians_match_the_exact_ones():
    exact = Model(_arm_scene([PythonLoad(_spring_damper, _spring_damper_jacobian,
                                         nodes=["arm:0"])], static=Static()))
    differenced = Model(_arm_scene([PythonLoad(_spring_damper, nodes=["arm:0"])],
                                   static=Static()))
    rng = np.random.default_rng(3)
    q = exact.reference + 0.05 * rng.standard_normal(exact.size)
    v = rng.standard_normal(exact.size)
    (f1, dq1, dv1), (f2, dq2, dv2) = (StateLoads(m).evaluate(q, np.ones(1), True, v, 0.3)
                                      for m in (exact, differenced))
    np.testing.assert_array_equal(f1, f2)
    assert np.abs(dq1).max() > 1e3 and np.abs(dv1).max() > 10
    np.testing.assert_allclose(dq2, dq1, rtol=0, atol=1e-7 * np.abs(dq1).max())
    np.testing.assert_allclose(dv2, dv1, rtol=0, atol=1e-7 * np.abs(dv1).max())


def test_both_engines_agree_on_a_velocity_feedback_controller():
    """Finite-difference Jacobians (d/dv in the damping part of the Newton matrix) in both
    engines, generalized-alpha."""
    data = _arm_scene([PythonLoad(_spring_damper, nodes=["arm:0"]),
                       PointForce("arm:-1", (0.0, -3e4))],
                      dynamic=Dynamic(t_end=0.02, step=1e-3, integrator="generalized_alpha"))
    runs = [run_scene(data, engine=engine, progress=False) for engine in ("python", "compiled")]
    for name in ("tip_x", "tip_y"):
        python, compiled = (run.sensors[name] for run in runs)
        assert np.abs(python).max() > 1e-4
        np.testing.assert_allclose(compiled, python, rtol=0, atol=1e-12)
    iterations = [run.summary["dynamic"]["newton_iterations"] for run in runs]
    assert iterations[0] == iterations[1]


def _toml(tmp_path, law: str = "", load: str = "") -> str:
    text = f"""
        [material.m]
        E = 2.1e11
        nu = 0.0
        rho = 7800.0
        [[body]]
        name = "arm"
        element = "beam2d"
        material = "m"
        section = {{ height = 0.05, width = 0.05 }}
        elements = 2
        start = [0.0, 0.0]
        end = [1.0, 0.0]
        [[constraint]]
        type = "pin"
        node = "arm:0"
        [[load]]
        type = "point_force"
        node = "arm:-1"
        force = [0.0, -100.0]
        {law}
        {load}
        [analysis.dynamic]
        t_end = 0.004
        step = 0.001
    """
    path = tmp_path / "scene.toml"
    path.write_text(textwrap.dedent(text))
    return str(path)


FUNCTIONS = """
import numpy as np

def ramp(t):
    return np.minimum(t / 0.002, 1.0)

def short(t):
    return t[:1]

def nan(t):
    return np.where(t > 0.5, np.nan, t)

def hub(t, q, v):
    f = np.zeros(q.size)
    f[4] = -50.0 * np.tanh(t / 0.001)
    return f

def wrong(t, q, v):
    return np.zeros(3)

def late_nan(t, q, v):
    f = np.zeros(q.size)
    f[4] = np.nan if t > 0.002 else 0.0
    return f
"""


def test_functions_are_imported_from_the_scene_folder(tmp_path):
    (tmp_path / "pyloads_functions.py").write_text(FUNCTIONS)
    path = _toml(tmp_path, 'time_law = { type = "python", function = "pyloads_functions:ramp" }',
                 '[[load]]\ntype = "python"\nfunction = "pyloads_functions:hub"\n'
                 'nodes = ["arm:0"]')
    data = load_scene(path)
    assert data.loads[0].time_law.value(0.001) == pytest.approx(0.5)
    result = run_scene(data, progress=False)
    assert result.summary["status"] == "ok"
    assert result.summary["loads"] == [
        'load[1] (pyloads_functions:hub): Jacobians df/dq and df/dv by central finite '
        'differences over the coordinates of arm:0 (4 k + 1 calls of the function for k '
        'coordinates); give jacobian = "module:function" for exact ones']
    assert load_scene(path) == data
    again = tmp_path / "again.toml"
    again.write_text(data.to_toml())
    assert load_scene(again) == data


@pytest.mark.parametrize("law, load, message", [
    ('time_law = { type = "python", function = "no_such_module:ramp" }', "",
     "load[0].time_law.function: no module \"no_such_module\" (looked in the scene's folder"),
    ('time_law = { type = "python", function = "pyloads_functions:missing" }', "",
     'load[0].time_law.function: module "pyloads_functions"'),
    ('time_law = { type = "python", function = "ramp" }', "",
     'load[0].time_law.function: expected "module:function"'),
    ('time_law = { type = "python", function = "pyloads_functions:short" }', "",
     "load[0].time_law.function: \"pyloads_functions:short\" returned shape (1,) for times of "
     "shape (2,)"),
    ('time_law = { type = "python", function = "pyloads_functions:nan" }', "",
     'load[0].time_law.function: "pyloads_functions:nan" returned a non-finite value nan at '
     "t = 1 s"),
    ("", '[[load]]\ntype = "python"\nfunction = "pyloads_functions:absent"',
     'load[1].function: module "pyloads_functions"'),
    ("", '[[load]]\ntype = "python"\nfunction = "pyloads_functions:hub"\nnodes = ["arm:9"]',
     "load[1].nodes[0]: node index 9 out of range"),
])
def test_scene_check_errors_name_the_key(tmp_path, law, load, message):
    (tmp_path / "pyloads_functions.py").write_text(FUNCTIONS)
    with pytest.raises(SceneError) as error:
        load_scene(_toml(tmp_path, law, load))
    assert message in str(error.value)


@pytest.mark.parametrize("function, message", [
    ("wrong", "diverged at t = 0 s: load[1].function: pyloads_functions:wrong returned "
     "shape (3,); expected a generalised force over the model's coordinates of shape (18,)"),
    ("late_nan", "diverged at t = 0.003 s: load[1].function: pyloads_functions:late_nan "
     "returned a non-finite value nan at t = 0.003 s"),
])
@pytest.mark.parametrize("engine", ["python", "compiled"])
def test_run_time_errors_of_a_python_load_stop_the_run_naming_the_key(tmp_path, function,
                                                                       message, engine):
    (tmp_path / "pyloads_functions.py").write_text(FUNCTIONS)
    path = _toml(tmp_path, "", f'[[load]]\ntype = "python"\n'
                 f'function = "pyloads_functions:{function}"\nnodes = ["arm:0"]')
    result = run_scene(path, engine=engine, progress=False)
    assert result.summary["status"] == "diverged"
    assert result.summary["message"] == message


def test_python_load_nodes_must_share_an_element():
    data = scene([_arm(4)], [Pin("arm:0")], [PythonLoad(_spring_damper,
                                                        nodes=["arm:0", "arm:-1"])],
                 [Displacement("tip_y", "arm:-1", component="y")], material=STEEL,
                 static=Static())
    with pytest.raises(SceneError, match=r"load\[0\]\.nodes: a Python load's nodes must share"):
        StateLoads(Model(data))


def test_cli_exits_2_on_a_missing_module(tmp_path):
    path = _toml(tmp_path, 'time_law = { type = "python", function = "absent_module:f" }')
    done = subprocess.run([sys.executable, "-m", "runtime.cli", "run", path, "--out",
                           str(tmp_path / "out"), "--quiet"], capture_output=True, text=True)
    assert done.returncode == 2
    assert "load[0].time_law.function: no module" in done.stderr + done.stdout


def test_auto_newton_redoes_with_full_newton_a_step_the_kept_jacobian_cannot_carry():
    """The stiff PD arm with the trapezoidal rule: modified Newton cannot carry its second
    step (the first step's Jacobian gives corrections thousands of times full Newton's);
    auto Newton does that step again from its start with full Newton and ends where full
    Newton does, with the same decisions in both engines.  With generalized-alpha (Newton
    from the last step's accelerations) the kept Jacobian's first correction of the second
    step is already far off, which taking back the growing corrections after it
    (python_engine.newton_loop) does not undo: modified Newton diverges there, and auto,
    redoing the step with full Newton, ends where full Newton does."""
    mass = RHO * H * H * LENGTH
    inertia = mass * (LENGTH**2 / 3 + H**2 / 12)
    omega, zeta, target = 2 * math.pi, 0.7, 0.5
    gain, rate_gain = inertia * omega**2, 2 * zeta * omega * inertia

    def run(newton, integrator, engine="python", t_end=0.1):
        data = _arm_scene([PythonLoad(_pd(gain, rate_gain, target), nodes=["arm:0"])],
                          dynamic=Dynamic(t_end=t_end, step=2e-3, output_every=0.01,
                                          integrator=integrator, newton=newton))
        return run_scene(data, engine=engine, progress=False)

    def same_motion(result, full):
        for name in ("tip_x", "tip_y"):
            np.testing.assert_allclose(result.sensors[name], full.sensors[name], rtol=0,
                                       atol=1e-8 * LENGTH)

    modified = run("modified", "trapezoidal", t_end=0.01)
    assert modified.status == "diverged" and "did not converge" in modified.summary["message"]
    full = run("full", "trapezoidal")
    autos = [run("auto", "trapezoidal", engine) for engine in ("python", "compiled")]
    counts = [(a.summary["dynamic"]["newton_iterations"], a.summary["dynamic"]["factorisations"])
              for a in autos]
    assert all(a.status == "ok" for a in autos) and counts[0] == counts[1]
    for auto in autos:
        same_motion(auto, full)
    full = run("full", "generalized_alpha")
    for engine in ("python", "compiled"):
        auto = run("auto", "generalized_alpha", engine)
        assert auto.status == "ok"
        same_motion(auto, full)
