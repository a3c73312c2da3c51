"""Compiled (numba) fast path of the 6-PSU chain model: the same equations as
:mod:`femcheck.chain.haptic_6psu_model` (docs/conventions.md §4-7), one pose at a time in machine code.

Why a second implementation: a haptic loop runs at 1 kHz and design sweeps evaluate millions of
poses; numpy's per-call overhead on 6x6 matrices makes the readable vectorized model ~10x too slow
for that. The tests require both paths to agree to 1e-10 relative, so the numpy model stays the
reference transcription of the equations and this kernel only has to be fast.

The element laws are not repeated here: the Hertz tangent stiffness and the cantilever tip compliance are the
functions of :mod:`femcheck.compliance` (``hertz_tangent_stiffness``, ``cantilever_terms``), passed in as
compiled first-class functions (:func:`femcheck.compliance.kernel_laws.kernel_laws`); the other laws arrive as
the per-pose parameters of :func:`femcheck.chain.device_parameters`.

The Hertz fixed point uses Woodbury's identity so that an iteration never inverts a 6x6 matrix:
``(S_fixed + c P P^T)^-1 = M - M P c (I + c P^T M P)^-1 P^T M`` with ``M = S_fixed^-1`` and
``P = [I3; 0]`` (the spherical joint compliance is an isotropic translation).
"""
from __future__ import annotations

import numpy as np
from numba import njit

# packed parameter columns (per pose)
(P_E_LG, P_G_LG, P_A_LG, P_IX_LG, P_IY_LG, P_JT_LG, P_KAPPA_LG, P_E_PR, P_G_PR, P_A_PR, P_IX_PR, P_IY_PR,
 P_JT_PR, P_KAPPA_PR, P_L2, P_C_ACT, P_ESTAR, P_RSTAR, P_FMIN, P_C_UC, P_C_UB, N_PARAMS) = range(22)

_TOL = 1e-12
_MAX_ITER = 200


@njit(cache=True, error_model="numpy")
def _cholesky(A, L):
    """Lower Cholesky factor of a symmetric positive definite A into L; False if A is not SPD.
    Explicit loops: the matrices are 6x6, where BLAS/LAPACK call overhead and threads dominate."""
    m = A.shape[0]
    for j in range(m):
        s = A[j, j]
        for k in range(j):
            s -= L[j, k] * L[j, k]
        if s <= 0.0:
            return False
        L[j, j] = np.sqrt(s)
        for i in range(j + 1, m):
            s = A[i, j]
            for k in range(j):
                s -= L[i, k] * L[j, k]
            L[i, j] = s / L[j, j]
    return True


@njit(cache=True, error_model="numpy")
def _cholesky_solve(L, b, x):
    """x = (L L^T)^-1 b (x may not alias b)."""
    m = L.shape[0]
    for i in range(m):
        s = b[i]
        for k in range(i):
            s -= L[i, k] * x[k]
        x[i] = s / L[i, i]
    for i in range(m - 1, -1, -1):
        s = x[i]
        for k in range(i + 1, m):
            s -= L[k, i] * x[k]
        x[i] = s / L[i, i]


@njit(cache=True, error_model="numpy")
def _spd_inverse(A, out, L, e, x):
    """out = A^-1 for a symmetric positive definite 6x6 A (workspaces L (6,6), e, x (6,))."""
    if not _cholesky(A, L):
        return False
    for j in range(A.shape[0]):
        e[:] = 0.0
        e[j] = 1.0
        _cholesky_solve(L, e, x)
        out[:, j] = x
    return True


@njit(cache=True, error_model="numpy")
def _inverse3(A, out):
    """out = A^-1 for a 3x3 matrix by the adjugate."""
    c00 = A[1, 1] * A[2, 2] - A[1, 2] * A[2, 1]
    c01 = A[1, 2] * A[2, 0] - A[1, 0] * A[2, 2]
    c02 = A[1, 0] * A[2, 1] - A[1, 1] * A[2, 0]
    det = A[0, 0] * c00 + A[0, 1] * c01 + A[0, 2] * c02
    out[0, 0] = c00 / det
    out[1, 0] = c01 / det
    out[2, 0] = c02 / det
    out[0, 1] = (A[0, 2] * A[2, 1] - A[0, 1] * A[2, 2]) / det
    out[1, 1] = (A[0, 0] * A[2, 2] - A[0, 2] * A[2, 0]) / det
    out[2, 1] = (A[0, 1] * A[2, 0] - A[0, 0] * A[2, 1]) / det
    out[0, 2] = (A[0, 1] * A[1, 2] - A[0, 2] * A[1, 1]) / det
    out[1, 2] = (A[0, 2] * A[1, 0] - A[0, 0] * A[1, 2]) / det
    out[2, 2] = (A[0, 0] * A[1, 1] - A[0, 1] * A[1, 0]) / det


