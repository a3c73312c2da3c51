"""``check-joints``: each joint's contact FE under the load the device puts on it, vs its closed-form law.

Load state (seed 000 eq. 1, docs/conventions.md §8). With ideal passive joints every leg is a two-force
member, so the TCP wrench W is carried by the leg forces f (6,) along the link axes u_i:

    J f = W,   J = [u_i ; (C_i − tcp) × u_i]  (6 x 6, column i per leg)

for the preload P_p (5 N) and P_p + P_T (20 N) along each of the case's test directions. The most
loaded joint (largest |f_i| over legs and directions at the test point) sets the joint's two force
levels F_5 = |f_i(P_p)|, F_20 = |f_i(P_p + P_T)|, which the contact FE applies along the joint axis
(:func:`femcheck.fe_device.joint_fe.solve_joint`).

The joint table compares, per joint and component (axial, lateral, tilt, spin), the
FE compliance with the analytical law (:func:`femcheck.fe_device.joint_fe.analytical_compliance`).
"""
from __future__ import annotations

import csv
import io
import logging
import math

import numpy as np

from femcheck.errors import FemcheckError
from femcheck.fe_device.joint_forces import joint_loads, leg_forces  # noqa: F401  (the load state of the check)

log = logging.getLogger(__name__)

#: table components: (name, index into the 6 x 6 diagonal)
TABLE_COMPONENTS = (("axial", 2), ("lateral", 0), ("tilt", 3), ("spin", 5))
#: a law is flagged when it is off by more than this
FLAG_PCT = 10.0


#: expected relative cost of each joint's contact FE (the universal joint's coarse mesh has 2.5x the DOFs of the
#: ball's, 238,470 vs 95,373, and measured 1.9-4x its wall time); ``BUILD_SHARE`` of it is meshing and
#: condensation (condense_s / seconds: 121 of 127 s for the universal, 28 of 30 s for the ball)
JOINT_COST = {"spherical": 1.0, "universal": 2.5}
BUILD_SHARE = 0.9


def check_joint(case, joint: str, mesh: str = "default", point: str = "P0", progress=None,
                use_cache: bool = False) -> dict:
    """Contact FE of ``joint`` at the device load of ``point``: the JSON object of ``check-joints``.

    Keys (contract): converged, dofs, iterations, seconds, fe_compliance, analytical_compliance
    (6 x 6, SI), error_pct (per component, on ``fe_component_compliance``: each component with the other
    five held, as the per-component springs of the analytical model are defined); plus fe_tangent_stiffness, loads_N, factorizations, augmentations, free_dofs,
    retained_dofs, condense_s, secant_axial_m_per_N, closed_points, mesh, point, contact_size_m, bulk_size_m,
    axial_size_m (universal: element length along the pins and through the yoke arms; None for the ball),
    line_search_cuts, stabilized_iterations, stabilization_force_share (< 1e-6 required), residual_rel. A joint that does not
    converge raises :class:`femcheck.errors.ConvergenceError` (residual history, chattering points).
    ``progress(description)`` is called after the build (mesh, condensation) and after the contact solve.
    ``use_cache``: read the contact FE's part from the result cache (:mod:`femcheck.fe.result_cache`, keyed by the
    joint's case sections, the loads, the mesh level and the FE code) and store it there after a solve; the
    analytical column is evaluated every time.
    """
    from femcheck.fe import result_cache
    from femcheck.fe_device import joint_fe as jf

    loads = joint_loads(case, point)
    key = joint_table_key(case, joint, mesh, point)
    fe_part = result_cache.load("joint_check", key) if use_cache else None
    if fe_part is None:
        fe_part = _joint_fe(case, joint, mesh, loads, progress)
        if use_cache:
            result_cache.store("joint_check", key, fe_part)
    elif progress:
        progress(f"{joint}: read from the cache")
        progress(f"{joint}: read from the cache")
    an = jf.analytical_compliance(case, joint, loads)
    return {**fe_part, "point": point.upper(), "analytical_compliance": _json_matrix(an),
            "error_pct": jf.error_pct(np.asarray(fe_part["fe_component_compliance"], float), an)}


