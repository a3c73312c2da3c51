"""Tangential contact stiffness from natural frequencies (seed 004 §4.3): FE specimen on contact springs.

Physics. The specimen (seed 004: a 5 x 3 x 0.75 in block, Fig. 16) rests on contact springs on its
contact faces (top and bottom). Seed 004 eq. 37 with the contact stiffness matrix of eq. 44,

    M d'' + (K + K_C(k_t)) d = F,      K_C = (k_t / A_c) K_t1 (+ (k_n / A_c) K_n1),

gives the eigenproblem (K + K_C) phi = omega^2 M phi; normal contact is stuck (u . n = 0 on the
patch: "the normal contact stiffness becomes infinity", seed 004 §4.3) unless a finite k_n is asked
for. k_t (N/m) is the total tangential stiffness of ONE contact patch (isotropic in the face,
k_t = k_tau as in seed 004 §3), spread uniformly over its nominal area A_c.

Frequency–stiffness relation. Because K_C is positive semi-definite and linear in k_t, every sorted
eigenvalue omega_i^2(k_t) is non-decreasing in k_t (Courant–Fischer), with the derivative
(Hellmann–Feynman, phi mass-normalized)

    d omega_i^2 / d k_t = phi_i^T (K_t1 / A_c) phi_i,   S_i = d ln f_i / d ln k_t = k_t phi_i^T (K_t1/A_c) phi_i / (2 omega_i^2).

For soft contact the block moves rigidly on the springs and f -> sqrt(n_c k_t / m) / (2 pi) for
the in-plane translations (n_c contact patches, m the mass; S -> 1/2); for stiff contact f tends to
the frequencies of the block with stuck faces (S -> 0).

Inversion. A measured f_i of mode i is bracketed on a log-spaced sweep of k_t, started by linear
interpolation of ln k against ln f, and refined by safeguarded Newton steps
ln k <- ln k + (ln f_meas - ln f_i(k)) / S_i on the FE model itself (tolerance 1e-7 in ln f), so the
result does not carry interpolation error. sigma(ln k_t) = (sigma_f / f) / S_i; the mode with the
smallest sigma(ln k_t) is the one used.
"""
from __future__ import annotations

import dataclasses
import logging

import numpy as np

from femcheck.contact_id.bar_on_spring import ContactIdError, modes_consistent
from femcheck.contact_id.specimen_fe import (
    BlockFE, Patch, assemble_block, component_dofs, contact_matrices, patch_facets, solve_modes)

log = logging.getLogger(__name__)

_NEWTON_MAX = 12
_NEWTON_TOL = 1e-7  # in ln f: 1e-7 relative frequency, far below any measurement


@dataclasses.dataclass(frozen=True)
class TangentialModel:
    """Assembled specimen: ``block`` (K, M), ``Kt1`` / ``Kn1`` unit per-area contact matrices
    (eq. 44), ``area_m2`` nominal area A_c of one patch, ``fixed_dofs`` stuck normal DOFs,
    ``k_n_N_m`` finite normal stiffness per patch (None = stuck), ``n_modes``, ``n_patches``,
    ``density_kg_m3``."""

    block: BlockFE
    Kt1: object
    Kn1: object
    area_m2: float
    fixed_dofs: np.ndarray
    k_n_N_m: float | None
    n_modes: int
    n_patches: int
    density_kg_m3: float

    @property
    def mass_kg(self) -> float:
        """Mass of the block, kg (rho times the box volume; the mass matrix integrates the same)."""
        return self.density_kg_m3 * float(np.prod(self.block.dims_m))

    def rigid_translation_Hz(self, k_t_N_m) -> np.ndarray:
        """Closed form of the soft-contact limit: f = sqrt(n_c k_t / m) / (2 pi), Hz."""
        return np.sqrt(self.n_patches * np.asarray(k_t_N_m, dtype=float) / self.mass_kg) / (2 * np.pi)