@njit(cache=True, error_model="numpy")
def _matmul(A, B, out):
    """out = A @ B with explicit loops (small matrices)."""
    for i in range(A.shape[0]):
        for j in range(B.shape[1]):
            acc = 0.0
            for k in range(A.shape[1]):
                acc += A[i, k] * B[k, j]
            out[i, j] = acc


@njit(cache=True, error_model="numpy")
def _cantilever(law, L, E, G, A, Ix, Iy, Jt, kappa, shear, S):
    """S (6, 6): the tip compliance whose entries the cantilever ``law`` gives (kernel_laws)."""
    for i in range(6):
        for j in range(6):
            S[i, j] = 0.0
    s00, s04, s44, s11, s13, s33, s22, s55 = law(L, E, G, A, Ix, Iy, Jt, kappa, shear)
    S[0, 0] = s00
    S[0, 4] = S[4, 0] = s04
    S[4, 4] = s44
    S[1, 1] = s11
    S[1, 3] = S[3, 1] = s13
    S[3, 3] = s33
    S[2, 2] = s22
    S[5, 5] = s55


@njit(cache=True, error_model="numpy")
def _rotate(R, S, out, tmp):
    """out = Rot(R) S Rot(R)^T for the 2x2 blocks of a 6x6 matrix (tmp: (6, 6) workspace)."""
    for bi in range(2):
        for bj in range(2):
            for i in range(3):
                for j in range(3):
                    acc = 0.0
                    for k in range(3):
                        acc += R[i, k] * S[3 * bi + k, 3 * bj + j]
                    tmp[3 * bi + i, 3 * bj + j] = acc
    for bi in range(2):
        for bj in range(2):
            for i in range(3):
                for j in range(3):
                    acc = 0.0
                    for k in range(3):
                        acc += tmp[3 * bi + i, 3 * bj + k] * R[j, k]
                    out[3 * bi + i, 3 * bj + j] = acc


@njit(cache=True, error_model="numpy")
def _twist_shift(r, T):
    """T = Jf(r)^T = [[I, -[r x]], [0, I]] (twist at P -> twist at Q, r = Q - P)."""
    for i in range(6):
        for j in range(6):
            T[i, j] = 1.0 if i == j else 0.0
    T[0, 4] = r[2]
    T[0, 5] = -r[1]
    T[1, 3] = -r[2]
    T[1, 5] = r[0]
    T[2, 3] = r[1]
    T[2, 4] = -r[0]


@njit(cache=True, error_model="numpy")
def _shift_compliance(r, S, out, tmp):
    """out = T S T^T with T = Jf(r)^T = [[I, -[r x]], [0, I]] (a compliance carried by the lever r).

    Written with the 3x3 blocks of S: 1/4 of the work of two dense 6x6 products.
    tmp: (6, 6) workspace; rows 0..2 receive -[r x] [S21 S22].
    """
    # tmp[0:3, :] = -[r x] @ S[3:6, :]  ( -[r x] v = v x r )
    for j in range(6):
        v0, v1, v2 = S[3, j], S[4, j], S[5, j]
        tmp[0, j] = v1 * r[2] - v2 * r[1]
        tmp[1, j] = v2 * r[0] - v0 * r[2]
        tmp[2, j] = v0 * r[1] - v1 * r[0]
    for i in range(6):
        for j in range(6):
            out[i, j] = S[i, j]
    # out += N S + (N S)^T + N S N^T, N = [[0, -[r x]], [0, 0]]
    for i in range(3):
        for j in range(6):
            out[i, j] += tmp[i, j]
            out[j, i] += tmp[i, j]
    for i in range(3):
        # (N S N^T)[i, k] = (tmp[i, 3:6]) . (-[r x])[k, :]  = -([r x] tmp[i,3:6])_k = (tmp[i,3:6] x r)_k
        w0, w1, w2 = tmp[i, 3], tmp[i, 4], tmp[i, 5]
        out[i, 0] += w1 * r[2] - w2 * r[1]
        out[i, 1] += w2 * r[0] - w0 * r[2]
        out[i, 2] += w0 * r[1] - w1 * r[0]


