"""Progress of long runs: a bar on a terminal, a line every few seconds in a log."""

from __future__ import annotations

import math
import sys
import time


class Progress:
    """Count ``total`` steps of a run and report them on ``stream``.

    On a terminal, a bar redrawn in place; otherwise (a log file, a pipe, a
    Snakemake log) one line every ``every`` seconds and one at the end.  Runs
    shorter than ``quiet_below`` seconds report nothing, so quick calls stay
    quiet.

    Parameters
    ----------
    total : int
        Number of steps.
    label : str
        What runs, first word of every report (e.g. ``"simulate"``).
    unit : str
        What a step is, for the log lines (e.g. ``"pressures"``).
    stream : file-like, optional
        Default ``sys.stderr``.
    every : float
        Seconds between two log lines.
    quiet_below : float
        Seconds before the first report.

    Examples
    --------
    >>> import io
    >>> log = io.StringIO()
    >>> bar = Progress(2, "demo", "steps", stream=log, every=0.0)
    >>> bar.step(); bar.step()
    >>> log.getvalue().splitlines()[-1].startswith("demo: 2/2 steps (100 %)")
    True
    """

    def __init__(self, total: int, label: str, unit: str = "steps", stream=None,
                 every: float = 10.0, quiet_below: float = 0.0):
        self.total, self.done = max(int(total), 1), 0
        self.label, self.unit = label, unit
        self.stream = stream or sys.stderr
        self.tty = hasattr(self.stream, "isatty") and self.stream.isatty()
        self.every, self.quiet_below = float(every), float(quiet_below)
        self.t0, self.last, self.shown = time.perf_counter(), -math.inf, False

    def step(self, n: int = 1, note: str = "") -> None:
        """``n`` more steps done; ``note`` (e.g. the current pressure) is shown too."""
        self.done = min(self.done + n, self.total)
        now = time.perf_counter() - self.t0
        end = self.done == self.total
        if now < self.quiet_below and not (end and self.shown):
            return
        eta = now / self.done * (self.total - self.done)
        extra = f", {note}" if note else ""
        if self.tty:
            bar = "#" * int(30 * self.done / self.total)
            self.stream.write(f"\r{self.label} [{bar:<30}] {self.done}/{self.total} "
                              f"{now:.0f} s, {eta:.0f} s left{extra} ")
            if end:
                self.stream.write("\n")
            self.stream.flush()
            self.shown = True
        elif now - self.last >= self.every or end:
            self.last = now
            print(f"{self.label}: {self.done}/{self.total} {self.unit} "
                  f"({100 * self.done / self.total:.0f} %), {now:.0f} s, about {eta:.0f} s "
                  f"left{extra}", file=self.stream, flush=True)
            self.shown = True

    def close(self) -> None:
        """End the bar's line on a terminal if the run stopped short of ``total``."""
        if self.tty and self.shown and self.done < self.total:
            self.stream.write("\n")
            self.stream.flush()
