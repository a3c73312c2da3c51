"""Progress of long work, for people and for logs.

On a terminal: a rich bar. Off a terminal (CI, ``make verify > log``): timestamped plain lines, one when
the stage starts, one at least every :data:`INTERVAL_S` seconds while it runs (from a heartbeat thread,
so a long single step still shows life), and one when it ends, each with the stage, done/total, the
elapsed time and an ETA::

    07:58:01 [FE solves] 12/55 (22 %) elapsed 41 s, ETA 2.4 min - detailed P3 +y

``-q`` silences both; the library only logs (``logging``), and this is the CLI's view of it.
"""
from __future__ import annotations

import sys
import threading
import time

#: the longest gap between two progress lines off a terminal (s)
INTERVAL_S = 10.0


def _fmt_s(seconds: float) -> str:
    if seconds < 90:
        return f"{seconds:.0f} s"
    if seconds < 5400:
        return f"{seconds / 60:.1f} min"
    return f"{seconds / 3600:.1f} h"


class StageProgress:
    """Progress of one stage of ``total`` steps (``total`` may be None until known).

    Use as a context manager; call :meth:`advance` after each step or :meth:`update` with absolute values.
    ``quiet`` shows nothing; ``tty`` (default: whether ``console`` writes to a terminal) picks the bar.
    """

    def __init__(self, stage: str, total: int | None, console, *, quiet: bool = False, tty: bool | None = None,
                 interval_s: float = INTERVAL_S):
        self.stage, self.total, self.console = stage, total, console
        self.quiet = quiet
        self.tty = console.is_terminal if tty is None else tty
        self.interval_s = interval_s
        self.done, self.description = 0, ""
        self._t0 = time.monotonic()
        self._last_line = 0.0
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._bar = self._task = self._thread = None

    # -- context ---------------------------------------------------------------------------------
    def __enter__(self):
        self._t0 = time.monotonic()
        if self.quiet:
            return self
        if self.tty:
            from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn, \
                TimeRemainingColumn
            self._bar = Progress(TextColumn(f"[bold]{self.stage}"), BarColumn(), MofNCompleteColumn(),
                                 TimeElapsedColumn(), TextColumn("ETA"), TimeRemainingColumn(),
                                 TextColumn("{task.description}"), console=self.console)
            self._bar.__enter__()
            self._task = self._bar.add_task("", total=self.total)
        else:
            self._line("started")
            self._thread = threading.Thread(target=self._heartbeat, daemon=True, name="femcheck-progress")
            self._thread.start()
        return self

    def __exit__(self, exc_type, exc, tb):
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=1.0)
        if self._bar is not None:
            self._bar.__exit__(exc_type, exc, tb)
        elif not self.quiet:
            self._line("interrupted" if exc_type is not None else "done")
        return False

    # -- updates ---------------------------------------------------------------------------------
    def advance(self, n: int = 1, description: str = "") -> None:
        self.update(completed=self.done + n, description=description)

    def update(self, completed: int | None = None, total: int | None = None, description: str | None = None) -> None:
        with self._lock:
            if completed is not None:
                self.done = int(completed)
            if total is not None:
                self.total = int(total)
            if description is not None:
                self.description = description
        if self._bar is not None:
            self._bar.update(self._task, completed=self.done, total=self.total, description=self.description)
        elif not self.quiet and time.monotonic() - self._last_line >= self.interval_s:
            self._line()

    # -- off-terminal lines -------------------------------------------------------------------------
    def status_line(self, note: str = "") -> str:
        """The plain progress line (also what the heartbeat prints)."""
        with self._lock:
            done, total, desc = self.done, self.total, self.description
        elapsed = time.monotonic() - self._t0
        count = f"{done}/{total} ({100 * done / total:.0f} %)" if total else f"{done}"
        eta = ""
        if total and 0 < done < total:
            eta = f", ETA {_fmt_s(elapsed / done * (total - done))}"
        tail = f" - {desc}" if desc else ""
        stamp = time.strftime("%H:%M:%S")
        return f"{stamp} [{self.stage}] {count} elapsed {_fmt_s(elapsed)}{eta}{tail}" + (f" ({note})" if note else "")

    def _line(self, note: str = "") -> None:
        self._last_line = time.monotonic()
        text = self.status_line(note)
        # plain write: no markup, no ANSI codes, flushed so CI logs show it now
        out = getattr(self.console, "file", None) or sys.stdout
        out.write(text + "\n")
        out.flush()

    def _heartbeat(self) -> None:
        while not self._stop.wait(min(1.0, self.interval_s)):
            if time.monotonic() - self._last_line >= self.interval_s:
                self._line()
