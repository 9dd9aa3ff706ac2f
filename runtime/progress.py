"""Progress of long phases on stderr: a tqdm bar on a terminal, a line every few seconds
elsewhere (logs, CI), nothing when silenced.

Three hooks, for every phase that can take more than a couple of seconds:

* :func:`phase` - a context manager around a step of unknown length, e.g. compiling a
  kernel: ``with progress.phase("compiling beam3d/gram_straight (first use on this machine,
  cached afterwards)"): ...`` prints the text when the step starts and its duration when it
  ends;
* :class:`Bar` - progress towards a known total: the simulated time of a dynamic run
  (``Bar("dynamic analysis", t_end, "s")``, ``update(t)``), or the cases of a study or
  benchmark (``Bar("error-vs-time", n, "cases")``, ``advance(note)``), with elapsed time and
  ETA;
* :func:`enabled` - a context manager that shows (True) or silences (False) every hook called
  within it, in this thread (``ancf ... --quiet`` and ``run_scene(progress=False)``).

Bars and lines appear only once a phase has lasted ``DELAY`` seconds: short runs stay quiet.
"""

from __future__ import annotations

import contextlib
import contextvars
import sys
import threading
import time
from collections.abc import Iterator
from types import TracebackType

__all__ = ["DELAY", "LINE_INTERVAL", "Bar", "enabled", "phase", "shown", "warn"]

#: seconds a bar waits before it first appears
DELAY = 2.0
#: seconds between two progress lines when stderr is not a terminal
LINE_INTERVAL = 5.0

_shown: contextvars.ContextVar[bool] = contextvars.ContextVar("ancf_progress", default=True)
_clock = time.monotonic


@contextlib.contextmanager
def enabled(show: bool = True) -> Iterator[None]:
    """Show (True) or silence (False) progress within the block (this thread or task)."""
    token = _shown.set(bool(show))
    try:
        yield
    finally:
        _shown.reset(token)


def shown() -> bool:
    """Whether progress is shown here (see :func:`enabled`)."""
    return _shown.get()


def _terminal() -> bool:
    try:
        return bool(sys.stderr is not None and sys.stderr.isatty())
    except (AttributeError, ValueError):  # a closed or replaced stderr
        return False


def _say(text: str) -> None:
    sys.stderr.write(text + "\n")
    sys.stderr.flush()


def _duration(seconds: float) -> str:
    """Seconds as ``42 s``, ``3 min 05 s`` or ``2 h 07 min``."""
    seconds = max(0, round(seconds))
    if seconds < 60:
        return f"{seconds} s"
    if seconds < 3600:
        return f"{seconds // 60} min {seconds % 60:02d} s"
    return f"{seconds // 3600} h {seconds % 3600 // 60:02d} min"


def warn(text: str) -> None:
    """A warning line on stderr (``ancf: warning: ...``), unless silenced."""
    if shown():
        _say(f"ancf: warning: {text}")


@contextlib.contextmanager
def phase(text: str) -> Iterator[None]:
    """Announce a step of unknown length once it has lasted ``DELAY`` seconds: ``text ...``
    then, when it ends normally, ``text: done in N s`` (nothing for short steps or when
    silenced).  The announcement comes from a timer thread, so it appears while the step
    blocks (a compiler run, say)."""
    if not shown():
        yield
        return
    start = _clock()
    announced = threading.Event()

    def announce() -> None:
        announced.set()
        _say(f"{text} ...")

    timer = threading.Timer(DELAY, announce)
    timer.daemon = True
    timer.start()
    try:
        yield
    finally:
        timer.cancel()
    if announced.is_set():
        _say(f"{text}: done in {_duration(_clock() - start)}")


class Bar:
    """Progress of ``label`` towards ``total`` (> 0) in ``unit`` ("s" of simulated time,
    "cases"), with elapsed time and ETA, on stderr once ``DELAY`` seconds have passed.

    On a terminal a tqdm bar; elsewhere a line every ``LINE_INTERVAL`` seconds and a last
    one at :meth:`close` (only if a line was printed, and the state changed since).
    Silenced (see :func:`enabled` at construction) it prints nothing.  A context manager;
    ``close`` is idempotent.
    """

    def __init__(self, label: str, total: float, unit: str) -> None:
        self.label, self.total, self.unit = label, float(total), unit
        self.done = 0.0
        self.note = ""
        self._start = _clock()
        self._last_line: float | None = None
        self._last_shown: tuple[float, str] | None = None
        self._closed = False
        self._bar = None
        self._lines = shown() and not _terminal()
        if shown() and not self._lines:
            from tqdm import tqdm

            self._bar = tqdm(total=self.total, desc=label, file=sys.stderr, delay=DELAY,
                             dynamic_ncols=True, bar_format=(
                                 "{desc}: {percentage:3.0f}%|{bar}| {n:.4g}/{total:.4g} "
                                 f"{unit} [{{elapsed}}<{{remaining}}]{{postfix}}"))

    def update(self, done: float, note: str = "") -> None:
        """Record progress up to ``done`` (in ``unit``); ``note`` names the last item."""
        if self._closed:
            return
        self.done, self.note = float(done), note
        if self._bar is not None:
            if note:
                self._bar.set_postfix_str(note, refresh=False)
            self._bar.update(self.done - self._bar.n)
        elif self._lines:
            now = _clock()
            if now - self._start >= DELAY and (self._last_line is None
                                              or now - self._last_line >= LINE_INTERVAL):
                self._line(now)

    def advance(self, note: str = "") -> None:
        """One more item done (a case of a study); ``note`` names it."""
        self.update(self.done + 1, note)

    def text(self, now: float | None = None) -> str:
        """The progress line: label, done/total unit (percent), elapsed, ETA, note."""
        elapsed = (_clock() if now is None else now) - self._start
        fraction = min(max(self.done / self.total, 0.0), 1.0) if self.total > 0 else 1.0
        eta = _duration(elapsed / fraction * (1 - fraction)) if fraction > 0 else "?"
        note = f"; last: {self.note}" if self.note else ""
        return (f"{self.label}: {self.done:.4g}/{self.total:.4g} {self.unit} "
                f"({fraction:.0%}), elapsed {_duration(elapsed)}, ETA {eta}{note}")

    def _line(self, now: float) -> None:
        _say(self.text(now))
        self._last_line, self._last_shown = now, (self.done, self.note)

    def close(self) -> None:
        """Draw the final state, unless the last line already shows it (idempotent)."""
        if self._closed:
            return
        self._closed = True
        if self._bar is not None:
            self._bar.close()
        elif self._last_line is not None and self._last_shown != (self.done, self.note):
            self._line(_clock())

    def __enter__(self) -> Bar:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.close()
