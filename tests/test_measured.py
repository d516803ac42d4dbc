"""Loading measured curves: valid files load, every bad file gets one clear error."""

import os
import tempfile

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from skinsuction.measured import MeasuredDataError, load_measured

HEADER = "probe_mm,pressure_mbar,deflection_mm"


def _write(tmp_path, text, name="m.csv", encoding="utf-8"):
    path = tmp_path / name
    if isinstance(text, bytes):
        path.write_bytes(text)
    else:
        path.write_bytes(text.encode(encoding))
    return path


def _curve_rows(probe=6, pressures=(0, 20, 40, 60, 80, 100), curve=None, scale=0.008):
    rows = []
    for p in pressures:
        row = f"{probe},{p},{scale * p:.4f}"
        rows.append(row + (f",{curve}" if curve is not None else ""))
    return rows


# ------------------------------------------------------------------ valid files
def test_loads_two_probes_replicates_and_metadata(tmp_path):
    lines = [
        "# subject: S01",
        "# site : volar forearm",
        "# free comment without key",
        HEADER + ",curve",
        *_curve_rows(6, curve="A"),
        "",
        *_curve_rows(6, curve="B", scale=0.009),
        *_curve_rows(2, pressures=(0, 50, 100), curve="A", scale=0.004),
    ]
    data = load_measured(_write(tmp_path, "\n".join(lines) + "\n"),
                         available_probes=[2.0, 6.0], pressure_range_mbar=(0, 100))
    assert data.probes == (2.0, 6.0)
    assert data.metadata == {"subject": "S01", "site": "volar forearm"}
    assert data.comments == ("subject: S01", "site : volar forearm", "free comment without key")
    assert [(c.probe_mm, c.curve, len(c)) for c in data.curves] == [
        (6.0, "A", 6), (6.0, "B", 6), (2.0, "A", 3)]
    assert data.curves[1].first_line == 12  # counts comments and blank lines
    b = data.curve(6, "B")
    np.testing.assert_allclose(b.deflection_mm, 0.009 * b.pressure_mbar, atol=1e-4)
    with pytest.raises(KeyError):
        data.curve(6)  # two replicates: ambiguous


def test_bom_crlf_quotes_whitespace_and_column_order(tmp_path):
    text = '\ufeff"deflection_mm", probe_mm ,pressure_mbar\r\n0,6,0\r\n 0.5 ,6, 50\r\n0.8,6,100\r\n'
    data = load_measured(_write(tmp_path, text))
    c = data.curve(6)
    assert c.pressure_mbar.tolist() == [0, 50, 100]
    assert c.deflection_mm.tolist() == [0, 0.5, 0.8]
    assert c.curve == ""


