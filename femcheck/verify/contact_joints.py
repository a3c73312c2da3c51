"""Which joint idealization the contact FE follows, by how much, and why.

Three measured pieces of evidence, all written into the verification report:

1. **Moment demand.** The ``rigid`` idealization makes every joint carry the moment of a welded frame.
   A contact joint can carry at most its friction moment: μ F R_b at the ball (tilt), μ F r_pin at a
   pin (:mod:`femcheck.fe_device.joint_friction`). :func:`moment_demand` evaluates the rigid detailed
   analytical model at the test points and returns the ratio demand / capacity per joint type,
   |M_B| / (μ F R_b) and |M_C,⊥u| / (μ F r_pin); a ratio above 1 means the joint slides.
2. **The contact FE of the ball alone** (:func:`femcheck.fe_device.joint_contact.spherical_joint_tilt`):
   the moment the ball-in-seat transmits under a tilt, frictionless (should vanish) and with μ (should
   saturate at μ F R_b). Its measured ratio M / (μ F R_b) in slip is the ``tilt_slip_ratio`` that the
   device's contact joints use.
3. **The device with contact joints**: deflections of the contact FE over those of the ``released`` and
   ``rigid`` FE, mean over points and directions.
"""
from __future__ import annotations

import dataclasses

import numpy as np


@dataclasses.dataclass(frozen=True)
class MomentDemand:
    """Ratios demand / friction capacity of the rigid idealization over points x directions x legs:
    ``ball`` and ``pin`` arrays (n,), with μ_sp, μ_uj used."""

    ball: np.ndarray
    pin: np.ndarray
    mu_sp: float
    mu_uj: float

    def summary(self) -> dict:
        return {"ball_min": float(self.ball.min()), "ball_median": float(np.median(self.ball)),
                "pin_min": float(self.pin.min()), "pin_median": float(np.median(self.pin)),
                "mu_sp": self.mu_sp, "mu_uj": self.mu_uj}


def moment_demand(case, points=None, load_N: float | None = None) -> MomentDemand:
    """Moment demand of the rigid detailed analytical model over its friction capacity (module doc, item 1).

    Evaluated at the test load (15 N) along every load direction at ``points`` (default the cube), one
    vectorized model call per direction.
    """
    from femcheck.chain import evaluate
    from femcheck.kinematics.directions import direction_unit
    from femcheck.kinematics.points import as_point_set

    pts = as_point_set(case, points)
    labels, P, legs = list(pts.labels), pts.poses, pts.legs
    load = case.loads.detailed_test_N if load_N is None else load_N
    mu_sp, mu_uj = case.solid.spherical_joint.friction, case.solid.universal_joint.friction
    ball, pin = [], []
    for d in case.loads.directions:
        r = evaluate(case, P, np.r_[load * direction_unit(d), 0.0, 0.0, 0.0], model="detailed", joints="rigid", legs=legs)
        F, M_C = r.chain_wrench[..., :3], r.chain_wrench[..., 3:]
        M_B = M_C + np.cross(legs.C - legs.B, F)
        f = np.linalg.norm(F, axis=-1)
        M_perp = M_C - np.einsum("...i,...i->...", M_C, legs.u)[..., None] * legs.u
        ball.append(np.linalg.norm(M_B, axis=-1) / (mu_sp * f * case.spherical_joint.ball_radius_m))
        pin.append(np.linalg.norm(M_perp, axis=-1) / (mu_uj * f * case.universal_joint.pin_radius_m))
    return MomentDemand(np.concatenate(ball).ravel(), np.concatenate(pin).ravel(), mu_sp, mu_uj)


def deflection_ratios(fe) -> dict:
    """Mean and range of contact / released and contact / rigid FE deflections (detailed level)."""
    out = {}
    for ref in ("released", "rigid"):
        r = np.array([fe.deflection(p, d, "detailed", "contact") / fe.deflection(p, d, "detailed", ref)
                      for p in fe.points for d in fe.directions])
        out[f"contact_over_{ref}"] = {"mean": float(r.mean()), "min": float(r.min()), "max": float(r.max())}
    return out


