"""FE-measured joint laws: the device FE's passive joints as their contact FE finds them.

The closed-form joint laws (Hertz point contact of the ball, Mindlin stick, Hertz line contact plus pin
bending of the U joint; seed 000 §4.4.1) stay in the analytical model. The device FE instead takes each
joint's response from the contact FE of that joint (:mod:`femcheck.fe_device.joint_fe`: meshed bodies, P2,
penalty contact with augmented Lagrangian, Newton on the contact energy), measured once over a **force
ladder** F_1 < … < F_n along the joint axis that spans the leg forces of the device at its test points:

* ``approach_m`` δ_k: the displacement of the joint's moving reference node along the load at F_k (for the
  U joint it includes taking up the 2c radial clearance, which cancels in the eq. 1 increment);
* ``stiffness`` K_k (6 x 6): the stick tangent stiffness between the two reference nodes at F_k
  (joint frame: x, y lateral, z axial; rotations θ_x, θ_y tilt / pin axes a1, a2, θ_z spin).

Between ladder points δ(F) is a piecewise power law δ = δ_k (F / F_k)^{p_k}, p_k = ln(δ_{k+1}/δ_k) /
ln(F_{k+1}/F_k) (exact for a Hertz contact, p = 2/3, and monotone for any increasing ladder); below F_1 and
above F_n the end segments are continued. The per-component stiffnesses K_kk(F) are interpolated linearly in
(ln F, ln K). The device FE (:func:`femcheck.fe_device.loads.solve_state`) then uses, per leg force F:

* ball: the secant F / δ_sp(F) on the three translations (isotropic, the same idealization as the
  analytical model's Hertz spring; a released leg carries no lateral joint force), stick tilt
  (K_33 + K_44) / 2 and spin K_55 for the frictional ``contact`` joints;
* U joint (frame B, z along the link): lateral K_00, K_11 (stick tangent), axial secant F / δ_uj(F),
  stick rotations about the pin axes K_33, K_44.

The slip moments of the frictional joints stay the closed forms of :mod:`.joint_friction` (μ F R_b ρ with ρ
from the ball-tilt contact FE, (3π/16) μ F a, μ F r_pin): the contact FE here is frictionless along the
load path and does not measure them.

Measurements are cached on disk (``<mesh cache>/joint_laws/<key>.npz``, key = geometry, materials, friction,
clearance, mesh level and its element sizes, ladder and the source of the joint FE code), so ``make verify`` and ``coverage`` do not
repeat them; a law mutation (``[model.law_scale]``, or an analytical law changed in :mod:`femcheck.compliance`) does
not enter the key: it changes no joint FE input (:mod:`femcheck.fe_device.contact_scales`).
"""
from __future__ import annotations

import dataclasses
import functools
import hashlib
import io
import json
import logging
import time
from pathlib import Path

import numpy as np

log = logging.getLogger(__name__)

#: number of load levels of the force ladder
LADDER_LEVELS = 7
#: the ladder reaches this factor above the largest leg force at the test points (eq. 1 test level)
LADDER_MARGIN = 1.25
JOINTS = ("spherical", "universal")


