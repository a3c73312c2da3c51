"""The ``parallel_device`` side of ``femcheck stiffness``: the same table layout as the 6-PSU path,
computed by :mod:`femcheck.parallel`."""
from __future__ import annotations

import numpy as np
import typer
from rich.table import Table

from femcheck.cli import console
from femcheck.cli._common import emit_json, parse_vector, print_contributions, print_directional_stiffness
from femcheck.cli._common import select_pose as _select_pose
from femcheck.parallel.chain_model import evaluate
from femcheck.parallel.device import POINT_LABELS, test_points
from femcheck.parallel.leg_kinematics import actuation_jacobian, solve_legs


def select_pose(case, point: str | None, pose: str | None, *, deg: bool = False, mm: bool = False) -> tuple[np.ndarray, str]:
    """The (1, 6) pose from --point or --pose (m, rad unless ``mm`` / ``deg``) over the device's own test points."""
    return _select_pose(case, point, pose, points=test_points(case), labels=POINT_LABELS, deg=deg, mm=mm)


def stiffness(case, case_path, *, model: str, joints: str | None, point, pose, wrench, json_out, deg: bool = False,
              mm: bool = False) -> None:
    P, label = select_pose(case, point, pose, deg=deg, mm=mm)
    dev = case.device
    state = solve_legs(dev, P)
    if not state.ok[0]:
        leg = next(i for i, s in enumerate(state.legs) if not s.ok[0])
        raise typer.BadParameter(f"pose {label} is not reachable by leg {leg} ({dev.legs[leg].name!r}): "
                                 "no inverse-kinematics solution inside the joint limits")
    W = parse_vector(wrench, 6, "--wrench") if wrench else np.array([0, 0, case.loads.test_N, 0, 0, 0.0])
    r = evaluate(dev, P, W, model=model, joints=joints or case.model.joint_rotations, state=state)
    contrib = {name: float(r.contributions[0, j]) for j, name in enumerate(r.element_names)
               if r.element_energy[0, :, j].any()}
    work = float(W @ r.twist[0])
    leg_contrib = {leg.name: {name: float(r.element_energy[0, i, j] / work) for j, name in enumerate(r.element_names)
                              if r.element_energy[0, i, j]} for i, leg in enumerate(dev.legs)} if work > 0 else {}
    q_act = [float(s.q[0, leg.actuated_dof]) for leg, s in zip(dev.legs, state.legs)]
    Ja = actuation_jacobian(dev, state)[0]
    sv = np.linalg.svd(Ja[:, :3], compute_uv=False)
    cond = float(sv[0] / sv[-1])
    if json_out:
        emit_json({"case": case.source, "pose": P[0].tolist(), "point": label, "model": r.model, "joints": r.joints,
                   "wrench": W.tolist(), "K": r.K[0].tolist(), "deflection": r.twist[0].tolist(),
                   "contributions": contrib, "leg_contributions": leg_contrib, "actuated_joints": q_act,
                   "translational_condition_number": cond},
                  json_out, inputs=[case_path])
        return
    con = console()
    con.print(f"[bold]{case.meta.name}[/] — {label}, model [bold]{r.model}[/], joints [bold]{r.joints}[/], "
              f"wrench {np.array2string(W, precision=3)} (N, N m)")
    kt = Table(title="TCP stiffness K (SI: N/m | N/rad ; N m/m | N m/rad)")
    for h in ("", "dx", "dy", "dz", "rx", "ry", "rz"):
        kt.add_column(h, justify="right")
    K = np.where(np.abs(r.K[0]) < 1e-12 * np.abs(r.K[0]).max(), 0.0, r.K[0])  # rounding noise shown as 0
    for i, h in enumerate(("Fx", "Fy", "Fz", "Mx", "My", "Mz")):
        kt.add_row(h, *[f"{v:.4g}" for v in K[i]])
    con.print(kt)
    t = r.twist[0]
    con.print(f"deflection: d = [{t[0]*1e3:.5f}, {t[1]*1e3:.5f}, {t[2]*1e3:.5f}] mm, "
              f"theta = [{t[3]*1e3:.5f}, {t[4]*1e3:.5f}, {t[5]*1e3:.5f}] mrad")
    print_directional_stiffness(con, r)
    con.print(f"{dev.n_legs} legs; actuated joints (from home, m or rad) {np.array2string(np.array(q_act), precision=4)}; "
              f"condition number of the actuation Jacobian's translational part {cond:.3f}")
    print_contributions(con, contrib, "contributions (share of deflection energy)")