# ------------------------------------------------------------------ bad files
BAD = {
    # name: (text, line, column, words in the message)
    "missing column": ("probe_mm,pressure_mbar\n6,0\n6,10\n", 1, "deflection_mm", "missing"),
    "extra column": (HEADER + ",temperature\n6,0,0,20\n", 1, "temperature", "unexpected"),
    "repeated column": ("probe_mm,pressure_mbar,deflection_mm,probe_mm\n", 1, "probe_mm", "twice"),
    "semicolons": ("probe_mm;pressure_mbar;deflection_mm\n6;0;0\n", 1, None, "';'"),
    "unit in column name": ("probe_mm,pressure_Pa,deflection_mm\n", 1, "pressure_Pa", "mbar"),
    "only comments": ("# subject: S01\n\n", 3, None, "no header"),
    "empty": ("", 1, None, "no header"),
    "no data": (HEADER + "\n", 2, None, "no data"),
    "too few fields": (HEADER + "\n6,0,0\n6,10\n", 3, None, "found 2 fields, expected 3"),
    "decimal comma": (HEADER + "\n6,0,0\n6,10,0,05\n", 3, None, "decimal comma"),
    "not a number": (HEADER + "\n6,0,0\n6,ten,0.1\n", 3, "pressure_mbar", "not a number"),
    "nan": (HEADER + "\n6,0,0\n6,10,nan\n", 3, "deflection_mm", "not finite"),
    "inf": (HEADER + "\n6,0,0\n6,-inf,0.1\n", 3, "pressure_mbar", "not finite"),
    "overflow": (HEADER + "\n6,0,0\n6,1e999,0.1\n", 3, "pressure_mbar", "too large"),
    "empty value": (HEADER + "\n6,0,0\n,10,0.1\n", 3, "probe_mm", "empty"),
    "hex": (HEADER + "\n6,0,0\n6,0x10,0.1\n", 3, "pressure_mbar", "not a number"),
    "zero probe": (HEADER + "\n0,0,0\n", 2, "probe_mm", "positive"),
    "empty curve id": (HEADER + ",curve\n6,0,0,A\n6,10,0.1,\n", 3, "curve", "empty"),
    "one point": (HEADER + "\n6,10,0.1\n", 2, None, "1 point"),
    "repeated pressure": (HEADER + "\n6,0,0\n6,10,0.1\n6,10,0.12\n", 4, "pressure_mbar", "repeats line 3"),
    "decreasing pressure": (HEADER + "\n6,0,0\n6,20,0.1\n6,10,0.12\n", 4, "pressure_mbar", "lower than"),
    "second curve without id": (HEADER + "\n6,0,0\n6,20,0.1\n6,0,0\n", 4, "pressure_mbar", "curve"),
    "negative pressure": (HEADER + "\n6,-100,0.5\n6,0,0\n", 2, "pressure_mbar", "negative"),
    "Pa": (HEADER + "\n6,0,0\n6,5000,0.4\n6,10000,0.7\n", 4, "pressure_mbar", "looks like Pa"),
    "bar": (HEADER + "\n6,0,0\n6,0.05,0.4\n6,0.1,0.7\n", 4, "pressure_mbar", "looks like bar or kPa"),
    "no suction": (HEADER + "\n6,0,0\n6,0,0.1\n", 3, "pressure_mbar", "repeats"),
    "µm": (HEADER + "\n6,0,0\n6,50,400\n6,100,700\n", 4, "deflection_mm", "looks like µm"),
    "metres": (HEADER + "\n6,0,0\n6,50,0.0004\n6,100,0.0007\n", 4, "deflection_mm", "metres"),
    "negative deflection": (HEADER + "\n6,0,0\n6,50,-0.4\n6,100,-0.7\n", 4, "deflection_mm", "negative"),
    "probe not simulated": (HEADER + "\n6,0,0\n6,50,0.3\n4,0,0\n4,50,0.2\n", 4, "probe_mm", "not in the simulated space"),
    "pressure beyond space": (HEADER + "\n6,0,0\n6,100,0.4\n6,150,0.7\n", 4, "pressure_mbar", "outside the simulated range"),
}


@pytest.mark.parametrize("name", sorted(BAD))
def test_each_bad_case_is_named_with_file_line_and_column(tmp_path, name):
    text, line, column, words = BAD[name]
    path = _write(tmp_path, text)
    with pytest.raises(MeasuredDataError) as info:
        load_measured(path, available_probes=[2, 6], pressure_range_mbar=(0, 100))
    err = info.value
    message = str(err)
    assert "\n" not in message
    assert message.startswith(str(path))
    assert (err.line, err.column) == (line, column), message
    assert f"line {line}" in message
    if column is not None:
        assert f"column '{column}'" in message
    assert words in message


def test_not_utf8_names_the_line(tmp_path):
    path = _write(tmp_path, (HEADER + "\n6,0,0\n6,10,0.1 \xb5m\n").encode("latin-1"))
    with pytest.raises(MeasuredDataError, match=r"line 3: not UTF-8"):
        load_measured(path)


