"""Which reading of seed 001 eq. 10 the paper's own Table 2 supports, and how isotropic TP3 is.

Seed 001 fits its weights three times to the same HISS device: on the D/F data, on the F/D data and on both
(Table 2). Each fit reproduces its measurements to a few tenths of a mm (Table 4), so a faithful reading of
eq. 10 must make the three columns predict about the same device. Eq. 10 can be read two ways
(:data:`femcheck.vjm.weight_fitting.STIFFNESS_EXPONENT`): the stiffness entry scales with w (``linear``) or with
w^2 (``quadratic``, ``K' = W K W^T`` as printed). For each reading and column this module computes the
platform deflection under 1 kg along the negative diagonal (the F/D load of sec. 4.3) at every test point; the
reading whose columns agree best (smallest ratio of the largest to the smallest column maximum) is the one the
paper's data support.

TP3 (all active joints at +30 deg) lies on the diagonal and the layout is invariant under the cyclic axis
permutation, so its translational compliance has one eigenvalue along the diagonal and a double one across it;
seed 001 calls TP3 fully isotropic. :func:`tp3_isotropy` reports the ratio of the largest to the smallest
eigenvalue of the 3x3 translational block of the platform compliance ``K^-1`` (1 = isotropic).

All deflections are in mm under the case's assumed layout (``rcube_geometry``), which the paper does not give.
"""
from __future__ import annotations

import numpy as np

from femcheck.vjm.weight_fitting import STIFFNESS_EXPONENT, scaled_stiffness

#: 1 kg along the negative diagonal at the platform point, N (seed 001 sec. 4.3)
ONE_KG_NEGATIVE_DIAGONAL = np.r_[-np.ones(3) / np.sqrt(3.0) * 9.81, np.zeros(3)]


def _platform_stiffness(case, weights, reading: str) -> np.ndarray:
    """(m, 6, 6) platform stiffness at the case's test points."""
    from femcheck.vjm.rcube_geometry import forward_position, rcube_stiffness
    K = scaled_stiffness(case.K_theta, np.asarray(weights, dtype=float), case.fitting.weight_map, reading)
    return rcube_stiffness(case.rcube, K, forward_position(case.rcube, case.test_point_angles_rad))[1]


def one_kg_deflections_mm(case, weights, reading: str) -> np.ndarray:
    """(m,) |translation| at the test points under 1 kg along the negative diagonal, mm."""
    Kp = _platform_stiffness(case, weights, reading)
    d = np.linalg.solve(Kp, np.broadcast_to(ONE_KG_NEGATIVE_DIAGONAL, (len(Kp), 6))[..., None])[..., 0]
    return 1e3 * np.linalg.norm(d[:, :3], axis=1)


def column_consistency(case) -> dict:
    """Per reading: per Table 2 column the 1 kg deflections (mm) at every test point, their maximum and where,
    and ``spread`` = largest / smallest column maximum; ``supported`` = the reading with the smaller spread."""
    from femcheck.vjm.hiss_published import TABLE2
    names = [tp.name for tp in case.test_points]
    out = {}
    for reading in STIFFNESS_EXPONENT:
        cols = {}
        for col, (w, _) in TABLE2.items():
            d = one_kg_deflections_mm(case, w, reading)
            cols[col] = {"max_mm": float(d.max()), "at": names[int(d.argmax())], "per_test_point_mm": d.tolist()}
        mx = [c["max_mm"] for c in cols.values()]
        out[reading] = {"columns": cols, "spread": float(max(mx) / min(mx))}
    return {"load": "1 kg along the negative diagonal at the platform point",
            "readings": out, "supported": min(out, key=lambda r: out[r]["spread"]),
            "case_reading": case.fitting.stiffness_scaling}


def tp3_isotropy(case, weights=None, reading: str | None = None, point: str = "TP3") -> dict:
    """Ratio of the largest to the smallest eigenvalue of the translational compliance at ``point`` (1 =
    isotropic), with the eigenvalues (mm/N). ``weights`` default 1 (the nominal model, where the reading does not
    matter); ``reading`` default the case's."""
    reading = case.fitting.stiffness_scaling if reading is None else reading
    w = np.ones(case.fitting.n_weights) if weights is None else np.asarray(weights, dtype=float)
    i = [tp.name.upper() for tp in case.test_points].index(point.upper())
    C = np.linalg.inv(_platform_stiffness(case, w, reading)[i])[:3, :3]
    ev = np.linalg.eigvalsh(0.5 * (C + C.T))
    return {"point": point, "reading": reading, "ratio": float(ev[-1] / ev[0]), "compliance_mm_per_N": (1e3 * ev).tolist()}


def isotropy_table(case) -> dict:
    """TP3's ratio for the nominal model and for each Table 2 column under each reading."""
    from femcheck.vjm.hiss_published import TABLE2
    return {"nominal": tp3_isotropy(case),
            **{reading: {col: tp3_isotropy(case, w, reading)["ratio"] for col, (w, _) in TABLE2.items()}
               for reading in STIFFNESS_EXPONENT}}