#: a parallel device's beam FE uses the analytical element laws, so analytical and FE agree to rounding; a
#: relative deflection error above this (%) means the chain algebra or the FE assembly is wrong
VERIFY_THRESHOLD_PCT = 1e-6


def _own_laws_text(laws) -> str:
    """What the solid-link FE's detailed level takes instead of the analytical drive and contact laws."""
    drives = "drives from their elements" if laws.drives else "the analytical drive springs"
    joints = "joint contacts from their contact FE" if laws.joints else "the analytical contact springs"
    return f"{drives}, {joints}"


def verify(case, case_path, *, levels, points, out, force, check, mesh: str = "default", joint_fe: bool = True,
           joint_mesh: str = "coarse") -> None:
    """Analytical vs FE at the test points: the solid-link FE (``mesh`` level) in errors_<level>.csv / .md, the
    beam-link FE (the chain algebra, to round-off) in errors_<level>_beam.csv / .md, a summary on screen;
    exit 1 above the verify thresholds (solid: simplified 5 %, detailed 10 % mean per level, idealization and
    direction; beam: 1e-6 %), with or without ``check`` (a parallel device has no drift baselines); the verdict
    opens and closes the terminal output and is written to ``verdict.json``. The solid-link FE's detailed level
    takes the drives from their elements and, with ``joint_fe``, the joints from their contact FE (``joint_mesh``,
    cached); the beam-link FE keeps the analytical laws (its check is the chain algebra)."""
    from femcheck.parallel.verification import verify_device
    from femcheck.report.atomic import write_text_atomic
    from femcheck.report.run_folder import prepare_run_folder

    labels = None
    if points:
        labels = [p.strip().upper() for p in points.split(",") if p.strip()]
        bad = [p for p in labels if p not in POINT_LABELS]
        if bad:
            raise typer.BadParameter(f"--points: {bad[0]!r}; expected P0..P8")
    levels = levels or ("simplified", "detailed")
    from femcheck.verify.check import ERROR_THRESHOLDS
    prepare_run_folder(out, "femcheck verify", force=force, inputs=[case_path])
    con = console()
    n_models = len(levels) * 2 * len(case.loads.directions)
    from femcheck.cli import progress as progress_bar
    # progress on stderr: stdout opens and closes with the verdict
    with progress_bar("FE models (solid links, then beam links)", 2 * n_models, console(stderr=True)) as bar:
        from femcheck.parallel.beam_fe import fe_laws_of
        laws = fe_laws_of(case, joint_fe and "detailed" in levels, joint_mesh)
        solid = verify_device(case, labels, levels, parts="solid", mesh=mesh, progress=lambda d: bar.advance(1, d),
                              fe_laws=laws)
        beam = verify_device(case, labels, levels, progress=lambda d: bar.advance(1, d))
    from femcheck.verify.check import passed_or_failed, verdict as make_verdict
    checks, worst = [], []
    sections = []
    printed = []
    for level in levels:
        for res, suffix, parts in ((solid, "", "solid"), (beam, "_beam", "beam")):
            rows = [r for r in res.rows if r["level"] == level]
            write_text_atomic(out / f"errors_{level}{suffix}.csv", type(res)(rows=tuple(rows)).to_csv())
            write_text_atomic(out / f"errors_{level}{suffix}.md", type(res)(rows=tuple(rows)).to_markdown())
        rows = [r for r in solid.rows if r["level"] == level]
        limit = 100 * ERROR_THRESHOLDS[level]
        title = (f"{case.meta.name}: {level} analytical vs FE with solid links (mesh {mesh}; deflection mm "
                 f"under {case.loads.test_N:g} N; threshold {limit:g} % mean)")
        t = Table(title=title)
        summary = []
        for c in ("joints", "direction", "points", "analytical_mm (min..max)", "mean |rel error| % (solid)",
                  "max |rel error| % (solid)", "max |rel error| % (beam)"):
            t.add_column(c, justify="right")
        for jt in ("rigid", "released"):
            for d in case.loads.directions:
                sel = [r for r in rows if r["joints"] == jt and r["direction"] == d]
                bsel = [r for r in beam.rows if r["level"] == level and r["joints"] == jt and r["direction"] == d]
                a = [r["analytical_mm"] for r in sel]
                mean = sum(abs(r["rel_error_pct"]) for r in sel) / len(sel)
                worst.append({"table": f"{level}/{jt}", "direction": d, "mean_error_pct": round(mean, 3)})
                checks.append(passed_or_failed(f"threshold {level}/{jt} {d}", "threshold", mean <= limit,
                                               f"{level}/{jt} {d}: mean |error| {mean:.2f} % "
                                               f"{'<=' if mean <= limit else '>'} {limit:g} % (solid links)"))
                t.add_row(jt, d, str(len(sel)), f"{min(a):.5f}..{max(a):.5f}", f"{mean:.3f}",
                          f"{max(abs(r['rel_error_pct']) for r in sel):.3f}",
                          f"{max(abs(r['rel_error_pct']) for r in bsel):.2e}")
                summary.append({"joints": jt, "direction": d, "points": len(sel), "mean |error| % (solid)": mean,
                                "max |error| % (solid)": max(abs(r["rel_error_pct"]) for r in sel),
                                "max |error| % (beam)": max(abs(r["rel_error_pct"]) for r in bsel)})
        printed.append(t)
        sections += _report_sections(title, summary, rows, limit)
    ok = beam.max_abs_error_pct <= VERIFY_THRESHOLD_PCT
    checks.append(passed_or_failed("threshold beam-link FE (chain algebra)", "threshold", ok,
                                   f"beam-link FE vs analytical: max |error| {beam.max_abs_error_pct:.2e} % "
                                   f"{'<=' if ok else '>'} {VERIFY_THRESHOLD_PCT:g} % (the chain algebra)"))
    worst = sorted(worst, key=lambda w: -w["mean_error_pct"])[:3]
    v = make_verdict(checks, worst)
    con.print(v.line(), style="bold green" if v.passed else "bold red", markup=False, highlight=False)
    for t in printed:
        con.print(t)
    con.print(f"solid links: each link meshed (geometry builders, P2) and condensed; beam links: the analytical "
              f"cantilevers (max |error| {beam.max_abs_error_pct:.2e} %, a check of the chain algebra); joints as "
              f"exact releases, rigid platform; solid links' detailed level: {_own_laws_text(laws)}; max |error| with solid "
              f"links {solid.max_abs_error_pct:.3f} % over {len(solid.rows)} deflections; wrote "
              f"{4 * len(levels) + 2} files to {out} (report.html)")
    _write_report(case, case_path, out, sections, checks, worst, solid, beam, mesh)
    for c in checks:
        if c.status == "fail":
            con.print(f"  [{c.kind}] {c.name}: {c.detail}", markup=False, highlight=False)
    con.print(v.line(), style="bold green" if v.passed else "bold red", markup=False, highlight=False)
    if not v.passed:
        raise typer.Exit(1)