def test_missing_file_is_a_measured_data_error(tmp_path):
    with pytest.raises(MeasuredDataError, match="cannot read"):
        load_measured(tmp_path / "nope.csv")


def test_is_a_value_error():
    assert issubclass(MeasuredDataError, ValueError)


def test_pressure_range_and_probe_checks_are_optional(tmp_path):
    path = _write(tmp_path, HEADER + "\n4,0,0\n4,150,0.5\n")
    assert load_measured(path).curve(4).pressure_mbar.tolist() == [0, 150]


# ------------------------------------------------------- property-based tests
def _assert_loads_or_clean_error(text_or_bytes):
    """Load from a fresh file: either a consistent result or a located one-line error."""
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "prop.csv")
        data = text_or_bytes if isinstance(text_or_bytes, bytes) else text_or_bytes.encode("utf-8", "surrogatepass")
        with open(path, "wb") as f:
            f.write(data)
        try:
            result = load_measured(path, available_probes=[2, 6], pressure_range_mbar=(0, 100))
        except MeasuredDataError as err:
            message = str(err)
            assert path in message
            assert err.line is not None and err.line >= 1
            assert f"line {err.line}" in message
            assert "\n" not in message and "\r" not in message
            return None
    for c in result.curves:
        assert c.probe_mm in (2.0, 6.0)
        assert len(c) >= 2
        assert np.all(np.diff(c.pressure_mbar) > 0)
        assert np.all(np.isfinite(c.deflection_mm))
        assert c.pressure_mbar.min() >= 0 and c.pressure_mbar.max() <= 100
    return result


PROPS = settings(max_examples=150, deadline=None,
                 suppress_health_check=[HealthCheck.too_slow])


@PROPS
@given(st.binary(max_size=300))
def test_random_bytes(data):
    _assert_loads_or_clean_error(data)


@PROPS
@given(st.text(alphabet=st.sampled_from(list("0123456789.,-e#:\n\r \tnaifx;\"") + ["µ", "\x00"]),
               max_size=200))
def test_random_csv_like_text(text):
    _assert_loads_or_clean_error(text)


@PROPS
@given(st.text(max_size=40), st.integers(0, 8))
def test_garbage_header_or_line(garbage, where):
    lines = [HEADER, *_curve_rows(6)]
    lines.insert(min(where, len(lines)), garbage)
    _assert_loads_or_clean_error("\n".join(lines))


VALID_LINES = [HEADER + ",curve", *_curve_rows(6, curve="A"), *_curve_rows(2, curve="A", scale=0.004)]


@PROPS
@given(st.sets(st.integers(0, 3), max_size=3))
def test_random_column_drops(dropped):
    rows = [line.split(",") for line in VALID_LINES]
    kept = [[f for i, f in enumerate(r) if i not in dropped] for r in rows]
    result = _assert_loads_or_clean_error("\n".join(",".join(r) for r in kept))
    if dropped & {0, 1, 2}:
        assert result is None  # a required column is gone


@PROPS
@given(st.integers(1, len(VALID_LINES) - 1), st.integers(0, 2),
       st.sampled_from(["nan", "NaN", "inf", "-inf", "", "x", "1e400", "--1", "1.2.3"]))
def test_random_bad_cells(row, column, value):
    rows = [line.split(",") for line in VALID_LINES]
    rows[row][column] = value
    assert _assert_loads_or_clean_error("\n".join(",".join(r) for r in rows)) is None


@PROPS
@given(st.permutations(list(range(1, len(VALID_LINES)))))
def test_shuffled_rows(order):
    lines = [VALID_LINES[0]] + [VALID_LINES[i] for i in order]
    result = _assert_loads_or_clean_error("\n".join(lines))
    # per curve, the file order must be increasing in pressure
    by_curve = {}
    for i in order:
        probe, p = VALID_LINES[i].split(",")[:2]
        by_curve.setdefault(probe, []).append(float(p))
    increasing = all(np.all(np.diff(v) > 0) for v in by_curve.values())
    assert (result is not None) == increasing


