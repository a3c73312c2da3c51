"""Bench ``joints``: contact FE of the passive joints, coarse / default / fine.

Per joint and mesh level: DOFs (P2 mesh), free DOFs after constraints, retained DOFs after condensation
(contact candidates + reference node), candidate / total contact points, condensation time (mesh,
assembly, pairing, PARDISO Schur complement, one factorization per body for the recovery), contact
iterations, factorizations (Schur + bodies + the contact loop's), Uzawa updates, total wall time, the eq. 1
axial secant and each component compliance (m/N, rad/(N m)), its error against the closed-form law (%),
and the spread of each component over the levels run (max − min over the finest level, %, target ≤ 3;
``<joint>_max_mesh_spread_pct`` the largest of them. Spherical levels are graded on the Hertz radius a
(patch edge a / 3, a / 4.5, a / 6, bulk unchanged), universal levels on the loaded lines (angular warp
0.5, 0.75, 0.875) and in the bulk (element length along the pins and through the yoke arms 2, 1.4, 1 mm,
``<key>_axial_size_m``; in-plane bulk 2 mm) (:func:`femcheck.fe_device.mesh_levels.joint_mesh_sizes`); ``low_rank_updates`` counts the active-set
changes solved by a Woodbury update of the last dense factorization instead of a new one.
Targets: universal ≤ 120 s and spherical ≤ 60 s at the default mesh on the 2-core machine.

Assembly (same mesh, side by side): ``<key>_assembly_s`` the vectorized stiffness assembly
(:func:`femcheck.fe.elasticity.assemble_stiffness`, the one every solve uses), ``<key>_assembly_skfem_s``
scikit-fem's generic ``asm`` of the same weak form, ``<key>_assembly_speedup`` their ratio and
``<key>_assembly_rel_diff`` max |K − K_skfem| / max |K_skfem| (round-off), on the levels of
``ASSEMBLY_COMPARE_LEVELS`` (the skfem form of the fine universal mesh alone needs > 6 GB). Non-MKL path:
``<key>_nonmkl_wall_s`` (and ``_nonmkl_iterations``, ``_nonmkl_factorizations``, ``_nonmkl_solver``) the
same check with the linear solver set to CHOLMOD (cvxopt; the Schur complement by one partial supernodal
factorization per body, reused for the recovery) on the joints and levels of ``NONMKL_LEVELS``, and
``<key>_nonmkl_max_compliance_diff_pct`` its largest component difference from the MKL run (%).
A level that fails records ``<joint>_<level>_error`` (the exception text) instead of numbers.
"""
from __future__ import annotations

import numpy as np

AREA = "joints"
LEVELS = ("coarse", "default", "fine")


#: levels per joint (both graded: the spherical fine level has 148 k DOFs, 3.5 GB; the universal fine level
#: 426 k DOFs, ≈ 6 GB; docs/verify.md)
JOINT_LEVELS = {"spherical": LEVELS, "universal": LEVELS}


#: levels with the side-by-side skfem assembly, and with the non-MKL (CHOLMOD) rerun of the check
ASSEMBLY_COMPARE_LEVELS = ("coarse", "default")
#: (universal: its non-MKL condensation is timed by the verify area's no-MKL step, make_verify_nomkl_s)
NONMKL_LEVELS = {"spherical": ("default",), "universal": ()}


def assembly_comparison(case, joint: str, level: str, max_load_N: float) -> dict:
    """Stiffness assembly of the joint's P2 mesh at ``level``: vectorized vs scikit-fem's weak form (s)."""
    import time

    from femcheck.fe.elasticity import assemble_stiffness, vector_basis
    from femcheck.fe_device import joint_fe as jf

    pm, mats, *_ = jf._joint_mesh(case, joint, level, max_load_N, None)
    basis = vector_basis(pm.to_skfem(), 2)
    E, nu = jf._materials(pm, mats)
    t0 = time.perf_counter()
    K = assemble_stiffness(basis, E, nu)
    t1 = time.perf_counter()
    K0 = assemble_stiffness(basis, E, nu, method="skfem")
    t2 = time.perf_counter()
    diff = float(abs(K - K0).max() / abs(K0).max())
    return {"assembly_s": round(t1 - t0, 3), "assembly_skfem_s": round(t2 - t1, 3),
            "assembly_speedup": round((t2 - t1) / (t1 - t0), 2), "assembly_rel_diff": diff}