def build_model(specimen, fe) -> TangentialModel:
    """Specimen FE model from the case sections ``specimen`` (geometry, material, contact) and
    ``fe`` (element, divisions, n_modes) — see :mod:`femcheck.case.contact_specimen`."""
    patches = tuple(Patch(face=f, size_m=specimen.contact_size_m) for f in specimen.contact_faces)
    mat = specimen.material
    block = assemble_block(specimen.dims_m, fe.divisions, mat.E_Pa, mat.nu, mat.density_kg_m3, fe.element, patches)
    Kn1, Kt1, area = contact_matrices(block, patches)
    if specimen.normal_contact == "stick":
        from femcheck.contact_id.specimen_fe import FACES
        fixed = np.unique(np.concatenate([component_dofs(block, patch_facets(block, p), FACES[p.face][0]) for p in patches]))
        k_n = None
    else:
        fixed = np.zeros(0, dtype=int)
        k_n = float(specimen.normal_stiffness_N_per_m)
    log.info("tangential model: %d dofs, %d stuck, A_c = %.4g m^2", block.ndof, fixed.size, area)
    return TangentialModel(block=block, Kt1=Kt1, Kn1=Kn1, area_m2=area, fixed_dofs=fixed, k_n_N_m=k_n,
                           n_modes=int(fe.n_modes), n_patches=len(patches),
                           density_kg_m3=float(mat.density_kg_m3))


