"""``run_scene``: every analysis in memory (no file I/O) - the summary as summary.json holds
it, sensor series, states, mode shapes, divergence, observers - and its agreement with
``ancf run``."""

from __future__ import annotations

import csv
import json
import os
from types import SimpleNamespace

import numpy as np
import pytest
import scipy.linalg
from scenes_small import body, cantilever, scene

from runtime.app.result import Modes, Observer, Result, States
from runtime.app.run import run
from runtime.app.simulation import requested, run_scene
from runtime.model.errors import SceneError
from runtime.model.scene import parse_scene
from runtime.model.toml_io import toml_text
from runtime.solve.modal import modal_shapes

SENSORS = [
    {"name": "tip_y", "type": "displacement", "node": "beam:-1", "component": "y"},
    {"name": "strain", "type": "strain_energy"},
    {"name": "kinetic", "type": "kinetic_energy"},
]


def small(analyses=("static", "modal", "dynamic"), **changes) -> dict:
    tables = {"static": {}, "modal": {"modes": 3},
              "dynamic": {"t_end": 0.05, "step": 2.5e-3, "output_every": 5e-3}}
    data = cantilever(elements=2, force=[0.0, -1000.0],
                      law={"type": "cosine_ramp", "duration": 0.02}, sensors=SENSORS,
                      **{k: tables[k] for k in analyses}).to_dict()
    data.update(changes)
    return data


def diverging() -> dict:
    # quiet until t = 0.05 s, then a 1e12 N tip load: Newton cannot follow
    return cantilever(elements=2, force=[0.0, -1e12], sensors=SENSORS,
                      law={"type": "table", "points": [[0.0, 0.0], [0.05, 0.0], [0.06, 1.0]]},
                      static={}, dynamic={"t_end": 0.2, "step": 5e-3}).to_dict()


@pytest.fixture(scope="module")
def full() -> Result:
    return run_scene(parse_scene(small()), store_states=True, progress=False)


def tip_dofs(model) -> np.ndarray:
    return model.node_dofs(model.node_index(model.scene.sensors[0].node), "r")


# --------------------------------------------------------------------------- in memory