@njit(cache=True, error_model="numpy")
def _link_frame(u, R):
    x0, x1 = -u[1], u[0]
    nx = np.sqrt(x0 * x0 + x1 * x1)
    x0 /= nx
    x1 /= nx
    R[0, 0], R[1, 0], R[2, 0] = x0, x1, 0.0
    R[0, 1] = u[1] * 0.0 - u[2] * x1
    R[1, 1] = u[2] * x0 - u[0] * 0.0
    R[2, 1] = u[0] * x1 - u[1] * x0
    R[0, 2], R[1, 2], R[2, 2] = u[0], u[1], u[2]


@njit(cache=True, error_model="numpy")
def _hertz_k(law, F, Estar, Rstar, Fmin):
    """The Hertz ``law`` (kernel_laws) at the force F floored at the linearization floor Fmin."""
    if F < Fmin:
        F = Fmin
    return law(F, Estar, Rstar)


@njit(cache=True, error_model="numpy")
def _released_leg_force(a_l, csp_l, g_l, t):
    """Signed axial force f = k_i g_i^T t of a two-force leg, 1/k_i = sum of its element compliances."""
    kl = 1.0 / (a_l[0] + a_l[1] + a_l[3] + a_l[4] + csp_l)
    f = 0.0
    for i in range(6):
        f += g_l[i] * t[i]
    return kl * f


