"""Bench area ``vjm``: VJM deflection throughput and latency (IRB 120, seed 003) and identification times.

Figures:

* ``batch_poses_per_s`` / ``batch_kc_poses_per_s``: deflections (with C, K and rank) per second for a batch
  of random IRB 120 postures, without / with the complementary stiffness K_C (one vectorized call, 100 000
  poses); ``batch_twist_only_kc_poses_per_s``: the deflection alone (``stiffness=False``), with K_C;
* ``single_pose_latency_s``: median time of one ``deflect`` call for one pose (with K_C);
* ``extended_batch_poses_per_s``: the 7-joint, 21-virtual-joint cobot case, with K_C;
* ``identification_time_s``: seed-002 least-squares identification (21 compliances, 8 configurations x 2
  wrenches); ``configuration_selection_time_s``: greedy choice of 8 configurations from 200 candidates;
* ``hiss_stiffness_per_s``: HISS platform stiffnesses (3 legs, bordered inverse) per second;
* ``hiss_fit_time_s``: seed-001 weight fitting (11 weights, 65 synthetic measurements, 8 starts);
* ``mitre_superelement_build_s``: one solid FE superelement of a mitred corner (the 140 x 6 mm tube, 28 224
  DOFs: mesh, assembly, condensation; the cache bypassed); ``bearings_world_identify_s``: seed 002's workflow on
  the cobot's bearings world (13 configurations x 2 wrenches, both VJMs; superelements from the cache), with
  its outcome beside it: ``bearings_world_conventional_error_pct``, ``bearings_world_extended_error_pct`` (mean
  over the 26 Table I tests) and their ratio ``bearings_world_extended_over_conventional``, for the default
  (nominal) drives and, suffixed ``_catalogue_drives``, the catalogue's piecewise law.
"""
from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np

AREA = "vjm"

_CASES = Path(__file__).resolve().parents[2] / "cases"


def _best_of(fn, repeats: int = 3) -> float:
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def run() -> dict:
    from femcheck.case import load_case
    from femcheck.vjm.extended_vjm import identify_compliances, select_configurations, virtual_jacobian
    from femcheck.vjm.rcube_geometry import forward_position, leg_jacobians, leg_poses, rcube_stiffness
    from femcheck.vjm.parallel_vjm import parallel_stiffness
    from femcheck.vjm.serial_vjm import deflect
    from femcheck.vjm.weight_fitting import fit_weights, scaled_stiffness

    rng = np.random.default_rng(0)
    out: dict = {}
    irb = load_case(_CASES / "irb120.toml").vjm()
    n = 100_000
    q = rng.uniform(-np.pi, np.pi, (n, 6))
    W = np.array([29.43, 0.0, -29.43, 1.0, 0.0, 0.0])
    out["batch_poses"] = n
    out["batch_poses_per_s"] = n / _best_of(lambda: deflect(irb, q, W, complementary=False))
    out["batch_kc_poses_per_s"] = n / _best_of(lambda: deflect(irb, q, W, complementary=True))
    out["batch_twist_only_kc_poses_per_s"] = n / _best_of(lambda: deflect(irb, q, W, complementary=True, stiffness=False))
    q1 = q[:1]
    lat = []
    for _ in range(200):
        t0 = time.perf_counter()
        deflect(irb, q1, W, complementary=True)
        lat.append(time.perf_counter() - t0)
    out["single_pose_latency_s"] = float(np.median(lat))

    cobot_case = load_case(_CASES / "cobot7.toml")
    cobot = cobot_case.vjm()
    qc = rng.uniform(-2.0, 2.0, (20_000, 7))
    out["extended_batch_poses_per_s"] = 20_000 / _best_of(lambda: deflect(cobot, qc, W, complementary=True))
    plan = cobot_case.identification
    qi = np.deg2rad(np.repeat(np.array(plan.configurations_deg), len(plan.wrenches), axis=0))
    Wi = np.tile(np.array(plan.wrenches), (len(plan.configurations_deg), 1))
    dX = deflect(cobot, qi, Wi, complementary=False).twist
    out["identification_time_s"] = _best_of(lambda: identify_compliances(
        virtual_jacobian(cobot.chain, qi, True, cobot.tilt_offset_m), Wi, dX[:, :3]), 5)
    cand = virtual_jacobian(cobot.chain, rng.uniform(-2.0, 2.0, (200, 7)), True, cobot.tilt_offset_m)
    out["configuration_selection_time_s"] = _best_of(lambda: select_configurations(cand, np.array(plan.wrenches), 8), 1)

    hiss = load_case(_CASES / "hiss.toml")
    geom = hiss.rcube
    phi = rng.uniform(-np.deg2rad(29), np.deg2rad(29), (5_000, 3))
    P = forward_position(geom, phi)
    out["hiss_stiffness_per_s"] = 5_000 / _best_of(lambda: rcube_stiffness(geom, hiss.K_theta, P))
    tp = hiss.test_point_angles_rad
    Jt, Jp = leg_jacobians(leg_poses(geom, forward_position(geom, tp)))
    idx = np.repeat(np.arange(len(tp)), 5)
    F = rng.normal(size=(idx.size, 6)) * [5, 5, 5, 0.3, 0.3, 0.3]
    wmap = hiss.fitting.weight_map

    def predict(w):
        _, K = parallel_stiffness(Jt, scaled_stiffness(hiss.K_theta, w, wmap), Jp)
        return np.linalg.solve(K[idx], F[..., None])[..., 0]

    meas = predict(rng.uniform(0.3, 1.2, hiss.fitting.n_weights))
    out["hiss_fit_time_s"] = _best_of(lambda: fit_weights(predict, meas, hiss.fitting.n_weights, restarts=8), 1)
    out.update(_bearings_world())
    return {k: (float(v) if isinstance(v, (float, np.floating)) else v) for k, v in out.items()}


def _bearings_world() -> dict:
    """The cobot bearings world: the corner superelement's build time, the identification's, and its outcome."""
    from femcheck.case import load_case
    from femcheck.vjm import mitre_superelement as ms
    from femcheck.vjm.bearing_world import cobot7_bearings_world
    from femcheck.vjm.world_identification import identify_on_world

    case = load_case(_CASES / "cobot7.toml")
    world = cobot7_bearings_world(case)
    tube = world.links[1]
    out = {"mitre_superelement_build_s": _best_of(lambda: ms._build(
        tube, math.pi / 2, ms.LEG_DIAMETERS * tube.outer_diameter_m, ms.N_CIRC, ms.N_LEG, ms.N_WALL), 1)}
    identify_on_world(case, world)                    # fills the superelement cache
    out["bearings_world_identify_s"] = _best_of(lambda: identify_on_world(case, world))
    for suffix, w in (("", world), ("_catalogue_drives", cobot7_bearings_world(case, drives="catalogue"))):
        st = identify_on_world(case, w)
        c, e = (st.summary(st.fits[k])["table1_all"]["mean"] for k in ("conventional", "extended"))
        out |= {f"bearings_world_conventional_error_pct{suffix}": c, f"bearings_world_extended_error_pct{suffix}": e,
                f"bearings_world_extended_over_conventional{suffix}": e / c}
    return out
