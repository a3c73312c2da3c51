"""Platform twist from three measured hole points before and after loading (seed 001 sec. 3).

The three holes lie on a circle on the platform. Its centre (circumcentre) and plane normal locate the
platform; the rigid motion between the two hole sets (Kabsch / SVD) gives the rotation. The twist is
(centre displacement in m, rotation vector in rad); shapes (m, 3, 3) holes -> (m, 6).
"""
from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation


def circle_centre_and_normal(holes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Circumcentre (m, 3) and unit plane normal (m, 3) of three points (m, 3, 3) (textbook circumcentre)."""
    H = np.asarray(holes, dtype=float)
    a, b = H[:, 0] - H[:, 2], H[:, 1] - H[:, 2]
    axb = np.cross(a, b)
    n2 = np.einsum("mk,mk->m", axb, axb)[:, None]
    aa, bb = np.einsum("mk,mk->m", a, a)[:, None], np.einsum("mk,mk->m", b, b)[:, None]
    centre = H[:, 2] + np.cross(aa * b - bb * a, axb) / (2 * n2)
    return centre, axb / np.sqrt(n2)


def platform_twist(before: np.ndarray, after: np.ndarray) -> np.ndarray:
    """(m, 6) twist: circle-centre displacement (m) and rotation vector (rad) of the hole triangle."""
    c0, _ = circle_centre_and_normal(before)
    c1, _ = circle_centre_and_normal(after)
    X, Y = np.asarray(before) - c0[:, None], np.asarray(after) - c1[:, None]
    U, _, Vt = np.linalg.svd(np.einsum("mpi,mpj->mij", X, Y))
    d = np.sign(np.linalg.det(np.einsum("mij,mjk->mik", U, Vt)))
    D = np.ones((len(d), 3)); D[:, 2] = d
    R = np.einsum("mji,mj,mkj->mik", Vt, D, U)                  # R = V D U^T maps before onto after
    return np.column_stack([c1 - c0, Rotation.from_matrix(R).as_rotvec()])
