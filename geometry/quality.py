"""Mesh quality and checks: watertightness, volume against the analytic volume, dihedral angles,
aspect ratio. One :class:`QualityReport` per body; the part's report gathers them.

Aspect ratio is the normalized radius ratio  q = R_circ / (3 r_in)  (1 for the regular tetrahedron,
growing without bound for slivers; Shewchuk 2002, "What is a good linear finite element?").
"""
from __future__ import annotations

import numpy as np

from geometry.part_mesh import tet_volumes
from geometry.regions import boundary_facets

_EDGES = np.array([[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]])


def is_watertight(tets: np.ndarray) -> bool:
    """True if the boundary of the tets is a closed, consistently oriented 2-manifold surface: every
    directed boundary edge appears exactly once and its reverse exactly once."""
    f = boundary_facets(tets)
    if len(f) == 0:
        return False
    e = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    d, counts = np.unique(e, axis=0, return_counts=True)
    if np.any(counts != 1):
        return False
    rev = np.unique(e[:, ::-1], axis=0)
    return len(rev) == len(d) and np.array_equal(rev, d)


def dihedral_angles_deg(points: np.ndarray, tets: np.ndarray) -> np.ndarray:
    """(m, 6) interior dihedral angles (deg) at the six edges of each tetrahedron."""
    P = points[tets]
    out = np.empty((len(tets), 6))
    for k, (i, j) in enumerate(_EDGES):
        o = [m for m in range(4) if m not in (i, j)]
        e = P[:, j] - P[:, i]
        n1 = np.cross(e, P[:, o[0]] - P[:, i])
        n2 = np.cross(e, P[:, o[1]] - P[:, i])
        c = np.einsum("ij,ij->i", n1, n2) / (np.linalg.norm(n1, axis=1) * np.linalg.norm(n2, axis=1) + 1e-300)
        out[:, k] = np.degrees(np.arccos(np.clip(c, -1.0, 1.0)))
    return out


def radius_ratio(points: np.ndarray, tets: np.ndarray) -> np.ndarray:
    """(m,) R_circ / (3 r_in): 1 for a regular tetrahedron."""
    P = points[tets]
    a, b, c = P[:, 1] - P[:, 0], P[:, 2] - P[:, 0], P[:, 3] - P[:, 0]
    vol6 = np.abs(np.einsum("ij,ij->i", np.cross(a, b), c))
    aa, bb, cc = (np.einsum("ij,ij->i", v, v) for v in (a, b, c))
    num = np.linalg.norm(aa[:, None] * np.cross(b, c) + bb[:, None] * np.cross(c, a) + cc[:, None] * np.cross(a, b), axis=1)
    R = num / (2.0 * vol6 + 1e-300)
    faces = [(P[:, 1], P[:, 2], P[:, 3]), (P[:, 0], P[:, 2], P[:, 3]), (P[:, 0], P[:, 1], P[:, 3]), (P[:, 0], P[:, 1], P[:, 2])]
    area = sum(0.5 * np.linalg.norm(np.cross(q - p, r - p), axis=1) for p, q, r in faces)
    r_in = 3.0 * (vol6 / 6.0) / (area + 1e-300)
    return R / (3.0 * r_in + 1e-300)


def edge_lengths(points: np.ndarray, tets: np.ndarray) -> np.ndarray:
    P = points[tets]
    return np.linalg.norm(P[:, _EDGES[:, 1]] - P[:, _EDGES[:, 0]], axis=2)


def body_report(points: np.ndarray, tets: np.ndarray, analytic_volume: float) -> dict:
    """Quality of one body: watertight, volume vs analytic, dihedral angles, aspect ratio, sizes."""
    vol = tet_volumes(points, tets)
    dih = dihedral_angles_deg(points, tets)
    q = radius_ratio(points, tets)
    le = edge_lengths(points, tets)
    V = float(vol.sum())
    return {
        "n_nodes": int(len(np.unique(tets))),
        "n_tets": int(len(tets)),
        "watertight": bool(is_watertight(tets)),
        "n_inverted": int((vol <= 0).sum()),
        "volume_m3": V,
        "analytic_volume_m3": float(analytic_volume),
        "volume_rel_error": float(V / analytic_volume - 1.0),
        "min_dihedral_deg": float(dih.min()),
        "max_dihedral_deg": float(dih.max()),
        "p01_min_dihedral_deg": float(np.percentile(dih.min(axis=1), 1)),
        "max_aspect_ratio": float(q.max()),
        "mean_aspect_ratio": float(q.mean()),
        "min_edge_m": float(le.min()),
        "max_edge_m": float(le.max()),
    }


def part_report(points, tets, body_of_tet, bodies) -> dict:
    """{'bodies': {name: body_report}, plus the worst figures over all bodies}."""
    per = {b.name: body_report(points, tets[body_of_tet == i], b.analytic_volume_m3) for i, b in enumerate(bodies)}
    vals = list(per.values())
    return {
        "bodies": per,
        "watertight": all(v["watertight"] for v in vals),
        "n_inverted": sum(v["n_inverted"] for v in vals),
        "max_abs_volume_rel_error": max(abs(v["volume_rel_error"]) for v in vals),
        "min_dihedral_deg": min(v["min_dihedral_deg"] for v in vals),
        "max_aspect_ratio": max(v["max_aspect_ratio"] for v in vals),
        "n_nodes": int(len(points)),
        "n_tets": int(len(tets)),
    }
