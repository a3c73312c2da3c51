"""Platform deflection of the R-CUBE (HISS) as a function of the eq. 12 weights, with its exact Jacobian.

The fit of seed 001 eqs. 10-12 needs the model's platform twist ``x = K(w)^-1 F`` at each measurement and,
for a robust solver and honest confidence intervals, its derivative with respect to ``s = log w``. Both
are computed here in closed form (no finite differences; cond(K_i) ~ 1e9 makes differences unreliable).

With ``D = diag(d(w))`` (eq. 12 map), ``K' = D K_theta D`` (eq. 10) and ``M_k = diag(dd/ds_k / d)`` (e/2 on
the diagonal entries tied to weight k, e the exponent of the eq. 10 reading: ``d = w^(e/2)``, e = 2 as printed,
e = 1 when the weight scales the stiffness linearly; ``weight_fitting.STIFFNESS_EXPONENT``)::

    dK'^-1/ds_k = -(K'^-1 M_k + M_k K'^-1)
    dC_i/ds_k   = J_theta dK'^-1/ds_k J_theta^T                      (C_i = J_theta K'^-1 J_theta^T, eq. 5)
    dK_i/ds_k   = -K_i dC_i/ds_k K_i                                 (upper-left block of the bordered inverse, eq. 6)
    dx/ds_k     = -K^-1 (sum_i dK_i/ds_k) x = K^-1 sum_i K_i dC_i/ds_k (K_i x)

The third line holds because only the upper-left block of the bordered matrix depends on w. A test
checks the Jacobian against central differences.

Units: F in N and N m, x in m and rad (the twist at the platform point P).
"""
from __future__ import annotations

import numpy as np

from femcheck.vjm.parallel_vjm import parallel_stiffness
from femcheck.vjm.weight_fitting import STIFFNESS_EXPONENT, weight_factors


class RCubeWeightModel:
    """x(w) = K(w)^-1 F for measurements at test points.

    ``J_theta`` (L, m, 6, k) and ``J_phi`` (L, m, 6, p) at the m test points (``rcube_geometry.leg_jacobians``);
    ``K_theta`` (k, k) nominal virtual-joint stiffness of one leg; ``weight_map`` (k,) eq. 12;
    ``point`` (N,) test-point index of each measurement; ``wrench`` (N, 6); ``reading`` of eq. 10
    (``linear`` | ``quadratic``).
    """

    def __init__(self, J_theta, J_phi, K_theta, weight_map, point, wrench, reading: str = "quadratic"):
        self.Jt = np.asarray(J_theta, dtype=float)
        self.Jp = np.asarray(J_phi, dtype=float)
        self.K = np.asarray(K_theta, dtype=float)
        self.map = np.asarray(weight_map)
        self.point = np.asarray(point, dtype=int)
        self.F = np.asarray(wrench, dtype=float).reshape(-1, 6)
        self.n_weights = int(self.map.max()) + 1
        self.reading = reading
        # (k, p) d log d_j / d log w_q: e/2 where diagonal entry j is tied to weight q, else 0
        self._tie = (self.map[:, None] == np.arange(self.n_weights)[None, :]) * (STIFFNESS_EXPONENT[reading] / 2)

    def platform_stiffness(self, w) -> tuple[np.ndarray, np.ndarray]:
        """(K_legs (L, m, 6, 6), K (m, 6, 6)) at the test points for weights w."""
        d = weight_factors(w, self.map, self.reading)
        return parallel_stiffness(self.Jt, d[:, None] * self.K * d[None, :], self.Jp)

    def predict(self, w) -> np.ndarray:
        """Platform twists (N, 6), m and rad."""
        _, K = self.platform_stiffness(w)
        return np.linalg.solve(K[self.point], self.F[..., None])[..., 0]

    def predict_and_jacobian(self, w) -> tuple[np.ndarray, np.ndarray]:
        """(x (N, 6), dx/dlog w (N, 6, p))."""
        d = weight_factors(w, self.map, self.reading)
        Kp = d[:, None] * self.K * d[None, :]
        Kl, K = parallel_stiffness(self.Jt, Kp, self.Jp)
        x = np.linalg.solve(K[self.point], self.F[..., None])[..., 0]           # (N, 6)
        Kinv = np.linalg.inv(Kp)
        J = self.Jt[:, self.point]                                              # (L, N, 6, k)
        G = J @ Kinv                                                            # J K'^-1
        KlN = Kl[:, self.point]                                                 # (L, N, 6, 6)
        u = np.einsum("lnab,nb->lna", KlN, x)                                   # leg wrenches K_i x
        a = np.einsum("lnak,lna->lnk", J, u)                                    # J^T u
        b = np.einsum("lnak,lna->lnk", G, u)                                    # G^T u
        # dC_i/ds_q u_i = -(G M_q J^T u + J M_q G^T u): per diagonal entry j, then summed over the entries of q
        T = G * a[:, :, None, :] + J * b[:, :, None, :]                          # (L, N, 6, k)
        dCu = -np.einsum("lnak,kq->lnaq", T, self._tie)                          # (L, N, 6, p)
        rhs = np.einsum("lnab,lnbq->naq", KlN, dCu)                              # sum_i K_i dC_i u_i
        dx = np.linalg.solve(K[self.point], rhs)                                 # (N, 6, p)
        return x, dx
