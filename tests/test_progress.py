"""Progress on stderr (runtime.progress): lines every few seconds off a terminal, a tqdm bar
on one, nothing for short phases or when silenced; the dynamic run reports through it."""

from __future__ import annotations

import time

import pytest
from scenes_small import cantilever

from runtime import progress
from runtime.app.simulation import run_scene
from runtime.model.scene import parse_scene
from runtime.progress import Bar, enabled, phase


class Clock:
    """A monotonic clock the test moves by hand."""

    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


@pytest.fixture
def clock(monkeypatch) -> Clock:
    fake = Clock()
    monkeypatch.setattr(progress, "_clock", fake)
    return fake


def lines(err: str) -> list[str]:
    return [line for line in err.split("\n") if line]


def test_lines_every_few_seconds_after_the_delay(clock, capsys):
    bar = Bar("dynamic analysis", 4.0, "s")
    clock.now += 1.0
    bar.update(0.5)                       # before the delay: nothing
    assert capsys.readouterr().err == ""
    clock.now += 1.0
    bar.update(1.68)                      # 2 s: the first line
    first = capsys.readouterr().err
    assert first == "dynamic analysis: 1.68/4 s (42%), elapsed 2 s, ETA 3 s\n"
    clock.now += 3.0
    bar.update(2.0)                       # 3 s after the last line: nothing
    assert capsys.readouterr().err == ""
    clock.now += 2.0
    bar.update(3.0)                       # 5 s after it: a line
    assert lines(capsys.readouterr().err) == ["dynamic analysis: 3/4 s (75%), elapsed 7 s, "
                                              "ETA 2 s"]
    clock.now += 2.0
    bar.update(3.6)                       # 2 s after it: nothing, until the last line
    assert capsys.readouterr().err == ""
    bar.close()
    bar.close()
    assert lines(capsys.readouterr().err) == ["dynamic analysis: 3.6/4 s (90%), elapsed 9 s, "
                                              "ETA 1 s"]


def test_the_last_line_is_not_repeated(clock, capsys):
    bar = Bar("study", 2, "cases")
    clock.now += 3.0
    bar.advance("a")
    bar.advance("b")                      # within LINE_INTERVAL of the first line
    clock.now += 1.0
    bar.close()
    assert lines(capsys.readouterr().err) == ["study: 1/2 cases (50%), elapsed 3 s, ETA 3 s; "
                                              "last: a",
                                              "study: 2/2 cases (100%), elapsed 4 s, ETA 0 s; "
                                              "last: b"]
    bar = Bar("study", 1, "cases")
    clock.now += 3.0
    bar.advance()
    bar.close()                           # the line of the advance shows the end already
    assert lines(capsys.readouterr().err) == ["study: 1/1 cases (100%), elapsed 3 s, ETA 0 s"]


def test_a_short_phase_prints_nothing(clock, capsys):
    with Bar("dynamic analysis", 4.0, "s") as bar:
        for i in range(100):
            bar.update(i * 0.04)
    assert capsys.readouterr().err == ""


def test_cases_count_with_their_names(clock, capsys):
    bar = Bar("error-vs-time", 10, "cases")
    for name in ("a", "b", "c"):
        clock.now += 1.0
        bar.advance(f"case {name}")
    assert lines(capsys.readouterr().err) == [
        "error-vs-time: 2/10 cases (20%), elapsed 2 s, ETA 8 s; last: case b"]
    assert bar.text() == "error-vs-time: 3/10 cases (30%), elapsed 3 s, ETA 7 s; last: case c"


def test_long_durations_read_in_minutes_and_hours(clock):
    bar = Bar("study", 4, "cases")
    clock.now += 125.0
    bar.advance()
    assert "elapsed 2 min 05 s, ETA 6 min 15 s" in bar.text()
    clock.now += 7200.0
    assert "elapsed 2 h 02 min" in bar.text()


def test_a_terminal_gets_a_tqdm_bar(monkeypatch, capsys):
    monkeypatch.setattr(progress, "_terminal", lambda: True)
    monkeypatch.setattr(progress, "DELAY", 0.0)
    with Bar("dynamic analysis", 4.0, "s") as bar:
        bar.update(1.68)
        bar.update(4.0)
    err = capsys.readouterr().err
    assert "dynamic analysis: 100%|" in err and "4/4 s" in err
    assert err.endswith("\n")


def test_phase_says_what_and_how_long(clock, capsys, monkeypatch):
    monkeypatch.setattr(progress, "DELAY", 0.05)
    text = "compiling beam3d/gram_straight (first use on this machine, cached afterwards)"
    with phase(text):
        time.sleep(0.3)          # the announcement comes while the step blocks
        assert lines(capsys.readouterr().err) == [f"{text} ..."]
        clock.now += 12.4
    assert lines(capsys.readouterr().err) == [f"{text}: done in 12 s"]


def test_short_phase_says_nothing(capsys):
    with phase("compiling a tiny module"):
        pass
    assert capsys.readouterr().err == ""


def test_silenced_prints_nothing_and_nests(clock, capsys, monkeypatch):
    monkeypatch.setattr(progress, "_terminal", lambda: True)
    with enabled(False):
        assert not progress.shown()
        with phase("compiling"):
            pass
        bar = Bar("dynamic analysis", 1.0, "s")
        clock.now += 10
        bar.update(1.0)
        bar.close()
        with enabled(True):
            assert progress.shown()
        assert not progress.shown()
    assert progress.shown()
    assert capsys.readouterr().err == ""


def test_a_dynamic_run_reports_simulated_time(monkeypatch, capsys):
    monkeypatch.setattr(progress, "DELAY", 0.0)
    monkeypatch.setattr(progress, "LINE_INTERVAL", 0.0)
    data = cantilever(elements=2, force=[0.0, -1000.0], solver={"backend": "numpy"},
                      dynamic={"t_end": 0.02, "step": 5e-3}).to_dict()
    run_scene(parse_scene(data))
    err = lines(capsys.readouterr().err)
    assert err[0].startswith("dynamic analysis: 0.005/0.02 s (25%), elapsed")
    assert err[-1].startswith("dynamic analysis: 0.02/0.02 s (100%)") and "ETA 0 s" in err[-1]
    run_scene(parse_scene(data), progress=False)
    assert capsys.readouterr().err == ""
