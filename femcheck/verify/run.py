"""One verification run: compute, write tables/plots/HTML/manifest into a run folder, check drift.

Today the run covers the analytical models (both levels, both joint idealizations, 9 points x 3
directions); the FE comparison plugs in here (``errors_simplified.csv`` / ``errors_detailed.csv``).
"""
from __future__ import annotations

import dataclasses
import json
import logging
import time
from pathlib import Path

import numpy as np

from femcheck.report import tables
from femcheck.report.atomic import write_bytes_atomic, write_text_atomic
from femcheck.report.html_page import HtmlPage
from femcheck.report.verify_plots import contributions_plot, deflection_plot
from femcheck.verify.analytical import JOINTS, LEVELS, AnalyticalVerification, run_analytical
from femcheck.verify.baseline import compare, load_baseline, save_baseline
from femcheck.verify.manifest import base_manifest

log = logging.getLogger(__name__)

#: analytical values may only drift by round-off (the model is closed-form)
ANALYTICAL_RTOL = 1e-9


@dataclasses.dataclass(frozen=True)
class VerifyRun:
    out_dir: Path
    analytical: AnalyticalVerification
    drift: tuple[str, ...]
    files: tuple[str, ...]
    seconds: float


def deflection_rows(av: AnalyticalVerification) -> list[dict]:
    return [{"point": r.point, "direction": r.direction, "level": r.level, "joints": r.joints, "load_N": r.load_N,
             "deflection_mm": r.deflection_m * 1e3, "dx_mm": r.twist[0] * 1e3, "dy_mm": r.twist[1] * 1e3,
             "dz_mm": r.twist[2] * 1e3} for r in av.rows]


def error_rows(av: AnalyticalVerification, joints: str) -> list[dict]:
    """Seed 000 Table 2/3 layout: a row per point, a column per direction (%), then average and max."""
    err = av.simplified_vs_detailed(joints)
    rows = [{"point": p, **{f"{d} error %": 100 * err[(p, d)] for d in av.directions}} for p in av.points]
    rows.append({"point": "average", **{f"{d} error %": 100 * np.mean([err[(p, d)] for p in av.points]) for d in av.directions}})
    rows.append({"point": "max", **{f"{d} error %": 100 * np.max([err[(p, d)] for p in av.points]) for d in av.directions}})
    return rows


def baseline_values(av: AnalyticalVerification) -> dict[str, float]:
    return {f"analytical/{r.level}/{r.joints}/{r.point}/{r.direction}/deflection_m": r.deflection_m for r in av.rows}


