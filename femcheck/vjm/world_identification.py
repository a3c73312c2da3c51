"""Seed 002's identification workflow run against a world that no VJM made.

The "measurements" are the TCP translations of a :class:`~femcheck.vjm.beam_world.BeamWorld` under the case's
``[identification]`` wrenches, at the identification configurations (seed 002 Table I, 1-8) and the
verification ones (9-13, and optionally random poses). Both VJM models are identified on the identification
rows by least squares (seed 002 eqs. 9-12, translations only, complementary stiffness neglected, as in the
seed): the conventional one (one torsion spring per joint) and the extended one (torsion and two tilts). Each
is then scored on every measurement by the relative deflection error ``|dx_model - dx| / |dx|`` (one per
configuration and wrench, the seed's "tests").

The torsion share (seed 002 sec. IV-B) is reported twice: the world's own (the deflection of the same arm
with rigid links and bearings, projected on the full deflection) and the identified extended model's (its
torsion springs' part, projected the same way; :mod:`femcheck.vjm.torsion_share`).
"""
from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from femcheck.vjm.beam_world import BeamWorld, tcp_deflections
from femcheck.vjm.extended_vjm import identification_matrix, identify_compliances, virtual_jacobian

log = logging.getLogger(__name__)

#: KUKA LBR iiwa 7 R800 joint limits, deg (data sheet), for the random verification poses
IIWA7_LIMITS_DEG = (170.0, 120.0, 170.0, 120.0, 170.0, 120.0, 175.0)


@dataclass(frozen=True)
class ModelFit:
    """One VJM model identified on the world: ``model`` name; ``compliance`` (k,) rad/(N m) and its
    ``compliance_ci`` (±1.96 classical LS standard error); ``cond_A``; ``error_pct`` (m, p) relative
    translation error ``|dx_model - dx| / |dx|`` per configuration and wrench, %; ``error_norm_pct`` (m, p) the
    error of the magnitude ``||dx_model| - |dx|| / |dx|``, % (seed 002's Fig. 4 compares total deformations,
    so its "relative error" may be this one); ``torsion_share`` (m, p) of the model's deflection."""

    model: str
    compliance: np.ndarray
    compliance_ci: np.ndarray
    cond_A: float
    error_pct: np.ndarray
    error_norm_pct: np.ndarray
    torsion_share: np.ndarray


@dataclass(frozen=True)
class WorldStudy:
    """Result of :func:`identify_on_world`. ``q_deg`` (m, n) configurations (identification first);
    ``is_identification`` (m,) bool; ``label`` (m,) seed 002 Table I numbers ("1".."13") or "r1".. for
    random poses; ``wrenches`` (p, 6); ``measured`` (m, p, 3) m (noise included); ``world_torsion_share``
    (m, p); ``self_weight_mm`` (m,) |TCP deflection under the self-weight| (0 without gravity);
    ``fits`` conventional and extended; ``noise_mm``, ``gravity`` as run."""

    q_deg: np.ndarray
    is_identification: np.ndarray
    label: tuple[str, ...]
    wrenches: np.ndarray
    measured: np.ndarray
    world_torsion_share: np.ndarray
    self_weight_mm: np.ndarray
    fits: dict
    noise_mm: float
    gravity: bool

    def summary(self, fit: ModelFit, norm: bool = False) -> dict:
        """Mean / max relative error over the identification tests, the Table I verification tests (9-13),
        the random poses and all Table I tests (the seed's 26), %; ``norm``: of the magnitudes."""
        ver_table = ~self.is_identification & np.array([not s.startswith("r") for s in self.label])
        rand = np.array([s.startswith("r") for s in self.label])
        out = {}
        for key, rows in (("identification", self.is_identification), ("verification", ver_table),
                          ("random", rand), ("table1_all", self.is_identification | ver_table)):
            e = (fit.error_norm_pct if norm else fit.error_pct)[rows]
            out[key] = {"mean": float(e.mean()), "max": float(e.max())} if e.size else {"mean": None, "max": None}
        return out