#: ball-in-seat mesh size (m) of the tilt study, the same at every verification mesh level (contact zone
#: refined toward 0.2-0.5 mm): 39,895 unknowns; measured 14 s frictionless and 150 s with friction (137 modified
#: Newton iterations, the friction status changes renew the factorization) on 2 cores, 1.3 GB.
TILT_SIZE_M = 0.002
#: tilt study load: the largest joint force of the detailed protocol is below 10 N (20 N at the TCP);
#: 20 N keeps the contact patch resolvable on the coarse meshes; the ratio M / (μ F R) does not depend on F
TILT_FORCE_N = 20.0
#: imposed tilt (rad): R_b θ = 35 µm of slip at the contact, ~10x the stick limit μ F / k_t (Mindlin), so the
#: contact slides as it does in the device (joint rotations of a few mrad at 15 N)
TILT_RAD = 0.01


def ball_tilt_study(case, progress=None, use_cache: bool = True) -> dict:
    """The contact FE of the ball alone under tilt, frictionless and with the case's μ (module doc, item 2).

    Returns {"frictionless": JointTiltResult, "friction": JointTiltResult}. Each result is cached on disk
    (:func:`_tilt_cache_path`: keyed by the joint, its materials, μ, the study's load and mesh and the source
    of the contact FE), so a second verification of the same device reads it instead of re-solving it.
    """
    from femcheck.fe_device.joint_contact import spherical_joint_tilt
    note = progress or (lambda desc: None)
    out = {}
    for name, mu in (("frictionless", 0.0), ("friction", case.solid.spherical_joint.friction)):
        path = _tilt_cache_path(case, mu)
        out[name] = _load_tilt(path) if use_cache else None
        if out[name] is None:
            out[name] = spherical_joint_tilt(case, TILT_FORCE_N, TILT_RAD, friction=mu, size_m=TILT_SIZE_M)
            if use_cache:
                _store_tilt(path, out[name])
        note(f"ball tilt contact FE, {name}")
    return out


def tilt_cached(case) -> bool:
    """Whether both runs of the tilt study are in the cache (:func:`ball_tilt_study` then reads them)."""
    return all(_tilt_cache_path(case, mu).is_file() for mu in (0.0, case.solid.spherical_joint.friction))


def _tilt_cache_path(case, mu: float):
    """``<cache>/ball_tilt/<key>.npz``; key = the inputs of :func:`spherical_joint_tilt` and the hash of the
    contact-FE source (any change of that code or of the joint measures it again)."""
    import hashlib
    import json
    from pathlib import Path

    from geometry.cache import cache_dir, code_version
    root = Path(__file__).resolve().parents[1]
    h = hashlib.sha256(code_version().encode())
    for f in [root / "fe_device" / "joint_contact.py", root / "fe" / "elasticity.py", root / "fe" / "constraints.py",
              root / "fe" / "newton.py", root / "fe_device" / "loads.py", *sorted((root / "fe" / "contact").glob("*.py"))]:
        h.update(f.read_bytes())
    inputs = {"code": h.hexdigest(), "spherical_joint": repr(case.spherical_joint), "solid": repr(case.solid),
              "mu": float(mu), "force_N": TILT_FORCE_N, "tilt_rad": TILT_RAD, "size_m": TILT_SIZE_M}
    return cache_dir() / "ball_tilt" / (hashlib.sha256(json.dumps(inputs, sort_keys=True).encode()).hexdigest()[:32] + ".npz")


def _load_tilt(path):
    from femcheck.fe_device.joint_contact import JointTiltResult
    if not path.is_file():
        return None
    try:
        with np.load(path, allow_pickle=False) as z:
            return JointTiltResult(**{f.name: (z[f.name] if z[f.name].ndim else z[f.name].item())
                                      for f in dataclasses.fields(JointTiltResult)})
    except Exception:  # a corrupt entry is solved again, never trusted
        return None


def _store_tilt(path, result) -> None:
    import io

    from femcheck.report.atomic import write_bytes_atomic
    buf = io.BytesIO()
    np.savez(buf, **dataclasses.asdict(result))
    try:
        write_bytes_atomic(path, buf.getvalue())
    except OSError:  # a read-only cache only costs the next run the solve
        pass


def tilt_slip_ratio(study: dict) -> float:
    """ρ = (M_μ − M_0) / (μ F R_b): the measured friction moment of the ball in slip over μ F R_b.

    M_0, the moment of the frictionless run, is a discretization remainder (exactly 0 for a sphere:
    its normal forces pass through B; on the 0.5 mm contact mesh the pressure centroid of the ~0.37 mm
    contact patch is resolved only roughly); it is subtracted as the same remainder is present with
    friction. Both raw values are in the report.
    """
    f, z = study["friction"], study["frictionless"]
    return float((abs(f.moment_Nm[-1]) - abs(z.moment_Nm[-1])) / (f.friction * f.normal_force_N[-1] * f.ball_radius_m))
