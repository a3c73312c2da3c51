"""The compiled path of the general parallel-device model: :func:`solve_legs_compiled` and
:func:`evaluate_compiled` call the numba kernels of :mod:`femcheck.parallel.chain_kernel` and return the same
objects as the numpy reference (:func:`femcheck.parallel.leg_kinematics.solve_legs`,
:func:`femcheck.parallel.chain_model.evaluate`), which select this path by default (``backend="compiled"``).

The tests hold both paths together (tests/test_parallel_device_compiled.py); the numpy path stays the
readable transcription of the equations.
"""
from __future__ import annotations

import numpy as np

from femcheck.kinematics.frames import rotvec_to_matrix
from femcheck.parallel.kernel_tables import device_tables

BACKENDS = ("compiled", "numpy")


def check_backend(backend: str) -> None:
    if backend not in BACKENDS:
        raise ValueError(f"backend: {backend!r}; expected one of {list(BACKENDS)}")


def solve_legs_compiled(device, P: np.ndarray, numeric_only: bool = False):
    """Inverse kinematics of every leg at TCP poses P (n, 6) (validated by the caller): a
    :class:`~femcheck.parallel.leg_kinematics.DeviceState` whose ``packed`` arrays feed :func:`evaluate_compiled`.
    ``numeric_only``: skip the closed forms (to check them against the numeric solution)."""
    from femcheck.parallel import chain_kernel as kern
    from femcheck.parallel.leg_state import DeviceState, LegState
    tb = device_tables(device)
    n, L = P.shape[0], device.n_legs
    R, C_t = _targets(tb, device, P)
    i_n = tb.tab[0]
    nd, nc, nl = tb.tab[1].shape[1], tb.tab[5].shape[1], tb.tab[7].shape[1]
    q, res, ok, closed, C, cen, tw, lR, llen = kern.state_buffers(L, n, nd, nc, nl)
    kern.ik_kernel(tb.tab, R, C_t, bool(numeric_only), q, res, ok, closed, C, cen, tw, lR, llen)
    legs = []
    for l in range(L):
        d, m, k = i_n[l, 0], i_n[l, 1], i_n[l, 2]
        legs.append(LegState(q=q[l, :, :d], ok=ok[l], residual=res[l], C=C[l], centres=cen[l, :, :m],
                             twists=tw[l, :, :d], link_R=lR[l, :, :k], link_length=llen[l, :, :k]))
    return DeviceState(poses=P, tcp=P[:, :3], R=R, legs=tuple(legs), packed=(C, cen, tw, lR, llen, closed))


def _targets(tb, device, P):
    """Platform orientations R (n, 3, 3) and leg attachment targets C_t (L, n, 3) of the TCP poses P (n, 6):
    ``C_t = T - R tcp_offset + R b_i``."""
    R = np.ascontiguousarray(rotvec_to_matrix(P[:, 3:]))
    origin = P[:, :3] - R @ device.tcp_offset
    return R, np.ascontiguousarray(origin[None, :, :] + np.einsum("nij,lj->lni", R, tb.tab[16]))


def _packed(device, state):
    """The leg-major padded state arrays of ``state`` (packed from its legs if it came from numpy)."""
    if state.packed is not None:
        return state.packed[:5]
    tb = device_tables(device)
    n, L = state.n, device.n_legs
    nd, nc, nl = tb.tab[1].shape[1], tb.tab[5].shape[1], tb.tab[7].shape[1]
    C = np.empty((L, n, 3))
    cen = np.zeros((L, n, nc, 3))
    tw = np.zeros((L, n, nd, 6))
    lR = np.zeros((L, n, nl, 3, 3))
    llen = np.ones((L, n, nl))
    for l, s in enumerate(state.legs):
        C[l] = s.C
        cen[l, :, :s.centres.shape[1]] = s.centres
        tw[l, :, :s.twists.shape[1]] = s.twists
        lR[l, :, :s.link_R.shape[1]] = s.link_R
        llen[l, :, :s.link_length.shape[1]] = s.link_length
    return C, cen, tw, lR, llen


