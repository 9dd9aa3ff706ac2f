"""``ancf study error-vs-time``: tiny work-precision sweeps checked against beam theory, the
[study] table, the command line, and every kind of bad input."""

from __future__ import annotations

import argparse
import csv
import socket
from pathlib import Path

import pytest

from runtime.studies.error_vs_time import CSV_COLUMNS, StudyError, add_cli, study
from runtime.studies.sweep import SchedulerError

SCENES = Path(__file__).resolve().parent.parent / "scenes"
CANTILEVER = SCENES / "cantilever.toml"
ROTATING = SCENES / "rotating_beam.toml"

# the paper's cantilever: L = 5 m, 0.1 m x 0.1 m, E = 132 GPa, P = 300 N, rho = 8245.2
LENGTH, SIDE, E_MODULUS, LOAD, RHO = 5.0, 0.1, 132e9, 300.0, 8245.2
INERTIA = SIDE**4 / 12
TIP = LOAD * LENGTH**3 / (3 * E_MODULUS * INERTIA)                          # 1.136 cm
OMEGA = 1.8751**2 * (E_MODULUS * INERTIA / (RHO * SIDE**2 * LENGTH**4)) ** 0.5   # 16.24 rad/s


def read_csv(path: Path) -> list[dict]:
    with path.open(newline="") as f:
        return list(csv.DictReader(f))


def scene_with(tmp_path: Path, study_table: str, base: Path = CANTILEVER,
               drop_sensor: str | None = None) -> Path:
    """A copy of a shipped scene with its [study] table replaced (and a sensor removed)."""
    text = base.read_text().split("\n[study]")[0]
    # the comment lines introducing the shipped [study] table may remain: harmless
    if drop_sensor is not None:
        blocks = text.split("[[sensor]]")
        text = blocks[0] + "".join("[[sensor]]" + b for b in blocks[1:]
                                   if f'name = "{drop_sensor}"' not in b)
        text = "\n".join(line for line in text.splitlines()
                         if not line.startswith(("frequency_of", "frequency_after")))
    path = tmp_path / f"{base.stem}_study.toml"
    path.write_text(text + "\n[study]\n" + study_table)
    return path


def cli(argv: list[str]) -> int:
    """``ancf study ...`` through a throwaway parser wired like runtime/cli.py."""
    parser = argparse.ArgumentParser(prog="ancf")
    commands = parser.add_subparsers(dest="command", required=True)
    add_cli(commands.add_parser("study").add_subparsers(dest="study", required=True))
    args = parser.parse_args(argv)
    return args.run(args)