def modal_at(model: TangentialModel, k_t_N_m: float, n_modes: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(frequencies_Hz (n,), sensitivity d ln f / d ln k_t (n,)) at tangential stiffness k_t (N/m per patch)."""
    k = float(k_t_N_m)
    if not np.isfinite(k) or k <= 0:
        raise ContactIdError(f"k_t = {k_t_N_m!r} N/m; expected a finite value > 0")
    n = int(n_modes or model.n_modes)
    K = model.block.K + (k / model.area_m2) * model.Kt1
    if model.k_n_N_m is not None:
        K = K + (model.k_n_N_m / model.area_m2) * model.Kn1
    res = solve_modes(K, model.block.M, model.fixed_dofs, n)
    phi = res.modes
    dw2 = np.einsum("ij,ij->j", phi, (model.Kt1 @ phi)) / model.area_m2
    w2 = (2 * np.pi * res.frequencies_Hz) ** 2
    return res.frequencies_Hz, k * dw2 / (2 * w2)


@dataclasses.dataclass(frozen=True)
class TangentialRelation:
    """Sweep: ``k_t_N_m`` (n_k,), ``frequencies_Hz`` (n_k, n_modes), ``sensitivity`` (n_k, n_modes)."""

    k_t_N_m: np.ndarray
    frequencies_Hz: np.ndarray
    sensitivity: np.ndarray

    def is_monotone(self, rtol: float = 1e-9) -> np.ndarray:
        """(n_modes,) True where f_i(k_t) is non-decreasing along the sweep (to ``rtol``)."""
        d = np.diff(self.frequencies_Hz, axis=0)
        return np.all(d >= -rtol * self.frequencies_Hz[1:], axis=0)


def relation(model: TangentialModel, k_t_N_m) -> TangentialRelation:
    """Frequency–stiffness relation of the first ``model.n_modes`` modes over ``k_t_N_m`` (n_k,) N/m."""
    ks = np.asarray(k_t_N_m, dtype=float)
    out = [modal_at(model, k) for k in ks]
    return TangentialRelation(k_t_N_m=ks, frequencies_Hz=np.array([o[0] for o in out]),
                              sensitivity=np.array([o[1] for o in out]))


@dataclasses.dataclass(frozen=True)
class TangentialIdentification:
    """Per measured mode (n,): ``modes``, ``frequencies_Hz``, ``k_t_N_m``, ``sensitivity`` (d ln f /
    d ln k_t at the solution), ``df_dlnk_Hz``, ``sigma_ln_k``, ``iterations``; ``best`` index used."""

    modes: np.ndarray
    frequencies_Hz: np.ndarray
    k_t_N_m: np.ndarray
    sensitivity: np.ndarray
    df_dlnk_Hz: np.ndarray
    sigma_ln_k: np.ndarray
    iterations: np.ndarray
    best: int
    area_m2: float

    @property
    def consistent(self) -> bool:
        """True when all modes agree with the mode used within 3 combined sigmas."""
        return modes_consistent(self.k_t_N_m, self.sigma_ln_k, self.best)

    @property
    def k_t_N_m_best(self) -> float:
        return float(self.k_t_N_m[self.best])

    @property
    def sigma_ln_k_best(self) -> float:
        return float(self.sigma_ln_k[self.best])

    def as_json(self) -> dict:
        return {
            "k_t_N_per_m": self.k_t_N_m_best,
            "k_t_per_area_N_per_m3": self.k_t_N_m_best / self.area_m2,
            "sigma_ln_k": self.sigma_ln_k_best,
            "mode_used": int(self.modes[self.best]),
            "modes_consistent": self.consistent,
            "per_mode": [
                {"mode": int(m), "frequency_Hz": float(f), "k_t_N_per_m": float(k), "sensitivity_dlnf_dlnk": float(s),
                 "df_dlnk_Hz": float(d), "sigma_ln_k": float(sg), "newton_iterations": int(it)}
                for m, f, k, s, d, sg, it in zip(self.modes, self.frequencies_Hz, self.k_t_N_m, self.sensitivity,
                                                 self.df_dlnk_Hz, self.sigma_ln_k, self.iterations)
            ],
        }


def identify_tangential_stiffness(model: TangentialModel, frequencies_Hz, modes=None, *, sweep: TangentialRelation,
                                  sigma_f_Hz: float = 1.0, sigma_f_rel: float = 1e-3) -> TangentialIdentification:
    """Measured frequencies (n,) Hz of FE modes ``modes`` (1-based, default 1..n) -> k_t per patch, N/m.

    ``sweep`` is the relation over the admissible k_t range (from :func:`relation`); a frequency
    outside the swept band raises :class:`ContactIdError` naming it and the band.
    """
    f = np.atleast_1d(np.asarray(frequencies_Hz, dtype=float))
    if f.ndim != 1 or f.size == 0 or np.any(~np.isfinite(f)) or np.any(f <= 0):
        raise ContactIdError(f"frequencies = {np.asarray(frequencies_Hz).tolist()}; expected finite values > 0 Hz")
    modes = np.arange(1, f.size + 1) if modes is None else np.atleast_1d(np.asarray(modes))
    if modes.size != f.size or not np.issubdtype(modes.dtype, np.integer) or np.any(modes < 1):
        raise ContactIdError(f"modes = {modes.tolist()}; expected one mode number >= 1 per frequency")
    n_modes = sweep.frequencies_Hz.shape[1]
    if np.any(modes > n_modes):
        raise ContactIdError(f"mode {int(modes.max())} requested but the relation has {n_modes} modes; raise fe.n_modes")
    lnk_grid = np.log(sweep.k_t_N_m)
    ks, ss, its = [], [], []
    for fm, mode in zip(f, modes):
        col = sweep.frequencies_Hz[:, mode - 1]
        if not (col[0] < fm < col[-1]):
            raise ContactIdError(
                f"frequency {fm:.6g} Hz of mode {mode} is outside {col[0]:.6g}–{col[-1]:.6g} Hz, the band of mode {mode} "
                f"for k_t in [{sweep.k_t_N_m[0]:.3g}, {sweep.k_t_N_m[-1]:.3g}] N/m; "
                "hint: check the mode numbering or widen identification.k_t_min/max_N_per_m")
        j = int(np.searchsorted(col, fm))  # col[j-1] < fm <= col[j]
        lo, hi = lnk_grid[j - 1], lnk_grid[j]
        t = (np.log(fm) - np.log(col[j - 1])) / (np.log(col[j]) - np.log(col[j - 1]))
        lnk = lo + t * (hi - lo)
        for it in range(1, _NEWTON_MAX + 1):
            fk, sk = modal_at(model, np.exp(lnk), n_modes=n_modes)
            r = np.log(fm) - np.log(fk[mode - 1])
            if r > 0:
                lo = max(lo, lnk)
            else:
                hi = min(hi, lnk)
            if abs(r) < _NEWTON_TOL:
                break
            s = sk[mode - 1]
            new = lnk + r / s if s > 1e-12 else 0.5 * (lo + hi)
            lnk = new if lo < new < hi else 0.5 * (lo + hi)  # safeguard: stay inside the bracket
        else:
            log.warning("tangential Newton for mode %d stopped after %d iterations, |r| = %.2e", mode, it, abs(r))
        ks.append(np.exp(lnk))
        ss.append(sk[mode - 1])
        its.append(it)
    k, s = np.array(ks), np.array(ss)
    sigma_f = np.hypot(sigma_f_Hz, sigma_f_rel * f)
    with np.errstate(divide="ignore"):
        sigma_ln_k = (sigma_f / f) / s
    best = int(np.argmin(sigma_ln_k))
    return TangentialIdentification(modes=modes.astype(int), frequencies_Hz=f, k_t_N_m=k, sensitivity=s,
                                    df_dlnk_Hz=s * f, sigma_ln_k=sigma_ln_k, iterations=np.array(its), best=best,
                                    area_m2=model.area_m2)
