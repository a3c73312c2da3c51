"""Performance figures quoted in the README are the committed bench snapshot's, and name its machine
(issue 22 item 4). ``make bench`` refreshes docs/bench/*.json; change the quote with it or this fails."""
from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _number(text: str) -> float:
    return float(text.replace(",", ""))


def test_readme_throughput_and_latency_are_the_snapshot_figures():
    bench = json.loads((ROOT / "docs" / "bench" / "analytical.json").read_text())
    readme = " ".join((ROOT / "README.md").read_text().split())
    m = re.search(r"does ([\d,]+) poses/s for the rigid detailed model and ([\d,]+) poses/s for the released "
                  r"model; single-pose latency ([\d.]+) ms \(on ([^,]+), one core", readme)
    assert m, "README must quote the analytical bench figures with their machine"
    # the README rounds to 2-3 significant figures: agree within 3 %
    assert _number(m.group(1)) == pytest.approx(bench["detailed_rigid_poses_per_s"], rel=0.03)
    assert _number(m.group(2)) == pytest.approx(bench["detailed_released_poses_per_s"], rel=0.03)
    assert float(m.group(3)) == pytest.approx(1e3 * bench["detailed_rigid_single_pose_latency_s"], rel=0.03, abs=0.005)
    assert m.group(4).strip() == bench["machine"].strip()


def test_calculix_side_by_side_table_is_the_snapshot():
    """docs/fe_contact.md's CalculiX table quotes docs/bench/calculix.json (issue 17), rounded to 2 decimals."""
    bench = json.loads((ROOT / "docs" / "bench" / "calculix.json").read_text())
    doc = (ROOT / "docs" / "fe_contact.md").read_text()
    section = doc[doc.index("### CalculiX side by side"):]
    rows = {line.split("|")[1].strip(): line.split("|")[2:5] for line in section.splitlines() if line.startswith("| ")}

    def pair(cell):
        return [float(v.replace("−", "-").replace("%", "").replace("*", "").strip()) for v in cell.split("/")]
    for row, key in (("approach", "approach_error_pct"), ("radius, contact-force moments (same extraction)", "radius_force_error_pct")):
        for cell, tag in zip(rows[row], ("femcheck", "femcheck_sphere", "ccx")):
            assert pair(cell) == pytest.approx([bench[f"{tag}_{key}_{F}N"] for F in (15, 50)], abs=0.006), (row, tag)
    walls = [float(c.split("s")[0]) for c in rows["wall time"]]
    assert walls == pytest.approx([bench["femcheck_wall_s"], bench["femcheck_sphere_wall_s"], bench["ccx_wall_s"]], abs=0.06)
    ratios = [float(c.strip().rstrip("×")) for c in rows["ccx / femcheck wall time"][:2]]
    assert ratios == pytest.approx([bench["wall_ratio_ccx_over_femcheck"], bench["wall_ratio_ccx_over_femcheck_sphere"]], abs=0.006)
