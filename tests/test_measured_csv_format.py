"""Measured-data CSV validation: errors name file, row and column;
the input is never modified."""
import hashlib

import numpy as np
import pytest

from femcheck.errors import MeasuredDataError
from femcheck.measured import read_measured_csv
from femcheck.measured.csv_format import format_measured_csv, parse_measured_csv

HEADER = "point,direction,trial,phase,load_N,fx_N,fy_N,fz_N,dx_mm,dy_mm,dz_mm\n"
GOOD = HEADER + "P0,+x,1,preload,5,5,0,0,0.09,0.00,0.00\nP0,+x,1,total,20,20,0,0,0.35,0.00,0.01\n"


def _err(text):
    with pytest.raises(MeasuredDataError) as ei:
        parse_measured_csv(text, "m.csv")
    return ei.value


def test_good_rows_are_parsed_to_si():
    d = parse_measured_csv(GOOD, "m.csv")
    assert len(d) == 2
    # mm -> m is an exact decimal scaling up to one rounding of the float product
    np.testing.assert_allclose(d.disp[1], [0.35e-3, 0.0, 0.01e-3], rtol=1e-12, atol=0)
    assert list(d.phase) == ["preload", "total"] and list(d.row) == [2, 3]


@pytest.mark.parametrize("text, row, column, words", [
    (HEADER.replace(",dz_mm", "") + "P0,+x,1,preload,5,5,0,0,0.09,0.00\n", 1, "dz_mm", "missing column"),
    (HEADER.replace("\n", ",extra\n") + "P0,+x,1,preload,5,5,0,0,0.09,0.00,0.00,1\n", 1, "extra", "unknown column"),
    (GOOD + "P1,+x,1,total,20,20,0,0,abc,0,0\n", 4, "dx_mm", "not a number"),
    (GOOD + "P1,+x,1,total,20,20,0,0,nan,0,0\n", 4, "dx_mm", "finite"),
    (GOOD + "P1,+w,1,total,20,20,0,0,0.1,0,0\n", 4, "direction", "+x, -x"),
    (GOOD + "P1,+x,0,total,20,20,0,0,0.1,0,0\n", 4, "trial", ">= 1"),
    (GOOD + "P1,+x,1.5,total,20,20,0,0,0.1,0,0\n", 4, "trial", "integer"),
    (GOOD + "P1,+x,1,loaded,20,20,0,0,0.1,0,0\n", 4, "phase", "preload, total, unload, sweep"),
    (GOOD + "P1,+y,1,total,20,20,0,0,0.1,0,0\n", 4, "fx_N", "requires 0"),
    (GOOD + "P0,+x,1,total,20,20,0,0,0.36,0,0\n", 4, "phase", "duplicate"),
    (GOOD + "P 1,+x,1,total,20,20,0,0,0.1,0,0\n", 4, "point", "pose id"),
    (GOOD + "P1,+x,1,total,20,20,0,0,0.1,0\n", 4, None, "fields"),
])
def test_bad_rows_name_row_and_column(text, row, column, words):
    e = _err(text)
    assert (e.row, e.column) == (row, column)
    assert words in str(e) and "m.csv" in str(e)


def test_empty_and_header_only_files_are_rejected():
    assert "empty" in str(_err(""))
    assert "no data rows" in str(_err(HEADER))


def test_named_load_case_needs_consistent_force():
    ok = parse_measured_csv(HEADER + "P0,diag,1,total,10,6,8,0,0.1,0.1,0\n", "m.csv")
    assert ok.direction[0] == "diag"
    e = _err(HEADER + "P0,diag,1,total,10,6,6,0,0.1,0.1,0\n")
    assert (e.row, e.column) == (2, "load_N")


def test_reading_never_modifies_the_file(tmp_path):
    p = tmp_path / "m.csv"
    p.write_text(GOOD)
    before = hashlib.sha256(p.read_bytes()).hexdigest(), p.stat().st_mtime_ns
    read_measured_csv(p)
    assert (hashlib.sha256(p.read_bytes()).hexdigest(), p.stat().st_mtime_ns) == before


def test_format_roundtrip_keeps_quantized_readings():
    disp = np.array([[0.09e-3, 0.0, -0.01e-3], [0.35e-3, 0.0, 0.0]])
    text = format_measured_csv(["P0", "P0"], ["+x", "+x"], [1, 1], ["preload", "total"], np.array([5.0, 20.0]),
                               np.array([[5.0, 0, 0], [20.0, 0, 0]]), disp, resolution_m=1e-5)
    d = parse_measured_csv(text)
    # printed with one digit beyond the 0.01 mm resolution: the round trip is exact to float rounding
    np.testing.assert_allclose(d.disp, disp, rtol=0, atol=1e-15)