def closed_port() -> int:
    """A local TCP port that nothing listens on."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


# --------------------------------------------------------------------------- studies

def test_static_tip_sweep_against_beam_theory(tmp_path):
    rows = study(CANTILEVER, tmp_path, elements=[2, 3], method=["gram"], error="static_tip",
                 serial=True)
    for name in ("csv", "png", "md"):
        assert (tmp_path / f"error_vs_time.{name}").stat().st_size > 0
    assert (tmp_path / "error_vs_time.png").read_bytes()[:4] == b"\x89PNG"
    table = read_csv(tmp_path / "error_vs_time.csv")
    assert tuple(table[0]) == CSV_COLUMNS and len(table) == 2
    assert all(r["status"] == "ok" and r["method"] == "gram" for r in rows)
    assert float(table[0]["exact"]) == pytest.approx(-TIP, rel=1e-12)   # tip_y is downward
    error = {r["elements"]: r["error"] for r in rows}
    # Table I: 1.07 cm with 2 elements against 1.136 cm, about 6 % short; 3 elements halve it
    assert 0.05 < error[2] < 0.075
    assert error[3] < 0.6 * error[2] < 0.1
    for r in rows:
        assert r["error"] == pytest.approx(abs(abs(r["value"]) - TIP) / TIP, rel=1e-9)
        assert 0 < r["simulate_s"] <= r["total_s"]
    summary = (tmp_path / "error_vs_time.md").read_text().split("## Summary")[1]
    assert "gram" in summary and "cheapest" in summary


def test_study_table_with_frequency_error_and_command_line_override(tmp_path, capsys):
    scene = scene_with(tmp_path, 'elements = [2, 3]\nstep = [1e-2]\nmethod = "gram"\n'
                                 'integrator = ["trapezoidal"]\nerror = "frequency"\n'
                                 'sensor = "tip_y"\nt_end = 4.0\n')
    rows = study(scene, tmp_path / "table", serial=True)
    assert [(r["elements"], r["step"], r["integrator"]) for r in rows] == \
        [(2, 1e-2, "trapezoidal"), (3, 1e-2, "trapezoidal")]
    for r in rows:
        assert r["exact"] == pytest.approx(OMEGA, rel=1e-4)
    error = {r["elements"]: r["error"] for r in rows}
    # beam3d meshes are too stiff: 2 elements ~5 % high, 3 elements ~2 %
    assert 0.03 < error[2] < 0.07 and error[3] < error[2]
    assert all(r["value"] > OMEGA for r in rows)
    # the command line overrides the table (one mesh instead of two)
    out = tmp_path / "cli"
    assert cli(["study", "error-vs-time", str(scene), "--elements", "2", "--serial",
                "--out", str(out)]) == 0
    assert len(read_csv(out / "error_vs_time.csv")) == 1
    printed = capsys.readouterr().out
    assert "| elements |" in printed and "## Summary" in printed


def test_reference_error_of_rotating_beam(tmp_path):
    rows = study(ROTATING, tmp_path, elements=[2, 4], step=[2e-2], method=["gram"], t_end=1.0,
                 integrator=["trapezoidal"], reference={"elements": 8, "step": 1e-2},
                 serial=True)
    sweep, reference = rows[:-1], rows[-1]
    assert reference["role"] == "reference" and reference["status"] == "ok"
    assert (reference["elements"], reference["step"]) == (8, 1e-2)
    assert reference["value"] > 0                       # max |tip deflection| of the reference
    assert [r["elements"] for r in sweep] == [2, 4]
    assert sweep[1]["error"] < sweep[0]["error"] < 1.0
    md = (tmp_path / "error_vs_time.md").read_text()
    assert "reference run (8 elements" in md


def test_closed_form_follows_the_section_axes_of_a_rectangular_beam(tmp_path):
    """A 0.2 m x 0.1 m beam along +y loaded along z bends across its width (local z = global
    z), so I = h w^3 / 12, a quarter of w h^3 / 12; the model must agree."""
    text = (CANTILEVER.read_text().split("\n[study]")[0]
            .replace("section = { height = 0.1, width = 0.1 }",
                     "section = { height = 0.2, width = 0.1 }")
            .replace("end = [5.0, 0.0, 0.0]", "end = [0.0, 5.0, 0.0]")
            .replace("force = [0.0, -300.0, 0.0]", "force = [0.0, 0.0, -300.0]")
            .replace('component = "y"', 'component = "z"'))
    scene = tmp_path / "rectangular.toml"
    scene.write_text(text)
    rows = study(scene, tmp_path / "out", elements=[5], method=["gram"], repeat=1, serial=True)
    weak = LOAD * LENGTH**3 / (3 * E_MODULUS * 0.2 * 0.1**3 / 12)       # 5.68 mm
    assert rows[0]["exact"] == pytest.approx(-weak, rel=1e-12)
    assert rows[0]["error"] < 0.02                      # 4x off if the axes were swapped


# --------------------------------------------------------------------------- bad input

BAD_TABLES = [
    ("elements = []", "study.elements: the study has no runs"),
    ("elements = [2, 'x']", "study.elements[1]: expected a positive integer, got 'x'"),
    ("error = 'frequency'\nstep = [1e-3, 'x']", "study.step[1]: expected a positive number"),
    ("method = ['gram', 'fast']", "study.method[1]: unknown method 'fast'"),
    ("error = 'frequency'\nintegrator = 'rk4'", "study.integrator[0]: unknown integrator"),
    ("error = 'exact'", "study.error: unknown error measure 'exact'"),
    ("sensor = 'tip_z'", "study.sensor: no sensor 'tip_z' in the scene; available sensors: tip_y"),
    ("sensor = 'strain_energy'", "study.sensor: sensor 'strain_energy' (strain_energy) cannot"),
    ("steps = [1e-3]", "study.steps: unknown key"),
    ("error = 'frequency'\nt_end = 3.0", "study.t_end: expected a time after frequency_after"),
    ("error = 'frequency'\nstep = 5.0", "study.step[0]: expected a step of at most t_end"),
    ("repeat = 0", "study.repeat: expected a positive integer"),
]


@pytest.mark.parametrize("table, message", BAD_TABLES)
def test_bad_study_table_names_the_key(tmp_path, table, message):
    with pytest.raises(StudyError) as info:
        study(scene_with(tmp_path, table), tmp_path / "out", serial=True)
    assert message in str(info.value)
    assert not (tmp_path / "out").exists()             # nothing ran


BAD_OVERRIDES = [
    ({"elements": []}, "--elements: the study has no runs"),
    ({"method": []}, "--method: the study has no runs"),
    ({"error": "frequency", "step": ["1e-3", 2e-3]}, "--step[0]: expected a positive number, "
                                                     "got '1e-3'"),
    ({"error": "frequency", "integrator": ["rk4"]}, "--integrator[0]: unknown integrator 'rk4'"),
    ({"backend": "fortran"}, "--backend: unknown backend 'fortran'"),
    ({"error": "frequency", "t_end": -1.0}, "--t-end: expected a positive number, got -1.0"),
    ({"workers": 0}, "--workers: expected a positive integer, got 0"),
]


@pytest.mark.parametrize("overrides, message", BAD_OVERRIDES)
def test_bad_override_names_the_option(tmp_path, overrides, message):
    with pytest.raises(StudyError) as info:
        study(CANTILEVER, tmp_path, serial=True, **overrides)
    assert message in str(info.value)


def test_scene_without_the_sensor_the_error_needs(tmp_path):
    scene = scene_with(tmp_path, "error = 'static_tip'", drop_sensor="tip_y")
    with pytest.raises(StudyError) as info:
        study(scene, tmp_path / "out", serial=True)
    message = str(info.value)
    assert message.startswith("study.sensor: error 'static_tip' needs a displacement sensor of "
                              "the loaded node beam:")
    assert "available sensors: strain_energy (strain_energy), kinetic_energy" in message


def test_closed_form_errors_need_a_cantilever_and_reference_runs_a_valid_table(tmp_path):
    with pytest.raises(StudyError, match=r"^--error: error 'static_tip' needs a cantilever"):
        study(ROTATING, tmp_path, error="static_tip", serial=True)
    with pytest.raises(StudyError, match=r"^--reference.elements: expected a positive integer"):
        study(ROTATING, tmp_path, reference={"elements": 0}, serial=True)
    with pytest.raises(StudyError, match=r"^--reference: expected ELEMENTS,STEP"):
        study(ROTATING, tmp_path, reference=[8], serial=True)


def test_unreachable_scheduler(tmp_path, capsys):
    address = f"tcp://127.0.0.1:{closed_port()}"
    with pytest.raises(SchedulerError, match=f"--scheduler {address}: cannot connect"):
        study(CANTILEVER, tmp_path, elements=[2], scheduler=address)
    assert cli(["study", "error-vs-time", str(CANTILEVER), "--scheduler", address]) == 2
    assert address in capsys.readouterr().err


def test_command_line_bad_value_exits_2_with_one_line(tmp_path, capsys):
    code = cli(["study", "error-vs-time", str(CANTILEVER), "--error", "frequency", "--step",
                "1e-3,x", "--out", str(tmp_path)])
    err = capsys.readouterr().err
    assert code == 2
    assert err.strip() == ("ancf study error-vs-time: --step[1]: expected a positive number, "
                           "got 'x'")
