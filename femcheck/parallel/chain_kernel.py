"""Compiled (numba) path of the general parallel-device chain model: the same equations as
:mod:`femcheck.parallel.leg_kinematics` and :mod:`femcheck.parallel.chain_model`, one pose and one leg at a time
in machine code, on the flat arrays of :mod:`femcheck.parallel.kernel_tables`.

Inverse kinematics (:func:`ik_kernel`), per leg and pose:

- closed form where the leg has one. ``F-P*-S-U`` (the 6-PSU): the slide from the sphere ``|C - B| = L``,
  ``q_P = b - sigma sqrt(b^2 - |r|^2 + L^2)`` with ``r = C - c_S``, ``b = u . r`` and sigma the home branch;
  the U angles from Paden-Kahan subproblem 2 (``Rot(a2, -q5) Rot(a1, -q4) d_0 = R^T d``) and the S angles
  from the rotation left over (Cardan angles about its orthonormal axes). ``U-P*-S`` (the hexapod strut): the
  leg length ``|p + R b - a|``, the U angles from subproblem 2 pointing the strut, the S angles as above.
  ``R*-U-U`` (the Delta): the crank angle from the elbow's circle about the crank axis meeting the sphere of the
  rod about C, the elbow U angles from subproblem 2, the platform U angles from the rotation left over
  (subproblem 1 twice); then the forward pass gives the rest and the end error, the orientation included (a
  rotation the leg cannot follow fails there).
  Where the closed form has no real solution the leg falls back to the numeric solution;
- numeric otherwise: Gauss-Newton from the home pose on the end frame, the step from the normal equations
  (``(J^T J) dq = J^T e``; ``J J^T`` for a redundant leg), limited to ``MAX_STEP`` as in numpy.

The numeric solution ends with the forward pass (product of exponentials of the home screws) that gives the
joint centres, the unit joint twists at C, the link frames and the residual. The P-S-U and U-P-S closed forms
write the same quantities from their angles directly and are checked by their own position residual (their
orientation holds by construction); the R*-U-U closed form runs the forward pass. The tests hold them to the
numeric solution.

Chain model (:func:`chain_kernel`), per pose: every element's compliance carried to C_i (cantilever links,
drive ``c xi xi^T``, Hertz line contact in the link frame), the leg's wrench basis N (``I`` for rigid joints;
for released joints the Householder complement of the passive twists), ``A = N^T S N``, ``E = G^T N`` and
``K_T = sum E A^-1 E^T``. The Hertz point contacts ``c I3`` on the translations are linearized at their leg's
force by fixed-point iteration: a two-force leg (m = 1) is a scalar ``k = 1 / (a + c |n_F|^2)``; any other leg
keeps ``A^-1`` and updates by Woodbury's identity with 3x3 inverses. Released
P-S-U and U-P-S legs use their one wrench directly, the force along the line of the S and U centres.

:func:`evaluate_kernel` runs both in one call over all poses, block by block (the default of
:func:`femcheck.parallel.chain_model.evaluate` when no state is given); there a closed-form leg computes only
what the chain model reads (no passive joint angles, unless a joint limit needs them, and no passive twists; the
R*-U-U leg gives all of them, its released wrench basis needs the passive twists). Every helper the per-pose loops
call is a leaf, for speed: see :func:`_rot`.

The element laws are not repeated here: the Hertz point-contact tangent stiffness and the cantilever tip compliance
are the functions of :mod:`femcheck.compliance` (``hertz_tangent_stiffness``, ``cantilever_terms``), passed in as
compiled first-class functions (:func:`femcheck.compliance.kernel_laws.kernel_laws`); the other laws arrive in the
device tables (:mod:`femcheck.parallel.kernel_tables`, from :func:`femcheck.parallel.device.device_from_case`).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

#: the numeric IK's constants (as :mod:`femcheck.parallel.leg_kinematics`)
MAX_ITER = 60
TOL = 1e-11
MAX_STEP = 0.3
_FP_TOL = 1e-12
_FP_MAX_ITER = 200
_LADDER_TOL = 1e-10


# ---------------------------------------------------------------- small dense algebra (explicit loops, size m)
@njit("boolean(f8[:, ::1], f8[:, ::1], i8)", cache=True, error_model="numpy")
def _chol(A, Lf, m):
    """Lower Cholesky factor of A[:m, :m] into Lf; False if not positive definite."""
    for j in range(m):
        s = A[j, j]
        for k in range(j):
            s -= Lf[j, k] * Lf[j, k]
        if not s > 0.0:
            return False
        Lf[j, j] = math.sqrt(s)
        for i in range(j + 1, m):
            s = A[i, j]
            for k in range(j):
                s -= Lf[i, k] * Lf[j, k]
            Lf[i, j] = s / Lf[j, j]
    return True


@njit("void(f8[:, ::1], f8[::1], f8[::1], i8)", cache=True, error_model="numpy")
def _chol_forward(Lf, b, x, m):
    """x[:m] = Lf^-1 b (forward substitution). With :func:`_chol_back`, the solve with Lf Lf^T: two leaves (one
    function holding both loops counts references, see :func:`_rot`)."""
    for i in range(m):
        s = b[i]
        for k in range(i):
            s -= Lf[i, k] * x[k]
        x[i] = s / Lf[i, i]


@njit("void(f8[:, ::1], f8[::1], i8)", cache=True, error_model="numpy")
def _chol_back(Lf, x, m):
    """x[:m] = Lf^-T x in place (back substitution)."""
    for ii in range(m):
        i = m - 1 - ii
        s = x[i]
        for k in range(i + 1, m):
            s -= Lf[k, i] * x[k]
        x[i] = s / Lf[i, i]


@njit("void(f8[:, ::1], f8[:, ::1], i8)", cache=True, error_model="numpy")
def _chol_inverse(Lf, out, m):
    """out[:m, :m] = (Lf Lf^T)^-1 = Lf^-T Lf^-1 from the Cholesky factor Lf, symmetric by construction.

    Lf^-1 (lower) is written transposed into the upper triangle of out (out[j, i] = (Lf^-1)[i, j], i >= j), then
    out[a, b] = sum_{k >= b} out[a, k] out[b, k] (a <= b) overwrites it row by row in place (an entry is read only
    before it is overwritten): m^3 / 3 multiplications, a third of m solves with the factor."""
    for j in range(m):
        out[j, j] = 1.0 / Lf[j, j]
        for i in range(j + 1, m):
            s = 0.0
            for k in range(j, i):
                s += Lf[i, k] * out[j, k]
            out[j, i] = -s / Lf[i, i]
    for a in range(m):
        for b in range(a, m):
            s = 0.0
            for k in range(b, m):
                s += out[a, k] * out[b, k]
            out[a, b] = s
    for a in range(m):
        for b in range(a + 1, m):
            out[b, a] = out[a, b]


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
def _rot(w0, w1, w2, c, s, R):
    """R = Rot(w, q) = c I + s [w x] + (1 - c) w w^T from c = cos q, s = sin q (unit axis w, its components).

    Machine-code note, for every helper the per-pose loops call: numba counts references to the array arguments
    of a function with atomic increments; they are pruned only in a function that calls no other compiled
    function (inlined or not). Such a leaf costs nothing to call, a function that calls others costs two atomic
    operations per array argument and call (~5 to 10 ns each); ``x ** 2`` and iterating over a tuple are calls
    too (the scalar functions called are ``math``'s: an instruction or a libm call). A function holding two loops one
    after the other may count as well (hence :func:`_chol_forward` and :func:`_chol_back`; :func:`_sp2_z` still
    counts). The helpers are leaves,
    and the closed forms are written out in :func:`_ik_range`'s loop (as an inlined function taking tuples of
    work arrays they cost ~50 atomic operations per leg and pose, a third of the released model's time)."""
    v = 1.0 - c
    R[0, 0] = c + w0 * w0 * v
    R[0, 1] = w0 * w1 * v - w2 * s
    R[0, 2] = w0 * w2 * v + w1 * s
    R[1, 0] = w1 * w0 * v + w2 * s
    R[1, 1] = c + w1 * w1 * v
    R[1, 2] = w1 * w2 * v - w0 * s
    R[2, 0] = w2 * w0 * v - w1 * s
    R[2, 1] = w2 * w1 * v + w0 * s
    R[2, 2] = c + w2 * w2 * v


@njit(cache=True, error_model="numpy")
def _rot_back(w, c, s, x0, x1, x2, out):
    """out = Rot(w, -q) x = c x - s (w x x) + (1 - c) (w . x) w (c = cos q, s = sin q)."""
    wx = w[0] * x0 + w[1] * x1 + w[2] * x2
    out[0] = c * x0 - s * (w[1] * x2 - w[2] * x1) + (1.0 - c) * wx * w[0]
    out[1] = c * x1 - s * (w[2] * x0 - w[0] * x2) + (1.0 - c) * wx * w[1]
    out[2] = c * x2 - s * (w[0] * x1 - w[1] * x0) + (1.0 - c) * wx * w[2]


@njit(cache=True, error_model="numpy")
def _target_rotation(R_t, R_home, Rn):
    """Rn = R_t R_home^T: the rotation the leg's freedoms must produce (R_t the platform's at the pose)."""
    for i in range(3):
        for j in range(3):
            Rn[i, j] = R_t[i, 0] * R_home[j, 0] + R_t[i, 1] * R_home[j, 1] + R_t[i, 2] * R_home[j, 2]


@njit(cache=True, error_model="numpy")
def _mm3(A, B, out):
    for i in range(3):
        for j in range(3):
            out[i, j] = A[i, 0] * B[0, j] + A[i, 1] * B[1, j] + A[i, 2] * B[2, j]


# ---------------------------------------------------------------- forward pass of one leg
@njit(cache=True, error_model="numpy")
def _forward(l, q, i_n, dkind, daxis, dpoint, Rp, tp, Rk, tk):
    """Prefix transforms Rp (nd+1, 3, 3), tp (nd+1, 3) of the freedoms of leg l at joint values q.
    (The tables are read element by element, never as views: a view costs two atomic reference counts.)"""
    nd = i_n[l, 0]
    for i in range(3):
        for j in range(3):
            Rp[0, i, j] = 1.0 if i == j else 0.0
        tp[0, i] = 0.0
    for k in range(nd):
        w0, w1, w2 = daxis[l, k, 0], daxis[l, k, 1], daxis[l, k, 2]
        if dkind[l, k] == 0:
            c, s = math.cos(q[k]), math.sin(q[k])
            v = 1.0 - c   # Rot(w, q) as _rot (written out: _forward stays a leaf)
            Rk[0, 0] = c + w0 * w0 * v
            Rk[0, 1] = w0 * w1 * v - w2 * s
            Rk[0, 2] = w0 * w2 * v + w1 * s
            Rk[1, 0] = w1 * w0 * v + w2 * s
            Rk[1, 1] = c + w1 * w1 * v
            Rk[1, 2] = w1 * w2 * v - w0 * s
            Rk[2, 0] = w2 * w0 * v - w1 * s
            Rk[2, 1] = w2 * w1 * v + w0 * s
            Rk[2, 2] = c + w2 * w2 * v
            c0, c1, c2 = dpoint[l, k, 0], dpoint[l, k, 1], dpoint[l, k, 2]
            for i in range(3):
                tk[i] = dpoint[l, k, i] - (Rk[i, 0] * c0 + Rk[i, 1] * c1 + Rk[i, 2] * c2)
        else:
            for i in range(3):
                for j in range(3):
                    Rk[i, j] = 1.0 if i == j else 0.0
            tk[0], tk[1], tk[2] = w0 * q[k], w1 * q[k], w2 * q[k]
        for i in range(3):
            for j in range(3):
                Rp[k + 1, i, j] = Rp[k, i, 0] * Rk[0, j] + Rp[k, i, 1] * Rk[1, j] + Rp[k, i, 2] * Rk[2, j]
            tp[k + 1, i] = Rp[k, i, 0] * tk[0] + Rp[k, i, 1] * tk[1] + Rp[k, i, 2] * tk[2] + tp[k, i]


@njit(cache=True, error_model="numpy")
def _end_error(l, i_n, cen, Rp, tp, R_t, C_t, C, e, Rend, Rerr, R_home):
    """C (3,) the leg's attachment, e (6,) [C_t - C; rotvec(R_t (R_nd R_home)^T)]; returns |e|."""
    nd = i_n[l, 0]
    m = i_n[l, 1] - 1
    cl0, cl1, cl2 = cen[l, m, 0], cen[l, m, 1], cen[l, m, 2]
    for i in range(3):
        C[i] = Rp[nd, i, 0] * cl0 + Rp[nd, i, 1] * cl1 + Rp[nd, i, 2] * cl2 + tp[nd, i]
        e[i] = C_t[i] - C[i]
    for i in range(3):
        for j in range(3):
            Rend[i, j] = Rp[nd, i, 0] * R_home[0, j] + Rp[nd, i, 1] * R_home[1, j] + Rp[nd, i, 2] * R_home[2, j]
    for i in range(3):
        for j in range(3):
            Rerr[i, j] = R_t[i, 0] * Rend[j, 0] + R_t[i, 1] * Rend[j, 1] + R_t[i, 2] * Rend[j, 2]
    # rotation vector of Rerr (as femcheck.kinematics.frames.matrix_to_rotvec, angles below pi)
    cs = (Rerr[0, 0] + Rerr[1, 1] + Rerr[2, 2] - 1.0) / 2.0
    cs = min(1.0, max(-1.0, cs))
    th = math.acos(cs)
    s = math.sin(th)
    f = 0.5 if th < 1e-8 else th / (2.0 * (1.0 if s == 0.0 else s))
    e[3] = (Rerr[2, 1] - Rerr[1, 2]) * f
    e[4] = (Rerr[0, 2] - Rerr[2, 0]) * f
    e[5] = (Rerr[1, 0] - Rerr[0, 1]) * f
    acc = 0.0
    for i in range(6):
        acc += e[i] * e[i]
    return math.sqrt(acc)


@njit(cache=True, error_model="numpy")
def _twists(l, i_n, dkind, daxis, dpoint, Rp, tp, C, tw, c):
    """(nd, 6) unit twists of leg l's freedoms at C: R [w x (C - c); w], P [u; 0] (as :func:`_set_twist`, with
    the freedom's axis w = Rp[k] a and point c = Rp[k] c_0 + tp[k] carried by the pose); c (3,) work array.
    Written out, not a call of :func:`_set_twist`: with the call the Delta's detailed model (R*-U-U legs, twists at
    every pose) ran 6 to 9 % slower (released joints; 4,000 poses, CPU time, best of 9, measured 3 times)."""
    for k in range(i_n[l, 0]):
        a0, a1, a2 = daxis[l, k, 0], daxis[l, k, 1], daxis[l, k, 2]
        c0, c1, c2 = dpoint[l, k, 0], dpoint[l, k, 1], dpoint[l, k, 2]
        for i in range(3):
            c[i] = Rp[k, i, 0] * c0 + Rp[k, i, 1] * c1 + Rp[k, i, 2] * c2 + tp[k, i]
        w0 = Rp[k, 0, 0] * a0 + Rp[k, 0, 1] * a1 + Rp[k, 0, 2] * a2
        w1 = Rp[k, 1, 0] * a0 + Rp[k, 1, 1] * a1 + Rp[k, 1, 2] * a2
        w2 = Rp[k, 2, 0] * a0 + Rp[k, 2, 1] * a1 + Rp[k, 2, 2] * a2
        if dkind[l, k] == 0:   # as _set_twist (written out: _twists stays a leaf)
            r0, r1, r2 = C[0] - c[0], C[1] - c[1], C[2] - c[2]
            tw[k, 0] = w1 * r2 - w2 * r1
            tw[k, 1] = w2 * r0 - w0 * r2
            tw[k, 2] = w0 * r1 - w1 * r0
            tw[k, 3], tw[k, 4], tw[k, 5] = w0, w1, w2
        else:
            tw[k, 0], tw[k, 1], tw[k, 2] = w0, w1, w2
            tw[k, 3] = tw[k, 4] = tw[k, 5] = 0.0


# ---------------------------------------------------------------- closed forms
@njit("f8(f8[::1], f8[::1], f8[::1], f8[::1], i8, boolean)", cache=True, error_model="numpy")
def _sp1(w, p, z, cs, k, angle):
    """Paden-Kahan subproblem 1: the angle rotating p into z about the unit axis w (its cos, sin into cs[k:k+2]);
    the angle itself (an arctan2) only if ``angle``, else 0."""
    wp = w[0] * p[0] + w[1] * p[1] + w[2] * p[2]
    wz = w[0] * z[0] + w[1] * z[1] + w[2] * z[2]
    p0, p1, p2 = p[0] - w[0] * wp, p[1] - w[1] * wp, p[2] - w[2] * wp
    z0, z1, z2 = z[0] - w[0] * wz, z[1] - w[1] * wz, z[2] - w[2] * wz
    cx, cy, cz = p1 * z2 - p2 * z1, p2 * z0 - p0 * z2, p0 * z1 - p1 * z0
    y, x = w[0] * cx + w[1] * cy + w[2] * cz, p0 * z0 + p1 * z1 + p2 * z2
    r = math.sqrt(x * x + y * y)
    if r > 0.0:
        ri = 1.0 / r
        cs[k], cs[k + 1] = x * ri, y * ri
    else:
        cs[k], cs[k + 1] = 1.0, 0.0
    return math.atan2(y, x) if angle else 0.0


@njit(cache=True, error_model="numpy")
def _sp2_z(w1, w2, p, qv, z):
    """Paden-Kahan subproblem 2, Rot(w1, t1) Rot(w2, t2) p = qv (axes through one point): the intermediate
    z = Rot(w2, t2) p = Rot(w1, -t1) qv nearest p (the home branch); False if none is real. The angles follow by
    subproblem 1 twice: t2 = _sp1(w2, p, z), t1 = _sp1(w1, z, qv)."""
    c12 = w1[0] * w2[0] + w1[1] * w2[1] + w1[2] * w2[2]
    den = 1.0 - c12 * c12
    if den < 1e-12:
        return False
    w1q = w1[0] * qv[0] + w1[1] * qv[1] + w1[2] * qv[2]
    w2p = w2[0] * p[0] + w2[1] * p[1] + w2[2] * p[2]
    al = (w1q - c12 * w2p) / den
    be = (w2p - c12 * w1q) / den
    cr0 = w1[1] * w2[2] - w1[2] * w2[1]
    cr1 = w1[2] * w2[0] - w1[0] * w2[2]
    cr2 = w1[0] * w2[1] - w1[1] * w2[0]
    pp = p[0] * p[0] + p[1] * p[1] + p[2] * p[2]
    g2 = (pp - al * al - be * be - 2.0 * al * be * c12) / den
    if g2 < 0.0 and g2 >= -1e-12 * pp:
        g2 = 0.0
    if not g2 >= 0.0:
        return False
    g = math.sqrt(abs(g2))   # (g2 >= 0 here; abs lets the compiler use the sqrt instruction, no libm call)
    # the two branches written out, the one nearer to p kept
    b0, b1, b2 = al * w1[0] + be * w2[0], al * w1[1] + be * w2[1], al * w1[2] + be * w2[2]
    gm, gp = -1.0 * g, 1.0 * g
    m0, m1, m2 = b0 + gm * cr0 - p[0], b1 + gm * cr1 - p[1], b2 + gm * cr2 - p[2]
    d_m = m0 * m0 + m1 * m1 + m2 * m2
    m0, m1, m2 = b0 + gp * cr0 - p[0], b1 + gp * cr1 - p[1], b2 + gp * cr2 - p[2]
    d_p = m0 * m0 + m1 * m1 + m2 * m2
    best = 1e300
    if d_m < best:
        best = d_m
        z[0], z[1], z[2] = b0 + gm * cr0, b1 + gm * cr1, b2 + gm * cr2
    if d_p < best:
        z[0], z[1], z[2] = b0 + gp * cr0, b1 + gp * cr1, b2 + gp * cr2
    return True


@njit("void(f8[:, ::1], f8[:, ::1], f8[::1], i8, f8[:, ::1], f8[:, ::1])", cache=True, error_model="numpy")
def _cardan(daxis_s, Rs, q, k0, A, T):
    """S joint angles q[k0:k0+3] with Rot(s1, q1) Rot(s2, q2) Rot(s3, q3) = Rs, s orthonormal right-handed."""
    for i in range(3):
        for j in range(3):
            A[i, j] = daxis_s[j, i]       # columns s1, s2, s3
    # T = A^T Rs A = Rx(q1) Ry(q2) Rz(q3); only T[0, :2] and T[:, 2] are needed
    for j in range(3):
        x0 = Rs[0, 0] * A[0, j] + Rs[0, 1] * A[1, j] + Rs[0, 2] * A[2, j]
        x1 = Rs[1, 0] * A[0, j] + Rs[1, 1] * A[1, j] + Rs[1, 2] * A[2, j]
        x2 = Rs[2, 0] * A[0, j] + Rs[2, 1] * A[1, j] + Rs[2, 2] * A[2, j]
        for i in range(3):
            T[i, j] = A[0, i] * x0 + A[1, i] * x1 + A[2, i] * x2
    q[k0 + 1] = math.asin(min(1.0, max(-1.0, T[0, 2])))
    q[k0] = math.atan2(-T[1, 2], T[2, 2])
    q[k0 + 2] = math.atan2(-T[0, 1], T[0, 0])


@njit("void(f8[:, :, ::1], f8[:, ::1], i8, f8[:, ::1], f8[::1], f8[::1])", cache=True, error_model="numpy")
def _set_transform(Rp, tp, k, R, c_from, c_to):
    """Prefix k: x -> R (x - c_from) + c_to, i.e. Rp[k] = R, tp[k] = c_to - R c_from."""
    for i in range(3):
        for j in range(3):
            Rp[k, i, j] = R[i, j]
        tp[k, i] = c_to[i] - (R[i, 0] * c_from[0] + R[i, 1] * c_from[1] + R[i, 2] * c_from[2])


@njit("void(f8[:, ::1], i8, f8[:, ::1], f8[::1], f8[::1], f8[::1], boolean)", cache=True, error_model="numpy")
def _set_twist(tw, k, R, a, C, c, revolute):
    """tw[k] = [w x (C - c); w] (revolute) or [w; 0] (slide), w = R a."""
    w0 = R[0, 0] * a[0] + R[0, 1] * a[1] + R[0, 2] * a[2]
    w1 = R[1, 0] * a[0] + R[1, 1] * a[1] + R[1, 2] * a[2]
    w2 = R[2, 0] * a[0] + R[2, 1] * a[1] + R[2, 2] * a[2]
    if revolute:
        r0, r1, r2 = C[0] - c[0], C[1] - c[1], C[2] - c[2]
        tw[k, 0] = w1 * r2 - w2 * r1
        tw[k, 1] = w2 * r0 - w0 * r2
        tw[k, 2] = w0 * r1 - w1 * r0
        tw[k, 3], tw[k, 4], tw[k, 5] = w0, w1, w2
    else:
        tw[k, 0], tw[k, 1], tw[k, 2] = w0, w1, w2
        tw[k, 3] = tw[k, 4] = tw[k, 5] = 0.0


@njit(cache=True, error_model="numpy")
def _s_axes(R, A, T, q1, out):
    """The S joint's three axes at the pose, R (rotation before the joint) times A e1, A Rx(q1) e2,
    A Rx(q1) Ry(q2) e3 (the last is A T[:, 2]); out (3, 3) rows. cos q1, sin q1 from T[:, 2] = [s2, -s1 c2, c1 c2]."""
    c2 = math.sqrt(T[1, 2] * T[1, 2] + T[2, 2] * T[2, 2])
    if c2 > 1e-9:
        c1, s1 = T[2, 2] / c2, -T[1, 2] / c2
    else:
        c1, s1 = math.cos(q1), math.sin(q1)
    for i in range(3):
        v0 = A[i, 0]
        v1 = A[i, 1] * c1 + A[i, 2] * s1
        v2 = A[i, 0] * T[0, 2] + A[i, 1] * T[1, 2] + A[i, 2] * T[2, 2]
        out[0, i], out[1, i], out[2, i] = v0, v1, v2
    for k in range(3):
        x0, x1, x2 = out[k, 0], out[k, 1], out[k, 2]
        for i in range(3):
            out[k, i] = R[i, 0] * x0 + R[i, 1] * x1 + R[i, 2] * x2


@njit("void(f8[:, :, ::1], i8, i8, f8[::1])", cache=True, error_model="numpy")
def _row(A, l, k, out):
    """out (3,) = A[l, k] copied (no view)."""
    out[0], out[1], out[2] = A[l, k, 0], A[l, k, 1], A[l, k, 2]


@njit("void(f8[:, :, ::1], f8[:, :, ::1], i8, i8, i8, i8, i8, f8[::1], f8[::1], f8[::1], f8[::1], f8[::1])",
      cache=True, error_model="numpy")
def _slide_u_s(daxis, cen, l, k_p, k_u, m_s, m_u, a_u, a_1, a_2, c_S, c_U):
    """The axes and centres the P-S-U / U-P-S closed forms read, copied (a leaf: element by element, no calls):
    the slide a_u = daxis[l, k_p], the U axes a_1, a_2 = daxis[l, k_u], daxis[l, k_u + 1], the S and U centres
    c_S = cen[l, m_s], c_U = cen[l, m_u]."""
    for i in range(3):
        a_u[i] = daxis[l, k_p, i]
        a_1[i] = daxis[l, k_u, i]
        a_2[i] = daxis[l, k_u + 1, i]
        c_S[i] = cen[l, m_s, i]
        c_U[i] = cen[l, m_u, i]


@njit(cache=True, error_model="numpy")
def _row2(A, k, out):
    """out (3,) = A[k] copied (no view)."""
    out[0], out[1], out[2] = A[k, 0], A[k, 1], A[k, 2]


@njit("void(f8[:, :, ::1], i8, i8, f8[:, ::1])", cache=True, error_model="numpy")
def _rows3(A, l, k, out):
    """out (3, 3) = A[l, k:k+3] copied (no view)."""
    for j in range(3):
        for i in range(3):
            out[j, i] = A[l, k + j, i]


# ---------------------------------------------------------------- inverse kinematics of every leg
@njit(cache=True, error_model="numpy")
def ik_kernel(tab, R_t, C_t, numeric_only, q_out, res_out, ok_out, closed_out, C_out, cen_out, tw_out, lR_out,
              len_out):
    """Inverse kinematics of every leg at n poses.

    R_t (n, 3, 3) platform orientations; C_t (L, n, 3) attachment targets; numeric_only: skip the closed forms.
    Outputs (leg-major, padded): q (L, n, nd), residual (L, n), ok (L, n), closed (L, n) closed form used,
    C (L, n, 3), centres (L, n, nc, 3), twists (L, n, nd, 6), link_R (L, n, nl, 3, 3), link_length (L, n, nl).
    """
    _ik_range(tab, R_t, C_t, numeric_only, True, 0, R_t.shape[0], q_out, res_out, ok_out, closed_out, C_out, cen_out,
              tw_out, lR_out, len_out)


@njit(cache=True, error_model="numpy")
def _ik_range(tab, R_t, C_t, numeric_only, full, p0, p1, q_out, res_out, ok_out, closed_out, C_out, cen_out, tw_out,
              lR_out, len_out):
    """:func:`ik_kernel` on the poses p0 <= p < p1, written at index p - p0 of the outputs. ``full``: the whole
    state; otherwise a closed-form leg writes only what the chain model reads (the actuated joint's value and
    twist, the transforms and C; the passive angles only if a joint limit needs them, and no passive twists)."""
    i_n, dkind, daxis, dpoint, cen, cen_first, lk_i, lk_x, lim_d, lim, f_leg, R_home = (
        tab[0], tab[1], tab[2], tab[3], tab[5], tab[6], tab[7], tab[8], tab[13], tab[14], tab[15], tab[18])
    L = i_n.shape[0]
    ndm = q_out.shape[2]
    Rp = np.zeros((ndm + 1, 3, 3))
    tp = np.zeros((ndm + 1, 3))
    Rk = np.zeros((3, 3))
    tk = np.zeros(3)
    C = np.zeros(3)
    e = np.zeros(6)
    Rend = np.zeros((3, 3))
    Rerr = np.zeros((3, 3))
    tw = np.zeros((ndm, 6))
    Mn = np.zeros((6, 6))
    Lf = np.zeros((6, 6))
    rhs = np.zeros(6)
    y = np.zeros(6)
    q = np.zeros(ndm)
    w3, z3, v3, ang = np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(6)
    Rn, Ra, Rb, Rs, A3, T3, Sx, I3 = (np.zeros((3, 3)), np.zeros((3, 3)), np.zeros((3, 3)), np.zeros((3, 3)),
                                      np.zeros((3, 3)), np.zeros((3, 3)), np.zeros((3, 3)), np.zeros((3, 3)))
    a_u, a_1, a_2, c_S, c_U, Ct3 = np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(3)
    f_1, f_2 = np.zeros(3), np.zeros(3)
    S3, Rt3 = np.zeros((3, 3)), np.zeros((3, 3))
    I3[0, 0] = I3[1, 1] = I3[2, 2] = 1.0
    for l in range(L):
        nd = i_n[l, 0]
        want_q = full or i_n[l, 8] > 0
        for p in range(p0, p1):
            jp = p - p0
            for k in range(ndm):
                q[k] = 0.0
            closed = False
            for i in range(3):
                Ct3[i] = C_t[l, p, i]
                for k in range(3):
                    Rt3[i, k] = R_t[p, i, k]
            if i_n[l, 7] == 3 and not numeric_only:
                # R*-U-U, dofs [R, U1, U2, U3, U4] (the Delta's crank, rod and platform U): the joint values by the
                # closed form, then the forward pass gives the rest and the end error, the orientation included (a
                # pose the five freedoms cannot reach falls back to the numeric solution). Written out here, as the
                # other closed forms, so that the loop calls only leaf helpers (see _rot).
                # - crank q0: the elbow E(q0) = A + (v.a) a + cos q0 v_perp + sin q0 (a x v_perp) (v = E_0 - A, a the
                #   crank axis a_u) on the sphere |C - E| = l (l = |C_0 - E_0|, the rod): alpha cos q0 + beta sin q0
                #   = kappa, alpha = 2 d.v_perp, beta = 2 d.(a x v_perp), kappa = |d|^2 + |v_perp|^2 - l^2,
                #   d = C - A - (v.a) a; q0 = atan2(beta, alpha) - sigma acos(kappa / rho), sigma the home branch;
                # - elbow U (q1, q2, axes a_1, a_2): subproblem 2,
                #   Rot(a_1, q1) Rot(a_2, q2) (C_0 - E_0) = Rot(a, -q0) (C - E);
                # - platform U (q3, q4, axes f_1, f_2): Rot(f_1, q3) Rot(f_2, q4) = (R_0 R_1 R_2)^T R_nd, subproblem 1
                #   on f_2 (for q3), then on f_1 (for q4).
                ok3 = False
                _target_rotation(Rt3, R_home, Rn)
                _row(daxis, l, 0, a_u)
                _row(daxis, l, 1, a_1)
                _row(daxis, l, 2, a_2)
                _row(daxis, l, 3, f_1)
                _row(daxis, l, 4, f_2)
                a0, a1, a2 = dpoint[l, 0, 0], dpoint[l, 0, 1], dpoint[l, 0, 2]       # a point of the crank axis
                v0, v1, v2 = cen[l, 1, 0] - a0, cen[l, 1, 1] - a1, cen[l, 1, 2] - a2
                vw = a_u[0] * v0 + a_u[1] * v1 + a_u[2] * v2
                vp0, vp1, vp2 = v0 - vw * a_u[0], v1 - vw * a_u[1], v2 - vw * a_u[2]
                vx0 = a_u[1] * vp2 - a_u[2] * vp1
                vx1 = a_u[2] * vp0 - a_u[0] * vp2
                vx2 = a_u[0] * vp1 - a_u[1] * vp0
                d0, d1, d2 = Ct3[0] - a0 - vw * a_u[0], Ct3[1] - a1 - vw * a_u[1], Ct3[2] - a2 - vw * a_u[2]
                l2 = 0.0
                for i in range(3):
                    w3[i] = cen[l, 2, i] - cen[l, 1, i]                                  # the rod at home, E_0 -> C_0
                    l2 += w3[i] * w3[i]
                al = 2.0 * (d0 * vp0 + d1 * vp1 + d2 * vp2)
                be = 2.0 * (d0 * vx0 + d1 * vx1 + d2 * vx2)
                ka = d0 * d0 + d1 * d1 + d2 * d2 + vp0 * vp0 + vp1 * vp1 + vp2 * vp2 - l2
                rho = math.sqrt(al * al + be * be)
                if rho > 0.0 and abs(ka) <= rho:
                    q0 = math.atan2(be, al) - f_leg[l, 1] * math.acos(ka / rho)
                    if q0 > np.pi:
                        q0 -= 2.0 * np.pi
                    elif q0 <= -np.pi:
                        q0 += 2.0 * np.pi
                    cq, sq = math.cos(q0), math.sin(q0)
                    # C - E(q0), turned back by the crank
                    x0 = Ct3[0] - (a0 + vw * a_u[0] + cq * vp0 + sq * vx0)
                    x1 = Ct3[1] - (a1 + vw * a_u[1] + cq * vp1 + sq * vx1)
                    x2 = Ct3[2] - (a2 + vw * a_u[2] + cq * vp2 + sq * vx2)
                    _rot_back(a_u, cq, sq, x0, x1, x2, z3)
                    if _sp2_z(a_1, a_2, w3, z3, v3):
                        ok3 = True
                        q[0] = q0
                        q[2] = _sp1(a_2, w3, v3, ang, 4, True)
                        q[1] = _sp1(a_1, v3, z3, ang, 2, True)
                        _rot(a_u[0], a_u[1], a_u[2], cq, sq, Ra)
                        _rot(a_1[0], a_1[1], a_1[2], ang[2], ang[3], Rb)
                        _mm3(Ra, Rb, Rs)
                        _rot(a_2[0], a_2[1], a_2[2], ang[4], ang[5], Rb)
                        _mm3(Rs, Rb, Ra)                                                 # R_0 R_1 R_2
                        for i in range(3):
                            for j in range(3):
                                # what is left for the platform U: R_rem = (R_0 R_1 R_2)^T R_nd
                                Rs[i, j] = Ra[0, i] * Rn[0, j] + Ra[1, i] * Rn[1, j] + Ra[2, i] * Rn[2, j]
                        for i in range(3):
                            z3[i] = Rs[i, 0] * f_2[0] + Rs[i, 1] * f_2[1] + Rs[i, 2] * f_2[2]
                        q[3] = _sp1(f_1, f_2, z3, ang, 0, True)   # Rot(f_1, q3) f_2 = R_rem f_2
                        _rot_back(f_1, ang[0], ang[1], Rs[0, 0] * f_1[0] + Rs[0, 1] * f_1[1] + Rs[0, 2] * f_1[2],
                                  Rs[1, 0] * f_1[0] + Rs[1, 1] * f_1[1] + Rs[1, 2] * f_1[2],
                                  Rs[2, 0] * f_1[0] + Rs[2, 1] * f_1[1] + Rs[2, 2] * f_1[2], z3)
                        q[4] = _sp1(f_2, f_1, z3, ang, 2, True)   # Rot(f_2, q4) f_1 = Rot(f_1, -q3) R_rem f_1
                if ok3:
                    _forward(l, q, i_n, dkind, daxis, dpoint, Rp, tp, Rk, tk)
                    res = _end_error(l, i_n, cen, Rp, tp, Rt3, Ct3, C, e, Rend, Rerr, R_home)
                    closed = res < TOL
                if not closed:
                    for k in range(ndm):
                        q[k] = 0.0
            elif i_n[l, 7] == 1 and not numeric_only:
                # F-P*-S-U: dofs [P, S1, S2, S3, U1, U2]. The slide from the sphere |C - B| = L; the U angles from
                # Rot(a2, -q5) Rot(a1, -q4) d_home = R_nd^T d (subproblem 2); the S angles from what is left.
                # Only what the outputs read unless ``full``; the passive angles only if ``want_q``.
                _target_rotation(Rt3, R_home, Rn)
                _slide_u_s(daxis, cen, l, 0, 4, 1, 2, a_u, a_1, a_2, c_S, c_U)
                b, rr, L2 = 0.0, 0.0, 0.0
                for i in range(3):
                    ri = Ct3[i] - c_S[i]
                    b += a_u[i] * ri
                    rr += ri * ri
                    L2 += (c_U[i] - c_S[i]) * (c_U[i] - c_S[i])
                disc = b * b - rr + L2
                if disc >= 0.0:
                    q[0] = b - f_leg[l, 1] * math.sqrt(disc)
                    for i in range(3):
                        w3[i] = Ct3[i] - c_S[i] - a_u[i] * q[0]               # d now (B -> C)
                        z3[i] = c_U[i] - c_S[i]                               # d at home
                    for i in range(3):
                        v3[i] = Rn[0, i] * w3[0] + Rn[1, i] * w3[1] + Rn[2, i] * w3[2]   # R_nd^T d
                    if _sp2_z(a_2, a_1, z3, v3, w3):
                        closed = True
                        q[4] = -_sp1(a_1, z3, w3, ang, 4, want_q)
                        q[5] = -_sp1(a_2, w3, v3, ang, 2, want_q)
                        _rot(a_2[0], a_2[1], a_2[2], ang[2], ang[3], Ra)
                        _rot(a_1[0], a_1[1], a_1[2], ang[4], ang[5], Rb)
                        _mm3(Rn, Ra, T3)
                        _mm3(T3, Rb, Rs)                                      # R_S = R_nd Rot(a2, -q5) Rot(a1, -q4)
                        if want_q:
                            _rows3(daxis, l, 1, S3)
                            _cardan(S3, Rs, q, 1, A3, T3)
                        for i in range(3):
                            v3[i] = c_S[i] + a_u[i] * q[0]                    # B
                        _set_transform(Rp, tp, 0, I3, c_S, c_S)
                        _set_transform(Rp, tp, 1, I3, c_S, v3)
                        _set_transform(Rp, tp, 4, Rs, c_S, v3)
                        for i in range(3):
                            C[i] = Rs[i, 0] * z3[0] + Rs[i, 1] * z3[1] + Rs[i, 2] * z3[2] + v3[i]
                        _set_transform(Rp, tp, 6, Rn, c_U, C)
                        _set_twist(tw, 0, I3, a_u, C, C, False)
                        if full:
                            _s_axes(I3, A3, T3, q[1], Sx)
                            for k in range(3):
                                _row2(Sx, k, w3)   # (the view Sx[k] would count references)
                                _set_twist(tw, 1 + k, I3, w3, C, v3, True)
                            _set_twist(tw, 4, Rs, a_1, C, C, True)
                            _set_twist(tw, 5, Rn, a_2, C, C, True)
            elif i_n[l, 7] == 2 and not numeric_only:
                # U-P*-S: dofs [U1, U2, P, S1, S2, S3]. The strut length |C - c_U|; the U angles pointing the strut
                # (subproblem 2); the S angles from what is left.
                _target_rotation(Rt3, R_home, Rn)
                _slide_u_s(daxis, cen, l, 2, 0, 1, 0, a_u, a_1, a_2, c_S, c_U)
                L0, Lw, sg = 0.0, 0.0, 0.0
                for i in range(3):
                    z3[i] = c_S[i] - c_U[i]
                    w3[i] = Ct3[i] - c_U[i]
                    L0 += z3[i] * z3[i]
                    Lw += w3[i] * w3[i]
                L0, Lw = math.sqrt(L0), math.sqrt(Lw)
                if Lw > 0.0:
                    for i in range(3):
                        z3[i] /= L0
                        w3[i] /= Lw
                        sg += a_u[i] * z3[i]
                    q[2] = (Lw - L0) / sg
                    if _sp2_z(a_1, a_2, z3, w3, v3):
                        closed = True
                        q[1] = _sp1(a_2, z3, v3, ang, 4, want_q)
                        q[0] = _sp1(a_1, v3, w3, ang, 2, want_q)
                        _rot(a_1[0], a_1[1], a_1[2], ang[2], ang[3], Ra)
                        _rot(a_2[0], a_2[1], a_2[2], ang[4], ang[5], Rb)
                        _mm3(Ra, Rb, Sx)                                      # R_U
                        for i in range(3):
                            for j in range(3):
                                # R_S = R_U^T R_nd
                                Rs[i, j] = Sx[0, i] * Rn[0, j] + Sx[1, i] * Rn[1, j] + Sx[2, i] * Rn[2, j]
                        if want_q:
                            _rows3(daxis, l, 3, S3)
                            _cardan(S3, Rs, q, 3, A3, T3)
                        for i in range(3):
                            for j in range(3):
                                Rb[i, j] = Sx[i, j]                           # keep R_U
                        for i in range(3):
                            v3[i] = c_S[i] + a_u[i] * q[2]                    # the S centre before the U turns it
                        _set_transform(Rp, tp, 0, I3, c_U, c_U)
                        _set_transform(Rp, tp, 2, Rb, c_U, c_U)
                        for i in range(3):
                            w3[i] = v3[i] - c_U[i]
                        for i in range(3):
                            C[i] = Rb[i, 0] * w3[0] + Rb[i, 1] * w3[1] + Rb[i, 2] * w3[2] + c_U[i]
                        for i in range(3):
                            w3[i] = c_U[i] - a_u[i] * q[2]
                        # after the slide: R_U (x + u q - c_U) + c_U
                        _set_transform(Rp, tp, 3, Rb, w3, c_U)
                        _set_transform(Rp, tp, 6, Rn, c_S, C)
                        _set_twist(tw, 2, Rb, a_u, C, C, False)
                        if full:
                            _set_twist(tw, 0, I3, a_1, C, c_U, True)
                            _set_twist(tw, 1, Ra, a_2, C, c_U, True)
                            _s_axes(Rb, A3, T3, q[3], Sx)
                            for k in range(3):
                                _row2(Sx, k, w3)
                                _set_twist(tw, 3 + k, I3, w3, C, C, True)
            if (i_n[l, 7] == 1 or i_n[l, 7] == 2) and not numeric_only:
                if closed:
                    # the orientation holds by construction (R_nd is the product); check the position
                    d0, d1, d2 = Ct3[0] - C[0], Ct3[1] - C[1], Ct3[2] - C[2]
                    res = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
                    closed = res < TOL
                if not closed:
                    for k in range(ndm):
                        q[k] = 0.0
            if not closed:
                for it in range(MAX_ITER):
                    _forward(l, q, i_n, dkind, daxis, dpoint, Rp, tp, Rk, tk)
                    res = _end_error(l, i_n, cen, Rp, tp, Rt3, Ct3, C, e, Rend, Rerr, R_home)
                    if not (res > TOL * 1e-2 and math.isfinite(res)):
                        break
                    _twists(l, i_n, dkind, daxis, dpoint, Rp, tp, C, tw, tk)
                    # least-squares step (pinv): normal equations, J (6, nd) = tw^T
                    if nd <= 6:
                        tr = 0.0
                        for a in range(nd):
                            for b in range(a, nd):
                                acc = 0.0
                                for i in range(6):
                                    acc += tw[a, i] * tw[b, i]
                                Mn[a, b] = acc
                                Mn[b, a] = acc
                            tr += Mn[a, a]
                            acc = 0.0
                            for i in range(6):
                                acc += tw[a, i] * e[i]
                            rhs[a] = acc
                        for a in range(nd):
                            Mn[a, a] += 1e-13 * tr
                        if not _chol(Mn, Lf, nd):
                            break
                        _chol_forward(Lf, rhs, y, nd)
                        _chol_back(Lf, y, nd)
                        for a in range(nd):
                            rhs[a] = y[a]
                    else:
                        tr = 0.0
                        for a in range(6):
                            for b in range(a, 6):
                                acc = 0.0
                                for k in range(nd):
                                    acc += tw[k, a] * tw[k, b]
                                Mn[a, b] = acc
                                Mn[b, a] = acc
                            tr += Mn[a, a]
                        for a in range(6):
                            Mn[a, a] += 1e-13 * tr
                        if not _chol(Mn, Lf, 6):
                            break
                        _chol_forward(Lf, e, y, 6)
                        _chol_back(Lf, y, 6)
                        for k in range(nd):
                            acc = 0.0
                            for i in range(6):
                                acc += tw[k, i] * y[i]
                            rhs[k] = acc
                    big = 0.0
                    for k in range(nd):
                        big = max(big, abs(rhs[k]))
                    f = min(1.0, MAX_STEP / max(big, 1e-300))
                    for k in range(nd):
                        q[k] += f * rhs[k]
                _forward(l, q, i_n, dkind, daxis, dpoint, Rp, tp, Rk, tk)
                res = _end_error(l, i_n, cen, Rp, tp, Rt3, Ct3, C, e, Rend, Rerr, R_home)
            # ---- outputs of the converged configuration
            closed_out[l, jp] = closed
            res_out[l, jp] = res
            ok = res < TOL
            for j in range(i_n[l, 5]):
                v = q[lim_d[l, j]]
                if not (v >= lim[l, j, 0] and v <= lim[l, j, 1]):
                    ok = False
            ok_out[l, jp] = ok
            for k in range(ndm):
                q_out[l, jp, k] = q[k]
            for i in range(3):
                C_out[l, jp, i] = C[i]
            fwd = not closed or i_n[l, 7] == 3   # the state from the forward pass (numeric, R*-U-U)
            if fwd:
                _twists(l, i_n, dkind, daxis, dpoint, Rp, tp, C, tw, tk)
            if full or fwd:
                for k in range(nd):
                    for i in range(6):
                        tw_out[l, jp, k, i] = tw[k, i]
            else:                                   # the chain model reads only the actuated twist
                for i in range(6):
                    tw_out[l, jp, i_n[l, 6], i] = tw[i_n[l, 6], i]
            nc = i_n[l, 1]
            for m in range(nc - 1):
                f0 = cen_first[l, m]
                for i in range(3):
                    cen_out[l, jp, m, i] = (Rp[f0, i, 0] * cen[l, m, 0] + Rp[f0, i, 1] * cen[l, m, 1]
                                            + Rp[f0, i, 2] * cen[l, m, 2] + tp[f0, i])
            for i in range(3):
                cen_out[l, jp, nc - 1, i] = C[i]
            for m in range(i_n[l, 2]):
                s, en, body = lk_i[l, m, 0], lk_i[l, m, 1], lk_i[l, m, 2]
                d0 = cen_out[l, jp, en, 0] - cen_out[l, jp, s, 0]
                d1 = cen_out[l, jp, en, 1] - cen_out[l, jp, s, 1]
                d2 = cen_out[l, jp, en, 2] - cen_out[l, jp, s, 2]
                ln = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
                len_out[l, jp, m] = ln
                li = 1.0 / ln
                z0, z1, z2 = d0 * li, d1 * li, d2 * li
                xa0, xa1, xa2 = lk_x[l, m, 0], lk_x[l, m, 1], lk_x[l, m, 2]
                x0 = Rp[body, 0, 0] * xa0 + Rp[body, 0, 1] * xa1 + Rp[body, 0, 2] * xa2
                x1 = Rp[body, 1, 0] * xa0 + Rp[body, 1, 1] * xa1 + Rp[body, 1, 2] * xa2
                x2 = Rp[body, 2, 0] * xa0 + Rp[body, 2, 1] * xa1 + Rp[body, 2, 2] * xa2
                xz = x0 * z0 + x1 * z1 + x2 * z2
                x0, x1, x2 = x0 - xz * z0, x1 - xz * z1, x2 - xz * z2
                xi = 1.0 / math.sqrt(x0 * x0 + x1 * x1 + x2 * x2)
                x0, x1, x2 = x0 * xi, x1 * xi, x2 * xi
                lR_out[l, jp, m, 0, 0], lR_out[l, jp, m, 1, 0], lR_out[l, jp, m, 2, 0] = x0, x1, x2
                lR_out[l, jp, m, 0, 1] = z1 * x2 - z2 * x1
                lR_out[l, jp, m, 1, 1] = z2 * x0 - z0 * x2
                lR_out[l, jp, m, 2, 1] = z0 * x1 - z1 * x0
                lR_out[l, jp, m, 0, 2], lR_out[l, jp, m, 1, 2], lR_out[l, jp, m, 2, 2] = z0, z1, z2


# ---------------------------------------------------------------- the chain model
@njit(cache=True, error_model="numpy")
def _null_basis(tw, passive, nd, Nb, Aw, Vr, vn):
    """Nb (6, m) orthonormal wrenches reciprocal to the passive twists: Householder reflectors of the passive
    twist matrix applied to the unit vectors e_k, k >= rank (workspaces Aw, Vr (6, 6), vn (6,)); returns m."""
    npv = 0
    for k in range(nd):
        if passive[k]:
            for i in range(6):
                Aw[i, npv] = tw[k, i]
            npv += 1
    for j in range(npv):
        nrm = 0.0
        for i in range(j, 6):
            nrm += Aw[i, j] * Aw[i, j]
        nrm = math.sqrt(nrm)
        for i in range(6):
            Vr[j, i] = Aw[i, j] if i >= j else 0.0
        Vr[j, j] += nrm if Aw[j, j] >= 0.0 else -nrm
        v2 = 0.0
        for i in range(j, 6):
            v2 += Vr[j, i] * Vr[j, i]
        vn[j] = v2
        if v2 == 0.0:
            continue
        for c in range(j + 1, npv):
            acc = 0.0
            for i in range(j, 6):
                acc += Vr[j, i] * Aw[i, c]
            f = 2.0 * acc / v2
            for i in range(j, 6):
                Aw[i, c] -= f * Vr[j, i]
    m = 6 - npv
    for c in range(m):
        for i in range(6):
            Nb[i, c] = 1.0 if i == npv + c else 0.0
        for j in range(npv - 1, -1, -1):   # Q e = H_0 H_1 ... H_{npv-1} e
            if vn[j] == 0.0:
                continue
            acc = 0.0
            for i in range(j, 6):
                acc += Vr[j, i] * Nb[i, c]
            f = 2.0 * acc / vn[j]
            for i in range(j, 6):
                Nb[i, c] -= f * Vr[j, i]
    return m


@njit(cache=True, error_model="numpy", inline="always")
def _link_form(cantilever, L, lk_p, l, k, shear, lR, jp, r, Nb, m, Ae, ns, V):
    """Ae[l, ns] (m, m) = N^T S_C N of link k of leg l: N = Nb[l]'s wrenches carried to the link tip E
    (r = C - E) and into the link frame R = lR[l, jp, k], then the sparse local tip compliance whose entries the
    ``cantilever`` law gives (femcheck.compliance.cantilever_beam.cantilever_terms, passed in by
    femcheck.compliance.kernel_laws) of length L and section lk_p[l, k]. Indexed in place (no views)."""
    s00, s04, s44, s11, s13, s33, s22, s55 = cantilever(L, lk_p[l, k, 0], lk_p[l, k, 1], lk_p[l, k, 2], lk_p[l, k, 3],
                                                        lk_p[l, k, 4], lk_p[l, k, 5], lk_p[l, k, 6], shear)
    for a in range(m):
        f0, f1, f2 = Nb[l, 0, a], Nb[l, 1, a], Nb[l, 2, a]
        m0 = Nb[l, 3, a] + r[1] * f2 - r[2] * f1
        m1 = Nb[l, 4, a] + r[2] * f0 - r[0] * f2
        m2 = Nb[l, 5, a] + r[0] * f1 - r[1] * f0
        for c in range(3):
            R0, R1, R2 = lR[l, jp, k, 0, c], lR[l, jp, k, 1, c], lR[l, jp, k, 2, c]
            V[a, c] = R0 * f0 + R1 * f1 + R2 * f2
            V[a, 3 + c] = R0 * m0 + R1 * m1 + R2 * m2
    for a in range(m):
        for b in range(a, m):
            v = (s00 * V[a, 0] * V[b, 0] + s04 * (V[a, 0] * V[b, 4] + V[a, 4] * V[b, 0]) + s44 * V[a, 4] * V[b, 4]
                 + s11 * V[a, 1] * V[b, 1] + s13 * (V[a, 1] * V[b, 3] + V[a, 3] * V[b, 1]) + s33 * V[a, 3] * V[b, 3]
                 + s22 * V[a, 2] * V[b, 2] + s55 * V[a, 5] * V[b, 5])
            Ae[l, ns, a, b] = v
            Ae[l, ns, b, a] = v


@njit(cache=True, error_model="numpy")
def _ladder_c(F, n, Fs, ds):
    """Axial tangent compliance d delta / dF of a force ladder (Fs, ds)[:n] at F, floored at Fs[0]
    (chain_model.ladder_compliance: piecewise power law, end segments continued)."""
    x = math.log(max(F, Fs[0]))
    k = 0
    for i in range(1, n - 1):
        if math.log(Fs[i]) < x:
            k = i
    lf = math.log(Fs[k])
    pk = (math.log(ds[k + 1]) - math.log(ds[k])) / (math.log(Fs[k + 1]) - lf)
    return pk * math.exp(math.log(ds[k]) + pk * (x - lf)) / math.exp(x)


@njit("void(i8, i8, i8, i8[:, :, ::1], f8[:, :, :, ::1], i8[:, ::1], f8[::1], i8, f8[:, :, ::1], f8[:, :, :, ::1],"
       "f8[:, :, :, :, ::1], f8[:, ::1], f8[:, :, ::1], f8[:, ::1], f8[:, ::1])", cache=True, error_model="numpy")
def _measured_law_form(l, p, m, ml_i, ml_S, ml_n, cl, which, C, cen, lR, Nb, scale, Ae, V):
    """Ae (m, m) = N^T S_e N of leg l's FE-measured joint laws, the constant ones (``which`` 0) or those with a force
    ladder (1: S_zz replaced by the current axial compliance cl[j], its row and column scaled by sqrt(cl / S_zz)):
    N's wrenches carried to each joint centre J (r = C - J) and into its link frame R, then the measured 6 x 6
    compliance; times the element scale."""
    for a in range(m):
        for b in range(m):
            Ae[a, b] = 0.0
    f = scale[p, l, ml_i[l, 0, 2]]
    for j in range(ml_i.shape[1]):
        if ml_i[l, j, 0] < 0 or (ml_n[l, j] > 0) != (which == 1):
            continue
        dz = math.sqrt(cl[j] / ml_S[l, j, 2, 2]) if which == 1 else 1.0
        R = lR[l, p, ml_i[l, j, 1]]
        c = ml_i[l, j, 0]
        r0 = C[l, p, 0] - cen[l, p, c, 0]
        r1 = C[l, p, 1] - cen[l, p, c, 1]
        r2 = C[l, p, 2] - cen[l, p, c, 2]
        for a in range(m):
            f0, f1, f2 = Nb[0, a], Nb[1, a], Nb[2, a]
            m0 = Nb[3, a] + r1 * f2 - r2 * f1
            m1 = Nb[4, a] + r2 * f0 - r0 * f2
            m2 = Nb[5, a] + r0 * f1 - r1 * f0
            for k in range(3):
                V[a, k] = R[0, k] * f0 + R[1, k] * f1 + R[2, k] * f2
                V[a, 3 + k] = R[0, k] * m0 + R[1, k] * m1 + R[2, k] * m2
        for a in range(m):
            for b in range(a, m):
                acc = 0.0
                for i in range(6):
                    for k in range(6):
                        acc += V[a, i] * ml_S[l, j, i, k] * V[b, k] * (dz if i == 2 else 1.0) * (dz if k == 2 else 1.0)
                Ae[a, b] += f * acc
                if b != a:
                    Ae[b, a] += f * acc


@njit(cache=True, error_model="numpy")
def _joint_rotation_forms(l, p, c_rot, jr, k_hp, k_hl, C, cen, lR, Ae, slot_kind, ns, Z, V):
    """Rigid joints with a joint-rotation compliance ``c_rot`` (rad/(N m)): one slot per S joint (``c_rot I3`` on
    the rotations about its centre J) and per U joint (``c_rot (I3 - z z^T)``, z the axis of the link ending at it)
    of leg l, carried to C: ``Ae = V^T Z V`` with ``V = [[r]x, I3]`` (the moment at J, ``m + r x f``, r = C - J).
    Their energy goes to the Hertz point (S) and Hertz line (U) element kinds, unscaled. Returns the slot count."""
    for j in range(jr.shape[1]):
        c = jr[l, j, 0]
        if c < 0:
            continue
        r0 = C[l, p, 0] - cen[l, p, c, 0]
        r1 = C[l, p, 1] - cen[l, p, c, 1]
        r2 = C[l, p, 2] - cen[l, p, c, 2]
        u = jr[l, j, 2] == 1
        for i in range(3):
            for k in range(3):
                zz = lR[l, p, jr[l, j, 1], i, 2] * lR[l, p, jr[l, j, 1], k, 2] if u else 0.0
                Z[i, k] = c_rot * ((1.0 if i == k else 0.0) - zz)
        for i in range(3):
            for k in range(3):
                V[i, 3 + k] = 1.0 if i == k else 0.0
        V[0, 0], V[0, 1], V[0, 2] = 0.0, -r2, r1
        V[1, 0], V[1, 1], V[1, 2] = r2, 0.0, -r0
        V[2, 0], V[2, 1], V[2, 2] = -r1, r0, 0.0
        for a in range(6):
            for b in range(6):
                acc = 0.0
                for i in range(3):
                    for k in range(3):
                        acc += V[i, a] * Z[i, k] * V[k, b]
                Ae[ns, a, b] = acc
        slot_kind[ns] = k_hl if u else k_hp
        ns += 1
    return ns


@njit(cache=True, error_model="numpy", inline="always")
def _sym_add(K, E, M, l, m, sign, xv):
    """K[upper] += sign E[l] M[l] E[l]^T, E[l] (6, m), M[l] (m, m) (indexed in place, no views)."""
    for i in range(6):
        for a in range(m):
            acc = 0.0
            for b in range(m):
                acc += E[l, i, b] * M[l, b, a]
            xv[a] = acc
        for j in range(i, 6):
            acc = 0.0
            for a in range(m):
                acc += xv[a] * E[l, j, a]
            K[i, j] += sign * acc


@njit(cache=True, error_model="numpy")
def chain_kernel(hertz, cantilever, tab, detailed, released, shear, c_rot, C, cen, tw, lR, llen, tcp, wrench, scale,
                 K_out, S_out, t_out, KL_out, WC_out, energy_out, kh_out, iters_out):
    """Evaluate n poses with the Hertz and cantilever laws ``hertz``, ``cantilever``
    (:func:`femcheck.compliance.kernel_laws.kernel_laws`). State arrays leg-major as :func:`ik_kernel` writes them; tcp (n, 3); wrench (n, 6);
    scale (n, L, E). Outputs K, S (n, 6, 6), t (n, 6), leg stiffness (n, L, 6, 6), leg wrench (n, L, 6),
    element energy (n, L, E), Hertz point stiffness (n, L, nhp + nml: then the axial tangent stiffness of the
    measured laws with a force ladder, mode 3 legs), iterations (n,). Returns 0; 1 + p if the
    fixed point of pose p did not converge; -1 - p if a leg or platform matrix of pose p is not positive definite.

    Per leg, with the wrench basis N (6, m) and every element's ``A_e = N^T S_e N``: ``A0 = sum A_e``,
    ``E = G^T N``; the leg adds ``E (A0 + c B B^T)^-1 E^T`` to K_T (B = N[:3]^T, c the Hertz point compliance).
    Modes: 0 no Hertz point (fixed), 1 m = 1 (a two-force leg: scalars), 2 Woodbury (3x3 per iteration).
    ``c_rot`` > 0 (rigid joints): the joint-rotation compliance of every S and U joint (:func:`_joint_rotation_forms`)."""
    return _chain_range(hertz, cantilever, tab, detailed, released, shear, c_rot, C, cen, tw, lR, llen, tcp, wrench,
                        scale, np.int64(0), tcp.shape[0],   # p0 not a literal: one specialization with the fused kernel
                        K_out, S_out, t_out, KL_out, WC_out, energy_out, kh_out, iters_out)


@njit(cache=True, error_model="numpy")
def _chain_range(hertz, cantilever, tab, detailed, released, shear, c_rot, C, cen, tw, lR, llen, tcp, wrench, scale,
                 p0, p1,
                 K_out, S_out, t_out, KL_out, WC_out, energy_out, kh_out, iters_out):
    """:func:`chain_kernel` on the poses p0 <= p < p1: the state arrays (C, cen, tw, lR, llen) at index p - p0,
    everything else at p."""
    i_n, passive, lk_i, lk_p, hl_c, hl_link, hp, f_leg, kinds = (tab[0], tab[4], tab[7], tab[9], tab[10], tab[11],
                                                                 tab[12], tab[15], tab[17])
    L = i_n.shape[0]
    nl = lk_i.shape[1]
    ml_i, ml_S, ml_n, ml_F, ml_d = tab[-1]   # FE-measured joint laws (kernel_tables._measured_law_tables)
    jr = tab[20]                             # S and U joints (kernel_tables._joint_rotation_table)
    n_slot = nl + 4 + jr.shape[1]
    cl = np.zeros((L, ml_i.shape[1]))     # current axial compliance of the ladder laws
    lad_slot = np.full(L, -1, np.int64)   # slot of a leg's ladder laws (mode 3: refactored every iteration)
    k_drive, k_hp, k_hl = kinds[0], kinds[1], kinds[2]
    Ae = np.zeros((L, n_slot, 6, 6))
    slot_kind = np.full((L, n_slot), -1, np.int64)
    n_slots = np.zeros(L, np.int64)
    V = np.zeros((6, 6))
    r3 = np.zeros(3)
    Nb = np.zeros((L, 6, 6))
    mm = np.zeros(L, np.int64)
    E = np.zeros((L, 6, 6))
    A0 = np.zeros((6, 6))
    Mi = np.zeros((L, 6, 6))     # A0^-1
    X = np.zeros((L, 6, 3))      # M B
    A3 = np.zeros((L, 3, 3))     # B^T M B
    H = np.zeros((L, 6, 3))      # E X
    P3 = np.zeros((L, 3, 6))     # N[:3] M E^T
    Q3 = np.zeros((L, 3, 3))     # N[:3] X
    Y = np.zeros((L, 3, 3))
    a1 = np.zeros(L)             # m = 1: A0, |N[:3]|^2, current leg stiffness
    b1 = np.zeros(L)
    k1 = np.zeros(L)
    mode = np.zeros(L, np.int64)
    c_hp = np.zeros(L)
    kh = np.zeros((L, hp.shape[1]))
    kh_floor = np.zeros((L, hp.shape[1]))   # the Hertz point stiffness at the floor force, where every pose starts
    for l in range(L):
        for j in range(i_n[l, 4] if detailed else 0):
            kh_floor[l, j] = hertz(hp[l, j, 2], hp[l, j, 0], hp[l, j, 1])
    Ai = np.zeros((6, 6))
    Lf = np.zeros((6, 6))
    xv = np.zeros(6)
    xi = np.zeros(6)
    K0 = np.zeros((6, 6))
    K = np.zeros((6, 6))
    t = np.zeros(6)
    z = np.zeros(6)
    yv = np.zeros((L, 6))
    WC = np.zeros((L, 6))
    Z3 = np.zeros((3, 3))
    Y3 = np.zeros((3, 3))
    Aw = np.zeros((6, 6))
    Vr = np.zeros((6, 6))
    vn = np.zeros(6)
    Ht = np.zeros(3)
    YHt = np.zeros(3)
    HY = np.zeros((6, 3))
    Mt = np.zeros((6, 6))
    wv = np.zeros(6)
    ik_kind = i_n[:, 7]
    for p in range(p0, p1):
        jp = p - p0
        for i in range(6):
            wv[i] = wrench[p, i]
        for i in range(6):
            for j in range(6):
                K0[i, j] = 0.0
        any_hp = False
        any_lad = False
        for l in range(L):
            # ---- wrench basis N (6, m)
            if not released:
                m = 6
                for i in range(6):
                    for j in range(6):
                        Nb[l, i, j] = 1.0 if i == j else 0.0
            elif ik_kind[l] == 1 or ik_kind[l] == 2:
                # F-P-S-U / U-P-S: the one wrench is the force along the line of the S and U centres (through C)
                o = 1 if ik_kind[l] == 1 else 0
                d0 = C[l, jp, 0] - cen[l, jp, o, 0]
                d1 = C[l, jp, 1] - cen[l, jp, o, 1]
                d2 = C[l, jp, 2] - cen[l, jp, o, 2]
                dn = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
                m = 1
                Nb[l, 0, 0], Nb[l, 1, 0], Nb[l, 2, 0] = d0 / dn, d1 / dn, d2 / dn
                Nb[l, 3, 0] = Nb[l, 4, 0] = Nb[l, 5, 0] = 0.0
            else:
                m = _null_basis(tw[l, jp], passive[l], i_n[l, 0], Nb[l], Aw, Vr, vn)
            mm[l] = m
            # ---- A_e = N^T S_e N of every element (compliances carried to C_l)
            ns = 0
            for k in range(i_n[l, 2]):
                kind = lk_i[l, k, 3]
                if kind < 0:
                    continue
                en = lk_i[l, k, 1]
                for i in range(3):
                    r3[i] = C[l, jp, i] - cen[l, jp, en, i]
                _link_form(cantilever, llen[l, jp, k], lk_p, l, k, shear, lR, jp, r3, Nb, m, Ae, ns, V)
                f = scale[p, l, kind]
                for a in range(m):
                    for b in range(m):
                        Ae[l, ns, a, b] *= f
                slot_kind[l, ns] = kind
                ns += 1
            if detailed:
                c = f_leg[l, 0] * scale[p, l, k_drive]
                ia = i_n[l, 6]
                for a in range(m):
                    acc = 0.0
                    for i in range(6):
                        acc += Nb[l, i, a] * tw[l, jp, ia, i]
                    xi[a] = acc
                for a in range(m):
                    for b in range(m):
                        Ae[l, ns, a, b] = c * xi[a] * xi[b]
                slot_kind[l, ns] = k_drive
                ns += 1
                if i_n[l, 3] > 0:
                    f = scale[p, l, k_hl]
                    for a in range(m):
                        for b in range(m):
                            Ae[l, ns, a, b] = 0.0
                    for j in range(i_n[l, 3]):
                        hk = hl_link[l, j]
                        for k in range(3):
                            ck = f * (hl_c[l, j, 0] + (hl_c[l, j, 1] if k == 2 else 0.0))
                            R0, R1, R2 = lR[l, jp, hk, 0, k], lR[l, jp, hk, 1, k], lR[l, jp, hk, 2, k]
                            for a in range(m):
                                xi[a] = R0 * Nb[l, 0, a] + R1 * Nb[l, 1, a] + R2 * Nb[l, 2, a]
                            for a in range(m):
                                for b in range(m):
                                    Ae[l, ns, a, b] += ck * xi[a] * xi[b]
                    slot_kind[l, ns] = k_hl
                    ns += 1
                if ml_i[l, 0, 0] >= 0:
                    _measured_law_form(l, p, m, ml_i, ml_S, ml_n, cl[l], 0, C, cen, lR, Nb[l], scale, Ae[l, ns], V)
                    slot_kind[l, ns] = ml_i[l, 0, 2]
                    ns += 1
                    lad_slot[l] = -1
                    for j in range(ml_i.shape[1]):
                        if ml_n[l, j] > 0:   # a force ladder: start at its floor, as the Hertz point contacts
                            cl[l, j] = _ladder_c(0.0, ml_n[l, j], ml_F[l, j], ml_d[l, j])
                            lad_slot[l] = ns
                    if lad_slot[l] >= 0:
                        _measured_law_form(l, p, m, ml_i, ml_S, ml_n, cl[l], 1, C, cen, lR, Nb[l], scale, Ae[l, ns], V)
                        slot_kind[l, ns] = ml_i[l, 0, 2]
                        ns += 1
            else:
                lad_slot[l] = -1
            if c_rot > 0.0 and not released:
                ns = _joint_rotation_forms(l, jp, c_rot, jr, k_hp, k_hl, C, cen, lR, Ae[l], slot_kind[l], ns, Z3, V)
            n_slots[l] = ns
            for a in range(m):
                for b in range(m):
                    acc = 0.0
                    for s in range(ns):
                        acc += Ae[l, s, a, b]
                    A0[a, b] = acc
            # ---- E = G^T N (wrenches at the TCP)
            for i in range(3):
                r3[i] = C[l, jp, i] - tcp[p, i]
            for a in range(m):
                f0, f1, f2 = Nb[l, 0, a], Nb[l, 1, a], Nb[l, 2, a]
                E[l, 0, a], E[l, 1, a], E[l, 2, a] = f0, f1, f2
                E[l, 3, a] = r3[1] * f2 - r3[2] * f1 + Nb[l, 3, a]
                E[l, 4, a] = r3[2] * f0 - r3[0] * f2 + Nb[l, 4, a]
                E[l, 5, a] = r3[0] * f1 - r3[1] * f0 + Nb[l, 5, a]
            nhp = i_n[l, 4] if detailed else 0
            c_hp[l] = 0.0
            for j in range(nhp):
                kh[l, j] = kh_floor[l, j]
                c_hp[l] += scale[p, l, k_hp] / kh[l, j]
            if nhp > 0:
                any_hp = True
            if lad_slot[l] >= 0:   # mode 3: the leg is refactored at every fixed-point iteration
                mode[l] = 3
                any_hp = True
                any_lad = True
                continue
            if nhp > 0 and m == 1:
                mode[l] = 1
                a1[l] = A0[0, 0]
                b1[l] = Nb[l, 0, 0] * Nb[l, 0, 0] + Nb[l, 1, 0] * Nb[l, 1, 0] + Nb[l, 2, 0] * Nb[l, 2, 0]
                continue
            mode[l] = 2 if nhp > 0 else 0
            if not _chol(A0, Lf, m):
                return -1 - p
            _chol_inverse(Lf, Mt, m)
            for a in range(m):
                for b in range(m):
                    Mi[l, a, b] = Mt[a, b]
            _sym_add(K0, E, Mi, l, m, 1.0, xv)
            if mode[l] == 2:
                for a in range(m):
                    for k in range(3):
                        acc = 0.0
                        for b in range(m):
                            acc += Mi[l, a, b] * Nb[l, k, b]
                        X[l, a, k] = acc
                for k in range(3):
                    for k2 in range(3):
                        acc = 0.0
                        for a in range(m):
                            acc += Nb[l, k, a] * X[l, a, k2]
                        A3[l, k, k2] = acc
                        Q3[l, k, k2] = acc
                for i in range(6):
                    for k in range(3):
                        acc = 0.0
                        for a in range(m):
                            acc += E[l, i, a] * X[l, a, k]
                        H[l, i, k] = acc
                # P3 = N[:3] M E^T = X^T E^T (M symmetric)
                for k in range(3):
                    for i in range(6):
                        P3[l, k, i] = H[l, i, k]
        # ---- Hertz fixed point
        it = 0
        while True:
            for i in range(6):
                for j in range(i, 6):
                    K[i, j] = K0[i, j]
            for l in range(L):
                if mode[l] == 1:
                    k1[l] = 1.0 / (a1[l] + c_hp[l] * b1[l])
                    for i in range(6):
                        for j in range(i, 6):
                            K[i, j] += k1[l] * E[l, i, 0] * E[l, j, 0]
                elif mode[l] == 2:
                    c = c_hp[l]
                    for i in range(3):
                        for j in range(3):
                            Z3[i, j] = c * A3[l, i, j] + (1.0 if i == j else 0.0)
                    _inverse3(Z3, Y3)          # I + c B^T M B is SPD
                    for i in range(3):
                        for j in range(3):
                            Y[l, i, j] = c * Y3[i, j]
                    for i in range(6):
                        for k in range(3):
                            HY[i, k] = H[l, i, 0] * Y[l, 0, k] + H[l, i, 1] * Y[l, 1, k] + H[l, i, 2] * Y[l, 2, k]
                    for i in range(6):
                        for j in range(i, 6):
                            K[i, j] -= HY[i, 0] * H[l, j, 0] + HY[i, 1] * H[l, j, 1] + HY[i, 2] * H[l, j, 2]
                elif mode[l] == 3:
                    m = mm[l]
                    _measured_law_form(l, p, m, ml_i, ml_S, ml_n, cl[l], 1, C, cen, lR, Nb[l], scale,
                                       Ae[l, lad_slot[l]], V)
                    for a in range(m):
                        for b in range(m):
                            acc = c_hp[l] * (Nb[l, 0, a] * Nb[l, 0, b] + Nb[l, 1, a] * Nb[l, 1, b] + Nb[l, 2, a] * Nb[l, 2, b])
                            for s in range(n_slots[l]):
                                acc += Ae[l, s, a, b]
                            A0[a, b] = acc
                    if not _chol(A0, Lf, m):
                        return -1 - p
                    _chol_inverse(Lf, Mt, m)
                    for a in range(m):
                        for b in range(m):
                            Mi[l, a, b] = Mt[a, b]
                    _sym_add(K, E, Mi, l, m, 1.0, xv)
            for i in range(6):
                for j in range(i + 1, 6):
                    K[j, i] = K[i, j]
            if not _chol(K, Lf, 6):
                return -1 - p
            _chol_forward(Lf, wv, t, 6)
            _chol_back(Lf, t, 6)
            if not any_hp:
                break
            # the force on each leg's Hertz point contacts: |N[:3] y| with W_C = N y
            change = 0.0
            change_l = 0.0   # the ladder laws' axial compliance (chain_model._LADDER_TOL)
            for l in range(L):
                if mode[l] == 0:
                    continue
                if mode[l] == 1:
                    acc = 0.0
                    for i in range(6):
                        acc += E[l, i, 0] * t[i]
                    F = abs(k1[l] * acc) * math.sqrt(b1[l])
                elif mode[l] == 3:
                    m = mm[l]
                    for a in range(m):
                        acc = 0.0
                        for i in range(6):
                            acc += E[l, i, a] * t[i]
                        z[a] = acc
                    for k in range(3):
                        acc = 0.0
                        for a in range(m):
                            for b in range(m):
                                acc += Nb[l, k, a] * Mi[l, a, b] * z[b]
                        Ht[k] = acc   # the leg's force W_C[:3]
                    F = math.sqrt(Ht[0] * Ht[0] + Ht[1] * Ht[1] + Ht[2] * Ht[2])
                    for j in range(ml_i.shape[1]):
                        if ml_n[l, j] > 0:   # the joint's axial force: along its link's z axis
                            R = lR[l, p, ml_i[l, j, 1]]
                            Fa = abs(R[0, 2] * Ht[0] + R[1, 2] * Ht[1] + R[2, 2] * Ht[2])
                            c_new = _ladder_c(Fa, ml_n[l, j], ml_F[l, j], ml_d[l, j])
                            d = abs(c_new - cl[l, j]) / c_new
                            if d > change_l:
                                change_l = d
                            cl[l, j] = c_new
                else:
                    for k in range(3):
                        Ht[k] = H[l, 0, k] * t[0] + H[l, 1, k] * t[1] + H[l, 2, k] * t[2] + H[l, 3, k] * t[3] \
                            + H[l, 4, k] * t[4] + H[l, 5, k] * t[5]
                    for k in range(3):
                        YHt[k] = Y[l, k, 0] * Ht[0] + Y[l, k, 1] * Ht[1] + Y[l, k, 2] * Ht[2]
                    F2 = 0.0
                    for k in range(3):
                        fk = Ht[k] - (Q3[l, k, 0] * YHt[0] + Q3[l, k, 1] * YHt[1] + Q3[l, k, 2] * YHt[2])
                        F2 += fk * fk
                    F = math.sqrt(F2)
                c_hp[l] = 0.0
                for j in range(i_n[l, 4]):
                    k_new = hertz(max(F, hp[l, j, 2]), hp[l, j, 0], hp[l, j, 1])
                    d = abs(k_new - kh[l, j]) / k_new
                    if d > change:
                        change = d
                    kh[l, j] = k_new
                    c_hp[l] += scale[p, l, k_hp] / k_new
            it += 1
            if change_l < _LADDER_TOL and change < (_LADDER_TOL if any_lad else _FP_TOL):
                break
            if it >= _FP_MAX_ITER:
                return 1 + p
        iters_out[p] = it + 1 if any_hp else 1
        # ---- outputs
        for i in range(6):
            t_out[p, i] = t[i]
            for j in range(6):
                K_out[p, i, j] = K[i, j]
        _chol_inverse(Lf, Mt, 6)
        for i in range(6):
            for j in range(6):
                S_out[p, i, j] = Mt[i, j]
        for l in range(L):
            m = mm[l]
            for j in range(i_n[l, 4] if detailed else 0):
                kh_out[p, l, j] = kh[l, j]
            for j in range(ml_i.shape[1]):
                if detailed and ml_n[l, j] > 0:   # after the Hertz point stiffnesses
                    kh_out[p, l, hp.shape[1] + j] = 1.0 / cl[l, j]
            # y = A_c^-1 E^T t (W_C = N y) and A_c^-1 (the leg stiffness N A_c^-1 N^T)
            for a in range(m):
                acc = 0.0
                for i in range(6):
                    acc += E[l, i, a] * t[i]
                z[a] = acc
            if mode[l] == 1:
                Ai[0, 0] = k1[l]
            else:
                for a in range(m):
                    for b in range(m):
                        Ai[a, b] = Mi[l, a, b]
                if mode[l] == 2:
                    for a in range(m):
                        for k in range(3):
                            xv[k] = Y[l, k, 0] * X[l, a, 0] + Y[l, k, 1] * X[l, a, 1] + Y[l, k, 2] * X[l, a, 2]
                        for b in range(m):
                            Ai[a, b] -= X[l, b, 0] * xv[0] + X[l, b, 1] * xv[1] + X[l, b, 2] * xv[2]
            for a in range(m):
                acc = 0.0
                for b in range(m):
                    acc += Ai[a, b] * z[b]
                yv[l, a] = acc
            for i in range(6):
                acc = 0.0
                for a in range(m):
                    acc += Nb[l, i, a] * yv[l, a]
                WC_out[p, l, i] = acc
            if released:
                for i in range(6):
                    for a in range(m):
                        acc = 0.0
                        for b in range(m):
                            acc += Nb[l, i, b] * Ai[b, a]
                        xv[a] = acc
                    for j in range(i, 6):
                        acc = 0.0
                        for a in range(m):
                            acc += xv[a] * Nb[l, j, a]
                        KL_out[p, l, i, j] = acc
                        KL_out[p, l, j, i] = acc
            else:
                for i in range(6):
                    for j in range(6):
                        KL_out[p, l, i, j] = Ai[i, j]
            # complementary energy y^T A_e y per element kind (W_C^T S_e W_C)
            for k in range(energy_out.shape[2]):
                energy_out[p, l, k] = 0.0
            for s in range(n_slots[l]):
                acc = 0.0
                for a in range(m):
                    for b in range(m):
                        acc += yv[l, a] * Ae[l, s, a, b] * yv[l, b]
                energy_out[p, l, slot_kind[l, s]] += acc
            if detailed and i_n[l, 4] > 0:
                F2 = (WC_out[p, l, 0] * WC_out[p, l, 0] + WC_out[p, l, 1] * WC_out[p, l, 1]
                      + WC_out[p, l, 2] * WC_out[p, l, 2])
                for j in range(i_n[l, 4]):
                    energy_out[p, l, k_hp] += F2 * scale[p, l, k_hp] / kh[l, j]
    return 0


@njit(cache=True)
def state_buffers(L, n, nd, nc, nl):
    """The leg-state arrays :func:`ik_kernel` writes for n poses of L legs padded to nd freedoms, nc centres and nl
    links: q (L, n, nd), residual (L, n), ok, closed form (L, n) bool, C (L, n, 3), centres (L, n, nc, 3), twists
    (L, n, nd, 6), link frames (L, n, nl, 3, 3), link lengths (L, n, nl); zero (the lengths one), so that the
    padding and what a closed form skips hold finite values."""
    return (np.zeros((L, n, nd)), np.zeros((L, n)), np.zeros((L, n), dtype=np.bool_), np.zeros((L, n), dtype=np.bool_),
            np.zeros((L, n, 3)), np.zeros((L, n, nc, 3)), np.zeros((L, n, nd, 6)), np.zeros((L, n, nl, 3, 3)),
            np.ones((L, n, nl)))


#: poses per block of the fused kernel: the block's leg state (~200 kB for six legs) stays in the cache
BLOCK = 64


@njit(cache=True, error_model="numpy")
def _pose_targets(P, p0, p1, tcp_off, b_plat, R_b, C_b):
    """Platform orientation R_b[p - p0] (Rodrigues, as ``femcheck.kinematics.frames.rotvec_to_matrix``:
    ``I + a K + b K^2``, K = skew(rotation vector), a = sin th / th, b = (1 - cos th) / th^2) and leg attachment
    targets C_b[l, p - p0] = T - R tcp_offset + R b_l of the poses P[p0:p1] (n, 6)."""
    L = b_plat.shape[0]
    Kx = np.zeros((3, 3))
    for p in range(p0, p1):
        j = p - p0
        x, y, z = P[p, 3], P[p, 4], P[p, 5]
        th2 = x * x + y * y + z * z
        th = math.sqrt(th2)
        if th < 1e-8:
            a, b = 1.0 - th2 / 6.0, 0.5 - th2 / 24.0
        else:
            a, b = math.sin(th) / th, (1.0 - math.cos(th)) / (th * th)
        Kx[0, 0], Kx[0, 1], Kx[0, 2] = 0.0, -z, y
        Kx[1, 0], Kx[1, 1], Kx[1, 2] = z, 0.0, -x
        Kx[2, 0], Kx[2, 1], Kx[2, 2] = -y, x, 0.0
        for r in range(3):
            for c in range(3):
                kk = Kx[r, 0] * Kx[0, c] + Kx[r, 1] * Kx[1, c] + Kx[r, 2] * Kx[2, c]
                R_b[j, r, c] = (1.0 if r == c else 0.0) + a * Kx[r, c] + b * kk
        for i in range(3):
            R0, R1, R2 = R_b[j, i, 0], R_b[j, i, 1], R_b[j, i, 2]
            o = P[p, i] - (R0 * tcp_off[0] + R1 * tcp_off[1] + R2 * tcp_off[2])
            for l in range(L):
                C_b[l, j, i] = o + (R0 * b_plat[l, 0] + R1 * b_plat[l, 1] + R2 * b_plat[l, 2])


@njit(cache=True, error_model="numpy")
def evaluate_kernel(hertz, cantilever, tab, detailed, released, shear, c_rot, P, wrench, scale,
                    K_out, S_out, t_out, KL_out, WC_out, energy_out, kh_out, iters_out, contrib_out, bad_out):
    """Inverse kinematics and chain model of the n TCP poses P (n, 6) in one call, block by block of ``BLOCK``
    poses: the targets (:func:`_pose_targets`), the legs (:func:`_ik_range`: a closed-form leg computes only
    what the chain model reads, no passive joint angles or twists), then :func:`_chain_range`. The leg state
    lives only in block-sized buffers.

    Outputs as :func:`chain_kernel`, and contributions (n, E): each element kind's share of the work
    ``W . t`` (NaN where it is not positive). bad_out (2,): the first pose and leg without an inverse-kinematics
    solution inside the joint limits (-1, -1 if none); the kernel stops there and returns 0."""
    i_n, cen_t, lk_i = tab[0], tab[5], tab[7]
    L = i_n.shape[0]
    n = P.shape[0]
    nd, nc, nl = tab[1].shape[1], cen_t.shape[1], lk_i.shape[1]
    E = energy_out.shape[2]
    B = min(BLOCK, max(n, 1))
    R_b = np.zeros((B, 3, 3))
    C_b = np.zeros((L, B, 3))
    q, res, ok, closed, C, cen, tw, lR, llen = state_buffers(L, B, nd, nc, nl)
    bad_out[0], bad_out[1] = -1, -1
    for p0 in range(0, n, B):
        p1 = min(n, p0 + B)
        _pose_targets(P, p0, p1, tab[19], tab[16], R_b, C_b)
        _ik_range(tab, R_b, C_b, False, False, 0, p1 - p0, q, res, ok, closed, C, cen, tw, lR, llen)
        for p in range(p0, p1):
            for l in range(L):
                if not ok[l, p - p0]:
                    bad_out[0], bad_out[1] = p, l
                    return 0
        status = _chain_range(hertz, cantilever, tab, detailed, released, shear, c_rot, C, cen, tw, lR, llen, P, wrench, scale,
                              p0, p1,
                              K_out, S_out, t_out, KL_out, WC_out, energy_out, kh_out, iters_out)
        if status != 0:
            return status
        for p in range(p0, p1):
            work = 0.0
            for i in range(6):
                work += wrench[p, i] * t_out[p, i]
            for k in range(E):
                if work > 0.0:
                    acc = 0.0
                    for l in range(L):
                        acc += energy_out[p, l, k]
                    contrib_out[p, k] = acc / work
                else:
                    contrib_out[p, k] = np.nan
    return 0
