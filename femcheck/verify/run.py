"""One verification run: compute, check and render into a run folder.

The run covers the analytical models (both levels, both joint idealizations, 9 points x 3 directions)
and, for the requested FE ``levels``, the device FE model (``femcheck.verify.fe``): relative-error
tables analytical vs FE (``errors_simplified.csv`` / ``errors_detailed.csv``, column ``rel_error_pct``,
seed 000 Tables 2-3 layout in report.md/report.html), deflection comparison plots (Figs. 9-11, 17-19),
contributions (Fig. 23), VTU of the deformed models (first point, or every point) and a few PNGs of them. Every
run applies the analytical-FE error thresholds, the contact FE's idealization check and the mesh convergence (when
studied); ``--check`` adds the drift of the analytical and FE values against the baselines
(:mod:`femcheck.verify.check`).

Three jobs, three modules: :mod:`~femcheck.verify.compute` builds the tables as data,
:mod:`~femcheck.verify.check` does drift and thresholds (a list of ``Check``), :mod:`~femcheck.verify.render`
writes report.md and report.html from one list of ``Section`` objects, led by the verdict, plus
``verdict.json`` and ``junit.xml``. This module runs them in order and writes the files (CSV next to each table).

Adding a report section: append ``Section(title, rows, formats, note=..., part=...)`` to ``sections`` (``part``
one of :data:`femcheck.verify.render.PARTS`: the report is ordered by part, whatever the order of appending;
``informational=True`` labels a table no check reads); adding a check: append a ``Check`` to ``checks``.
"""
from __future__ import annotations

import dataclasses
import json
import logging
import time
from pathlib import Path

from femcheck.kinematics.points import point_set
from femcheck.report import tables
from femcheck.report.atomic import write_bytes_atomic, write_text_atomic
from femcheck.report.verify_plots import contributions_plot, deflection_plot
from femcheck.verify.analytical import JOINTS, LEVELS, AnalyticalVerification, run_analytical
from femcheck.verify.check import (ANALYTICAL_RTOL, ERROR_THRESHOLDS, FE_RTOL, Check, average_row,  # noqa: F401
                                   EXPECTED_CONTACT_IDEALIZATION, drift_check, drift_lines, followed_idealization,
                                   passed_or_failed, require_baseline_keys, threshold_checks, threshold_failures,
                                   update_baseline_file, verdict)
from femcheck.verify.compute import (baseline_values, conditioning_rows, contact_section, deflection_rows,  # noqa: F401
                                     error_rows, error_table, expected_fe_baseline_keys, fe_baseline_values, fe_error_rows,
                                     has_contact_joints, worst_errors)
from femcheck.verify.manifest import base_manifest
from femcheck.verify.render import Section, junit_xml, render_html, render_markdown, verdict_json, verdict_section

log = logging.getLogger(__name__)

_average = average_row


@dataclasses.dataclass(frozen=True)
class VerifyRun:
    """A finished verification run: its folder, the analytical and FE results, the drift lines, the files
    written (relative to ``out_dir``), wall time (s), threshold failures and every :class:`Check`."""

    out_dir: Path
    analytical: AnalyticalVerification
    drift: tuple[str, ...]          # baseline drift lines (analytical, then FE); empty = none
    files: tuple[str, ...]
    seconds: float
    fe: object = None               # FEVerification, or None when no FE level ran
    failures: tuple[str, ...] = ()  # failed threshold, idealization and mesh-convergence checks (details)
    checks: tuple = ()
    worst_errors: tuple = ()        # the largest mean analytical-FE errors (compute.worst_errors)

    @property
    def verdict(self):
        """The run's :class:`~femcheck.verify.check.Verdict` (PASS only if a check was evaluated and none failed)."""
        return verdict(self.checks, self.worst_errors)