def test_run_scene_writes_no_file(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    result = run_scene(parse_scene(small()), progress=False)
    assert result.status == "ok" and result.exit_code == 0
    assert os.listdir(tmp_path) == []


def test_summary_is_what_ancf_run_writes(full, tmp_path):
    summary, code = run(parse_scene(small()), tmp_path / "out", quiet=True)
    assert code == 0
    on_disk = json.loads((tmp_path / "out" / "summary.json").read_text())
    # everything but what the writers add (files) and what differs run to run (timings)
    volatile = {"files", "timing", "kernel_s"}
    assert set(on_disk) - volatile == set(json.loads(json.dumps(full.summary))) - volatile
    for key in ("scene", "title", "status", "message", "method", "backend", "static", "modal",
                "kernels"):
        assert json.loads(json.dumps(full.summary[key])) == on_disk[key], key
    for key in ("t_end", "steps", "newton_iterations", "t_reached", "sensors_final"):
        assert full.summary["dynamic"][key] == on_disk["dynamic"][key], key
    assert set(full.summary["timing"]) == set(on_disk["timing"])
    assert full.summary["timing"]["total_s"] >= full.summary["timing"]["simulate_s"] > 0


def test_sensor_series_are_the_csv_columns(full, tmp_path):
    run(parse_scene(small()), tmp_path / "out", quiet=True, plots=False)
    with (tmp_path / "out" / "timeseries.csv").open(newline="") as f:
        rows = list(csv.reader(f))
    assert list(full.sensors) == rows[0] == ["t", "tip_y", "strain", "kinetic"]
    for j, name in enumerate(rows[0]):
        assert full.sensors[name].tolist() == [float(row[j]) for row in rows[1:]]
    assert full.sensors["t"].shape == (11,)


def test_states_are_full_size_at_the_output_times(full):
    model, states = full.model, full.states
    assert isinstance(states, States)
    assert states.t.tolist() == full.sensors["t"].tolist()
    assert states.q.shape == states.v.shape == (11, model.size)
    assert np.array_equal(states.q[0], model.reference)
    assert not states.v[0].any()
    # the tip sensor is the tip node's y displacement in every state
    tip = tip_dofs(model)
    assert np.array_equal(states.q[:, tip[1]] - model.reference[tip[1]], full.sensors["tip_y"])
    assert np.abs(states.v[-1]).max() > 0


def test_static_state_and_sensors(full):
    tip = tip_dofs(full.model)
    assert full.static.shape == (full.model.size,)
    assert full.static[tip[1]] - full.model.reference[tip[1]] == \
        full.summary["static"]["sensors"]["tip_y"]


def test_mode_shapes_are_normalised_eigenvectors(full):
    model, modes = full.model, full.modes
    assert isinstance(modes, Modes)
    assert modes.frequencies_rad_s.tolist() == full.summary["modal"]["frequencies_rad_s"]
    assert modes.shapes.shape == (3, model.size)
    assert np.array_equal(modes.about, model.reference)
    assert not modes.shapes[:, model.fixed].any()
    positions = np.concatenate([model.node_dofs(n, "r") for n in range(model.n_nodes)])
    for shape in modes.shapes:
        assert np.abs(shape[positions]).max() == pytest.approx(1.0, rel=1e-12)
        assert shape[positions][np.argmax(np.abs(shape[positions]))] > 0
    # K phi = omega^2 M phi over the free coordinates, and M-orthogonal modes
    _, data = model.internal_forces(modes.about)
    stiffness = -model.jacobian_matrix(data).toarray()
    mass = model.mass_ff.toarray()
    free = modes.shapes[:, model.free]
    for omega, phi in zip(modes.frequencies_rad_s, free, strict=True):
        residual = stiffness @ phi - omega**2 * (mass @ phi)
        assert np.abs(residual).max() <= 1e-8 * np.abs(stiffness @ phi).max()
    gram = free @ mass @ free.T
    assert np.abs(gram - np.diag(np.diag(gram))).max() <= 1e-9 * np.diag(gram).max()


def test_mode_shapes_with_a_joint_satisfy_it():
    h, n = 0.05, 3
    data = scene([body("a", "beam2d", n, [0.0, 0.0], [1.0, 0.0], h, h),
                  body("b", "beam2d", n, [1.0, 0.0], [2.0, 0.0], h, h)],
                 [{"type": "clamp", "node": "a:0"}, {"type": "clamp", "node": "b:-1"},
                  {"type": "revolute", "nodes": ["a:-1", "b:0"]}], [], [],
                 modal={"modes": 3}, solver={"backend": "numpy"}).to_dict()
    result = run_scene(parse_scene(data), progress=False)
    model, modes = result.model, result.modes
    assert np.abs(model.joints @ modes.shapes.T).max() <= 1e-12
    # the generalised eigenproblem on the joints' null space
    basis = scipy.linalg.null_space(model.joints_free.toarray())
    _, data_ = model.internal_forces(model.reference)
    stiffness = basis.T @ (-model.jacobian_matrix(data_).toarray()) @ basis
    mass = basis.T @ model.mass_ff.toarray() @ basis
    expected = np.sqrt(scipy.linalg.eigh(stiffness, mass, eigvals_only=True)[:3])
    assert modes.frequencies_rad_s == pytest.approx(expected, rel=1e-9)
    # symmetric first mode: both sides of the hinge move together
    hinge = model.node_dofs(model.node_index(parse_scene(data).constraints[2].nodes[0]), "r")
    assert abs(modes.shapes[0][hinge[1]]) > 0.1


def test_modal_shapes_match_the_frequencies_alone(full):
    from runtime.solve.modal import modal

    found = modal_shapes(full.model, full.model.reference, 3)
    assert found.frequencies.tolist() == pytest.approx(
        modal(full.model, full.model.reference, 3).tolist(), rel=1e-12)


def test_no_states_unless_asked(tmp_path):
    result = run_scene(parse_scene(small(("dynamic",))), progress=False)
    assert result.states is None and result.static is None and result.modes is None
    assert set(result.sensors) == {"t", "tip_y", "strain", "kinetic"}
    static_only = run_scene(parse_scene(small(("static",))), progress=False,
                            store_states=True)
    assert static_only.sensors == {} and static_only.states is None
    assert "dynamic" not in static_only.summary


def test_output_table_is_read_when_present():
    assert requested(SimpleNamespace(output=SimpleNamespace(states=True)), "states")
    assert not requested(SimpleNamespace(output=SimpleNamespace(states=False)), "states")
    assert not requested(SimpleNamespace(), "vtk")  # scenes without an [output] table


def test_a_scene_file_path_is_accepted(tmp_path):
    path = tmp_path / "scene.toml"
    path.write_text(toml_text(small(("static",))))
    result = run_scene(path, method="cij", backend="numpy", progress=False)
    assert result.summary["scene"] == str(path)
    assert result.summary["method"] == "cij" and result.summary["backend"] == "numpy"
    with pytest.raises(SceneError, match="missing.toml"):
        run_scene(tmp_path / "missing.toml")


# --------------------------------------------------------------------------- divergence

def test_divergence_keeps_the_results_up_to_then():
    result = run_scene(parse_scene(diverging()), store_states=True, progress=False)
    assert result.status == "diverged" and result.exit_code == 1
    assert "t = " in result.summary["message"]
    t = result.sensors["t"]
    assert t[0] == 0.0 and 0.05 <= t[-1] < 0.2
    assert result.summary["dynamic"]["t_reached"] == t[-1]
    assert result.states.q.shape[0] == t.size
    assert np.isfinite(result.states.q).all()
    assert result.static is not None  # the static analysis before it is kept


def test_static_divergence_stops_the_run():
    data = small()
    data["analysis"]["static"] = {"max_iterations": 1}
    result = run_scene(parse_scene(data), progress=False)
    assert result.exit_code == 1 and result.status == "diverged"
    assert "static" in result.summary["message"]
    assert result.static is None and result.modes is None and result.sensors == {}
    assert not {"static", "modal", "dynamic"} & set(result.summary)


# --------------------------------------------------------------------------- observers

class Recorder(Observer):
    def __init__(self):
        self.calls = []

    def begin(self, model):
        self.calls.append(("begin", model.size))

    def static(self, q):
        self.calls.append(("static", q.shape))

    def modal(self, modes):
        self.calls.append(("modal", modes.shapes.shape[0]))

    def dynamic_start(self, names):
        self.calls.append(("start", tuple(names)))

    def sample(self, t, q, v, values):
        self.calls.append(("sample", t, values["tip_y"]))

    def dynamic_end(self):
        self.calls.append(("end",))


def test_observers_see_every_result_in_order():
    recorder = Recorder()
    result = run_scene(parse_scene(small()), observers=[recorder], progress=False)
    kinds = [c[0] for c in recorder.calls]
    assert kinds == ["begin", "static", "modal", "start"] + ["sample"] * 11 + ["end"]
    assert recorder.calls[3] == ("start", ("tip_y", "strain", "kinetic"))
    samples = [c for c in recorder.calls if c[0] == "sample"]
    assert [c[1] for c in samples] == result.sensors["t"].tolist()
    assert [c[2] for c in samples] == result.sensors["tip_y"].tolist()


def test_an_observer_that_fails_stops_the_run_and_ends_the_others():
    class Failing(Observer):
        def sample(self, t, q, v, values):
            if t > 0.012:
                raise OSError("disk full")

    recorder = Recorder()
    with pytest.raises(OSError, match="disk full"):
        run_scene(parse_scene(small(("dynamic",))), observers=[Failing(), recorder],
                  progress=False)
    assert recorder.calls[-1] == ("end",)
    assert [c[1] for c in recorder.calls if c[0] == "sample"] == [0.0, 0.005, 0.01]
