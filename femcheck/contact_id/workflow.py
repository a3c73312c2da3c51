"""One identification run on a ``contact_specimen`` case: measured frequencies (at one or more
preloads) -> contact stiffness per preload -> preload law; used by ``femcheck contact-id`` and the bench.

``kind = "normal"`` uses the 1-D bar (seed 004 §4.1, :mod:`bar_on_spring`), ``kind = "tangential"``
the FE specimen (seed 004 §4.3, :mod:`tangential`). The returned :class:`ContactIdReport` holds the
per-preload identifications, the fitted power law (two or more preloads) and the frequency–stiffness
relation to plot.
"""
from __future__ import annotations

import dataclasses
import logging
import math

import numpy as np

from femcheck.contact_id import bar_on_spring, tangential
from femcheck.contact_id.bar_on_spring import ContactIdError
from femcheck.contact_id.preload_law import PowerLaw, fit_power_law

log = logging.getLogger(__name__)

KINDS = ("normal", "tangential")


@dataclasses.dataclass(frozen=True)
class ContactIdReport:
    """``kind``; ``identifications`` one per measurement group; ``preloads_N`` (n_groups,) or None;
    ``law`` fitted power law or None; ``relation_k_N_m`` (n_k,) and ``relation_f_Hz`` (n_k, n_modes)
    the frequency–stiffness curves; ``model`` a dict of the model figures (k*, c, mass, area)."""

    kind: str
    identifications: tuple
    preloads_N: np.ndarray | None
    law: PowerLaw | None
    relation_k_N_m: np.ndarray
    relation_f_Hz: np.ndarray
    model: dict
    confidence: float

    @property
    def k_best_N_m(self) -> np.ndarray:
        key = "k_n_N_m_best" if self.kind == "normal" else "k_t_N_m_best"
        return np.array([getattr(r, key) for r in self.identifications])

    @property
    def sigma_ln_k(self) -> np.ndarray:
        return np.array([r.sigma_ln_k_best for r in self.identifications])

    def as_json(self) -> dict:
        sym = "k_n" if self.kind == "normal" else "k_t"
        rows = []
        for j, r in enumerate(self.identifications):
            row = {"preload_N": None if self.preloads_N is None else float(self.preloads_N[j])}
            row.update(r.as_json())
            rows.append(row)
        out = {"kind": self.kind, "stiffness": sym, "model": self.model, "identified": rows, "preload_law": None}
        if self.law is not None:
            law = self.law.as_json()
            lo, hi = self.law.band(self.preloads_N, level=self.confidence)
            law["confidence"] = self.confidence
            law["band_at_preloads_N_per_m"] = [[float(a), float(b)] for a, b in zip(lo, hi)]
            out["preload_law"] = law
        return out


def _normal(case, groups, modes, sigma_f_Hz, sigma_f_rel):
    b = case.bar
    bar = bar_on_spring.Bar(length_m=b.length_m, area_m2=b.area_m2, E_Pa=b.material.E_Pa,
                            density_kg_m3=b.material.density_kg_m3)
    ids = tuple(bar_on_spring.identify_normal_stiffness(bar, f, modes, sigma_f_Hz=sigma_f_Hz, sigma_f_rel=sigma_f_rel)
                for f in groups)
    n_modes = int(max(max(r.modes) for r in ids))
    k_star = bar.structure_stiffness_N_m
    k = k_star * np.logspace(-2, 2, 161)  # beta 0.01..100 (seed 004 Fig. 8 shows 0.1..10)
    rel_f = bar_on_spring.natural_frequencies_Hz(bar, k, n_modes=max(n_modes, 3))
    model = {"structure_stiffness_k_star_N_per_m": k_star, "wave_speed_m_per_s": bar.wave_speed_m_s,
             "bar_mass_kg": bar.mass_kg, "contact_area_m2": b.contact_area_m2}
    return ids, k, rel_f, model


def _tangential(case, groups, modes, sigma_f_Hz, sigma_f_rel):
    idf = case.identification
    model = tangential.build_model(case.specimen, case.fe)
    ks = np.logspace(math.log10(idf.k_t_min_N_per_m), math.log10(idf.k_t_max_N_per_m), idf.sweep_points)
    sweep = tangential.relation(model, ks)
    mono = sweep.is_monotone()
    if not np.all(mono):  # cannot happen for a PSD contact matrix (Courant–Fischer); guard against solver trouble
        log.warning("frequency–stiffness relation not monotone for modes %s", list(np.flatnonzero(~mono) + 1))
    ids = tuple(tangential.identify_tangential_stiffness(model, f, modes, sweep=sweep, sigma_f_Hz=sigma_f_Hz,
                                                         sigma_f_rel=sigma_f_rel) for f in groups)
    info = {"specimen_mass_kg": model.mass_kg, "contact_area_m2": model.area_m2, "contact_patches": model.n_patches,
            "dofs": model.block.ndof, "element": case.fe.element, "normal_contact": case.specimen.normal_contact,
            "relation_monotone": bool(np.all(mono))}
    return ids, ks, sweep.frequencies_Hz, info


def run_identification(case, frequency_groups, preloads_N=None, modes=None, kind: str = "normal") -> ContactIdReport:
    """Identify contact stiffness for each group of measured frequencies (Hz); fit k = c P^m when
    two or more ``preloads_N`` (one per group) are given. ``modes``: 1-based mode numbers of the
    frequencies in each group (default 1..n)."""
    if kind not in KINDS:
        raise ContactIdError(f"--mode {kind!r}; expected one of {list(KINDS)}")
    groups = [np.atleast_1d(np.asarray(g, dtype=float)) for g in frequency_groups]
    if not groups:
        raise ContactIdError("no frequencies given")
    if preloads_N is not None:
        preloads_N = np.atleast_1d(np.asarray(preloads_N, dtype=float))
        if preloads_N.size != len(groups):
            raise ContactIdError(f"{preloads_N.size} preloads but {len(groups)} groups of frequencies; "
                                 "expected one preload per group (groups separated by ';')")
    idf = case.identification
    run = _normal if kind == "normal" else _tangential
    ids, k, rel_f, info = run(case, groups, modes, idf.frequency_sigma_Hz, idf.frequency_rel_sigma)
    law = None
    if preloads_N is not None and preloads_N.size >= 2:
        kb = np.array([r.sigma_ln_k_best for r in ids])
        key = "k_n_N_m_best" if kind == "normal" else "k_t_N_m_best"
        law = fit_power_law(preloads_N, [getattr(r, key) for r in ids], sigma_ln_k=kb)
    return ContactIdReport(kind=kind, identifications=ids, preloads_N=preloads_N, law=law, relation_k_N_m=k,
                           relation_f_Hz=rel_f, model=info, confidence=idf.confidence)
