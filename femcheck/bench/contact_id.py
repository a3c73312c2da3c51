"""Bench area ``contact_id``: speed of the 1-D root finding and of the FE tangential identification."""
from __future__ import annotations

import time

import numpy as np

AREA = "contact_id"


def run() -> dict:
    from femcheck.case import load_case
    from femcheck.contact_id.bar_on_spring import frequency_roots
    from femcheck.contact_id.tangential import build_model, identify_tangential_stiffness, modal_at, relation

    beta = np.logspace(-3, 3, 100_000)
    t0 = time.perf_counter()
    frequency_roots(beta, 4)
    roots_s = time.perf_counter() - t0
    case = load_case("cases/contact_specimen.toml")
    t0 = time.perf_counter()
    model = build_model(case.specimen, case.fe)
    build_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    sweep = relation(model, np.logspace(6, 11, case.identification.sweep_points))
    sweep_s = time.perf_counter() - t0
    f, _ = modal_at(model, 2e9)
    t0 = time.perf_counter()
    r = identify_tangential_stiffness(model, f[:1], sweep=sweep)
    ident_s = time.perf_counter() - t0
    return {"roots_per_s": 4 * beta.size / roots_s, "specimen_dofs": int(model.block.ndof),
            "specimen_assembly_s": round(build_s, 3), "tangential_sweep_s": round(sweep_s, 3),
            "eigen_solves_per_s": round(case.identification.sweep_points / sweep_s, 2),
            "tangential_identify_s": round(ident_s, 3), "tangential_roundtrip_rel_error": abs(r.k_t_N_m_best / 2e9 - 1)}