@njit(cache=True, error_model="numpy")
def chain_kernel(hertz, cantilever, B, C, u, tcp, zP, slider, R_lg, e, params, scale, wrench, released, sp_present,
                 shear, c_rot, K_out, t_out, Wc_out, ksp_out, energy_out, iters_out):
    """Evaluate n poses with the Hertz and cantilever laws ``hertz``, ``cantilever``
    (:func:`femcheck.compliance.kernel_laws.kernel_laws`). Shapes: B, C, u (n, 6, 3); tcp, zP (n, 3); slider (n, 6); R_lg (6, 3, 3); e (3,);
    params (n, N_PARAMS); scale (n, 6, 5); wrench (n, 6). Outputs K_out (n, 6, 6), t_out (n, 6),
    Wc_out (n, 6, 6), ksp_out (n, 6), energy_out (n, 6, 5), iters_out (n,). Returns 0; 1 + p if the
    fixed point of pose p did not converge; -1 - p if a chain or platform matrix of pose p is not
    positive definite."""
    n = B.shape[0]
    S_L = np.zeros((6, 6))
    S_P = np.zeros((6, 6))        # proximal link tip compliance (local), the same for the six legs of a pose
    S_tmp = np.zeros((6, 6))
    S_e = np.zeros((6, 5, 6, 6))
    RB = np.zeros((3, 3))
    T = np.zeros((6, 6))
    G = np.zeros((6, 6, 6))
    M = np.zeros((6, 6, 6))
    X = np.zeros((6, 6, 3))       # M P per chain
    H = np.zeros((6, 6, 3))       # G^T M P per chain
    A3 = np.zeros((6, 3, 3))      # P^T M P
    MG = np.zeros((6, 6, 6))      # M G per chain
    g = np.zeros((6, 6))
    a = np.zeros((6, 5))
    csp = np.zeros(6)
    ksp = np.zeros(6)
    W6 = np.zeros((6, 6))
    L6 = np.zeros((6, 6))
    e6 = np.zeros(6)
    x6 = np.zeros(6)
    w3 = np.zeros(3)
    col = np.zeros(6)
    a1 = np.zeros(3)
    a2 = np.zeros(3)
    XY = np.zeros((6, 3))
    Gt = np.zeros(6)
    Wc = np.zeros(6)
    K0 = np.zeros((6, 6))
    t = np.zeros(6)
    K = np.zeros((6, 6))
    Y = np.zeros((6, 3, 3))   # c (I + c A)^-1 per chain
    Z3 = np.zeros((3, 3))
    HY = np.zeros((6, 3))
    Ht = np.zeros(3)
    YHt = np.zeros(3)
    r3 = np.zeros(3)
    rc3 = np.zeros(3)
    for p in range(n):
        pr = params[p]
        W = wrench[p]
        _cantilever(cantilever, pr[P_L2], pr[P_E_PR], pr[P_G_PR], pr[P_A_PR], pr[P_IX_PR], pr[P_IY_PR], pr[P_JT_PR],
                    pr[P_KAPPA_PR], shear, S_P)
        for l in range(6):
            _cantilever(cantilever, slider[p, l], pr[P_E_LG], pr[P_G_LG], pr[P_A_LG], pr[P_IX_LG], pr[P_IY_LG], pr[P_JT_LG],
                        pr[P_KAPPA_LG], shear, S_L)
            _rotate(R_lg[l], S_L, S_tmp, W6)            # guideway tip compliance at B_i, frame U
            _link_frame(u[p, l], RB)
            ue = u[p, l, 0] * e[0] + u[p, l, 1] * e[1] + u[p, l, 2] * e[2]
            if released:
                acc = 0.0
                for i in range(3):
                    for j in range(3):
                        acc += u[p, l, i] * S_tmp[i, j] * u[p, l, j]
                a[l, 0] = acc * scale[p, l, 0]
                a[l, 1] = pr[P_C_ACT] * ue * ue * scale[p, l, 1]
                a[l, 2] = 0.0
                a[l, 3] = S_P[2, 2] * scale[p, l, 3]   # the link's axial compliance L / (E A)
                a[l, 4] = (pr[P_C_UC] + pr[P_C_UB]) * scale[p, l, 4]  # u^T R_B diag R_B^T u = c_uc + c_ub
                g[l, 0], g[l, 1], g[l, 2] = u[p, l, 0], u[p, l, 1], u[p, l, 2]
                rx, ry, rz = C[p, l, 0] - tcp[p, 0], C[p, l, 1] - tcp[p, 1], C[p, l, 2] - tcp[p, 2]
                g[l, 3] = ry * u[p, l, 2] - rz * u[p, l, 1]
                g[l, 4] = rz * u[p, l, 0] - rx * u[p, l, 2]
                g[l, 5] = rx * u[p, l, 1] - ry * u[p, l, 0]
                continue
            # rigid joints: element compliances carried to C_i
            r = r3
            for i in range(3):
                r[i] = C[p, l, i] - B[p, l, i]
            _shift_compliance(r, S_tmp, S_e[l, 0], W6)
            for i in range(6):
                for j in range(6):
                    S_e[l, 0, i, j] *= scale[p, l, 0]
                    S_e[l, 1, i, j] = 0.0
                    S_e[l, 2, i, j] = 0.0
                    S_e[l, 4, i, j] = 0.0
            for i in range(3):
                for j in range(3):
                    S_e[l, 1, i, j] = pr[P_C_ACT] * e[i] * e[j] * scale[p, l, 1]
                    S_e[l, 4, i, j] = (RB[i, 0] * RB[j, 0] * pr[P_C_UC] + RB[i, 1] * RB[j, 1] * pr[P_C_UC]
                                       + RB[i, 2] * RB[j, 2] * (pr[P_C_UC] + pr[P_C_UB])) * scale[p, l, 4]
            _rotate(RB, S_P, S_e[l, 3], W6)
            for i in range(6):
                for j in range(6):
                    S_e[l, 3, i, j] *= scale[p, l, 3]
            if c_rot > 0.0:
                # passive joint rotations as torsional springs: S joint [w x r; w], U joint [0; a1], [0; a2]
                for k in range(3):
                    w = w3
                    w[:] = 0.0
                    w[k] = 1.0
                    col[0] = w[1] * r[2] - w[2] * r[1]
                    col[1] = w[2] * r[0] - w[0] * r[2]
                    col[2] = w[0] * r[1] - w[1] * r[0]
                    col[3], col[4], col[5] = w[0], w[1], w[2]
                    for i in range(6):
                        for j in range(6):
                            S_e[l, 2, i, j] += c_rot * col[i] * col[j]
                uu = u[p, l]
                a1[0] = zP[p, 1] * uu[2] - zP[p, 2] * uu[1]
                a1[1] = zP[p, 2] * uu[0] - zP[p, 0] * uu[2]
                a1[2] = zP[p, 0] * uu[1] - zP[p, 1] * uu[0]
                a1 /= np.sqrt(a1[0] ** 2 + a1[1] ** 2 + a1[2] ** 2)
                a2[0] = uu[1] * a1[2] - uu[2] * a1[1]
                a2[1] = uu[2] * a1[0] - uu[0] * a1[2]
                a2[2] = uu[0] * a1[1] - uu[1] * a1[0]
                for i in range(3):
                    for j in range(3):
                        S_e[l, 4, 3 + i, 3 + j] += c_rot * (a1[i] * a1[j] + a2[i] * a2[j])
            for i in range(6):
                for j in range(6):
                    S_tmp[i, j] = S_e[l, 0, i, j] + S_e[l, 1, i, j] + S_e[l, 2, i, j] + S_e[l, 3, i, j] + S_e[l, 4, i, j]
            if not _spd_inverse(S_tmp, M[l], L6, e6, x6):
                return -1 - p
            for i in range(6):
                for j in range(i + 1, 6):
                    s = 0.5 * (M[l, i, j] + M[l, j, i])
                    M[l, i, j] = s
                    M[l, j, i] = s
            rc = rc3
            for i in range(3):
                rc[i] = C[p, l, i] - tcp[p, i]
            _twist_shift(rc, T)
            G[l] = T                                    # G_i = Jf(C_i - T)^T = [[I, -[rc x]], [0, I]]
            # M G: left block M[:, :3]; right block M[:, 3:] - M[:, :3] [rc x]  (row m -> m x rc)
            for i in range(6):
                m0, m1, m2 = M[l, i, 0], M[l, i, 1], M[l, i, 2]
                MG[l, i, 0], MG[l, i, 1], MG[l, i, 2] = m0, m1, m2
                MG[l, i, 3] = M[l, i, 3] - (m1 * rc[2] - m2 * rc[1])
                MG[l, i, 4] = M[l, i, 4] - (m2 * rc[0] - m0 * rc[2])
                MG[l, i, 5] = M[l, i, 5] - (m0 * rc[1] - m1 * rc[0])
                for j in range(3):
                    X[l, i, j] = M[l, i, j]
            # H = G^T X: top X[0:3]; bottom [rc x] X[0:3] + X[3:6] (column-wise rc x col)
            for j in range(3):
                x0, x1, x2 = X[l, 0, j], X[l, 1, j], X[l, 2, j]
                H[l, 0, j], H[l, 1, j], H[l, 2, j] = x0, x1, x2
                H[l, 3, j] = X[l, 3, j] + rc[1] * x2 - rc[2] * x1
                H[l, 4, j] = X[l, 4, j] + rc[2] * x0 - rc[0] * x2
                H[l, 5, j] = X[l, 5, j] + rc[0] * x1 - rc[1] * x0
            for i in range(3):
                for j in range(3):
                    A3[l, i, j] = M[l, i, j]

        # ---- K0 = sum_i G_i^T M_i G_i (rigid joints; the part that does not change in the fixed point)
        K0[:, :] = 0.0
        if not released:
            for l in range(6):
                # G^T (M G): top rows = (M G)[0:3]; bottom rows = [rc x] (M G)[0:3] + (M G)[3:6]
                rx, ry, rz = C[p, l, 0] - tcp[p, 0], C[p, l, 1] - tcp[p, 1], C[p, l, 2] - tcp[p, 2]
                for j in range(6):
                    a0, a1_, a2_ = MG[l, 0, j], MG[l, 1, j], MG[l, 2, j]
                    K0[0, j] += a0
                    K0[1, j] += a1_
                    K0[2, j] += a2_
                    K0[3, j] += MG[l, 3, j] + ry * a2_ - rz * a1_
                    K0[4, j] += MG[l, 4, j] + rz * a0 - rx * a2_
                    K0[5, j] += MG[l, 5, j] + rx * a1_ - ry * a0
        # ---- Hertz fixed point over the six spherical joints (docs/conventions.md §6)
        for l in range(6):
            csp[l] = 0.0
            ksp[l] = np.nan
        it = 0
        converged = not sp_present
        while True:
            if released:
                for i in range(6):
                    for j in range(6):
                        K[i, j] = 0.0
                for l in range(6):
                    kl = 1.0 / (a[l, 0] + a[l, 1] + a[l, 3] + a[l, 4] + csp[l])
                    for i in range(6):
                        for j in range(6):
                            K[i, j] += kl * g[l, i] * g[l, j]
            else:
                for i in range(6):
                    for j in range(6):
                        K[i, j] = K0[i, j]
                for l in range(6):
                    c = csp[l]
                    if c == 0.0:
                        Y[l, :, :] = 0.0
                        continue
                    for i in range(3):
                        for j in range(3):
                            Z3[i, j] = c * A3[l, i, j] + (1.0 if i == j else 0.0)
                    _inverse3(Z3, Y[l])
                    for i in range(3):
                        for j in range(3):
                            Y[l, i, j] *= c
                    _matmul(H[l], Y[l], HY)
                    for i in range(6):
                        for j in range(i, 6):
                            K[i, j] -= HY[i, 0] * H[l, j, 0] + HY[i, 1] * H[l, j, 1] + HY[i, 2] * H[l, j, 2]
            if released:
                for i in range(6):
                    for j in range(i + 1, 6):
                        s = 0.5 * (K[i, j] + K[j, i])
                        K[i, j] = s
                        K[j, i] = s
            else:   # only the upper triangle was updated by the Woodbury terms
                for i in range(6):
                    for j in range(i + 1, 6):
                        K[j, i] = K[i, j]
            if not _cholesky(K, L6):
                return -1 - p
            _cholesky_solve(L6, W, t)
            if converged or it >= _MAX_ITER:
                break
            change = 0.0
            for l in range(6):
                if released:
                    F = abs(_released_leg_force(a[l], csp[l], g[l], t))
                else:
                    for j in range(3):
                        acc = 0.0
                        for i in range(6):
                            acc += H[l, i, j] * t[i]
                        Ht[j] = acc
                    for i in range(3):
                        acc = 0.0
                        for j in range(3):
                            acc += Y[l, i, j] * Ht[j]
                        YHt[i] = acc
                    F2 = 0.0
                    for i in range(3):
                        fi = 0.0
                        for j in range(6):
                            fi += MG[l, i, j] * t[j]
                        for j in range(3):
                            fi -= X[l, i, j] * YHt[j]
                        F2 += fi * fi
                    F = np.sqrt(F2)
                k_new = _hertz_k(hertz, F, pr[P_ESTAR], pr[P_RSTAR], pr[P_FMIN])
                if it > 0:
                    d = abs(k_new - ksp[l]) / k_new
                    if d > change:
                        change = d
                ksp[l] = k_new
                csp[l] = scale[p, l, 2] / k_new
            if it > 0 and change < _TOL:
                converged = True
            it += 1
        iters_out[p] = max(it, 1)
        if not converged:
            return 1 + p
        K_out[p] = K
        t_out[p] = t
        for l in range(6):
            ksp_out[p, l] = ksp[l]
        # ---- chain wrenches and complementary energy per element
        for l in range(6):
            if released:
                f = _released_leg_force(a[l], csp[l], g[l], t)
                for i in range(3):
                    Wc_out[p, l, i] = f * u[p, l, i]
                    Wc_out[p, l, 3 + i] = 0.0
                a[l, 2] = csp[l]
                for k in range(5):
                    energy_out[p, l, k] = f * f * a[l, k]
            else:
                _matmul(X[l], Y[l], XY)
                for i in range(6):
                    acc = 0.0
                    for j in range(6):
                        acc += G[l, i, j] * t[j]
                    Gt[i] = acc
                for i in range(6):
                    acc = 0.0
                    for j in range(6):
                        kij = M[l, i, j]
                        for k in range(3):
                            kij -= XY[i, k] * X[l, j, k]
                        acc += kij * Gt[j]
                    Wc[i] = acc
                for i in range(6):
                    Wc_out[p, l, i] = Wc[i]
                for i in range(3):
                    S_e[l, 2, i, i] += csp[l]
                for k in range(5):
                    acc = 0.0
                    for i in range(6):
                        for j in range(6):
                            acc += Wc[i] * S_e[l, k, i, j] * Wc[j]
                    energy_out[p, l, k] = acc
    return 0