@dataclasses.dataclass(frozen=True)
class MeasuredJointLaw:
    """One joint's contact-FE response over a force ladder (module doc; SI, joint frame).

    ``loads_N`` (n,) ascending; ``approach_m`` (n,); ``stiffness`` (n, 6, 6) N/m, N, N m/rad;
    ``dofs``, ``iterations`` (contact iterations over the ladder), ``seconds`` (of the measurement, also
    when read from the cache), ``cached`` (read from the cache in this run), ``mesh`` level."""

    joint: str
    mesh: str
    loads_N: np.ndarray
    approach_m: np.ndarray
    stiffness: np.ndarray
    dofs: int
    iterations: int
    seconds: float
    cached: bool = False

    def __post_init__(self):
        F, d = np.asarray(self.loads_N, float), np.asarray(self.approach_m, float)
        if F.ndim != 1 or F.size < 2 or np.any(np.diff(F) <= 0) or F[0] <= 0:
            raise ValueError(f"{self.joint} joint law: loads_N must be >= 2 increasing positive forces, got {F}")
        if d.shape != F.shape or np.any(d <= 0) or np.any(np.diff(d) <= 0):
            raise ValueError(f"{self.joint} joint law: the measured approach must grow with the load "
                             f"(got {d} m at {F} N): the contact FE lost the joint")

    def approach(self, F) -> np.ndarray:
        """δ(F) (m), F (N) any shape (piecewise power law through the ladder, module doc)."""
        F = np.asarray(F, float)
        lF, ld = np.log(self.loads_N), np.log(self.approach_m)
        p = np.diff(ld) / np.diff(lF)
        k = np.clip(np.searchsorted(lF, np.log(np.maximum(F, 1e-300))) - 1, 0, p.size - 1)
        return np.exp(ld[k] + p[k] * (np.log(np.maximum(F, 1e-300)) - lF[k]))

    def tangent_compliance(self, F) -> np.ndarray:
        """dδ/dF (m/N) of the piecewise power law at F (N, any shape): p_k δ(F) / F on the segment of F
        (the Hertz tangent (2/3) δ / F for p = 2/3); F floored at the ladder's first force."""
        F = np.maximum(np.asarray(F, float), self.loads_N[0])
        lF, ld = np.log(self.loads_N), np.log(self.approach_m)
        p = np.diff(ld) / np.diff(lF)
        k = np.clip(np.searchsorted(lF, np.log(F)) - 1, 0, p.size - 1)
        return p[k] * self.approach(F) / F

    def secant(self, F) -> np.ndarray:
        """F / δ(F) (N/m): the secant stiffness that reproduces the joint force at that state."""
        F = np.asarray(F, float)
        return F / self.approach(F)

    def component_stiffness(self, F) -> np.ndarray:
        """(..., 6) diagonal of the stick tangent stiffness at F (each component with the other five held),
        interpolated in (ln F, ln K) and held constant beyond the ladder."""
        F = np.asarray(F, float)
        diag = np.diagonal(self.stiffness, axis1=1, axis2=2)
        lF = np.log(self.loads_N)
        x = np.clip(np.log(np.maximum(F, 1e-300)), lF[0], lF[-1])
        pos = np.all(diag > 0, axis=0)
        out = np.empty(F.shape + (6,))
        for c in range(6):   # 6 components, not a loop over poses or elements
            y = np.log(diag[:, c]) if pos[c] else diag[:, c]
            v = np.interp(x, lF, y)
            out[..., c] = np.exp(v) if pos[c] else v
        return out

    def summary(self) -> dict:
        return {"source": "contact_fe", "mesh": self.mesh, "loads_N": [round(float(f), 4) for f in self.loads_N],
                "dofs": self.dofs, "contact_iterations": self.iterations, "seconds": round(self.seconds, 2),
                "cached": self.cached}


@dataclasses.dataclass(frozen=True)
class JointLaws:
    """The joint laws the device FE uses: a :class:`MeasuredJointLaw` per joint type, or None for the
    closed form (``--no-joint-fe``)."""

    spherical: MeasuredJointLaw | None = None
    universal: MeasuredJointLaw | None = None

    def source(self, joint: str) -> str:
        return "contact_fe" if getattr(self, joint) is not None else "closed_form"

    def sources(self) -> dict:
        """``{"spherical": "contact_fe" | "closed_form", "universal": …}`` (manifest ``joint_laws``)."""
        return {j: self.source(j) for j in JOINTS}

    def details(self) -> dict:
        return {j: (getattr(self, j).summary() if getattr(self, j) is not None else {"source": "closed_form"})
                for j in JOINTS}

    @property
    def any_measured(self) -> bool:
        return self.spherical is not None or self.universal is not None


CLOSED_FORM = JointLaws()


def force_ladder(case, points=None, levels: int = LADDER_LEVELS) -> np.ndarray:
    """(levels,) N: geometric ladder from the Hertz linearization floor ``min_contact_force_N`` to
    :data:`LADDER_MARGIN` × the largest leg force at the test points (released-joint statics J f = W at the
    eq. 1 test level, every test direction)."""
    from femcheck.fe_device.joint_forces import leg_forces
    from femcheck.kinematics.psu6 import POINT_LABELS

    pts = list(points) if points else list(POINT_LABELS)
    f_max = max(float(np.abs(leg_forces(case, p)).max()) for p in pts)
    f_lo = float(case.spherical_joint.min_contact_force_N)
    f_hi = max(LADDER_MARGIN * f_max, 4.0 * f_lo)
    return np.geomspace(f_lo, f_hi, levels)


@functools.lru_cache(maxsize=1)
def _code_version() -> str:
    """Hash of the joint-FE source (joint FE, contact, elasticity, constraints, geometry builders)."""
    from geometry.cache import code_version as geometry_version
    root = Path(__file__).resolve().parents[1]
    h = hashlib.sha256(geometry_version().encode())
    files = [Path(__file__), root / "fe_device" / "joint_fe.py", root / "fe_device" / "mesh_levels.py",
             root / "fe_device" / "contact_scales.py",
             root / "fe" / "elasticity.py",
             root / "fe" / "constraints.py", *sorted((root / "fe" / "contact").glob("*.py"))]
    for f in files:
        h.update(f.read_bytes())
    return h.hexdigest()[:16]