@PROPS
@given(st.lists(st.tuples(st.sampled_from([2.0, 6.0, 4.0]),
                          st.floats(-50, 200, allow_nan=False),
                          st.floats(-1, 30, allow_nan=False)), max_size=12),
       st.booleans())
def test_random_numeric_tables(rows, with_curve):
    header = HEADER + (",curve" if with_curve else "")
    body = [f"{a!r},{b!r},{c!r}" + (",r1" if with_curve else "") for a, b, c in rows]
    _assert_loads_or_clean_error("\n".join([header, *body]))


# ------------------------------------------------------------------ plausibility (per probe)
def _curve_file(tmp_path, rows, probe=6):
    path = tmp_path / "c.csv"
    path.write_text("probe_mm,pressure_mbar,deflection_mm\n"
                    + "".join(f"{probe},{p:g},{m:g}\n" for p, m in rows))
    return path


GOOD = [(0, 0.0), (25, 0.21), (50, 0.38), (75, 0.52), (100, 0.64)]


@pytest.mark.parametrize("rows, probe, words", [
    ([(p, 0.0) for p, _ in GOOD], 6, "all 0"),
    ([(0, 0), (25, 0.5), (50, 0.4), (75, 0.3), (100, 0.2)], 6, "falls with the pressure"),
    ([(p, m + 0.3) for p, m in GOOD], 6, "zeroed at 0 mbar"),
    ([(p, 15 * m / 0.64) for p, m in GOOD], 2, "looks like µm"),  # 2 mm curve in µm, max 15
    ([(p, 0.0015 * m / 0.64) for p, m in GOOD], 6, "looks like metres"),
    ([(0, 0), (-50, 0.2), (-100, 0.4)], 6, "negative; give the suction as positive"),
    ([(p, 4.0 * m / 0.64) for p, m in GOOD], 2, "beyond the 2 mm aperture"),
])
def test_implausible_curves_are_one_line_errors(tmp_path, rows, probe, words):
    with pytest.raises(MeasuredDataError) as err:
        load_measured(_curve_file(tmp_path, rows, probe))
    assert words in str(err.value) and "\n" not in str(err.value)


def test_a_noisy_but_real_curve_passes_and_a_low_pressure_curve_is_a_warning(tmp_path):
    rng = np.random.default_rng(0)
    p = np.arange(0.0, 101.0, 2.0)
    m = 0.004 * (p / 100) + rng.normal(0, 0.002, p.size)  # stiff skin: 4 µm dome, 2 µm noise
    m[0] = 0.0
    data = load_measured(_curve_file(tmp_path, zip(p, m), probe=2))
    assert data.warnings == ()
    kpa = load_measured(_curve_file(tmp_path, [(p / 10, m) for p, m in GOOD]))
    assert any("multiply by 10" in w for w in kpa.warnings)


def test_a_huge_file_fails_fast_with_a_located_error(tmp_path):
    path = tmp_path / "huge.csv"
    with open(path, "w") as f:
        f.write("probe_mm,pressure_mbar,deflection_mm\n")
        for k in range(20_001):
            f.write(f"6,{k * 0.01:.2f},{k * 1e-5:.5f}\n")
    with pytest.raises(MeasuredDataError) as err:
        load_measured(path)
    assert "more than 2000 points" in str(err.value) and "line 2002" in str(err.value)