def joint_table_key(case, joint: str, mesh: str, point: str = "P0") -> str:
    """Result-cache key of :func:`check_joint`'s contact FE: the joint's case sections, its loads at ``point``, the
    mesh level (and the FE code, :func:`femcheck.fe.result_cache.result_key`)."""
    from femcheck.fe import result_cache
    return result_cache.result_key("joint_check", {
        "joint": joint, "mesh": mesh, "loads_N": list(joint_loads(case, point)),
        "spherical_joint": repr(case.spherical_joint), "universal_joint": repr(case.universal_joint),
        "solid": repr(case.solid)})


def _joint_fe(case, joint: str, mesh: str, loads, progress=None) -> dict:
    """The contact-FE part of :func:`check_joint` (everything but the analytical column)."""
    from femcheck.fe_device import joint_fe as jf

    from femcheck.fe_device.joint_models import solve_widening
    tol, start = jf.contact_start(case, joint, loads)
    # spherical: the ball is pressed into the seat (−z); universal: the link pushes its yoke along +z
    sign = -1.0 if joint == "spherical" else 1.0
    # spherical: the stick state sticks the contact area (closed points and points within 1e-3 of the
    # approach increment); universal: the closed points (as measured before). A thin pin that bends out of the
    # loaded lines' band is solved again on a wider one, as the measured joint laws are.
    first = [True]   # a flag, not the models: a failed narrower model must be free to go (its factorization)

    def solve(m):
        if progress and first[0]:       # one step per build however many bands are tried (the bars count two)
            progress(f"{joint}: mesh and condensation")
        first[0] = False
        return m, jf.solve_joint(m, loads, sign, penetration_tol=tol, initial_gap_m=start,
                                 area_gap_rel=1e-3 if joint == "spherical" else 0.0)

    model, r = solve_widening(case, joint, mesh, max(loads), solve)
    if progress:
        progress(f"{joint}: contact solve")
    from femcheck.fe_device.mesh_levels import joint_mesh_sizes
    ms = joint_mesh_sizes(case, joint, mesh, max(loads))
    fe = r.fe_compliance
    return {"joint": joint, "mesh": mesh, "converged": True, "dofs": r.dofs,
            "free_dofs": r.free_dofs, "retained_dofs": r.retained, "iterations": r.iterations,
            "factorizations": r.factorizations + model.factorizations, "augmentations": r.augmentations,
            "low_rank_updates": r.low_rank_updates, "contact_size_m": ms.contact_m, "bulk_size_m": ms.bulk_m,
            "axial_size_m": ms.axial_m,
            "hertz_contact_radius_m": ms.contact_radius_m,
            "seconds": r.seconds, "condense_s": r.condense_s, "loads_N": list(loads),
            "line_search_cuts": r.line_search_cuts, "stabilized_iterations": r.stabilized_iterations,
            "stabilization_force_share": r.stabilization_force_share, "residual_rel": r.residual_rel,
            "secant_axial_m_per_N": r.secant_axial_m_per_N, "closed_points": r.closed_points,
            "fe_compliance": _json_matrix(fe),
            "fe_component_compliance": _json_matrix(r.component_compliance[None])[0],
            "fe_tangent_stiffness": _json_matrix(r.tangent_stiffness)}


def progress_weights(joints) -> list[float]:
    """Expected relative cost of the steps that :func:`check_joint` reports for each of ``joints`` in turn."""
    return [w for j in joints for w in (BUILD_SHARE * JOINT_COST[j], (1 - BUILD_SHARE) * JOINT_COST[j])]


def verdict_line(rows: list[dict]) -> str:
    """One line that sums up the joint table: which laws are within 10 % of the contact FE, which are not."""
    flagged = [f"{r['joint']} {r['component']} ({r['error_pct']:+.1f} %)" for r in rows if r["off_by_more_than_10pct"]]
    n = sum(r["error_pct"] is not None for r in rows)
    what = f"{n} joint-table laws compared ({', '.join(c for c, _k in TABLE_COMPONENTS)} per joint)"
    if not flagged:
        return f"verdict: every closed-form joint law within {FLAG_PCT:g} % of the contact FE; {what}"
    return (f"verdict: {len(flagged)} closed-form joint laws off by more than {FLAG_PCT:g} % from the contact FE: "
            f"{', '.join(flagged)}; {what}")


