"""Second audit, command line: every list option reads the same written with spaces, with
commas or repeated; every option the README's usage lines name exists; commands that write
files say where before writing, by default into results/<command>."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from test_readme import ROOT

from runtime import cli
from runtime.studies import report
from runtime.studies.error_vs_time import run as error_vs_time_run
from runtime.studies.stability import cli as stability_cli

README = (ROOT / "README.md").read_text()

#: (command words, list option, three spellings of one value, the value parsed)
LISTS = [
    (["generate"], "--element", ("beam2d", "beam3d"), ["beam2d", "beam3d"]),
    (["generate"], "--backend", ("c", "numpy"), ["c", "numpy"]),
    (["generate"], "--method", ("gram", "cij"), ["gram", "cij"]),
    (["invariants"], "--quadrature", ("5", "3", "3"), [5, 3, 3]),
    (["bench", "kernels"], "--element", ("beam2d", "plate3d"), ["beam2d", "plate3d"]),
    (["bench", "kernels"], "--method", ("gram", "quadrature"), ["gram", "quadrature"]),
    (["bench", "kernels"], "--backend", ("numpy", "c"), ["numpy", "c"]),
    (["bench", "steps"], "--elements", ("10", "100"), [10, 100]),
    (["study", "error-vs-time", "S"], "--elements", ("2", "5", "10"), ["2", "5", "10"]),
    (["study", "error-vs-time", "S"], "--step", ("1e-3", "5e-4"), ["1e-3", "5e-4"]),
    (["study", "error-vs-time", "S"], "--method", ("gram", "cij"), ["gram", "cij"]),
    (["study", "error-vs-time", "S"], "--integrator", ("trapezoidal", "generalized_alpha"),
     ["trapezoidal", "generalized_alpha"]),
    (["study", "error-vs-time", "S"], "--targets", ("1e-3", "1e-4"), ["1e-3", "1e-4"]),
    (["study", "error-vs-time", "S"], "--reference", ("20", "1e-4"), ["20", "1e-4"]),
]


@pytest.mark.parametrize(("words", "flag", "values", "parsed"), LISTS)
def test_list_options_read_the_same_with_spaces_commas_or_repeated(words, flag, values,
                                                                     parsed):
    dest = flag[2:].replace("-", "_")
    spellings = [[flag, *values], [flag, ",".join(values)],
                 [item for v in values for item in (flag, v)]]
    for spelling in spellings:
        assert getattr(cli.parser().parse_args([*words, *spelling]), dest) == parsed, spelling


def test_list_options_check_their_values(capsys):
    assert cli.main(["generate", "--backend", "c", "fortran", "--check"]) == 2
    assert "invalid choice: 'fortran'" in capsys.readouterr().err
    assert cli.main(["bench", "steps", "--elements", "10", "x"]) == 2
    assert "--elements: invalid value 'x'" in capsys.readouterr().err


def _usage_lines() -> list[str]:
    """The README's usage lines: each `ancf ...` code span of its Commands section."""
    commands = README.split("## Commands", 1)[1]
    return [m for m in re.findall(r"`(ancf [^`]+)`", commands) if "--" in m]


def _subparser(words: list[str]):
    parser = cli.parser()
    for word in words:
        actions = [a for a in parser._actions if a.choices and isinstance(a.choices, dict)]
        if not actions or word not in actions[0].choices:
            break
        parser = actions[0].choices[word]
    return parser


def test_every_option_of_a_readme_usage_line_exists():
    lines = _usage_lines()
    assert any("bench steps" in line for line in lines)
    for line in lines:
        words = line.split()[1:3]
        parser = _subparser(words)
        known = {s for a in parser._actions for s in a.option_strings}
        for flag in re.findall(r"--[a-z][a-z-]*", line):
            assert flag in known, (line, flag)


@pytest.mark.parametrize("argv", [
    ["bench", "steps", "--elements", "10", "100"],                       # [--elements N ...]
    ["study", "error-vs-time", "S", "--elements", "2,5,10"],
    ["study", "error-vs-time", "S", "--elements", "2", "5", "10"],
    ["invariants", "--element", "beam3d", "--quadrature", "5,3,3"],
    ["invariants", "--element", "beam3d", "--quadrature", "5", "3", "3"],
    ["generate", "--element", "beam2d", "--backend", "numpy", "--method", "gram", "--check"],
])
def test_readme_usage_lines_parse_as_written(argv):
    cli.parser().parse_args(argv)


def test_report_quick_writes_into_results_report_and_says_so_first(tmp_path, monkeypatch,
                                                                     capsys):
    seen = []

    def build(out, quick, **kwargs):
        seen.append((Path(out), capsys.readouterr().out))
        return Path(out) / "report.md"

    monkeypatch.setattr(report, "build", build)
    monkeypatch.chdir(tmp_path)
    assert cli.main(["report", "--quick"]) == 0
    folder, said = seen[-1]
    assert folder == Path("results/report") and folder.is_dir()
    assert str((tmp_path / "results" / "report").resolve()) in said


def test_error_vs_time_says_where_it_writes_before_the_runs(tmp_path, monkeypatch, capsys):
    class Stop(Exception):
        pass

    def run_cases(*args, **kwargs):
        raise Stop(capsys.readouterr().out)

    monkeypatch.setattr(error_vs_time_run, "run_cases", run_cases)
    monkeypatch.chdir(tmp_path)
    scene = ROOT / "scenes" / "cantilever.toml"
    with pytest.raises(Stop) as stop:
        cli.main(["study", "error-vs-time", str(scene), "--elements", "2", "--serial"])
    where = tmp_path / "results" / "error-vs-time" / "cantilever"
    assert f"writing into {where.resolve()}" in str(stop.value)


def test_stability_says_where_it_writes_before_the_runs(tmp_path, monkeypatch, capsys):
    def study(**kwargs):
        raise RuntimeError(capsys.readouterr().out)

    monkeypatch.setattr(stability_cli, "stability_study", study)
    monkeypatch.chdir(tmp_path)
    with pytest.raises(RuntimeError, match=re.escape(str(tmp_path / "results" / "stability"))):
        cli.main(["study", "stability", "--quick"])
