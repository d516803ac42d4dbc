"""The time protocols of ``skinsuction simulate``: Cutometer mode 1, mode 2, any p(t).

:func:`protocol_from_args` turns ``--mode1 P,ON,OFF,CYCLES``, ``--mode2
P,RISE,FALL,CYCLES`` or ``--history FILE`` into a :class:`TimeProtocol` (the suction
piecewise linear in time, and the times a curve is sampled at, ``--sample-hz``);
:func:`simulate_protocol` solves it with :func:`skinsuction.viscoelastic.simulate_history`
(each layer's spectrum; an elastic skin follows the load quasi-statically);
:func:`time_csv` writes the curve, :func:`rparams_text` the R parameters of a mode-1
curve through :func:`skinsuction.measured.r_parameters`. Mode 1 and mode 2 are
:func:`skinsuction.viscoelastic.mode1_history` and ``mode2_history``: their graded
time steps after each switch, with every sample time added.

Examples
--------
>>> parse_numbers("450,3,3,2", "--mode1", "P,ON,OFF,CYCLES", "450,3,3,2")
(450.0, 3.0, 3.0, 2.0)
>>> parse_numbers("450,3", "--mode1", "P,ON,OFF,CYCLES", "450,3,3,2")
Traceback (most recent call last):
...
skinsuction.commands._common.CLIError: --mode1 450,3: expected 4 numbers P,ON,OFF,CYCLES (e.g. 450,3,3,2), got 2
>>> sample_times(0.0, 1.0, 4).tolist()
[0.0, 0.25, 0.5, 0.75, 1.0]
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ._common import CLIError, fmt

__all__ = ["TimeProtocol", "TIME_OPTIONS", "DEFAULT_SAMPLE_HZ", "MAX_MBAR", "SWITCH_S",
           "parse_numbers",
           "protocol_from_args", "read_history", "sample_times", "solve_grid", "simulate_protocol",
           "time_csv", "rparams_text", "header_lines"]

#: the options that choose a time protocol (at most one, and not with a ramp option)
TIME_OPTIONS = ("mode1", "mode2", "history")

#: a Cutometer samples at 100 Hz
DEFAULT_SAMPLE_HZ = 100.0

#: the largest suction the model takes (a ramp's too); above it, a file's Pa
MAX_MBAR = 1000.0

#: s: each mode-1 switch is a linear ramp this long (the device's is not documented)
SWITCH_S = 0.01


@dataclass(frozen=True)
class TimeProtocol:
    """A suction history and the times its curve is sampled at.

    Attributes
    ----------
    kind : str
        ``"mode 1"``, ``"mode 2"`` or ``"history"``.
    label : str
        The ``# protocol:`` line, in the words of the shipped examples
        (``mode 1, 450 mbar, 3 s on / 3 s off, 2 cycles``).
    times_s, pressure_mbar : ndarray
        The suction, piecewise linear between these points (from 0 mbar).
    samples_s : ndarray
        The output times (``--sample-hz`` from the first time on).
    extra : tuple of str
        More ``#`` lines (a history file's path and SHA-256).
    """

    kind: str
    label: str
    times_s: np.ndarray
    pressure_mbar: np.ndarray
    samples_s: np.ndarray
    extra: tuple = ()


def parse_numbers(text: str, option: str, names: str, example: str = "") -> tuple:
    """The comma-separated numbers of an option such as ``--mode1 450,3,3,2``.

    Parameters
    ----------
    text : str
        What the user gave.
    option : str
        The option's flag, named in the error.
    names : str
        What the numbers are, e.g. ``"P,ON,OFF,CYCLES"`` (their count is expected).
    example : str
        A valid value, shown in the error.

    Returns
    -------
    tuple of float

    Raises
    ------
    CLIError
        Wrong count, or a field that is not a finite number.
    """
    fields = [f.strip() for f in str(text).split(",")]
    want = len(names.split(","))
    if len(fields) != want:
        raise CLIError(f"{option} {text}: expected {want} numbers {names}"
                       + (f" (e.g. {example})" if example else "") + f", got {len(fields)}")
    values = []
    for name, field in zip(names.split(","), fields):
        try:
            value = float(field)
        except ValueError:
            value = math.nan
        if not math.isfinite(value):
            raise CLIError(f"{option} {text}: {name} is not a number ({field!r})")
        values.append(value)
    return tuple(values)


def _cycle_protocol(args, option: str) -> tuple:
    """``(P, first s, second s, cycles)`` of ``--mode1`` or ``--mode2``, checked."""
    names = "P,ON,OFF,CYCLES" if option == "--mode1" else "P,RISE,FALL,CYCLES"
    text = getattr(args, option[2:])
    p, a, b, cycles = parse_numbers(text, option, names, "450,3,3,2")
    first, second = names.split(",")[1:3]
    if not 0 < p <= MAX_MBAR:
        raise CLIError(f"{option} {text}: P = {p:g} mbar must lie in (0, {MAX_MBAR:g}] "
                       "(a Cutometer applies up to about 500 mbar)")
    # ON and OFF must outlast mode 1's switch
    floor = SWITCH_S if option == "--mode1" else 0.0
    for name, value in ((first, a), (second, b)):
        if not value > floor:
            raise CLIError(f"{option} {text}: {name} = {value:g} s must be > {floor:g} s"
                           + (f" (each switch is a {SWITCH_S:g} s ramp)" if floor else ""))
    if cycles != int(cycles) or cycles < 1:
        raise CLIError(f"{option} {text}: CYCLES = {cycles:g} must be a whole number >= 1")
    return p, a, b, int(cycles)


def sample_times(start: float, end: float, hz: float) -> np.ndarray:
    """Times from ``start`` every ``1/hz`` s up to ``end`` (included if on the grid).

    Parameters
    ----------
    start, end : float
        The protocol's first and last time, s.
    hz : float
        The sampling rate, Hz.

    Returns
    -------
    ndarray
    """
    n = int(math.floor((end - start) * hz + 1e-9))
    return start + np.arange(n + 1) / hz


def protocol_from_args(args) -> TimeProtocol | None:
    """The time protocol the options give, None for a ramp.

    Parameters
    ----------
    args : argparse.Namespace
        ``mode1``, ``mode2``, ``history`` (at most one given) and ``sample_hz``
        (None: :data:`DEFAULT_SAMPLE_HZ`).

    Returns
    -------
    TimeProtocol or None

    Raises
    ------
    CLIError
        A malformed option, or fewer than 2 samples at ``--sample-hz``.
    """
    from skinsuction.viscoelastic import mode1_history, mode2_history

    hz = args.sample_hz or DEFAULT_SAMPLE_HZ
    extra = ()
    if args.mode1 is not None:
        p, on, off, cycles = _cycle_protocol(args, "--mode1")
        h = mode1_history(p, on_s=on, off_s=off, cycles=cycles, rise_s=SWITCH_S)
        kind, times, pressures = "mode 1", h.times_s, h.pressure_mbar
        label = (f"mode 1, {p:g} mbar, {on:g} s on / {off:g} s off, {cycles} "
                 f"cycle{'s' * (cycles > 1)}")
    elif args.mode2 is not None:
        p, rise, fall, cycles = _cycle_protocol(args, "--mode2")
        h = mode2_history(p, p / rise, fall_rate_mbar_s=p / fall, cycles=cycles)
        kind, times, pressures = "mode 2", h.times_s, h.pressure_mbar
        label = (f"mode 2, up to {p:g} mbar in {rise:g} s and down in {fall:g} s, {cycles} "
                 f"cycle{'s' * (cycles > 1)}")
    elif args.history is not None:
        times, pressures, extra = read_history(args.history)
        kind = "history"
        label = (f"history, {len(times)} points, {fmt(times[0])} to "
                 f"{fmt(times[-1])} s, up to {fmt(pressures.max())} mbar")
    else:
        return None
    samples = sample_times(float(times[0]), float(times[-1]), hz)
    if samples.size < 2:
        raise CLIError(f"--sample-hz {hz:g} gives {samples.size} sample over the "
                       f"{fmt(times[-1] - times[0])} s of the protocol; sample faster")
    return TimeProtocol(kind, label, np.asarray(times, float), np.asarray(pressures, float),
                        samples, extra)


def read_history(path) -> tuple:
    """A suction history from a CSV file: a ``time_s,pressure_mbar`` header, then rows.

    ``#`` lines and blank lines are skipped. Times (s) must increase strictly;
    suction (mbar) is positive, at most :data:`MAX_MBAR`, and 0 at the first time
    (the skin at rest).

    Parameters
    ----------
    path : str or path-like

    Returns
    -------
    (ndarray, ndarray, tuple of str)
        Times, pressures, and the ``#`` lines that record the file (path, SHA-256).

    Raises
    ------
    CLIError
        One line naming the file and the line: unreadable, no or a wrong header, a
        row of the wrong length, not a number, a time not after the one before, a
        negative or too large suction, fewer than 2 rows, not at rest at first.
    """
    from pathlib import Path

    from skinsuction._files import file_sha256

    try:
        lines = Path(path).read_text(encoding="utf-8-sig").splitlines()
    except (OSError, UnicodeDecodeError) as err:
        reason = getattr(err, "strerror", None) or err
        raise CLIError(f"--history {path}: cannot read ({reason})") from None
    header, rows = None, []
    for lineno, line in enumerate(lines, start=1):
        text = line.strip()
        if not text or text.startswith("#"):
            continue
        fields = [f.strip() for f in text.split(",")]
        if header is None:
            if sorted(fields) != ["pressure_mbar", "time_s"]:
                raise CLIError(f"{path}, line {lineno}: the header must be time_s,pressure_mbar "
                               f"(time in s, suction in mbar), not {text!r}")
            header = fields
            continue
        rows.append(_history_row(path, lineno, header, fields, rows))
    if len(rows) < 2:
        raise CLIError(f"{path}: a history needs a time_s,pressure_mbar header and at least 2 "
                       f"rows, found {len(rows)}")
    _, t, p = (np.array(c, float) for c in zip(*rows))
    if p[0] != 0:
        raise CLIError(f"{path}, line {rows[0][0]}: the suction must be 0 at the first time "
                       f"(the skin at rest), not {p[0]:g} mbar")
    if not p.max() > 0:
        raise CLIError(f"{path}: no suction above 0 mbar")
    return t, p, (f"# history_file: {path}", f"# history_sha256: {file_sha256(path)}")


def _history_row(path, lineno, header, fields, rows) -> tuple:
    """``(line, time, pressure)`` of one row, checked against the one before."""
    if len(fields) != 2:
        raise CLIError(f"{path}, line {lineno}: {len(fields)} fields, expected 2 "
                       "(time_s,pressure_mbar)" + (" (a decimal comma? use '.')"
                                                    if len(fields) > 2 else ""))
    row = {}
    for name, field in zip(header, fields):
        try:
            row[name] = float(field)
        except ValueError:
            row[name] = math.nan
        if not math.isfinite(row[name]):
            raise CLIError(f"{path}, line {lineno}, column {name!r}: not a number ({field!r})")
    t, p = row["time_s"], row["pressure_mbar"]
    if rows and t <= rows[-1][1]:
        raise CLIError(f"{path}, line {lineno}, column 'time_s': time {t:g} s is not after "
                       f"{rows[-1][1]:g} s on line {rows[-1][0]}; times must increase strictly")
    if p < 0:
        raise CLIError(f"{path}, line {lineno}, column 'pressure_mbar': suction {p:g} mbar is "
                       "negative; give the suction as positive mbar")
    if p > MAX_MBAR:
        raise CLIError(f"{path}, line {lineno}, column 'pressure_mbar': suction {p:g} mbar is "
                       f"above {MAX_MBAR:g} (Pa? 1 mbar = 100 Pa)")
    return lineno, t, p


def solve_grid(protocol: TimeProtocol) -> tuple:
    """The solver's times: the history's points and every sample, up to the last sample.

    Parameters
    ----------
    protocol : TimeProtocol

    Returns
    -------
    (ndarray, ndarray, ndarray)
        The times (s), the suction there (mbar) and the index of each sample among them.

    Examples
    --------
    >>> p = TimeProtocol("history", "", np.array([0.0, 0.3, 1.0]), np.array([0.0, 30, 30]),
    ...                  sample_times(0.0, 1.0, 2))
    >>> [v.tolist() for v in solve_grid(p)]
    [[0.0, 0.3, 0.5, 1.0], [0.0, 30.0, 30.0, 30.0], [0, 2, 3]]
    """
    # to the ns: a sample on a history's own point is that point, not a step of 1e-17 s
    samples = np.round(protocol.samples_s, 9)
    grid = np.union1d(np.round(protocol.times_s, 9), samples)
    grid = grid[grid <= samples[-1]]
    pressure = np.interp(grid, protocol.times_s, protocol.pressure_mbar)
    return grid, pressure, np.searchsorted(grid, samples)


def simulate_protocol(skin, probe_mm, protocol: TimeProtocol, refinement, progress=None):
    """Solve a time protocol on a skin; the curve at the sample times.

    The FE model in time (:func:`skinsuction.viscoelastic.simulate_history`), each
    layer with its spectrum, stepping through the history's points (graded after
    each switch in mode 1 and 2) and every sample time, so that each sample is an
    equilibrium of the solver, not an interpolation.

    Parameters
    ----------
    skin : skinsuction.model.Skin
    probe_mm : float
    protocol : TimeProtocol
    refinement : float
        The mesh density factor.
    progress : callable, optional
        ``progress(k, n, t_s)`` after each of the ``n`` solver times.

    Returns
    -------
    (skinsuction.viscoelastic.History, ndarray, ndarray)
        The solver's history (its own times), and the suction and deflection at
        the sample times (NaN after a stop).

    Raises
    ------
    CLIError
        Parameters the model refuses.
    """
    from skinsuction.model import ParameterError
    from skinsuction.viscoelastic import simulate_history

    grid, pressure, index = solve_grid(protocol)
    try:
        history = simulate_history(skin, grid, pressure, probe=probe_mm,
                                   mesh={"refinement": refinement}, progress=progress)
    except (ParameterError, ValueError) as err:
        raise CLIError(f"the model refused the parameters: {err}") from None
    return history, pressure[index], history.deflection_mm[index]


def header_lines(title: str, skin, probe_mm: float) -> list:
    """The first ``#`` lines of every ``simulate`` output: version and title, probe,
    the paper's two layers (if the skin is them), the skin as JSON, the bottom.

    Parameters
    ----------
    title : str
        What the curve is, e.g. ``"apex deflection M(p) of the suction test"``.
    skin : skinsuction.model.Skin
    probe_mm : float

    Returns
    -------
    list of str
    """
    import json

    from skinsuction import __version__
    from skinsuction.model import ParameterError

    lines = [f"# skinsuction simulate {__version__}: {title}", f"# probe_mm: {fmt(probe_mm)}"]
    try:  # the paper's two layers keep the header lines they always had
        v = skin.two_layer_values()
        lines += [f"# x1d_mpa: {fmt(v['x1d'])}", f"# x1h_mpa: {fmt(v['x1h'])}",
                  f"# x2d_mpa: {fmt(v['x2d'])}", f"# x2h_mpa: {fmt(v['x2h'])}",
                  f"# t_d_mm: {fmt(v['t_d'])}", f"# t_h_mm: {fmt(v['t_h'])}"]
    except ParameterError:
        pass
    return lines + [f"# skin: {json.dumps(skin.to_dict(), separators=(',', ':'))}",
                    f"# bottom: {skin.bottom}"]


def time_csv(skin, probe_mm, protocol: TimeProtocol, result, refinement, hz,
             measured_format=False) -> str:
    """The CSV text of a simulated time curve: ``#`` lines, then one row per sample.

    Parameters
    ----------
    skin : skinsuction.model.Skin
    probe_mm : float
    protocol : TimeProtocol
    result : tuple
        What :func:`simulate_protocol` returns.
    refinement, hz : float
        The mesh factor and the sampling rate, recorded in the ``#`` lines.
    measured_format : bool
        Write ``probe_mm,time_s,pressure_mbar,deflection_mm`` (the format ``rparams``,
        ``identify`` and ``diagnose`` read for time curves), the samples the solver
        reached only; else ``time_s,pressure_mbar,deflection_mm`` (NaN after a stop).

    Returns
    -------
    str
    """
    history, pressure, deflection = result
    reached = history.times_s[np.isfinite(history.deflection_mm)]
    lines = header_lines("apex deflection against time of the suction test", skin, probe_mm)
    lines += [
        f"# protocol: {protocol.label}", *protocol.extra,
        f"# sample_hz: {fmt(hz)}",
        f"# refinement: {fmt(refinement)}",
        f"# converged: {'true' if history.converged else 'false'}",
        f"# last_converged_s: {fmt(reached[-1])}",
        f"# reason: {' '.join(str(history.reason or '').split())}",
        f"# newton_iterations: {int(history.newton_iterations)}",
        f"# time_steps: {int(history.steps)}",
        f"# dofs: {int(history.dofs)}",
        f"# seconds: {float(history.seconds):.3f}",
    ]
    rows = zip(protocol.samples_s, pressure, deflection)
    if measured_format:
        # a measured file has no NaN rows: the curve stops where the solver stopped
        lines.append("probe_mm,time_s,pressure_mbar,deflection_mm")
        lines += [f"{fmt(probe_mm)},{fmt(t)},{fmt(p)},{fmt(m)}" for t, p, m in rows if m == m]
    else:
        lines.append("time_s,pressure_mbar,deflection_mm")
        lines += [f"{fmt(t)},{fmt(p)},{fmt(m)}" for t, p, m in rows]
    return "\n".join(lines) + "\n"


def rparams_text(measured_csv: str, ue_time_s: float = 0.1) -> str:
    """The R parameters of a simulated mode-1 curve, as ``skinsuction rparams`` prints them.

    The curve in the measured format is read by
    :func:`skinsuction.measured.load_time_curves` (the phases found as in a
    measured file), then :func:`skinsuction.measured.r_parameters`.

    Parameters
    ----------
    measured_csv : str
        :func:`time_csv` with ``measured_format=True``.
    ue_time_s : float
        When Ue and Ur are read after the onset and the release, s.

    Returns
    -------
    str
        A heading line and the table (Ue ... Ua in mm, R0-R9; one row per cycle).

    Raises
    ------
    CLIError
        The simulated curve does not read as a mode-1 curve (e.g. sampled too slowly).
    """
    import tempfile
    from pathlib import Path

    from skinsuction.measured import R_COLUMNS, MeasuredDataError, load_time_curves, r_parameters

    from .rparams import _table_text, r_heading

    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "simulated.csv"
        path.write_text(measured_csv, encoding="utf-8")
        try:
            (curve,) = load_time_curves(path).curves
        except MeasuredDataError as err:
            raise CLIError(f"--rparams: the simulated curve does not read as a time curve: "
                           f"{err.reason}") from None
    if curve.protocol != "mode 1":
        raise CLIError(f"--rparams: the simulated curve reads as {curve.protocol}, not mode 1 "
                       f"({'; '.join(curve.notes)}); sample faster (--sample-hz)")
    try:
        table = r_parameters(curve, ue_time_s=ue_time_s)
    except ValueError as err:
        raise CLIError(f"--rparams: {err}") from None
    table = table[[k for k in R_COLUMNS if k != "curve"]]  # one curve: no replicate id
    return r_heading(ue_time_s) + "\n" + _table_text(table) + "\n"