DETAILED_FE_NOTE = (
    "Detailed FE: solid guideways and links (P2 super-elements), the actuation as its axial spring, the spherical "
    "joint's approach as a nonlinear Hertz spring (secant, solved exactly at 5 N and 20 N, eq. 1 protocol) and the U "
    "joint's translations as its springs. Joint rotations: tied ('rigid'), free ('released'), or 'contact': the "
    "frictional stick/slip law of a real ball-in-seat and pin-in-bore contact, with the ball's slip moment measured by "
    "the contact FE of the spherical joint alone (docs/verify.md). The contact joints enter the legs as condensed "
    "joint laws, not as contact pairs meshed into the whole device.")

DEFLECTION_FMT = {"deflection_mm": "{:.4f}", "dx_mm": "{:.4f}", "dy_mm": "{:.4f}", "dz_mm": "{:.4f}"}


def _fmt(rows, spec, skip=("point",)) -> dict:
    return {k: spec for k in rows[0] if k not in skip}


#: which points get a VTU of their deformed FE models: the first (default), every point, or none
VTU_CHOICES = ("first", "all", "none")


def vtu_points(vtu, points) -> tuple:
    """The points whose VTU is written for ``vtu`` (one of :data:`VTU_CHOICES`; True/False: 'first'/'none')."""
    which = {True: "first", False: "none"}.get(vtu, vtu)
    if which not in VTU_CHOICES:
        raise ValueError(f"vtu = {vtu!r}; expected one of {', '.join(VTU_CHOICES)}")
    return {"first": tuple(points[:1]), "all": tuple(points), "none": ()}[which]


def _fe_sections(case, av, fe, pts, put, sections: list, out, vtu: bool, pngs: bool, tilt=None) -> tuple[dict, dict]:
    """Tables, plots and files of the FE comparison; appends its sections; returns the error tables and timings."""
    from femcheck.fe_device.results import deformed_png, write_point_vtu
    tabs = {}
    t0 = time.perf_counter()
    sections.append(Section(f"Analytical vs FE (mesh {fe.mesh.level}: guideway {fe.mesh.guideway_m * 1e3:g} mm, "
                            f"link {fe.mesh.link_m * 1e3:g} mm, {fe.kind} parts)", part="errors"))
    for level in fe.levels:
        load = case.loads.simplified_test_N if level == "simplified" else case.loads.detailed_test_N
        variants = [None]
        note = ""
        if level == "detailed":
            note = DETAILED_FE_NOTE
            if has_contact_joints(fe):
                variants = ["contact", None]
        for fe_joints in variants:
            rows = fe_error_rows(av, fe, level, fe_joints)
            suffix = "_matched" if fe_joints is None and len(variants) > 1 else ""
            put(f"errors_{level}{suffix}.csv", tables.to_csv(rows))
            for j in JOINTS:
                tab = error_table(rows, j, fe.directions)
                tabs[(level, j, fe_joints or j)] = tab
                what = f"{j} joints" if fe_joints is None else f"{j} analytical joints vs contact-joint FE"
                sections.append(Section(f"{level.capitalize()} analytical vs {level} FE, {what} (relative error at "
                                        f"{load:g} N, %)", tuple(tab), _fmt(tab, "{:.2f}"), note=note, part="errors"))
                note = ""
        if level == "detailed" and has_contact_joints(fe):
            from femcheck.verify.contact_joints import moment_demand
            text, trows = contact_section(fe, tabs, moment_demand(case, pts), tilt)
            put("contact_joints.md", text + "\n" + (tables.to_markdown(trows) if trows else ""))
            if trows:
                put("contact_joint_tilt.csv", tables.to_csv(trows))
            sections.append(Section("Which idealization the contact FE follows", tuple(trows), note=text, part="errors",
                                    informational=True))
        for d in fe.directions:
            series = {f"{src} {j}": [(av.deflection(p, d, level, j) if src == "analytical" else fe.deflection(p, d, level, j))
                                     for p in fe.points] for j in JOINTS for src in ("analytical", "FE")}
            if (level, "contact", d) in fe.results[fe.points[0]].cases:
                series["FE contact"] = [fe.deflection(p, d, level, "contact") for p in fe.points]
            png = deflection_plot(list(fe.points), series, d, load)
            name = f"fe_deflection_{level}_{d[-1]}.png"
            put(name, png)
            sections.append(Section(f"{level.capitalize()} model, deflection along {d} at {load:g} N (seed 000 Figs. "
                                    f"{'9-11' if level == 'simplified' else '17-19'})", images=((name, png, f"{level} {d}"),)))
    if "detailed" in fe.levels:
        ratio = [{"point": p, **{f"{d} released/rigid": fe.deflection(p, d, "detailed", "released") /
                                 fe.deflection(p, d, "detailed", "rigid") for d in fe.directions},
                  **{f"{d} contact/released": fe.deflection(p, d, "detailed", "contact") /
                     fe.deflection(p, d, "detailed", "released") for d in fe.directions}} for p in fe.points]
        put("fe_detailed_released_over_rigid.csv", tables.to_csv(ratio))
        sections.append(Section("Detailed FE: released / rigid and contact / released deflection ratios", tuple(ratio),
                                _fmt(ratio, "{:.2f}"), informational=True))
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
    sections.append(Section(f"Contributions, {lvl} level: analytical vs FE (share of strain energy, seed 000 Fig. 23)",
                            tuple(crow), _fmt(crow, "{:.1f}", ("element",)),
                            images=(("fe_contributions.png", png, "FE contributions"),), informational=True))
    t_tables = time.perf_counter() - t0
    t0 = time.perf_counter()
    n_vtu = 0
    for p in vtu_points(vtu, fe.points):
        if write_point_vtu(out / "vtu" / f"{p}.vtu", fe.models[p], fe.results[p],
                           ((case.guideway.material.E_Pa, case.guideway.material.nu),
                            (case.proximal_link.material.E_Pa, case.proximal_link.material.nu))):
            put.files.append(f"vtu/{p}.vtu")
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
                sections.append(Section(f"Deformed FE model {p0}, {lvl_}, {j}, load {d}", images=((name, img, name),)))
    return tabs, {"tables_plots": round(t_tables, 3), "vtu_png": round(time.perf_counter() - t0, 3), "vtu_files": n_vtu}