def _json_matrix(C: np.ndarray) -> list:
    """6 x 6 as nested lists; infinite entries (a mechanism) as None (JSON has no inf)."""
    return [[float(v) if math.isfinite(v) else None for v in row] for row in np.asarray(C)]


def joint_table_rows(results: list[dict]) -> list[dict]:
    """Joint table: one row per (joint, component) with FE and analytical compliance
    (SI), error %, and the law the FE supports where the closed form is off by more than 10 %."""
    rows = []
    for res in results:
        fe, an = res["fe_component_compliance"], res["analytical_compliance"]
        for comp, k in TABLE_COMPONENTS:
            f, a = fe[k], an[k][k]
            err = None if (f is None or a in (None, 0.0)) else 100.0 * (f - a) / a
            flag = err is not None and abs(err) > FLAG_PCT
            rows.append({"joint": res["joint"], "component": comp, "fe_compliance": f, "analytical_compliance": a,
                         "error_pct": err, "off_by_more_than_10pct": flag,
                         "better_law": _better_law(res["joint"], comp) if flag else ""})
    return rows


def _better_law(joint: str, component: str) -> str:
    if joint == "universal" and component == "axial":
        return "conformal pin-in-bore contact (Persson) with yoke bulk, instead of Hertz line contact"
    if joint == "universal" and component == "lateral":
        return ("stick friction at the loaded line in series with cross and yoke-arm bending (the bore side is "
                "open by the clearance), instead of Hertz line contact")
    if joint == "spherical" and component == "axial":
        return "Hertz plus seat-bulk term (finite seat thickness)"
    return "FE-measured compliance (the closed-form stick law is not resolved by the analytical model)"


def write_joint_table_csv(rows: list[dict]) -> str:
    """CSV text of :func:`joint_table_rows` (compliances in SI, error in %)."""
    buf = io.StringIO()
    keys = ("joint", "component", "fe_compliance", "analytical_compliance", "error_pct", "off_by_more_than_10pct",
            "better_law")
    w = csv.DictWriter(buf, fieldnames=keys, lineterminator="\n")
    w.writeheader()
    for r in rows:
        w.writerow({k: ("" if r[k] is None else r[k]) for k in keys})
    return buf.getvalue()


def joint_law_adjustments(results: list[dict]):
    """The FE-measured joint laws as an option of the extended analytical model.

    A leg with ideal passive joints is a two-force member, so its joints work along their axes: the
    axial compliance is the joint law that enters the leg. This returns
    :class:`femcheck.chain.ChainAdjustments` whose ``element_scale`` multiplies the
    ``sp`` and ``uj`` element compliances of every chain by FE / closed form of the axial component
    (``check_joint`` results, one per joint type; a joint not given keeps its closed form, factor 1).
    ``femcheck diagnose`` and the sweeps take such adjustments (``evaluate(..., adjust=...)``).
    """
    from femcheck.chain import ELEMENTS, ChainAdjustments

    scale = np.ones((6, len(ELEMENTS)))
    for res in results:
        fe, an = res["fe_component_compliance"][2], res["analytical_compliance"][2][2]
        if fe is None or not an:
            raise FemcheckError(f"{res['joint']} joint: no finite axial compliance to build the joint law from")
        scale[:, ELEMENTS.index("sp" if res["joint"] == "spherical" else "uj")] = fe / an
    return ChainAdjustments(element_scale=scale)


def law_scale_factors(results: list[dict]) -> dict:
    """``{"sp": x, "uj": y}``: FE / closed-form axial (eq. 1 secant) compliance of each joint in ``results``
    (``check_joint`` objects): the ``[model.law_scale]`` entries that put the FE-measured joint laws into the
    analytical model (the axial law is the one a leg with ideal passive joints loads, :func:`joint_law_adjustments`)."""
    out = {}
    for res in results:
        fe, an = res["fe_component_compliance"][2], res["analytical_compliance"][2][2]
        if fe is None or not an:
            raise FemcheckError(f"{res['joint']} joint: no finite axial compliance to build the joint law from")
        out["sp" if res["joint"] == "spherical" else "uj"] = float(fe) / float(an)
    return out