def _report_sections(title, summary, rows, limit) -> list:
    from femcheck.verify.render import Section
    return [Section(title, tuple(summary), {k: "{:.3f}" if "solid" in k else "{:.2e}" for k in summary[0] if "%" in k},
                    note=f"Mean and max over the test points of |analytical − FE| / |FE| (%); the solid-link FE must "
                         f"stay within {limit:g} % on average (verify threshold); the beam-link FE reproduces the "
                         "analytical cantilevers, so its error is round-off (a check of the chain algebra)."),
            Section(title.split(":")[0] + ": every point (solid links)", tuple(rows),
                    {"analytical_mm": "{:.5f}", "fe_mm": "{:.5f}", "rel_error_pct": "{:+.3f}"})]


def _write_report(case, case_path, out, sections, checks, worst, solid, beam, mesh) -> None:
    """report.md / report.html: the verdict, then the tables of each level (:mod:`femcheck.verify.render`);
    ``verdict.json``."""
    from femcheck.report.atomic import write_text_atomic
    from femcheck.verify.check import verdict as make_verdict
    from femcheck.verify.render import VERDICT_TITLE, Section, render_html, render_markdown, verdict_json
    verdict_line = make_verdict(checks, worst).line()
    write_text_atomic(out / "verdict.json", verdict_json(checks, worst, 0.0))
    head = Section(VERDICT_TITLE, pre=f"{verdict_line}\nmax |error| solid links {solid.max_abs_error_pct:.3f} %, beam links "
                                     f"{beam.max_abs_error_pct:.2e} % over {len(solid.rows)} deflections")
    title = f"femcheck verify — {case.meta.name}"
    intro = (f"case {case_path}: parallel device, {len(case.device.legs)} legs; FE from the case description with "
             f"solid links (geometry builders, P2, condensed; mesh {mesh}) and with beam links; joints as exact "
             "releases with the analytical drive and contact springs; rigid platform (docs/parallel_device.md).")
    write_text_atomic(out / "report.md", render_markdown(title, intro, [head] + sections))
    write_text_atomic(out / "report.html", render_html(title, intro, [head] + sections))