def identify_on_world(case, world: BeamWorld, noise_mm: float = 0.0, seed: int = 0, gravity: bool = False,
                      random_poses: int = 0) -> WorldStudy:
    """Run seed 002's workflow on ``world`` with the plan of ``case.identification`` (module docstring).

    ``noise_mm``: Gaussian noise (sigma, mm) on every measured translation component, seeded by ``seed``.
    ``gravity``: the measurement includes the self-weight deflection (a measurement without a zero
    reference); seed 002's FE loads only the wrench, so it is off by default. ``random_poses``: that many
    extra verification configurations, uniform within the iiwa's joint limits (same ``seed``).
    """
    plan = case.identification
    if plan is None:
        raise ValueError(f"{case.source}: [identification] is required")
    n = case.n_joints
    q_id = np.array(plan.configurations_deg, dtype=float).reshape(-1, n)
    q_ver = np.array(plan.verification_configurations_deg, dtype=float).reshape(-1, n)
    rng = np.random.default_rng(seed)
    lim = np.array(IIWA7_LIMITS_DEG[:n]) if n == 7 else np.full(n, 170.0)
    q_rand = rng.uniform(-lim, lim, (random_poses, n))
    q_deg = np.vstack([q_id, q_ver, q_rand])
    labels = tuple(str(i + 1) for i in range(len(q_id) + len(q_ver))) + tuple(f"r{i + 1}" for i in range(random_poses))
    ident = np.arange(len(q_deg)) < len(q_id)
    W = np.array(plan.wrenches, dtype=float)
    q = np.radians(q_deg)
    res = tcp_deflections(world, q, W, gravity=gravity)
    measured = res.twist[:, :, :3] + noise_mm * 1e-3 * rng.standard_normal(res.twist[:, :, :3].shape)
    clean = res.twist[:, :, :3] - res.self_weight[:, None, :3]     # the wrenches' part
    rigid = tcp_deflections(world.with_rigid_structure(), q, W).twist[:, :, :3]
    world_share = np.einsum("mpi,mpi->mp", rigid, clean) / np.einsum("mpi,mpi->mp", clean, clean)
    m, p = len(q), len(W)
    fits = {}
    for name, ext in (("conventional", False), ("extended", True)):
        J = virtual_jacobian(case.chain, q, ext, np.array([j.tilt_offset_m for j in case.joints]) if ext else None)
        Jr = np.repeat(J, p, axis=0)                          # (m p, 6, k), row order (configuration, wrench)
        Wr = np.tile(W, (m, 1))
        dX = measured.reshape(-1, 3)
        rows = np.repeat(ident, p)
        fit = identify_compliances(Jr[rows], Wr[rows], dX[rows])
        A = identification_matrix(Jr, Wr).reshape(m * p, 3, -1)
        pred = np.einsum("trk,k->tr", A, fit.compliance)
        tors = np.einsum("trk,k->tr", A[:, :, 0::3] if ext else A, fit.compliance[0::3] if ext else fit.compliance)
        err = 100 * np.linalg.norm(pred - dX, axis=1) / np.linalg.norm(dX, axis=1)
        err_norm = 100 * np.abs(np.linalg.norm(pred, axis=1) - np.linalg.norm(dX, axis=1)) / np.linalg.norm(dX, axis=1)
        share = np.einsum("tr,tr->t", tors, pred) / np.einsum("tr,tr->t", pred, pred)
        fits[name] = ModelFit(model=name, compliance=fit.compliance, compliance_ci=1.96 * fit.standard_error,
                              cond_A=fit.condition_number, error_pct=err.reshape(m, p),
                              error_norm_pct=err_norm.reshape(m, p),
                              torsion_share=share.reshape(m, p))
        log.info("%s: cond(A) %.3g, rank %d", name, fit.condition_number, fit.rank)
    return WorldStudy(q_deg=q_deg, is_identification=ident, label=labels, wrenches=W, measured=measured,
                      world_torsion_share=world_share, self_weight_mm=1e3 * np.linalg.norm(res.self_weight[:, :3], axis=1),
                      fits=fits, noise_mm=float(noise_mm), gravity=bool(gravity))