def extended_case_text(case_text: str, case_path: str, results: list[dict]) -> str:
    """The case file ``case_text`` plus a ``[model.law_scale]`` table with :func:`law_scale_factors`: an
    extended analytical model whose joint laws are the contact FE's, for ``femcheck diagnose``, ``sweep``,
    ``map`` and ``stiffness`` (they read the case). Refuses a case that already sets ``[model.law_scale]``."""
    import tomllib
    doc = tomllib.loads(case_text)
    if "law_scale" in doc.get("model", {}):
        raise FemcheckError(f"{case_path}: [model.law_scale] is already set; expected a case without it "
                            "(the extended case multiplies the closed-form joint laws by the FE / closed-form ratio)")
    from femcheck.case.toml_edit import append_table
    f = law_scale_factors(results)
    return append_table(case_text, "model.law_scale", {k: float(f"{v:.6g}") for k, v in f.items()},
                        ("written by femcheck check-joints --extended-case: the FE-measured joint laws",
                         "(axial eq. 1 secant of the contact FE / the closed form, mesh "
                         f"{results[0]['mesh']}, point {results[0]['point']})"))


def joint_table_html(rows: list[dict]) -> str:
    """The joint table as an HTML section for ``reports/verify/report.html`` (the integrator adds it
    through the verify report's section API): compliances in SI, error %, the flagged laws named."""
    import html

    def num(v, fmt):
        return "∞" if v is None else format(v, fmt)

    body = "".join(
        f"<tr><td>{html.escape(r['joint'])}</td><td>{r['component']}</td><td>{num(r['fe_compliance'], '.4g')}</td>"
        f"<td>{num(r['analytical_compliance'], '.4g')}</td><td>{'–' if r['error_pct'] is None else format(r['error_pct'], '+.1f')}</td>"
        f"<td>{'off by > 10 %: ' + html.escape(r['better_law']) if r['off_by_more_than_10pct'] else 'within 10 %'}</td></tr>"
        for r in rows)
    return ("<section id='joint-table'><h2>Joint table: contact FE vs the analytical joint laws</h2>"
            "<table><thead><tr><th>joint</th><th>component</th><th>FE compliance (SI)</th>"
            "<th>analytical (SI)</th><th>error %</th><th>verdict</th></tr></thead><tbody>"
            f"{body}</tbody></table></section>")


def joint_table_section(rows: list[dict]):
    """The joint table as a :class:`femcheck.verify.render.Section` of the verify report's "joints" part:
    ``sections.append(joint_table_section(joint_table_rows(results)))``."""
    from femcheck.verify.render import Section

    flagged = [f"{r['joint']} {r['component']}: {r['better_law']}" for r in rows if r["off_by_more_than_10pct"]]
    note = ("Contact FE of each passive joint at the eq. 1 loads vs the closed-form joint laws (seed 000 §4.4.1); "
            "compliances in SI (m/N for forces, rad/(N m) for moments), error_pct = 100 (FE - analytical) / "
            "analytical. " + ("Off by more than 10 %: " + "; ".join(flagged) + "." if flagged else "Every law within 10 %."))
    keys = ("joint", "component", "fe_compliance", "analytical_compliance", "error_pct", "off_by_more_than_10pct")
    return Section("Joint table: contact FE vs the analytical joint laws",
                   tuple({k: r[k] for k in keys} for r in rows),
                   {"fe_compliance": "{:.4g}", "analytical_compliance": "{:.4g}", "error_pct": "{:+.1f}"}, note=note,
                   part="joints", explain={"fe_compliance": "the contact FE gives no compliance for this component",
                                           "analytical_compliance": "the closed-form law has no term for this component",
                                           "error_pct": "no error without both compliances"})
