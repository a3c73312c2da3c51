"""Tables of a verification run, as data (rows = lists of dicts): no files, no formatting.

Errors are relative, in percent (``rel_error_pct`` = 100 |FE - analytical| / |FE|), in the CSVs and in the
tables alike. One pivot (:func:`pivot_errors`) builds the seed 000 Table 2/3 layout for every comparison.
"""
from __future__ import annotations

import numpy as np

from femcheck.verify.analytical import JOINTS, AnalyticalVerification
from femcheck.verify.check import average_row, followed_idealization


def deflection_rows(av: AnalyticalVerification) -> list[dict]:
    return [{"point": r.point, "direction": r.direction, "level": r.level, "joints": r.joints, "load_N": r.load_N,
             "deflection_mm": r.deflection_m * 1e3, "dx_mm": r.twist[0] * 1e3, "dy_mm": r.twist[1] * 1e3,
             "dz_mm": r.twist[2] * 1e3} for r in av.rows]


def pivot_errors(err_pct: dict, points, directions) -> list[dict]:
    """Seed 000 Table 2/3 layout from {(point, direction): error %}: a row per point, a column per direction
    (%), then average and max."""
    rows = [{"point": p, **{f"{d} error %": err_pct[(p, d)] for d in directions}} for p in points]
    rows.append({"point": "average", **{f"{d} error %": np.mean([err_pct[(p, d)] for p in points]) for d in directions}})
    rows.append({"point": "max", **{f"{d} error %": np.max([err_pct[(p, d)] for p in points]) for d in directions}})
    return rows


def error_rows(av: AnalyticalVerification, joints: str) -> list[dict]:
    """Simplified vs detailed analytical model (seed 000 Table 2/3 layout, %)."""
    err = av.simplified_vs_detailed(joints)
    return pivot_errors({k: 100 * v for k, v in err.items()}, av.points, av.directions)


def fe_error_rows(av: AnalyticalVerification, fe, level: str, fe_joints: str | None = None) -> list[dict]:
    """The one comparison: the analytical and FE results share the keyed accessor
    ``deflection(point, direction, level, joints)`` (m, along the load), so any two of them compare here. Rows ``point, direction, joints, analytical_mm, fe_mm, rel_error_pct`` (100 |FE - analytical| / |FE|) for
    one level; ``joints`` is the analytical idealization compared. The FE joints are ``fe_joints`` (e.g.
    ``contact``: the detailed FE with frictional contact joints, compared with both idealizations) or, by
    default, the same idealization as the analytical model (couplings tied / released)."""
    rows = []
    for j in JOINTS:
        for p in fe.points:
            for d in fe.directions:
                a, f = av.deflection(p, d, level, j), fe.deflection(p, d, level, fe_joints or j)
                rows.append({"point": p, "direction": d, "joints": j, "analytical_mm": a * 1e3, "fe_mm": f * 1e3,
                             "rel_error_pct": 100 * abs(a - f) / abs(f)})
    return rows


def error_table(rows: list[dict], joints: str, directions) -> list[dict]:
    """Seed 000 Table 2/3 layout from :func:`fe_error_rows` for one analytical idealization."""
    sel = [r for r in rows if r["joints"] == joints]
    return pivot_errors({(r["point"], r["direction"]): r["rel_error_pct"] for r in sel},
                        list(dict.fromkeys(r["point"] for r in sel)), directions)


def worst_errors(tabs: dict, n: int = 3) -> list[dict]:
    """The ``n`` largest mean analytical-FE errors over the checked error tables ({table, direction,
    mean_error_pct}); the contact FE against the idealization it is not expected to follow is informative and
    left out."""
    from femcheck.verify.check import EXPECTED_CONTACT_IDEALIZATION
    checked = {key: tab for key, tab in tabs.items()
               if len(key) < 3 or key[2] == key[1] or key[1] == EXPECTED_CONTACT_IDEALIZATION}
    out = [{"table": "/".join(dict.fromkeys(key)), "direction": k.split()[0], "mean_error_pct": round(float(v), 3)}
           for key, tab in checked.items() for k, v in average_row(tab).items()]
    return sorted(out, key=lambda w: -w["mean_error_pct"])[:n]


def baseline_values(av: AnalyticalVerification) -> dict[str, float]:
    return {f"analytical/{r.level}/{r.joints}/{r.point}/{r.direction}/deflection_m": r.deflection_m for r in av.rows}


def has_contact_joints(fe) -> bool:
    return "detailed" in fe.levels and ("detailed", "contact", fe.directions[0]) in fe.results[fe.points[0]].cases


def fe_baseline_key(mesh: str, kind: str, level: str, joints: str, point: str, direction: str, *,
                    slip_measured: bool, laws_measured: bool) -> str:
    """Baseline key of one FE deflection. The contact joints are keyed by where their ball slip moment came
    from (``contact``: theory, ρ = 1, ``--no-joint-fe``; ``contact_fe_slip``: the ball tilt contact FE), and
    the detailed level's joints by their laws (``+joint_fe``: measured by the joints' contact FE, else the
    closed forms): other numbers, other keys."""
    name = ("contact_fe_slip" if joints == "contact" and slip_measured else joints) + \
        ("+joint_fe" if level == "detailed" and laws_measured else "")
    return f"fe/{mesh}/{kind}/{level}/{name}/{point}/{direction}/deflection_m"


def fe_baseline_values(fe) -> dict[str, float]:
    """{baseline key (:func:`fe_baseline_key`): deflection (m)} of every FE load case of the run."""
    measured = fe.friction is not None and fe.friction.tilt_slip_ratio != 1.0
    laws = getattr(fe, "joint_laws", None) is not None and fe.joint_laws.any_measured
    return {fe_baseline_key(fe.mesh.level, fe.kind, lvl, j, p, d, slip_measured=measured, laws_measured=laws):
            c.deflection_m for p, r in fe.results.items() for (lvl, j, d), c in r.cases.items()}


def expected_fe_baseline_keys(points, directions, levels, mesh: str, kind: str, joint_fe: bool) -> set[str]:
    """The FE baseline keys a run will produce, known before it runs: both idealizations per level, the contact
    joints at the detailed level; with ``joint_fe`` the detailed level has the measured joint laws and slip
    moment (:func:`fe_baseline_key`)."""
    from femcheck.fe_device.joints import FE_JOINTS
    measured = joint_fe and "detailed" in levels
    return {fe_baseline_key(mesh, kind, lvl, j, p, d, slip_measured=measured, laws_measured=measured)
            for lvl in levels for j in FE_JOINTS if not (j == "contact" and lvl != "detailed")
            for p in points for d in directions}


def conditioning_rows(av: AnalyticalVerification) -> list[dict]:
    return [{"point": p, "cond_J_h": float(av.jacobian_condition[k]),
             **{f"cond_K_T_{j}": float(av.stiffness_condition[j][k]) for j in JOINTS},
             "slider_min_mm": float(av.sliders_m[k].min() * 1e3), "slider_max_mm": float(av.sliders_m[k].max() * 1e3)}
            for k, p in enumerate(av.points)]


def contact_section(fe, tabs: dict, demand, tilt) -> tuple[str, list[dict]]:
    """Text and table rows saying which idealization the contact FE follows, by how much and why."""
    from femcheck.verify.contact_joints import deflection_ratios
    followed = followed_idealization(tabs)
    means = {j: average_row(tabs[("detailed", j, "contact")]) for j in JOINTS}
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