def evaluate_compiled(device, state, W: np.ndarray, scale: np.ndarray, model: str, joints: str, c_rot: float = 0.0):
    """The chain model by :func:`femcheck.parallel.chain_kernel.chain_kernel` on a solved ``state``: (K, S, t,
    leg stiffness, leg wrench, element energy, hertz stiffness dict, iterations), or None where the kernel does
    not cover the device (released joints with dependent passive twists: the numpy path then runs)."""
    from femcheck.parallel import chain_kernel as kern
    tb = device_tables(device)
    if joints == "released" and not tb.released_ok:
        return None
    C, cen, tw, lR, llen = _packed(device, state)
    out = _outputs(tb, state.n, device.n_legs)
    from femcheck.compliance.kernel_laws import kernel_laws
    status = kern.chain_kernel(*kernel_laws(), tb.tab, model == "detailed", joints == "released", bool(device.beam_shear),
                               float(c_rot), C, cen, tw, lR, llen, np.ascontiguousarray(state.tcp), np.ascontiguousarray(W),
                               np.ascontiguousarray(scale), *out)
    return _finish(tb, device, model, status, out)


def fused_available(device, joints: str) -> bool:
    """:func:`evaluate_fused` covers ``device`` with ``joints`` (not released joints with dependent passive twists)."""
    return joints == "rigid" or device_tables(device).released_ok


def evaluate_fused(device, P: np.ndarray, W: np.ndarray, scale: np.ndarray, model: str, joints: str,
                   c_rot: float = 0.0):
    """Inverse kinematics and chain model of the TCP poses P (n, 6) (validated by the caller) in one compiled call
    (:func:`femcheck.parallel.chain_kernel.evaluate_kernel`; the device must be :func:`fused_available`):
    the tuple of :func:`evaluate_compiled` followed by the contributions (n, E), or ``(pose, leg)`` of the first
    pose a leg cannot reach (inside its joint limits), as a 2-tuple of ints."""
    from femcheck.parallel import chain_kernel as kern
    tb = device_tables(device)
    n = P.shape[0]
    out = _outputs(tb, n, device.n_legs)
    contributions = np.empty((n, tb.n_elem))
    bad = np.empty(2, dtype=np.int64)
    from femcheck.compliance.kernel_laws import kernel_laws
    status = kern.evaluate_kernel(*kernel_laws(), tb.tab, model == "detailed", joints == "released", bool(device.beam_shear),
                                  float(c_rot), np.ascontiguousarray(P), np.ascontiguousarray(W), np.ascontiguousarray(scale),
                                  *out, contributions, bad)
    if bad[0] >= 0:
        return int(bad[0]), int(bad[1])
    return _finish(tb, device, model, status, out) + (contributions,)


def _outputs(tb, n: int, L: int):
    """The output arrays of the chain kernels: K, S, t, leg stiffness, leg wrench, energy, Hertz k, iterations."""
    return (np.empty((n, 6, 6)), np.empty((n, 6, 6)), np.empty((n, 6)), np.empty((n, L, 6, 6)), np.empty((n, L, 6)),
            np.empty((n, L, tb.n_elem)), np.full((n, L, tb.hp_joint.shape[1] + tb.ml_joint.shape[1]), np.nan), np.zeros(n, dtype=np.int64))


def _finish(tb, device, model, status, out):
    from femcheck.errors import ConvergenceError
    if status < 0:
        raise np.linalg.LinAlgError(f"leg or platform stiffness not positive definite at pose #{-status - 1}")
    if status:
        raise ConvergenceError("Hertz linearization fixed point of the parallel device did not converge "
                               f"at pose #{status - 1}", [], {"pose": int(status - 1)})
    K, S, t, KL, WC, energy, kh, iters = out
    hertz = {}
    if model == "detailed":
        for l in range(device.n_legs):
            for j, joint in enumerate(tb.hp_joint[l]):
                if joint >= 0:
                    hertz[l, int(joint)] = kh[:, l, j]
            for j, joint in enumerate(tb.ml_joint[l]):   # measured laws with a force ladder: axial tangent
                if joint >= 0 and not np.isnan(kh[0, l, tb.hp_joint.shape[1] + j]):
                    hertz[l, int(joint)] = kh[:, l, tb.hp_joint.shape[1] + j]
    return K, S, t, KL, WC, energy, hertz, int(iters.max(initial=1))