def _cache_key(case, joint: str, mesh: str, ladder: np.ndarray) -> str:
    """Key of a measured law: the inputs of the joint FE, including the sizes of the mesh level (so a change
    of the levels, e.g. the universal joint's axial refinement, never reuses a stale law)."""
    from femcheck.fe_device.mesh_levels import joint_mesh_sizes
    sizes = repr(joint_mesh_sizes(case, joint, mesh, float(ladder[-1])))
    inputs = {"joint": joint, "mesh": mesh, "ladder": [float(f) for f in ladder], "code": _code_version(), "mesh_sizes": sizes,
              "spherical_joint": repr(case.spherical_joint), "universal_joint": repr(case.universal_joint),
              "solid": repr(case.solid), **({"hub_held": True} if getattr(case, "hub_held", False) else {})}
    return hashlib.sha256(json.dumps(inputs, sort_keys=True).encode()).hexdigest()[:32]


def _cache_path(key: str) -> Path:
    from geometry.cache import cache_dir
    return cache_dir() / "joint_laws" / f"{key}.npz"


def _load(path: Path, joint: str, mesh: str) -> MeasuredJointLaw | None:
    if not path.is_file():
        return None
    try:
        with np.load(path, allow_pickle=False) as z:
            return MeasuredJointLaw(joint, mesh, z["loads_N"], z["approach_m"], z["stiffness"], int(z["dofs"]),
                                    int(z["iterations"]), float(z["seconds"]), cached=True)
    except Exception as exc:  # a corrupt entry is measured again, never trusted
        log.warning("ignoring unreadable joint-law cache entry %s: %s", path, exc)
        return None


def _store(path: Path, law: MeasuredJointLaw) -> None:
    from femcheck.report.atomic import write_bytes_atomic
    buf = io.BytesIO()
    np.savez(buf, loads_N=law.loads_N, approach_m=law.approach_m, stiffness=law.stiffness, dofs=law.dofs,
             iterations=law.iterations, seconds=law.seconds)
    try:
        write_bytes_atomic(path, buf.getvalue())
    except OSError as exc:
        log.warning("could not write the joint-law cache %s: %s", path, exc)


def measure_joint_law(case, joint: str, mesh: str = "coarse", ladder=None, use_cache: bool = True) -> MeasuredJointLaw:
    """Contact FE of ``joint`` loaded along its axis over ``ladder`` (N; default :func:`force_ladder`), one
    condensation and one load-stepped contact solve; cached (module doc). A joint that does not converge
    raises :class:`femcheck.errors.ConvergenceError` (residual history, chattering points)."""
    from femcheck.fe_device import joint_fe as jf

    ladder = np.asarray(force_ladder(case) if ladder is None else ladder, float)
    path = _cache_path(_cache_key(case, joint, mesh, ladder))
    if use_cache:
        hit = _load(path, joint, mesh)
        if hit is not None:
            log.info("%s joint law (%s mesh) read from the cache %s", joint, mesh, path.name)
            return hit
    t0 = time.perf_counter()
    from femcheck.fe_device.joint_models import solve_widening
    # as check-joints: tolerance and starting patch from the FE's own estimate, stick the contact area
    tol, start = jf.contact_start(case, joint, (float(ladder[0]), float(ladder[-1])))
    sign = -1.0 if joint == "spherical" else 1.0
    r = solve_widening(case, joint, mesh, float(ladder[-1]), lambda model: jf.solve_joint(
        model, tuple(ladder), sign, penetration_tol=tol, initial_gap_m=start,
        area_gap_rel=1e-3 if joint == "spherical" else 0.0, level_tangents=True))
    law = MeasuredJointLaw(joint, mesh, ladder, np.asarray(r.axial_m, float), np.asarray(r.level_tangent_stiffness),
                           r.dofs, r.iterations, time.perf_counter() - t0)
    log.info("%s joint law measured (%s mesh, %d DOFs, %d contact iterations, %.1f s)", joint, mesh, r.dofs,
             r.iterations, law.seconds)
    if use_cache:
        _store(path, law)
    return law


def cached(case, mesh: str = "coarse", points=None) -> dict[str, bool]:
    """{joint: whether its law over the ladder of ``points`` is in the cache} (a read then takes milliseconds)."""
    ladder = np.asarray(force_ladder(case, points), float)
    return {j: _cache_path(_cache_key(case, j, mesh, ladder)).is_file() for j in JOINTS}


def measure_joint_laws(case, mesh: str = "coarse", points=None, use_cache: bool = True, progress=None) -> JointLaws:
    """Both joints' laws (:func:`measure_joint_law`) over the ladder of ``points`` (default all nine)."""
    ladder = force_ladder(case, points)
    out = {}
    for j in JOINTS:
        out[j] = measure_joint_law(case, j, mesh, ladder, use_cache)
        if progress:
            progress(f"{j} joint law")
    return JointLaws(**out)
