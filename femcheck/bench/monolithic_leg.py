"""Bench ``monolithic_leg``: one complete leg as one contact FE model vs the substructured leg.

Per test point (P0, P5; the most compressed leg, coarse meshes): the leg force at the eq. 1 levels (N), the
monolithic model's size (P2 DOFs, free DOFs, retained DOFs after condensation, contact / candidate / closed
points), its contact iterations, factorizations, Uzawa updates and line-search cuts, the condensation and
total wall time (s), the displacement of C_i along the leg at both levels for both models (m), the eq. 1
increments and their relative difference (target |.| ≤ 2 %), the same for the joints' share of the
increment alone (the bodies' own compliances agree by construction: same meshes), the guideway's share of
the increment, and the substructured leg's wall time (the
two joint contact FE solves and the two super-elements). A point that fails records ``<point>_error``.
"""
from __future__ import annotations

AREA = "monolithic_leg"
POINTS = ("P0", "P5")


def run(points=POINTS, mesh: str = "coarse") -> dict:
    from femcheck.case import load_case
    from femcheck.fe_device.monolithic_leg import check_monolithic_leg

    case = load_case("cases/haptic_6psu.toml")
    out: dict = {"mesh": mesh}
    for p in points:
        key = p.lower()
        try:
            r = check_monolithic_leg(case, p, mesh)
        except Exception as exc:  # a bench records failures, it does not stop at the first
            out[f"{key}_error"] = str(exc)[:300]
            continue
        j = r.to_json()
        out[f"{key}_chain"] = j["chain"]
        out[f"{key}_direction"] = j["direction"]
        out[f"{key}_load_preload_N"] = round(j["loads_N"][0], 4)
        out[f"{key}_load_test_N"] = round(j["loads_N"][1], 4)
        out[f"{key}_inclination_deg"] = round(j["inclination_deg"], 2)
        for k in ("dofs", "free_dofs", "retained_dofs", "contact_points", "candidate_points", "closed_points",
                  "iterations", "factorizations", "augmentations", "line_search_cuts"):
            out[f"{key}_{k}"] = j[k]
        out[f"{key}_stabilization_force_share"] = j["stabilization_force_share"]
        out[f"{key}_residual_rel"] = j["residual_rel"]
        out[f"{key}_condense_s"] = round(j["condense_s"], 3)
        out[f"{key}_monolithic_wall_s"] = round(j["seconds"], 3)
        out[f"{key}_substructured_wall_s"] = round(j["substructured_seconds"], 3)
        for lvl, i in (("preload", 0), ("test", 1)):
            out[f"{key}_C_displacement_monolithic_{lvl}_m"] = j["displacement_monolithic_m"][i]
            out[f"{key}_C_displacement_substructured_{lvl}_m"] = j["displacement_substructured_m"][i]
        out[f"{key}_C_increment_monolithic_m"] = j["increment_monolithic_m"]
        out[f"{key}_C_increment_substructured_m"] = j["increment_substructured_m"]
        out[f"{key}_relative_difference_pct"] = round(100 * j["relative_difference"], 4)
        out[f"{key}_relative_difference_total_pct"] = round(100 * j["relative_difference_total"], 4)
        out[f"{key}_joint_increment_monolithic_m"] = j["joint_increment_monolithic_m"]
        out[f"{key}_joint_increment_substructured_m"] = j["joint_increment_substructured_m"]
        out[f"{key}_joint_relative_difference_pct"] = round(100 * j["joint_relative_difference"], 4)
        out[f"{key}_guideway_share_of_increment"] = round(
            (j["loads_N"][1] - j["loads_N"][0]) * j["substructured_guideway_m_per_N"] / j["increment_substructured_m"], 4)
    return out
