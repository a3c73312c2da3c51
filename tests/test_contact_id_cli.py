"""contact_specimen case kind and ``femcheck contact-id``: outputs and bad-input errors."""
import json
from pathlib import Path

import numpy as np
from typer.testing import CliRunner

from femcheck.case import load_case
from femcheck.cli import get_app, main
from femcheck.contact_id.bar_on_spring import Bar, natural_frequencies_Hz
from femcheck.errors import CaseError

CASE = "cases/contact_specimen.toml"


def _bar():
    b = load_case(CASE).bar
    return Bar(b.length_m, b.area_m2, b.material.E_Pa, b.material.density_kg_m3)


def test_case_loads_seed_dimensions():
    c = load_case(CASE)
    # seed 004 §4.3: 5 x 3 x 0.75 in, exact inch conversion
    assert np.allclose(c.specimen.dims_m, (5 * 0.0254, 3 * 0.0254, 0.75 * 0.0254), rtol=1e-12)


def test_case_errors_name_file_and_key(tmp_path):
    text = Path(CASE).read_text().replace("length_m = 0.5 ", "length_m = -0.5 ")
    p = tmp_path / "bad.toml"
    p.write_text(text)
    try:
        load_case(p)
    except CaseError as exc:
        assert "bad.toml" in str(exc) and "bar.length_m" in str(exc)
    else:
        raise AssertionError("negative length accepted")
    p.write_text(Path(CASE).read_text().replace('contact_faces = ["z-", "z+"]', 'contact_faces = ["top"]'))
    try:
        load_case(p)
    except CaseError as exc:
        assert "specimen.contact_faces" in str(exc)
    else:
        raise AssertionError("bad face accepted")


def test_cli_json_with_preloads(tmp_path):
    P = np.array([100.0, 200.0, 400.0, 800.0])
    k = 4.0e5 * P**0.9
    groups = ";".join(",".join(f"{v:.6f}" for v in natural_frequencies_Hz(_bar(), kk, 3)) for kk in k)
    png = tmp_path / "rel.png"
    res = CliRunner().invoke(get_app(), ["contact-id", CASE, "--frequencies", groups, "--preloads", "100,200,400,800",
                                         "--json", "-", "--plot", str(png)])
    assert res.exit_code == 0, res.output
    out = json.loads(res.output)
    ks = np.array([r["k_n_N_per_m"] for r in out["identified"]])
    # frequencies printed with 1e-6 Hz: k recovered to < 1e-6 relative; 1e-3 is the acceptance
    assert np.max(np.abs(ks / k - 1)) < 1e-3
    assert abs(out["preload_law"]["m"] - 0.9) < 1e-4
    assert png.stat().st_size > 10_000 and png.read_bytes()[:4] == b"\x89PNG"


def test_cli_bad_input_exits_2(capsys):
    assert main(["contact-id", CASE, "--frequencies", "abc"]) == 2
    assert "--frequencies" in capsys.readouterr().err
    assert main(["contact-id", CASE, "--frequencies", "1000", "--mode", "shear"]) == 2
    assert main(["contact-id", CASE, "--frequencies", "1000,2000;3000", "--preloads", "1,2,3"]) == 2
    assert main(["contact-id", CASE, "--frequencies", "99999"]) == 2  # outside mode-1 band
    assert main(["contact-id", "cases/haptic_6psu.toml", "--frequencies", "1000"]) == 2
