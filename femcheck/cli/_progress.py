"""Progress of long work, for people and for logs.

On a terminal: a rich bar. Off a terminal (CI, ``make verify > log``): timestamped plain lines, one when
the stage starts, one at least every :data:`INTERVAL_S` seconds while it runs (from a heartbeat thread,
so a long single step still shows life), and one when it ends, each with the stage, done/total, the
elapsed time and an ETA::

    07:58:01 [FE solves] 12/55 (22 %) elapsed 41 s, ETA 2.4 min - detailed P3 +y

``-q`` silences both; the library only logs (``logging``), and this is the CLI's view of it.

The ETA is ``elapsed * (work left) / (work done)``. Steps of unequal cost (a contact FE beside a dense
solve) are given ``weights``, their expected relative costs; the ETA then counts work, not steps, and
stays within a small factor of the truth once a tenth of the work is done (tests/test_progress.py checks
3x on a fake clock). The bar and the plain lines show the same ETA.
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
    ``weights``: expected relative cost of each step (``total`` of them; default: all alike), for the ETA;
    ``quiet`` shows nothing; ``tty`` (default: whether ``console`` writes to a terminal) picks the bar;
    ``clock``: seconds, monotonic (a fake one in tests).
    """

    def __init__(self, stage: str, total: int | None, console, *, quiet: bool = False, tty: bool | None = None,
                 interval_s: float = INTERVAL_S, weights=None, clock=time.monotonic):
        self.stage, self.total, self.console = stage, total, console
        self.quiet = quiet
        self.tty = console.is_terminal if tty is None else tty
        self.interval_s = interval_s
        self.clock = clock
        self.weights = None if weights is None else [float(w) for w in weights]
        if self.weights is not None:
            self.total = len(self.weights)
        self.done, self.description = 0, ""
        self._work_done: float | None = None   # work reported by advance(work=...), when the steps say what they cost
        self._t0 = clock()
        self._last_line = 0.0
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._bar = self._task = self._thread = None

    # -- context ---------------------------------------------------------------------------------
    def __enter__(self):
        self._t0 = self.clock()
        if self.quiet:
            return self
        if self.tty:
            from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn
            # the bar runs in work units; the step count and the ETA are this object's (one ETA for both views)
            self._bar = Progress(TextColumn(f"[bold]{self.stage}"), BarColumn(), TextColumn("{task.fields[steps]}"),
                                 TimeElapsedColumn(), TextColumn("{task.fields[eta]}"),
                                 TextColumn("{task.description}"), console=self.console)
            self._bar.__enter__()
            self._task = self._bar.add_task("", total=self._work(self.total), steps=self._steps(), eta="")
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
    def advance(self, n: int = 1, description: str = "", work: float | None = None) -> None:
        """``n`` more steps done; ``work``: their expected cost in the weights' units, when the steps do not come in
        the order of the weights (parallel workers finish in any order): the ETA then counts this work."""
        if work is not None:
            with self._lock:
                self._work_done = (self._work_done or 0.0) + float(work)
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
            eta = self.eta_s()
            self._bar.update(self._task, completed=self._done_work(self.done), total=self._work(self.total),
                             description=self.description, steps=self._steps(),
                             eta="" if eta is None else f"ETA {_fmt_s(eta)}")
        elif not self.quiet and self.clock() - self._last_line >= self.interval_s:
            self._line()

    def plan(self, weights) -> None:
        """Set the steps' expected relative costs once they are known (after the stage started)."""
        with self._lock:
            self.weights = [float(w) for w in weights]
            self.total = len(self.weights)
        if self._bar is not None:
            self._bar.update(self._task, total=self._work(self.total), steps=self._steps())

    # -- work and ETA ----------------------------------------------------------------------------
    def _work(self, steps: int | None) -> float | None:
        """Work of the first ``steps`` steps (in steps when there are no weights)."""
        if steps is None:
            return None
        return float(steps) if self.weights is None else sum(self.weights[:steps])

    def _done_work(self, done: int) -> float | None:
        """Work of the steps done: as reported by ``advance(work=...)``, else the first ``done`` weights."""
        return self._work_done if self._work_done is not None else self._work(done)

    def _steps(self) -> str:
        return f"{self.done}/{self.total}" if self.total else f"{self.done}"

    def eta_s(self) -> float | None:
        """Seconds left: elapsed time per unit of work done times the work left; None before the first step
        and once all is done."""
        with self._lock:
            done, total = self.done, self.total
        if not total or not 0 < done < total:
            return None
        work_done, work_all = self._done_work(done), self._work(total)
        if work_done <= 0 or work_done >= work_all:
            return None
        return (self.clock() - self._t0) / work_done * (work_all - work_done)

    # -- off-terminal lines -------------------------------------------------------------------------
    def status_line(self, note: str = "") -> str:
        """The plain progress line (also what the heartbeat prints)."""
        with self._lock:
            done, total, desc = self.done, self.total, self.description
        elapsed = self.clock() - self._t0
        share = min(self._done_work(done) / self._work(total), 1.0) if total and self._work(total) else 0.0
        count = f"{done}/{total} ({100 * share:.0f} %)" if total else f"{done}"
        left = self.eta_s()
        eta = "" if left is None else f", ETA {_fmt_s(left)}"
        tail = f" - {desc}" if desc else ""
        stamp = time.strftime("%H:%M:%S")
        return f"{stamp} [{self.stage}] {count} elapsed {_fmt_s(elapsed)}{eta}{tail}" + (f" ({note})" if note else "")

    def _line(self, note: str = "") -> None:
        self._last_line = self.clock()
        text = self.status_line(note)
        # plain write: no markup, no ANSI codes, flushed so CI logs show it now
        out = getattr(self.console, "file", None) or sys.stdout
        out.write(text + "\n")
        out.flush()

    def _heartbeat(self) -> None:
        while not self._stop.wait(min(1.0, self.interval_s)):
            if self.clock() - self._last_line >= self.interval_s:
                self._line()