def test_a_million_rows_load_in_bounded_memory_or_fail_fast(tmp_path):
    """1e6 rows under a 3 GB address-space cap: as one curve it fails at its 2001st point;
    as 500 replicate curves of 2000 points it loads (issue: 24 GB RSS before)."""
    import subprocess
    import sys

    one, many = tmp_path / "one.csv", tmp_path / "many.csv"
    p = np.tile(np.arange(2000) * 0.05, 500)
    m = p * 0.006
    with open(one, "w") as f:
        f.write("probe_mm,pressure_mbar,deflection_mm\n")
        f.writelines(f"6,{k * 1e-4:.4f},{k * 6e-7:.7f}\n" for k in range(1_000_000))
    with open(many, "w") as f:
        f.write("probe_mm,pressure_mbar,deflection_mm,curve\n")
        f.writelines(f"6,{a:.2f},{b:.4f},R{k // 2000}\n" for k, (a, b) in enumerate(zip(p, m)))
    code = (
        "import resource, sys, time\n"
        "resource.setrlimit(resource.RLIMIT_AS, (3 * 2**30, 3 * 2**30))\n"
        "from skinsuction.measured import load_measured, MeasuredDataError\n"
        "t = time.perf_counter()\n"
        "try:\n"
        "    d = load_measured(sys.argv[1]); print('loaded', len(d.curves))\n"
        "except MeasuredDataError as e:\n"
        "    print('error', e)\n"
        "print('seconds', time.perf_counter() - t)\n"
        "print('maxrss_mb', resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)\n"
    )
    out = {}
    for path in (one, many):
        res = subprocess.run([sys.executable, "-c", code, str(path)], capture_output=True,
                             text=True, timeout=300)
        assert res.returncode == 0, res.stderr[-2000:]
        out[path.name] = res.stdout
    assert "error" in out["one.csv"] and "more than 2000 points" in out["one.csv"]
    assert "line 2002" in out["one.csv"]
    assert "loaded 500" in out["many.csv"]
    rss = float(out["many.csv"].split("maxrss_mb")[1])
    assert rss < 3 * 1024


def test_a_rejection_crosses_a_process_pool():
    # study and benchmark workers send exceptions back by pickle: the error must come
    # back whole (it once broke the pool: its __init__ needs four arguments)
    import pickle

    from skinsuction.measured import MeasuredDataError

    err = MeasuredDataError("m.csv", 7, "deflection_mm", "not a number: 'abc'")
    back = pickle.loads(pickle.dumps(err))
    assert type(back) is MeasuredDataError and str(back) == str(err)
    assert (back.path, back.line, back.column, back.reason) == ("m.csv", 7, "deflection_mm",
                                                                 "not a number: 'abc'")


def test_a_small_noisy_curve_loads_and_a_falling_one_does_not(tmp_path):
    # a 2 mm curve of stiff skin rises 19 µm over 100 mbar; with 4.7 µm of noise its
    # running maximum falls by more than 20 µm somewhere (the old rule's floor), yet it
    # rises: the curve's own noise (third differences) sets the tolerance
    p = np.arange(0.0, 101.0, 2.0)
    clean = 0.196e-3 * p
    rng = np.random.default_rng(301004)
    for _ in range(200):  # a draw whose largest fall exceeds 20 µm
        m = clean + rng.normal(0, 4.7e-3, p.size)
        m[0] = 0.0
        if (np.maximum.accumulate(m) - m).max() > 0.020:
            break
    else:
        pytest.fail("no draw with a fall above 20 µm")
    rows = [HEADER, *(f"2,{a:g},{b:.5f}" for a, b in zip(p, m))]
    data = load_measured(_write(tmp_path, "\n".join(rows) + "\n"))
    assert data.curves[0].deflection_mm.size == p.size
    # the same noise on a curve that falls after 50 mbar (sign flipped there): refused
    bent = np.where(p <= 50, 2e-3 * p, 2e-3 * (100 - p)) + rng.normal(0, 4.7e-3, p.size)
    bent[0] = 0.0
    rows = [HEADER, *(f"2,{a:g},{b:.5f}" for a, b in zip(p, bent))]
    with pytest.raises(MeasuredDataError, match="falls with the pressure"):
        load_measured(_write(tmp_path, "\n".join(rows) + "\n", name="bent.csv"))