def nonmkl_check(case, joint: str, level: str, mkl_result: dict | None) -> dict:
    """The joint check with the linear solver set to CHOLMOD (no MKL used): wall s, counts, difference."""
    import time

    from femcheck.fe import linear_solver as ls
    from femcheck.fe_device.joint_check import check_joint

    if not ls.cvxopt_available():
        return {"nonmkl_error": "cvxopt not installed"}
    before = ls.preferred()
    ls.set_preferred("cholmod")
    try:
        t0 = time.perf_counter()
        r = check_joint(case, joint, level, "P0")
        wall = time.perf_counter() - t0
    finally:
        ls.set_preferred(None if before == "auto" else before)
        if before == "auto":
            import os
            os.environ.pop(ls.ENV_VAR, None)
    out = {"nonmkl_solver": "cholmod", "nonmkl_wall_s": round(wall, 3), "nonmkl_iterations": r["iterations"],
           "nonmkl_factorizations": r["factorizations"]}
    if mkl_result is not None:
        d = [abs(a - b) / abs(b) * 100.0 for a, b in zip(r["fe_component_compliance"], mkl_result["fe_component_compliance"])
             if a is not None and b is not None and b != 0]
        out["nonmkl_max_compliance_diff_pct"] = float(max(d)) if d else None
    return out


def run(joints=("spherical", "universal"), levels=None) -> dict:
    from femcheck.case import load_case
    from femcheck.fe_device.joint_check import check_joint
    from femcheck.fe_device.joint_fe import COMPONENTS

    case = load_case("cases/haptic_6psu.toml")
    out: dict = {"point": "P0"}
    for joint in joints:
        comps = {}
        jl = JOINT_LEVELS[joint] if levels is None else levels
        for level in jl:
            key = f"{joint}_{level}"
            try:
                r = check_joint(case, joint, level, "P0")
            except Exception as exc:  # a bench records failures, it does not stop at the first
                out[f"{key}_error"] = str(exc)[:300]
                continue
            out[f"{key}_dofs"] = r["dofs"]
            out[f"{key}_free_dofs"] = r["free_dofs"]
            out[f"{key}_retained_dofs"] = r["retained_dofs"]
            out[f"{key}_condense_s"] = round(r["condense_s"], 3)
            out[f"{key}_iterations"] = r["iterations"]
            out[f"{key}_factorizations"] = r["factorizations"]
            out[f"{key}_augmentations"] = r["augmentations"]
            out[f"{key}_low_rank_updates"] = r["low_rank_updates"]
            out[f"{key}_closed_points"] = r["closed_points"]
            out[f"{key}_contact_size_m"] = r["contact_size_m"]
            out[f"{key}_bulk_size_m"] = r["bulk_size_m"]
            if r.get("axial_size_m") is not None:
                out[f"{key}_axial_size_m"] = r["axial_size_m"]
            out[f"{key}_line_search_cuts"] = r["line_search_cuts"]
            out[f"{key}_stabilization_force_share"] = r["stabilization_force_share"]
            out[f"{key}_residual_rel"] = r["residual_rel"]
            out[f"{key}_wall_s"] = round(r["seconds"], 3)
            out[f"{key}_load_preload_N"] = round(r["loads_N"][0], 4)
            out[f"{key}_load_test_N"] = round(r["loads_N"][1], 4)
            if level in ASSEMBLY_COMPARE_LEVELS:
                try:
                    for k, v in assembly_comparison(case, joint, level, max(r["loads_N"])).items():
                        out[f"{key}_{k}"] = v
                except Exception as exc:
                    out[f"{key}_assembly_error"] = str(exc)[:300]
            if level in NONMKL_LEVELS.get(joint, ()):
                try:
                    for k, v in nonmkl_check(case, joint, level, r).items():
                        out[f"{key}_{k}"] = v
                except Exception as exc:
                    out[f"{key}_nonmkl_error"] = str(exc)[:300]
            for k, name in enumerate(COMPONENTS):
                v = r["fe_component_compliance"][k]
                out[f"{key}_{name}_compliance_SI"] = v
                e = r["error_pct"][name]
                out[f"{key}_{name}_error_pct"] = None if e is None else round(e, 3)
                if v is not None:
                    comps.setdefault(name, []).append(v)
        spreads = []
        for name, vals in comps.items():
            if len(vals) == len(jl):
                v = np.asarray(vals, float)
                spreads.append(round(float(100 * (v.max() - v.min()) / abs(v[-1])), 3))
                out[f"{joint}_{name}_mesh_spread_pct"] = spreads[-1]
        if spreads:
            out[f"{joint}_max_mesh_spread_pct"] = max(spreads)
            out[f"{joint}_mesh_spread_levels"] = "/".join(jl)
    return out
