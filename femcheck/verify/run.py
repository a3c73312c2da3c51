"""One verification run: compute, write tables/plots/HTML/manifest into a run folder, check drift.

The run covers the analytical models (both levels, both joint idealizations, 9 points x 3 directions)
and, for the requested FE ``levels``, the device FE model (``femcheck.verify.fe``): relative-error
tables analytical vs FE (``errors_simplified.csv`` / ``errors_detailed.csv``, seed 000 Tables 2-3
layout in report.md/report.html), deflection comparison plots (Figs. 9-11, 17-19), contributions
(Fig. 23), VTU per point and a few PNGs of deformed models. ``--check`` fails on (a) analytical drift,
(b) FE drift against the FE baseline, (c) a mean analytical-FE error above its threshold.
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
#: FE values: deterministic structured meshes; direct solvers differ by round-off only (1e-10 seen),
#: so 1e-6 flags any real change of mesh, model or solver while tolerating BLAS/thread differences
FE_RTOL = 1e-6
#: mean relative error analytical vs FE per direction and idealization that --check accepts (issue 6)
ERROR_THRESHOLDS = {"simplified": 0.05, "detailed": 0.10}


@dataclasses.dataclass(frozen=True)
class VerifyRun:
    out_dir: Path
    analytical: AnalyticalVerification
    drift: tuple[str, ...]
    files: tuple[str, ...]
    seconds: float
    fe: object = None
    failures: tuple[str, ...] = ()


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


def fe_error_rows(av: AnalyticalVerification, fe, level: str, fe_joints: str | None = None) -> list[dict]:
    """Rows ``point, direction, joints, analytical_mm, fe_mm, rel_error`` (|FE - analytical| / |FE|) for one
    level; ``joints`` is the analytical idealization compared. The FE joints are ``fe_joints`` (e.g.
    ``contact``: the detailed FE with frictional contact joints, compared with both idealizations) or, by
    default, the same idealization as the analytical model (couplings tied / released)."""
    rows = []
    for j in JOINTS:
        for p in fe.points:
            for d in fe.directions:
                a, f = av.deflection(p, d, level, j), fe.deflection(p, d, level, fe_joints or j)
                rows.append({"point": p, "direction": d, "joints": j, "analytical_mm": a * 1e3, "fe_mm": f * 1e3,
                             "rel_error": abs(a - f) / abs(f)})
    return rows


def has_contact_joints(fe) -> bool:
    return "detailed" in fe.levels and ("detailed", "contact", fe.directions[0]) in fe.results[fe.points[0]].cases


def error_table(rows: list[dict], joints: str, directions) -> list[dict]:
    """Seed 000 Table 2/3 layout from :func:`fe_error_rows`: a row per point, a column per direction (%),
    then average and max."""
    sel = [r for r in rows if r["joints"] == joints]
    pts = list(dict.fromkeys(r["point"] for r in sel))
    err = {(r["point"], r["direction"]): r["rel_error"] for r in sel}
    out = [{"point": p, **{f"{d} error %": 100 * err[(p, d)] for d in directions}} for p in pts]
    out.append({"point": "average", **{f"{d} error %": 100 * np.mean([err[(p, d)] for p in pts]) for d in directions}})
    out.append({"point": "max", **{f"{d} error %": 100 * np.max([err[(p, d)] for p in pts]) for d in directions}})
    return out


def followed_idealization(tabs: dict) -> str | None:
    """The analytical idealization the contact FE follows: the one with the smaller mean error over the
    directions (``tabs`` keyed (level, joints) or (level, joints, fe_joints))."""
    cand = {j: np.mean(list(_average(tabs[("detailed", j, "contact")]).values()))
            for j in JOINTS if ("detailed", j, "contact") in tabs}
    return min(cand, key=cand.get) if cand else None


def _average(tab) -> dict:
    return {k: v for k, v in next(r for r in tab if r["point"] == "average").items() if k != "point"}


def fe_baseline_values(fe) -> dict[str, float]:
    """Baseline keys; the contact joints are keyed by where their ball slip moment came from (``contact``:
    theory, ρ = 1, ``--no-joint-fe``; ``contact_fe_slip``: the ball tilt contact FE)."""
    measured = fe.friction is not None and fe.friction.tilt_slip_ratio != 1.0

    def name(j):
        return "contact_fe_slip" if j == "contact" and measured else j
    return {f"fe/{fe.mesh.level}/{fe.kind}/{lvl}/{name(j)}/{p}/{d}/deflection_m": c.deflection_m
            for p, r in fe.results.items() for (lvl, j, d), c in r.cases.items()}


def threshold_failures(tables_by_level: dict) -> list[str]:
    """Lines for every (level, joints, direction) whose mean error exceeds ERROR_THRESHOLDS[level]: the
    matching idealizations, and the contact FE against the idealization it follows (issue 6)."""
    out = []
    followed = followed_idealization(tables_by_level)
    for key, tab in tables_by_level.items():
        level, joints = key[:2]
        contact = len(key) == 3 and key[2] != joints
        if contact and joints != followed:
            continue  # contact FE vs the idealization it does not follow: informative only
        name = f"{level}/{joints}" + (" vs contact FE" if contact else "")
        for k, v in _average(tab).items():
            if v > 100 * ERROR_THRESHOLDS[level]:
                out.append(f"{name} {k.split()[0]}: mean analytical-FE error {v:.2f} % > "
                           f"{100 * ERROR_THRESHOLDS[level]:.0f} %")
    return out


DETAILED_FE_NOTE = (
    "Detailed FE: solid guideways and links (P2 super-elements), the actuation as its axial spring, the spherical "
    "joint's approach as a nonlinear Hertz spring (secant, solved exactly at 5 N and 20 N, eq. 1 protocol) and the U "
    "joint's translations as its springs. Joint rotations: tied ('rigid'), free ('released'), or 'contact': the "
    "frictional stick/slip law of a real ball-in-seat and pin-in-bore contact, with the ball's slip moment measured by "
    "the contact FE of the spherical joint alone (docs/verify.md). The contact joints enter the legs as condensed "
    "joint laws, not as contact pairs meshed into the whole device.")


def contact_section(fe, tabs: dict, demand, tilt) -> tuple[str, list[dict]]:
    """Text and table rows saying which idealization the contact FE follows, by how much and why."""
    from femcheck.verify.contact_joints import deflection_ratios
    followed = followed_idealization(tabs)
    means = {j: _average(tabs[("detailed", j, "contact")]) for j in JOINTS}
    ratios = deflection_ratios(fe)
    d = demand.summary()
    text = (f"The detailed FE with contact joints follows the '{followed}' idealization: mean error "
            + "; ".join(f"vs {j} " + " / ".join(f"{v:.2f}" for v in means[j].values()) + " %" for j in JOINTS)
            + f" ({' / '.join(k.split()[0] for k in means[JOINTS[0]])}). Contact / released deflection "
            f"{ratios['contact_over_released']['mean']:.3f} on average "
            f"({ratios['contact_over_released']['min']:.3f}-{ratios['contact_over_released']['max']:.3f}); contact / rigid "
            f"{ratios['contact_over_rigid']['mean']:.2f}. Why: the rigid idealization asks each ball joint for a moment "
            f"{d['ball_min']:.1f}-{d['ball_median']:.1f} x (min-median) its friction capacity mu F R_b (mu = {d['mu_sp']:g}) and "
            f"each U-joint pin for {d['pin_min']:.1f}-{d['pin_median']:.1f} x mu F r_pin (mu = {d['mu_uj']:g}), so every "
            f"joint slides and carries only its friction moment; the remaining stiffening over 'released' is that "
            f"friction moment.")
    rows = []
    if tilt is not None:
        from femcheck.verify.contact_joints import tilt_slip_ratio
        mu = tilt["friction"].friction
        for name, r in tilt.items():
            rows.append({"ball tilt contact FE": name, "mu": r.friction, "normal_force_N": float(r.normal_force_N[-1]),
                         "tilt_mrad": float(r.rotation_rad[-1] * 1e3), "moment_Nmm": float(r.moment_Nm[-1] * 1e3),
                         f"moment / ({mu:g} F R_b)": float(abs(r.moment_Nm[-1]) / (mu * r.normal_force_N[-1] * r.ball_radius_m)),
                         "sliding_points_%": 100 * float(r.slip_fraction[-1]), "unknowns": r.dofs,
                         "seconds": round(r.seconds, 1)})
        text += (f" The contact FE of the ball alone (table below) shows the mechanism: without friction the ball "
                 f"transmits only a discretization remainder; with mu = {mu:g} the moment is "
                 f"{tilt_slip_ratio(tilt):.2f} x mu F R_b once that remainder is subtracted (the slip ratio the "
                 f"device's contact joints use).")
    return text, rows


def _write_fe(case, av, fe, put, page, md, out, vtu: bool, pngs: bool, tilt=None) -> tuple[dict, dict]:
    from femcheck.fe_device.results import deformed_png, write_point_vtu
    from femcheck.report.verify_plots import contributions_plot, deflection_plot
    tabs = {}
    t0 = time.perf_counter()
    page.heading(f"Analytical vs FE (mesh {fe.mesh.level}: guideway {fe.mesh.guideway_m * 1e3:g} mm, "
                 f"link {fe.mesh.link_m * 1e3:g} mm, {fe.kind} parts)")
    for level in fe.levels:
        load = case.loads.simplified_test_N if level == "simplified" else case.loads.detailed_test_N
        variants = [None]
        if level == "detailed":
            page.paragraph(DETAILED_FE_NOTE, "note")
            md.append(f"\n> {DETAILED_FE_NOTE}\n")
            if has_contact_joints(fe):
                variants = ["contact", None]
        for fe_joints in variants:
            rows = fe_error_rows(av, fe, level, fe_joints)
            suffix = "_matched" if fe_joints is None and len(variants) > 1 else ""
            put(f"errors_{level}{suffix}.csv", tables.to_csv(rows))
            for j in JOINTS:
                tab = error_table(rows, j, fe.directions)
                tabs[(level, j, fe_joints or j)] = tab
                fmt = {k: "{:.2f}" for k in tab[0] if k != "point"}
                what = f"{j} joints" if fe_joints is None else f"{j} analytical joints vs contact-joint FE"
                title = (f"{level.capitalize()} analytical vs {level} FE, {what} (relative error at {load:g} N, %)")
                md += [f"\n## {title}\n", tables.to_markdown(tab, fmt)]
                page.heading(title).raw(tables.to_html(tab, fmt))
        if level == "detailed" and has_contact_joints(fe):
            from femcheck.verify.contact_joints import moment_demand
            text, trows = contact_section(fe, tabs, moment_demand(case, fe.points), tilt)
            put("contact_joints.md", text + "\n" + (tables.to_markdown(trows) if trows else ""))
            md += ["\n## Which idealization the contact FE follows\n", text + "\n"]
            page.heading("Which idealization the contact FE follows").paragraph(text)
            if trows:
                put("contact_joint_tilt.csv", tables.to_csv(trows))
                md += ["\n", tables.to_markdown(trows)]
                page.raw(tables.to_html(trows))
        for d in fe.directions:
            series = {f"{src} {j}": [(av.deflection(p, d, level, j) if src == "analytical" else fe.deflection(p, d, level, j))
                                     for p in fe.points] for j in JOINTS for src in ("analytical", "FE")}
            if (level, "contact", d) in fe.results[fe.points[0]].cases:
                series["FE contact"] = [fe.deflection(p, d, level, "contact") for p in fe.points]
            png = deflection_plot(list(fe.points), series, d, load)
            put(f"fe_deflection_{level}_{d[-1]}.png", png)
            page.heading(f"{level.capitalize()} model, deflection along {d} at {load:g} N (seed 000 Figs. "
                         f"{'9-11' if level == 'simplified' else '17-19'})").image(png, f"{level} {d}")
    if "detailed" in fe.levels:
        ratio = [{"point": p, **{f"{d} released/rigid": fe.deflection(p, d, "detailed", "released") /
                                 fe.deflection(p, d, "detailed", "rigid") for d in fe.directions},
                  **{f"{d} contact/released": fe.deflection(p, d, "detailed", "contact") /
                     fe.deflection(p, d, "detailed", "released") for d in fe.directions}} for p in fe.points]
        put("fe_detailed_released_over_rigid.csv", tables.to_csv(ratio))
        rfmt = {k: "{:.2f}" for k in ratio[0] if k != "point"}
        page.heading("Detailed FE: released / rigid and contact / released deflection ratios").raw(tables.to_html(ratio, rfmt))
        md += ["\n## Detailed FE: released / rigid and contact / released deflection ratios\n", tables.to_markdown(ratio, rfmt)]
    from femcheck.chain import ELEMENT_NAMES, ELEMENTS
    lvl = "detailed" if "detailed" in fe.levels else "simplified"
    shares = {}
    for j in JOINTS + (("contact",) if lvl == "detailed" else ()):
        shares[f"analytical {j}"] = av.mean_contributions(j) if lvl == "detailed" and j in JOINTS else None
        c = fe.mean_contributions(lvl, j)
        shares[f"FE {j}"] = {ELEMENT_NAMES[e]: float(v) for e, v in zip(ELEMENTS, c)}
    shares = {k: v for k, v in shares.items() if v is not None}
    png = contributions_plot(shares)
    put("fe_contributions.png", png)
    crow = [{"element": e, **{f"{k} %": 100 * v[e] for k, v in shares.items()}} for e in next(iter(shares.values()))]
    put("fe_contributions.csv", tables.to_csv(crow))
    page.heading(f"Contributions, {lvl} level: analytical vs FE (share of strain energy, seed 000 Fig. 23)")
    page.raw(tables.to_html(crow, {k: "{:.1f}" for k in crow[0] if k != "element"})).image(png, "FE contributions")
    t_tables = time.perf_counter() - t0
    t0 = time.perf_counter()
    n_vtu = 0
    if vtu:
        for p in fe.points:
            if write_point_vtu(out / "vtu" / f"{p}.vtu", fe.models[p], fe.results[p],
                               ((case.guideway.material.E_Pa, case.guideway.material.nu),
                                (case.proximal_link.material.E_Pa, case.proximal_link.material.nu))):
                files_vtu = f"vtu/{p}.vtu"
                put.files.append(files_vtu)
                n_vtu += 1
    if pngs:
        p0 = fe.points[0]
        picks = [(lvl_, j, "+x") for lvl_ in fe.levels for j in JOINTS][:4]
        if "detailed" in fe.levels:
            picks.append(("detailed", "contact", "+x"))
        for lvl_, j, d in picks:
            img = deformed_png(fe.models[p0], fe.results[p0], f"u_{lvl_}_{j}_{d}", f"{p0} {lvl_} {j} {d}")
            if img:
                name = f"deformed_{p0}_{lvl_}_{j}_{d[-1]}.png"
                put(name, img)
                page.heading(f"Deformed FE model {p0}, {lvl_}, {j}, load {d}").image(img, name)
    return tabs, {"tables_plots": round(t_tables, 3), "vtu_png": round(time.perf_counter() - t0, 3), "vtu_files": n_vtu}


def run_verify(case, out_dir, points=None, check: bool = False, baseline_path=None,
               update_baseline: bool = False, command: str = "femcheck verify", levels=(), mesh: str = "default",
               jobs: int = 1, progress=None, fe_kind: str = "solid", fe_baseline_path=None, vtu: bool = True,
               pngs: bool = True, convergence_point: str | None = None, joint_fe: bool = False) -> VerifyRun:
    """Run the verification on ``case`` and write everything into ``out_dir`` (atomically, file by file).

    ``levels``: FE levels to run ('simplified', 'detailed'; empty = analytical only); ``mesh``: FE mesh
    level; ``jobs``: worker processes for the FE solves; ``progress(description)`` after each FE solve;
    ``fe_baseline_path``: FE baseline for --check / --update-baseline; ``convergence_point``: run the
    mesh-convergence study (coarse/default/fine) at this point and write ``mesh_convergence.csv``;
    ``joint_fe``: run the contact FE of the ball alone under tilt (:func:`femcheck.verify.contact_joints.ball_tilt_study`)
    and give the device's contact joints its measured slip ratio (else the theoretical 1).
    """
    t0 = time.perf_counter()
    from femcheck.case.solver_options import apply as apply_solver_choice
    log.info("linear solver: %s", apply_solver_choice(case))
    out = Path(out_dir)
    av = run_analytical(case, tuple(points) if points else ("P0", "P1", "P2", "P3", "P4", "P5", "P6", "P7", "P8"))
    t_analytical = time.perf_counter() - t0
    files: list[str] = []

    def put(name: str, data):
        (write_bytes_atomic if isinstance(data, bytes) else write_text_atomic)(out / name, data)
        files.append(name)
    put.files = files
    fe = None
    tilt, friction, t_tilt = None, None, 0.0
    if levels and joint_fe and "detailed" in levels:
        from femcheck.fe_device.joint_friction import joint_friction
        from femcheck.verify.contact_joints import ball_tilt_study, tilt_slip_ratio
        tc = time.perf_counter()
        tilt = ball_tilt_study(case, progress)
        friction = joint_friction(case, tilt_slip_ratio=tilt_slip_ratio(tilt))
        t_tilt = time.perf_counter() - tc
    if levels:
        from femcheck.verify.fe import run_fe
        fe = run_fe(case, av.points, tuple(levels), mesh, jobs, kind=fe_kind, progress=progress, friction=friction)

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

    fe_tabs, fe_times = ({}, {})
    contact_diag = None
    if fe is not None:
        fe_tabs, fe_times = _write_fe(case, av, fe, put, page, md, out, vtu, pngs, tilt)
        fe_times["ball_tilt_contact_fe"] = round(t_tilt, 2)
        if has_contact_joints(fe) and len(fe.points) == 9:
            from femcheck.verify.contact_diagnosis import diagnose_contact_fe
            tc = time.perf_counter()
            contact_diag = diagnose_contact_fe(case, fe, friction)
            put("contact_fe_experiment.csv", contact_diag.csv_text)
            put("contact_fe_truth.json", json.dumps(contact_diag.truth, indent=2) + "\n")
            put("contact_fe_diagnosis.json", json.dumps({"rigid": contact_diag.rigid, "released": contact_diag.released},
                                                        indent=2, default=float) + "\n")
            drows = contact_diag.summary_rows()
            dfmt = {"held-out error before %": "{:.2f}", "held-out error after %": "{:.2f}"}
            title = "Contact FE as a virtual experiment, diagnosed (femcheck diagnose, issue 7)"
            md += [f"\n## {title}\n", tables.to_markdown(drows, dfmt)]
            page.heading(title).paragraph(
                "Readings of the paper's protocol (9 points, +-x +-y +-z, preload 5 N, 3 trials, noise, 0.01 mm dials) "
                "from the detailed FE with contact joints, diagnosed against the detailed analytical model: which "
                "cause femcheck names and the held-out error before and after (files contact_fe_*.csv/json).").raw(
                tables.to_html(drows, dfmt))
            fe_times["contact_fe_diagnosis"] = round(time.perf_counter() - tc, 2)
    conv_info = None
    if convergence_point and levels:
        from femcheck.verify.convergence import CONVERGENCE_TOL, mesh_convergence
        tc = time.perf_counter()
        conv_rows, conv_mesh = mesh_convergence(case, convergence_point, tuple(levels), jobs=jobs, progress=progress,
                                                 known={mesh: fe} if fe_kind == "solid" else None)
        put("mesh_convergence.csv", tables.to_csv(conv_rows))
        fmt = {k: "{:.4f}" if k.endswith("_mm") else "{:.2f}" for k in conv_rows[0] if k.endswith(("_mm", "_%"))}
        title = (f"Mesh convergence at {convergence_point} (deflection mm; change vs the fine mesh %, "
                 f"acceptance: default within {100 * CONVERGENCE_TOL:.0f} %)")
        md += [f"\n## {title}\n", tables.to_markdown(conv_rows, fmt), "\n", tables.to_markdown(conv_mesh)]
        page.heading(title).raw(tables.to_html(conv_rows, fmt)).raw(tables.to_html(conv_mesh))
        worst = max(r["default_vs_fine_%"] for r in conv_rows)
        conv_info = {"point": convergence_point, "meshes": conv_mesh, "default_vs_fine_max_pct": round(worst, 4),
                     "seconds": round(time.perf_counter() - tc, 2)}
        if check and worst > 100 * CONVERGENCE_TOL:
            conv_fail = f"mesh convergence: default mesh {worst:.2f} % from the fine mesh > {100 * CONVERGENCE_TOL:.0f} %"
        else:
            conv_fail = None
    else:
        conv_fail = None
    drift: list[str] = []
    failures = threshold_failures(fe_tabs) if check else []
    if conv_fail:
        failures.append(conv_fail)
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
    if fe is not None and fe_baseline_path is not None:
        fe_current = fe_baseline_values(fe)
        if update_baseline:
            merged = dict(load_baseline(fe_baseline_path) or {})
            merged.update(fe_current)
            save_baseline(fe_baseline_path, merged)
        elif check:
            base = load_baseline(fe_baseline_path)
            if base is None:
                drift.append(f"FE baseline {fe_baseline_path} not found (create it with --update-baseline)")
            else:
                subset = {k: v for k, v in base.items() if k in fe_current}
                drift += compare(fe_current, subset, FE_RTOL) if subset else \
                    [f"FE baseline {fe_baseline_path} has none of these keys"]
    if check:
        page.heading("Regression check")
        page.paragraph("no drift against the baseline" if not drift else f"{len(drift)} value(s) drifted:")
        if drift:
            page.raw("<pre>" + "\n".join(drift) + "</pre>")
        if fe is not None:
            page.paragraph("all mean analytical-FE errors within their thresholds "
                           f"({', '.join(f'{k} {100 * v:.0f} %' for k, v in ERROR_THRESHOLDS.items())})"
                           if not failures else f"{len(failures)} threshold(s) exceeded:")
            if failures:
                page.raw("<pre>" + "\n".join(failures) + "</pre>")
    put("report.md", "".join(md))
    put("report.html", page.render())
    seconds = time.perf_counter() - t0
    manifest = base_manifest(case, command)
    fe_info = "not run (no --level)"
    if fe is not None:
        fe_info = {"levels": list(fe.levels), "parts": fe.kind, "mesh_level": fe.mesh.level,
                   "mesh_sizes_m": {"guideway": fe.mesh.guideway_m, "link": fe.mesh.link_m},
                   "dofs": fe.dofs, "tets": fe.tets, "linear_solver": fe.linear_solver,
                   "solver_iterations": {"linear": 1, "hertz_fixed_point_max": fe.fixed_point_iterations},
                   "jobs": jobs, "timings_s": {**fe.timings_s, **fe_times},
                   "mean_rel_error_pct": {f"{key[0]}/{key[1]}" + ("" if key[1] == key[-1] else f"_vs_{key[-1]}_fe"):
                                          {k.split()[0]: round(v, 3) for k, v in _average(tab).items()}
                                          for key, tab in fe_tabs.items()},
                   "thresholds": ERROR_THRESHOLDS, "mesh_convergence": conv_info,
                   "contact_joints": {"follows": followed_idealization(fe_tabs),
                                      "diagnosis": contact_diag.summary_rows() if contact_diag else None,
                                      "tilt_slip_ratio": None if friction is None else friction.tilt_slip_ratio,
                                      "ball_tilt_fe": None if tilt is None else {
                                          k: {"moment_Nm": float(r.moment_Nm[-1]), "normal_force_N": float(r.normal_force_N[-1]),
                                              "unknowns": r.dofs, "iterations": r.iterations, "seconds": round(r.seconds, 2)}
                                          for k, r in tilt.items()}}}
    manifest.update({"points": list(av.points), "directions": list(av.directions), "files": files + ["manifest.json"],
                     "timings_s": {"analytical": round(t_analytical, 4), "total": round(seconds, 4)},
                     "fe": fe_info,
                     "check": {"baseline": str(baseline_path) if baseline_path else None,
                               "fe_baseline": str(fe_baseline_path) if fe_baseline_path else None,
                               "drift": drift, "threshold_failures": failures} if check else None})
    put("manifest.json", json.dumps(manifest, indent=2) + "\n")
    return VerifyRun(out_dir=out, analytical=av, drift=tuple(drift), files=tuple(files), seconds=seconds, fe=fe,
                     failures=tuple(failures))