def diagnose(case, case_path, measured, *, model: str, joints: str | None, json_out, force: bool = False,
             warnings=(), extended_case=None) -> None:
    """Which element kind, and which leg, the measured deflections put the model's error in. ``force``: go on with
    readings more than 10x off the model's scale; ``warnings``: lines about the case, kept in the JSON;
    ``extended_case``: path of the corrected case to write."""
    from rich.markup import escape

    from femcheck.errors import MeasuredDataError
    from femcheck.measured.csv_format import read_measured_csv
    from femcheck.parallel.diagnosis import diagnose as run
    from femcheck.parallel.diagnosis import readings_from, scale_problem

    if json_out and json_out != "-":
        from femcheck.report.atomic import refuse_input_overwrite
        refuse_input_overwrite(json_out, [case_path, measured])
    data = read_measured_csv(measured)
    try:
        if not force:
            problem = scale_problem(case, readings_from(case, data), model=model,
                                    joints=joints or case.model.joint_rotations)
            if problem:
                raise MeasuredDataError(measured, None, "dx_mm..dz_mm", problem)
        d = run(case, data, model=model, joints=joints)
    except MeasuredDataError:
        raise
    except ValueError as exc:
        raise typer.BadParameter(str(exc)) from None
    result = {"case": case.source, "case_sha256": case.sha256, "measured": str(measured), "model": model,
              "joints": joints or case.model.joint_rotations, **d.as_json(), "warnings": list(warnings)}
    if extended_case:
        from pathlib import Path
        from femcheck.parallel.extended_case import extended_case_text
        from femcheck.report.atomic import write_text_atomic
        write_text_atomic(extended_case, extended_case_text(case, Path(case_path).read_text(), d))
    if json_out:
        emit_json(result, json_out, inputs=[case_path, measured])
        if json_out == "-":
            return
    con = console()
    t = Table(title=f"{escape(case.meta.name)}: candidate explanations of {escape(str(measured))} ({model} model, "
                    f"{joints or case.model.joint_rotations} joints)")
    for c in ("candidate", "factors", "RMS before mm", "RMS after mm"):
        t.add_column(c, justify="right")
    for c in d.candidates:
        t.add_row(escape(c.what), str(len(c.factors)), f"{c.rms_before_mm:.5f}", f"{c.rms_after_mm:.5f}")
    con.print(t)
    b = d.best
    con.print(f"kept (BIC): [bold]{escape(b.what)}[/]: " + escape(", ".join(f"{n} x{f:.3g}" for n, f in zip(b.names, b.factors))))
    con.print(f"RMS {b.rms_before_mm:.5f} mm -> {b.rms_after_mm:.5f} mm; held out (leave one point out) "
              f"{b.held_out_rms_mm:.5f} mm")
    if not d.effects:
        con.print("no element's compliance moved beyond the threshold: the model explains the data")
    elif d.located is not None:
        loc = d.located
        lo, hi = loc["factor_ci"]
        con.print(f"effect located: [bold]{escape(loc['cause'])}[/]: {escape(loc['element'])} of leg"
                  f"{'s' if len(loc['legs']) > 1 else ''} [bold]{escape(', '.join(loc['legs']))}[/] x{loc['factor']:.3g} "
                  f"of its modelled compliance (95 % [{lo:.4g}, {hi:.4g}])")
    else:
        con.print("effect: " + ", ".join(f"[bold]{escape(n)}[/] x{f:.3g}" for n, f in d.effects) + " (every leg)")