def run_verify(case, out_dir, points=None, check: bool = False, baseline_path=None,
               update_baseline: bool = False, command: str = "femcheck verify", levels=(), mesh: str = "default",
               jobs: int = 1, progress=None, fe_kind: str = "solid", fe_baseline_path=None, vtu: str = "first",
               pngs: bool = True, convergence_point: str | None = None, joint_fe: bool = False,
               joint_mesh: str = "coarse") -> VerifyRun:
    """Run the verification on ``case`` and write everything into ``out_dir`` (atomically, file by file).

    ``levels``: FE levels to run ('simplified', 'detailed'; empty = analytical only); ``mesh``: FE mesh
    level; ``jobs``: worker processes for the FE solves; ``progress(description)`` after each FE solve and
    each later stage (the steps of :func:`femcheck.verify.progress_plan.plan`);
    ``fe_baseline_path``: FE baseline for --check / --update-baseline; ``vtu``: deformed FE models as VTU
    at the first point ('first'), at every point ('all') or nowhere ('none'); ``convergence_point``: run the
    mesh-convergence study (coarse/default/fine) at this point and write ``mesh_convergence.csv``;
    ``joint_fe``: run the contact FE of the ball alone under tilt (:func:`femcheck.verify.contact_joints.ball_tilt_study`)
    and give the device's contact joints its measured slip ratio (else the theoretical 1); measure the laws of
    both passive joints by their contact FE at ``joint_mesh`` over the device's force ladder
    (:mod:`femcheck.fe_device.joint_laws`) and use them in the detailed device FE instead of the closed forms
    (``manifest.json`` ``joint_laws``); run the joint table.
    """
    t0 = time.perf_counter()
    note = progress or (lambda desc: None)
    from femcheck.case.solver_options import apply as apply_solver_choice
    log.info("linear solver: %s", apply_solver_choice(case))
    out = Path(out_dir)
    pts = point_set(case, points)     # labels -> poses -> inverse kinematics, once for the whole run
    av = run_analytical(case, pts)
    t_analytical = time.perf_counter() - t0
    if check and not update_baseline:
        # a baseline without this configuration's keys is bad input, found before the FE runs (not drift)
        if baseline_path is not None:
            require_baseline_keys("analytical baseline", baseline_path, baseline_values(av))
        if levels and fe_baseline_path is not None:
            require_baseline_keys("FE baseline", fe_baseline_path, expected_fe_baseline_keys(
                av.points, av.directions, tuple(levels), mesh, fe_kind, joint_fe))
    files: list[str] = []

    def put(name: str, data):
        (write_bytes_atomic if isinstance(data, bytes) else write_text_atomic)(out / name, data)
        files.append(name)
    put.files = files
    fe = None
    tilt, friction, t_tilt = None, None, 0.0
    joint_laws, t_laws = None, 0.0
    if levels and joint_fe and "detailed" in levels:
        from femcheck.verify.fe import contact_joint_inputs
        cj = contact_joint_inputs(case, joint_mesh, progress)
        tilt, friction, joint_laws, t_tilt, t_laws = cj.tilt, cj.friction, cj.joint_laws, cj.tilt_s, cj.laws_s
    joint_results, t_joints = [], 0.0
    if levels and joint_fe and "detailed" in levels:
        # the joint table: contact FE of each passive joint at the coarse joint mesh
        # (≈ 25 s, docs/verify.md) vs its closed-form law
        from femcheck.fe_device.joint_check import check_joint
        from femcheck.fe_device.joint_fe import JOINTS as JOINT_TYPES
        tc = time.perf_counter()
        from femcheck.fe_device.joint_models import release
        joint_results = [check_joint(case, j, joint_mesh, "P0", progress=progress, use_cache=True) for j in JOINT_TYPES]
        release()
        t_joints = time.perf_counter() - tc
    if levels:
        from femcheck.verify.fe import run_fe
        fe = run_fe(case, pts, tuple(levels), mesh, jobs, kind=fe_kind, progress=progress, friction=friction,
                    joint_laws=joint_laws)

    sections: list[Section] = []
    rows = deflection_rows(av)
    put("analytical_deflections.csv", tables.to_csv(rows))
    put("analytical_deflections.md", tables.to_markdown(rows, DEFLECTION_FMT))
    for joints in JOINTS:
        er = error_rows(av, joints)
        put(f"simplified_vs_detailed_{joints}.csv", tables.to_csv(er))
        sections.append(Section(f"Simplified vs detailed analytical model, {joints} joints (relative error at "
                                f"{case.loads.detailed_test_N:g} N, %)", tuple(er), _fmt(er, "{:.1f}"),
                                informational=True))
    shares = {j: av.mean_contributions(j) for j in JOINTS}
    crow = [{"element": e, **{f"{j} %": 100 * shares[j][e] for j in JOINTS}} for e in shares[JOINTS[0]]]
    put("contributions.csv", tables.to_csv(crow))
    png = contributions_plot(shares)
    put("contributions.png", png)
    sections.append(Section("Contributions of the compliant elements, detailed model (share of the complementary "
                            "energy, %, seed 000 Fig. 23)", tuple(crow), _fmt(crow, "{:.1f}", ("element",)),
                            images=(("contributions.png", png, "contributions"),), informational=True))
    for d in av.directions:
        series = {f"{lvl} {j}": [av.deflection(p, d, lvl, j) * (case.loads.detailed_test_N / (case.loads.simplified_test_N if lvl == 'simplified' else case.loads.detailed_test_N))
                                 for p in av.points] for lvl in LEVELS for j in JOINTS}
        png = deflection_plot(av.points, series, d, case.loads.detailed_test_N)
        put(f"deflection_{d[-1]}.png", png)
        sections.append(Section(f"Deflection along {d} at {case.loads.detailed_test_N:g} N",
                                images=((f"deflection_{d[-1]}.png", png, f"deflection {d}"),)))
    cond_rows = conditioning_rows(av)
    put("conditioning.csv", tables.to_csv(cond_rows))
    sections.append(Section("Conditioning (Jacobian homogenized with R_p; K_T in twists [d; R_p theta], detailed, "
                            "worst direction)", tuple(cond_rows), _fmt(cond_rows, "{:.3f}"), informational=True))
    sections.append(Section("Raw deflections, analytical models (mm)", tuple(rows), DEFLECTION_FMT, part="raw",
                            informational=True, collapsed=True))

    fe_tabs, fe_times = ({}, {})
    contact_diag = None
    if fe is not None:
        fe_tabs, fe_times = _fe_sections(case, av, fe, pts, put, sections, out, vtu, pngs, tilt)
        note("tables, plots and VTU")
        fe_times["ball_tilt_contact_fe"] = round(t_tilt, 2)
        if joint_results:
            from femcheck.fe_device.joint_check import joint_table_rows, joint_table_section, write_joint_table_csv
            jrows = joint_table_rows(joint_results)
            put("joint_table.csv", write_joint_table_csv(jrows))
            put("joint_fe.json", json.dumps(joint_results, indent=2) + "\n")
            sections.append(joint_table_section(jrows))
            fe_times["joint_contact_fe"] = round(t_joints, 2)
        fe_times["joint_laws_contact_fe"] = round(t_laws, 2)
        if has_contact_joints(fe) and len(fe.points) == 9:
            from femcheck.verify.contact_diagnosis import diagnose_contact_fe
            tc = time.perf_counter()
            contact_diag = diagnose_contact_fe(case, fe, friction, jobs=jobs)
            put("contact_fe_experiment.csv", contact_diag.csv_text)
            put("contact_fe_truth.json", json.dumps(contact_diag.truth, indent=2) + "\n")
            put("contact_fe_diagnosis.json", json.dumps({"rigid": contact_diag.rigid, "released": contact_diag.released},
                                                        indent=2, default=float) + "\n")
            drows = contact_diag.summary_rows()
            sections.append(Section(
                "Contact FE as a virtual experiment, diagnosed (femcheck diagnose)", tuple(drows),
                {"held-out error before %": "{:.2f}", "held-out error after %": "{:.2f}"}, part="contact_diagnosis",
                informational=True,
                note="Readings of the paper's protocol (9 points, +-x +-y +-z, preload 5 N, 3 trials, noise, 0.01 mm "
                     "dials) from the detailed FE with contact joints, diagnosed against the detailed analytical model: "
                     "which cause femcheck names and the held-out error before and after (files contact_fe_*.csv/json)."))
            fe_times["contact_fe_diagnosis"] = round(time.perf_counter() - tc, 2)
            note("contact FE diagnosis")
    coverage = None
    if fe is not None and "detailed" in fe.levels and has_contact_joints(fe):
        # which elements does this FE check at all? mutate each law, reuse the condensed super-elements
        from femcheck.coverage import element_coverage
        tc = time.perf_counter()
        coverage = element_coverage(case, fe.points, mesh=mesh, fe_models=fe.models, joint_laws=fe.joint_laws)
        put("coverage.json", json.dumps(coverage.as_json(), indent=2, default=float) + "\n")
        cov_rows = coverage.rows()
        put("coverage.csv", tables.to_csv(cov_rows))
        caught = [r["element"] for r in cov_rows if r["detected"]]
        missed = [r["element"] for r in cov_rows if not r["detected"]]
        sections.append(Section(
            "Verification coverage: which element laws the FE checks",
            tuple(cov_rows), part="coverage",
            explain={"min_detectable_pct": "no mutation of this law is caught (the error does not move, or the FE "
                                           "reuses the law)"},
            note=f"The mutation of {coverage.mutation_pct:+g} % is caught for: {', '.join(caught) or 'none'}; not "
                 f"caught for: {', '.join(missed) or 'none'} (column detected). Covered share (caught at this "
                 f"mutation): {coverage.covered_share_pct:.1f} % of the detailed compliance; modelled by the FE on its "
                 f"own: {coverage.independent_share_pct:.1f} %. "
                 f"Each element's compliance law multiplied by {1 + coverage.mutation_pct / 100:g} where it is defined; "
                 f"analytical ({coverage.analytical_joints}) and FE ({coverage.fe_joints} joints) rerun at "
                 f"{', '.join(coverage.points)}. fe_source from behaviour: 'meshed' when the FE does not move with the "
                 "law (an independent model; 'contact_fe' where that model is the joint's contact FE), "
                 "'shared_closed_form' when it moves alike (the FE reuses the law: an "
                 "agreement there holds by construction). femcheck coverage, docs/verify.md."))
        fe_times["coverage"] = round(time.perf_counter() - tc, 2)
        note("coverage")
    checks: list[Check] = []
    conv_info, conv_check = None, None
    if convergence_point and levels:
        from femcheck.verify.convergence import CONVERGENCE_TOL, mesh_convergence
        tc = time.perf_counter()
        conv_rows, conv_mesh = mesh_convergence(case, convergence_point, tuple(levels), jobs=jobs, progress=progress,
                                                 known={mesh: fe} if fe_kind == "solid" else None,
                                                 joint_laws=joint_laws)
        put("mesh_convergence.csv", tables.to_csv(conv_rows))
        fmt = {k: "{:.4f}" if k.endswith("_mm") else "{:.2f}" for k in conv_rows[0] if k.endswith(("_mm", "_%"))}
        sections.append(Section(f"Mesh convergence at {convergence_point} (deflection mm; change vs the fine mesh %, "
                                f"acceptance: default within {100 * CONVERGENCE_TOL:.0f} %)", tuple(conv_rows), fmt,
                                extra_rows=tuple(conv_mesh), part="convergence"))
        worst = max(r["default_vs_fine_%"] for r in conv_rows)
        conv_info = {"point": convergence_point, "meshes": conv_mesh, "default_vs_fine_max_pct": round(worst, 4),
                     "seconds": round(time.perf_counter() - tc, 2)}
        ok = worst <= 100 * CONVERGENCE_TOL
        conv_check = passed_or_failed("mesh convergence", "convergence", ok,
                                      f"mesh convergence: default mesh {worst:.2f} % from the fine mesh "
                                      f"{'<=' if ok else '>'} {100 * CONVERGENCE_TOL:.0f} %")
    # checks: the analytical-FE thresholds, the idealization and the mesh convergence always; drift under --check
    if update_baseline and baseline_path is not None:
        update_baseline_file("analytical drift", baseline_values(av), baseline_path)
    if update_baseline and fe is not None and fe_baseline_path is not None:
        update_baseline_file("FE drift", fe_baseline_values(fe), fe_baseline_path)
    checks.append(drift_check("analytical drift", baseline_values(av), baseline_path, ANALYTICAL_RTOL, check,
                              update_baseline))
    drift = drift_lines(baseline_values(av), baseline_path, ANALYTICAL_RTOL) if checks[-1].status == "fail" else []
    if fe is not None:
        checks.append(drift_check("FE drift", fe_baseline_values(fe), fe_baseline_path, FE_RTOL, check, update_baseline))
        if checks[-1].status == "fail":
            drift += drift_lines(fe_baseline_values(fe), fe_baseline_path, FE_RTOL)
        checks += threshold_checks(fe_tabs)
    if conv_check is not None:
        checks.append(conv_check)
    failures = [c.detail for c in checks if c.status == "fail" and c.kind != "drift"]
    if drift:
        sections.append(Section("Regression check: drifted values", pre="\n".join(drift), part="errors"))
    worst_err = worst_errors(fe_tabs)
    seconds = time.perf_counter() - t0
    sections.append(verdict_section(checks, worst_err, seconds))
    title = f"femcheck verify — {case.meta.name}"
    intro = (f"case {case.source} (sha256 {case.sha256[:12]}), points {', '.join(av.points)}, "
             f"directions {', '.join(av.directions)}. Loads: simplified {case.loads.simplified_test_N:g} N, "
             f"detailed {case.loads.detailed_test_N:g} N (deflection along the load, mm).")
    put("report.md", render_markdown(title, intro, sections))
    put("report.html", render_html(title, intro, sections))
    put("verdict.json", verdict_json(checks, worst_err, seconds))
    put("junit.xml", junit_xml(checks, seconds))
    manifest = base_manifest(case, command)
    fe_info = "not run (no --level)"
    if fe is not None:
        fe_info = {"levels": list(fe.levels), "parts": fe.kind, "mesh_level": fe.mesh.level,
                   "mesh_sizes_m": {"guideway": fe.mesh.guideway_m, "link": fe.mesh.link_m},
                   "dofs": fe.dofs, "tets": fe.tets, "linear_solver": fe.linear_solver,
                   "solver_iterations": {"linear": 1, "hertz_fixed_point_max": fe.fixed_point_iterations},
                   "jobs": jobs, "timings_s": {**fe.timings_s, **fe_times},
                   "joint_laws": fe.joint_law_sources,
                   "joint_law_details": (joint_laws.details() if joint_laws is not None else
                                         {j: {"source": "closed_form", "why": "--no-joint-fe" if joint_fe is False
                                              else "no detailed FE level"} for j in fe.joint_law_sources}),
                   "mean_rel_error_pct": {f"{key[0]}/{key[1]}" + ("" if key[1] == key[-1] else f"_vs_{key[-1]}_fe"):
                                          {k.split()[0]: round(v, 3) for k, v in average_row(tab).items()}
                                          for key, tab in fe_tabs.items()},
                   "thresholds": ERROR_THRESHOLDS, "mesh_convergence": conv_info,
                   "contact_joints": {"expected": EXPECTED_CONTACT_IDEALIZATION, "follows": followed_idealization(fe_tabs),
                                      "diagnosis": contact_diag.summary_rows() if contact_diag else None,
                                      "tilt_slip_ratio": None if friction is None else friction.tilt_slip_ratio,
                                      "ball_tilt_fe": None if tilt is None else {
                                          k: {"moment_Nm": float(r.moment_Nm[-1]), "normal_force_N": float(r.normal_force_N[-1]),
                                              "unknowns": r.dofs, "iterations": r.iterations, "seconds": round(r.seconds, 2)}
                                          for k, r in tilt.items()}}}
    seconds = time.perf_counter() - t0
    manifest.update({"points": list(av.points), "directions": list(av.directions), "files": files + ["manifest.json"],
                     "timings_s": {"analytical": round(t_analytical, 4), "total": round(seconds, 4)},
                     "fe": fe_info,
                     "check": {"drift_checked": bool(check and not update_baseline),
                               "baseline": str(baseline_path) if baseline_path else None,
                               "fe_baseline": str(fe_baseline_path) if fe_baseline_path else None,
                               "drift": drift, "threshold_failures": failures},
                     "verdict": verdict(checks, worst_err).as_json()})
    put("manifest.json", json.dumps(manifest, indent=2) + "\n")
    note("report")
    return VerifyRun(out_dir=out, analytical=av, drift=tuple(drift), files=tuple(files), seconds=seconds, fe=fe,
                     failures=tuple(failures), checks=tuple(checks), worst_errors=tuple(worst_err))
