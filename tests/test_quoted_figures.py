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