def run_verify(case, out_dir, points=None, check: bool = False, baseline_path=None,
               update_baseline: bool = False, command: str = "femcheck verify") -> VerifyRun:
    """Run the verification on ``case`` and write everything into ``out_dir`` (atomically, file by file)."""
    t0 = time.perf_counter()
    out = Path(out_dir)
    av = run_analytical(case, tuple(points) if points else ("P0", "P1", "P2", "P3", "P4", "P5", "P6", "P7", "P8"))
    t_analytical = time.perf_counter() - t0
    files: list[str] = []

    def put(name: str, data):
        (write_bytes_atomic if isinstance(data, bytes) else write_text_atomic)(out / name, data)
        files.append(name)

    rows = deflection_rows(av)
    put("analytical_deflections.csv", tables.to_csv(rows))
    put("analytical_deflections.md", tables.to_markdown(rows, {"deflection_mm": "{:.4f}", "dx_mm": "{:.4f}", "dy_mm": "{:.4f}", "dz_mm": "{:.4f}"}))
    page = HtmlPage(f"femcheck verify — {case.meta.name}")
    page.paragraph(f"case {case.source} (sha256 {case.sha256[:12]}), points {', '.join(av.points)}, "
                   f"directions {', '.join(av.directions)}. Loads: simplified {case.loads.simplified_test_N:g} N, "
                   f"detailed {case.loads.detailed_test_N:g} N (deflection along the load, mm).", "note")
    md = [f"# femcheck verify — {case.meta.name}\n", f"case `{case.source}` sha256 `{case.sha256[:12]}`\n"]
    for joints in JOINTS:
        er = error_rows(av, joints)
        put(f"simplified_vs_detailed_{joints}.csv", tables.to_csv(er))
        fmt = {k: "{:.1f}" for k in er[0] if k != "point"}
        md += [f"\n## Simplified vs detailed analytical model, {joints} joints (relative error at "
               f"{case.loads.detailed_test_N:g} N, %)\n", tables.to_markdown(er, fmt)]
        page.heading(f"Simplified vs detailed analytical model — {joints} joints (relative error, %)")
        page.raw(tables.to_html(er, fmt))
    shares = {j: av.mean_contributions(j) for j in JOINTS}
    crow = [{"element": e, **{f"{j} %": 100 * shares[j][e] for j in JOINTS}} for e in shares[JOINTS[0]]]
    put("contributions.csv", tables.to_csv(crow))
    md += ["\n## Mean contributions, detailed model (%, CONVENTIONS.md §7)\n", tables.to_markdown(crow, {f"{j} %": "{:.1f}" for j in JOINTS})]
    png = contributions_plot(shares)
    put("contributions.png", png)
    page.heading("Contributions of the compliant elements (seed 000 Fig. 23)").raw(tables.to_html(crow, {f"{j} %": "{:.1f}" for j in JOINTS})).image(png, "contributions")
    for d in av.directions:
        series = {f"{lvl} {j}": [av.deflection(p, d, lvl, j) * (case.loads.detailed_test_N / (case.loads.simplified_test_N if lvl == 'simplified' else case.loads.detailed_test_N))
                                 for p in av.points] for lvl in LEVELS for j in JOINTS}
        png = deflection_plot(av.points, series, d, case.loads.detailed_test_N)
        put(f"deflection_{d[-1]}.png", png)
        page.heading(f"Deflection along {d} at {case.loads.detailed_test_N:g} N").image(png, f"deflection {d}")
    cond_rows = [{"point": p, "cond_J_h": float(av.jacobian_condition[k]),
                  **{f"cond_K_T_{j}": float(av.stiffness_condition[j][k]) for j in JOINTS},
                  "slider_min_mm": float(av.sliders_m[k].min() * 1e3), "slider_max_mm": float(av.sliders_m[k].max() * 1e3)}
                 for k, p in enumerate(av.points)]
    put("conditioning.csv", tables.to_csv(cond_rows))
    page.heading("Conditioning (Jacobian homogenized with R_p; K_T in twists [d; R_p theta], detailed, worst direction)")
    page.raw(tables.to_html(cond_rows, {k: "{:.3f}" for k in cond_rows[0] if k != "point"}))
    page.heading("Deflections (mm)").raw(tables.to_html(rows, {"deflection_mm": "{:.4f}", "dx_mm": "{:.4f}", "dy_mm": "{:.4f}", "dz_mm": "{:.4f}"}))

    drift: list[str] = []
    current = baseline_values(av)
    if baseline_path is not None:
        if update_baseline:
            save_baseline(baseline_path, current)
        elif check:
            base = load_baseline(baseline_path)
            if base is None:
                drift = [f"baseline {baseline_path} not found (create it with --update-baseline)"]
            else:
                subset = {k: v for k, v in base.items() if k in current}
                drift = compare(current, subset, ANALYTICAL_RTOL) if subset else [f"baseline {baseline_path} has none of these keys"]
    if check:
        page.heading("Regression check")
        page.paragraph("no drift against the baseline" if not drift else f"{len(drift)} value(s) drifted:")
        if drift:
            page.raw("<pre>" + "\n".join(drift) + "</pre>")
    put("report.md", "".join(md))
    put("report.html", page.render())
    seconds = time.perf_counter() - t0
    manifest = base_manifest(case, command)
    manifest.update({"points": list(av.points), "directions": list(av.directions), "files": files + ["manifest.json"],
                     "timings_s": {"analytical": round(t_analytical, 4), "total": round(seconds, 4)},
                     "fe": "not run: the FE verification is not available yet",
                     "check": {"baseline": str(baseline_path) if baseline_path else None, "drift": drift} if check else None})
    put("manifest.json", json.dumps(manifest, indent=2) + "\n")
    return VerifyRun(out_dir=out, analytical=av, drift=tuple(drift), files=tuple(files), seconds=seconds)
