"""The next measurements: which poses, load directions and load levels best separate the rival explanations
of a diagnosis.

Candidates
    *Poses* anywhere in the reachable workspace: a scrambled Sobol' sample of TCP positions in a box of
    ``±box_m`` around the nominal TCP and of platform orientations within ``±tilt_rad`` of the case's about each
    world axis (rotation vector components; ``tilt_rad = 0`` keeps the case's orientation), kept where every leg
    reaches
    (:func:`femcheck.kinematics.psu6.leg_geometry`) and the pose is well conditioned,
    cond(J_h) <= ``max_condition`` (:func:`femcheck.kinematics.conditioning.pose_conditioning`; the reference
    cube has 3.8-4.3), plus the nine cube points. *Load directions*: the 26 unit vectors of the axes, face and
    body diagonals (both signs). Forces only: the haptic case states no fixture for applied moments and the
    reading model takes TCP forces, so no moment is proposed (the plan says so). *Load levels*: the case's
    detailed test load P_T and 2 P_T (the preload staircase of the protocol already reaches 30 N).
    A measurement follows the protocol of the data: preload P_p, total P_p + load, unload to P_p and to 0,
    over ``trials`` trials, so a reading state has sigma_r / sqrt(trials) with sigma_r the reading noise of
    the data.

Criterion (T-optimal / expected log Bayes factor, Atkinson & Fedorov 1975; Box & Hill 1967)
    For rival explanations i, j (fitted to the data so far), if i is true the new readings are i's
    predictions plus noise and j refits its parameters to old and new data together. Linearized (Jacobian
    G of j's weighted predictions at the new states, H = J^T J of j on the old data), the expected increase
    of j's chi^2 over i's is

        D_ij = e^T e - b^T (H + G^T G)^-1 b,   e = (d_i - d_j) / sigma,   b = G^T e,

    i.e. ``sum (d_i - d_j)^2 / sigma^2`` less what j's refit absorbs. The expected log Bayes factor of i over j
    after the plan is ln B_ij = (BIC_j - BIC_i) / 2 + D_ij / 2 (BIC penalties at the new N), and the
    expected posterior of i if i is true is 1 / (1 + sum_j exp(-ln B_ij)). Greedy selection adds, one at a
    time, the candidate that maximizes the *expected log posterior of the true explanation*
    sum_i p_i ln P_i over the top rivals (p_i their current posterior, renormalized): it grows with every
    pair's log Bayes factor and saturates once a pair is separated, so later picks go to the pairs still
    confused. The top rivals are the fewest leading explanations holding 95 % of the posterior (2 to 5);
    the expected posteriors are renormalized over them.
    The refit is linear and ignores parameter bounds (a bound would only raise D).
"""
from __future__ import annotations

import dataclasses
import itertools
import logging
import time

import numpy as np
from scipy.special import softmax

from femcheck.diagnose.model import predict_readings

log = logging.getLogger(__name__)

#: default cond(J_h) limit for a planned pose: 2.5x the reference cube's ~4, far below the refusal level of
#: femcheck.kinematics.conditioning (1000), so the model is as trustworthy there as at the cube
PLAN_MAX_CONDITION = 10.0
#: half-width (m) of the box around the nominal TCP in which poses are sampled (the reach check trims it)
BOX_M = 0.15
#: half-width (rad) of the platform tilt sampled about each axis (rotation-vector components): 10 deg, the
#: orientation range a desktop haptic master is used in; the reach and conditioning checks trim it
TILT_RAD = float(np.deg2rad(10.0))
#: rivals whose posterior is below this are not planned for (they keep D = 0 in the expected posterior)
MIN_RIVAL_PROBABILITY = 1e-3
#: finite-difference step of the rival Jacobians, in the optimizer's scaled coordinates (value / typical or log10)
_FD_STEP = 1e-4


def unit_directions() -> tuple[np.ndarray, tuple[str, ...]]:
    """(26, 3) unit load directions (axes, face diagonals, body diagonals, both signs) and their labels,
    e.g. '+x', '+x-y', '-x+y+z'."""
    vecs, labels = [], []
    for s in itertools.product((-1, 0, 1), repeat=3):
        if not any(s):
            continue
        v = np.array(s, float)
        vecs.append(v / np.linalg.norm(v))
        labels.append("".join(f"{'+' if c > 0 else '-'}{a}" for c, a in zip(s, "xyz") if c))
    order = np.argsort([np.count_nonzero(v) for v in vecs], kind="stable")
    return np.array(vecs)[order], tuple(labels[i] for i in order)


@dataclasses.dataclass(frozen=True)
class CandidatePoses:
    """``ids`` (n,) pose ids (P0..P8 for the cube, Q001.. for sampled ones), ``poses`` (n, 6) m/rad, ``cond`` (n,)
    cond(J_h); ``box_m`` the sampling half-width, ``max_condition`` the limit used, ``n_drawn`` positions drawn."""

    ids: tuple[str, ...]
    poses: np.ndarray
    cond: np.ndarray
    box_m: float
    max_condition: float
    n_drawn: int


def candidate_poses(case, n_poses: int = 120, *, seed: int = 0, box_m: float = BOX_M, tilt_rad: float = TILT_RAD,
                    max_condition: float = PLAN_MAX_CONDITION) -> CandidatePoses:
    """The cube points plus up to ``n_poses`` reachable, well-conditioned poses sampled in the workspace
    (scrambled Sobol' positions in nominal +- ``box_m`` and orientations within +- ``tilt_rad`` of the case's
    about each axis, as rotation-vector increments; ``tilt_rad = 0``: the case's orientation). Vectorized: one
    inverse-kinematics and one conditioning pass over all drawn poses."""
    from scipy.stats import qmc

    from femcheck.kinematics.conditioning import pose_conditioning
    from femcheck.kinematics.psu6 import POINT_LABELS, leg_geometry, test_points

    cube = test_points(case)
    n_draw = int(2 ** np.ceil(np.log2(max(16 * n_poses, 16))))
    u = qmc.Sobol(6 if tilt_rad > 0 else 3, scramble=True, seed=seed).random(n_draw)
    poses = np.tile(cube[0], (n_draw, 1))
    poses[:, :3] += (2.0 * u[:, :3] - 1.0) * box_m
    if tilt_rad > 0:
        # compose the sampled tilt with the case's orientation (R = R_tilt R_case), as rotation vectors
        from scipy.spatial.transform import Rotation
        tilt = Rotation.from_rotvec((2.0 * u[:, 3:] - 1.0) * tilt_rad)
        poses[:, 3:] = (tilt * Rotation.from_rotvec(cube[0, 3:])).as_rotvec()
    legs = leg_geometry(case, poses, check_reach=False)
    reach = np.all(np.isfinite(legs.slider), axis=1)
    cond = np.full(n_draw, np.inf)
    if reach.any():
        sub = leg_geometry(case, poses[reach])
        cond[reach] = pose_conditioning(case, sub, max(max_condition, 1.0 + 1e-9)).cond
    keep = np.flatnonzero(reach & (cond <= max_condition))[:n_poses]
    cube_legs = leg_geometry(case, cube, labels=list(POINT_LABELS))
    cube_cond = pose_conditioning(case, cube_legs).cond
    ids = tuple(POINT_LABELS) + tuple(f"Q{k + 1:03d}" for k in range(len(keep)))
    return CandidatePoses(ids=ids, poses=np.vstack([cube, poses[keep]]), cond=np.concatenate([cube_cond, cond[keep]]),
                          box_m=float(box_m), max_condition=float(max_condition), n_drawn=n_draw)


@dataclasses.dataclass(frozen=True)
class MeasurementStates:
    """The reading states of candidate measurements, with the fields the effects read (duck-typed like
    :class:`femcheck.measured.Readings`): per measurement c (n) four states preload, total, unload to the
    preload, unload to 0 (m = 4 n, state 4 c + s). ``pose`` (m, 6), ``force`` (m, 3) N, ``load_N``, ``peak_N`` (m,),
    ``phase`` (m,) str, ``case_index`` (m,), ``case_unit`` (n, 3)."""

    pose: np.ndarray
    force: np.ndarray
    load_N: np.ndarray
    peak_N: np.ndarray
    phase: np.ndarray
    case_index: np.ndarray
    case_unit: np.ndarray


PHASES = ("preload", "total", "unload", "unload")


def measurement_states(poses: np.ndarray, units: np.ndarray, loads: np.ndarray, preload_N: float) -> MeasurementStates:
    """States of n measurements: ``poses`` (n, 6), ``units`` (n, 3) load directions, ``loads`` (n,) test loads N
    (total = preload + load)."""
    n = len(poses)
    lv = np.stack([np.full(n, preload_N), preload_N + loads, np.full(n, preload_N), np.zeros(n)], axis=1)   # (n, 4)
    peak = np.stack([lv[:, 0], lv[:, 1], lv[:, 1], lv[:, 1]], axis=1)
    return MeasurementStates(pose=np.repeat(poses, 4, axis=0), force=(lv[..., None] * units[:, None, :]).reshape(-1, 3),
                             load_N=lv.ravel(), peak_N=peak.ravel(), phase=np.tile(np.array(PHASES, dtype=object), n),
                             case_index=np.repeat(np.arange(n), 4), case_unit=np.asarray(units, float))


def _scaled(fit):
    params = [p for e in fit.effects for p in e.params]
    x = np.array([p.to_x(v) for p, v in zip(params, np.concatenate(fit.values) if params else [])], float)
    hi = np.array([p.to_x(p.upper) for p in params], float)
    return params, x, hi


def _values(fit, params, x):
    v = np.array([p.from_x(xi) for p, xi in zip(params, x)], float)
    out, k = [], 0
    for e in fit.effects:
        out.append(v[k:k + len(e.params)])
        k += len(e.params)
    return out


def rival_response(model, fit, states, sigma) -> tuple[np.ndarray, np.ndarray]:
    """Weighted predictions of explanation ``fit`` (a FitResult) at ``states``: (m * 3,) d / sigma and its Jacobian
    (m * 3, k) with respect to the fit's scaled parameters (forward differences, stepping inwards at an upper
    bound). ``sigma`` (m, 3) or a scalar, m."""
    params, x, hi = _scaled(fit)
    d0 = predict_readings(model, states, fit.effects, fit.values)
    sig = np.broadcast_to(np.asarray(sigma, float), d0.shape)
    J = np.zeros((d0.size, len(params)))
    for k in range(len(params)):
        h = _FD_STEP if x[k] + _FD_STEP <= hi[k] else -_FD_STEP
        xk = x.copy()
        xk[k] += h
        J[:, k] = ((predict_readings(model, states, fit.effects, _values(fit, params, xk)) - d0) / sig).ravel() / h
    return (d0 / sig).ravel(), J


def refit_separation(A: np.ndarray, b: np.ndarray, ee: np.ndarray) -> np.ndarray:
    """D = ee - b^T A^-1 b, batched: the chi^2 a rival cannot absorb by a linearized refit (module docstring).
    ``A`` (n, k, k) = H + G^T G, ``b`` (n, k) = G^T e, ``ee`` (n,) = e^T e; k = 0 gives ee. A tiny ridge
    (1e-10 of the largest diagonal entry) keeps parameters the data do not determine from making A singular."""
    k = A.shape[-1]
    if not k:
        return np.asarray(ee, float)
    reg = 1e-10 * max(float(np.max(np.abs(np.diagonal(A, axis1=-2, axis2=-1)))), 1e-300)
    sol = np.linalg.solve(A + reg * np.eye(k), b[..., None])[..., 0]
    return ee - np.einsum("ck,ck->c", b, sol)


def separation(model, readings, truth, rival, states, sigma_state: float) -> np.ndarray:
    """(n,) expected chi^2 increase D of explanation ``rival`` over ``truth`` (FitResults on ``readings``) from each
    single candidate measurement of ``states`` (4 states each, :func:`measurement_states`), with the rival's
    linearized refit to the old and the new readings. For Gaussian noise the expected log Bayes factor gained is
    D / 2."""
    yt, _ = rival_response(model, truth, states, sigma_state)
    yr, G = rival_response(model, rival, states, sigma_state)
    _, Jo = rival_response(model, rival, readings, readings.sigma)
    n = len(states.case_unit)
    e, G = (yt - yr).reshape(n, 12), G.reshape(n, 12, -1)
    A = (Jo.T @ Jo)[None] + np.einsum("cik,cil->ckl", G, G)
    return np.maximum(refit_separation(A, np.einsum("cik,ci->ck", G, e), np.einsum("ci,ci->c", e, e)), 0.0)


@dataclasses.dataclass(frozen=True)
class PlannedMeasurement:
    """One proposed measurement: ``pose_id``, ``pose`` (6,) m/rad, ``direction`` (3,) unit force direction and its
    ``direction_label``, ``preload_N`` and ``load_N`` (the test load: total = preload + load), ``cond`` cond(J_h)
    of the pose, ``objective_after`` the selection objective once it is added."""

    pose_id: str
    pose: np.ndarray
    direction: np.ndarray
    direction_label: str
    preload_N: float
    load_N: float
    cond: float
    objective_after: float

    def as_dict(self) -> dict:
        x, y, z = (float(v) * 1e3 for v in self.pose[:3])
        rx, ry, rz = (float(v) for v in self.pose[3:])
        return {"pose_id": self.pose_id, "x_mm": x, "y_mm": y, "z_mm": z, "rx_rad": rx, "ry_rad": ry, "rz_rad": rz,
                "direction": self.direction_label, "ux": round(float(self.direction[0]), 4),
                "uy": round(float(self.direction[1]), 4), "uz": round(float(self.direction[2]), 4),
                "preload_N": self.preload_N, "load_N": self.load_N, "total_N": self.preload_N + self.load_N,
                "cond": round(float(self.cond), 3), "objective_after": self.objective_after}


CRITERION = ("greedy maximum of the expected log posterior of the true explanation, sum_i p_i ln P_i, over the top "
             "rivals; P_i from the expected log Bayes factors ln B_ij = (BIC_j - BIC_i) / 2 + D_ij / 2 with "
             "D_ij = sum (d_i - d_j)^2 / sigma^2 less what rival j absorbs by a linearized refit (T-optimality)")


@dataclasses.dataclass(frozen=True)
class Plan:
    """Result of :func:`plan_measurements` (see module docstring). ``rivals``: per top rival its ``ids``,
    ``probability`` now and ``expected_posterior_if_true`` after the plan; ``expected_log_bayes_factor_top2``: ln B
    of the leader over the runner-up if the leader is true (and ``..._reverse`` if the runner-up is)."""

    measurements: tuple[PlannedMeasurement, ...]
    rivals: tuple[dict, ...]
    objective_before: float
    objective_after: float
    expected_log_bayes_factor_top2: float
    expected_log_bayes_factor_top2_reverse: float
    log_bayes_factor_top2_now: float
    expected_posterior_leader: float
    expected_cause_probability_leader: dict
    rival_mass: float
    sigma_state_m: float
    trials: int
    n_candidate_poses: int
    n_candidates: int
    load_levels_N: tuple[float, ...]
    max_condition: float
    wall_s: float
    notes: tuple[str, ...]

    def as_json(self) -> dict:
        lead = self.rivals[0] if self.rivals else {"ids": ["none"]}
        return {"criterion": CRITERION, "criterion_value": self.expected_log_bayes_factor_top2,
                "criterion_value_meaning": "expected log Bayes factor of the leading explanation over the runner-up "
                                           "after the plan, if the leader is true",
                "expected_log_bayes_factor_top2": self.expected_log_bayes_factor_top2,
                "expected_log_bayes_factor_top2_reverse": self.expected_log_bayes_factor_top2_reverse,
                "log_bayes_factor_top2_now": self.log_bayes_factor_top2_now,
                "objective_before": self.objective_before, "objective_after": self.objective_after,
                "leading_explanation": "+".join(lead["ids"]),
                "posterior_leader_now": lead.get("probability", 1.0),
                "expected_posterior_leader": self.expected_posterior_leader,
                "expected_cause_probability_leader": self.expected_cause_probability_leader,
                "rival_mass": self.rival_mass,
                "measurements": [m.as_dict() for m in self.measurements], "rivals": list(self.rivals),
                "sigma_state_m": self.sigma_state_m, "trials": self.trials,
                "n_candidate_poses": self.n_candidate_poses, "n_candidates": self.n_candidates,
                "load_levels_N": list(self.load_levels_N), "max_condition": self.max_condition,
                "moments": False, "plan_wall_s": round(self.wall_s, 2), "notes": list(self.notes)}

    def protocol_rows(self, trials: int | None = None):
        """The readings that carry the plan out, in the layout of
        :func:`femcheck.experiment.simulate.protocol_rows`: (point, direction, trial, phase, load_N, force (r, 3)).
        Point = the pose id, direction = a named load case ``plan<k>`` (one per measurement; its direction is
        the applied force)."""
        trials = int(trials or self.trials)
        rows = []
        for t in range(1, trials + 1):
            for k, m in enumerate(self.measurements):
                for phase, load in (("preload", m.preload_N), ("total", m.preload_N + m.load_N),
                                    ("unload", m.preload_N), ("unload", 0.0)):
                    rows.append((m.pose_id, f"plan{k + 1}", t, phase, load, load * m.direction))
        point, direction, trial, phase, load, force = zip(*rows)
        return (np.array(point, dtype=object), np.array(direction, dtype=object), np.array(trial, int),
                np.array(phase, dtype=object), np.array(load, float), np.array(force, float).reshape(-1, 3))

    def pose_table(self) -> dict[str, np.ndarray]:
        """{pose id: (6,) pose} of the planned poses (for :func:`femcheck.measured.process`)."""
        return {m.pose_id: np.asarray(m.pose, float) for m in self.measurements}


def plan_measurements(model, readings, weighing, *, budget: int = 3, n_poses: int = 120, rivals: int = 5,
                      coverage: float = 0.95,
                      seed: int = 0, trials: int | None = None, load_levels_N=None,
                      max_condition: float = PLAN_MAX_CONDITION, box_m: float = BOX_M,
                      tilt_rad: float = TILT_RAD) -> Plan:
    """Propose ``budget`` measurements that best separate the top ``rivals`` explanations of ``weighing`` (the
    :class:`~femcheck.diagnose.evidence.Weighing` of a diagnosis, whose explanations carry their FitResult) given
    ``readings`` (module docstring)."""
    t0 = time.perf_counter()
    case = model.case
    trials = int(trials or case.measurement.trials)
    preload = float(case.loads.detailed_preload_N)
    levels = tuple(float(v) for v in (load_levels_N or (case.loads.detailed_test_N, 2.0 * case.loads.detailed_test_N)))
    ex, prob = list(weighing.explanations), np.asarray(weighing.probability, float)
    # the rivals with a fit: a summed family of unfitted placements (Explanation.fixed_scores) has no prediction to
    # discriminate; the plan's probabilities are renormalized over the fitted rivals
    fitted = [i for i, e in enumerate(ex) if e.fixed_scores is None]
    ex, prob = [ex[i] for i in fitted], prob[fitted] / prob[fitted].sum()
    order = np.argsort(-prob, kind="stable")
    ex, prob = [ex[i] for i in order], prob[order]
    # the top rivals: the fewest leading explanations holding ``coverage`` of the posterior (at least 2, at most
    # ``rivals``, none below MIN_RIVAL_PROBABILITY)
    cum = np.cumsum(prob)
    n_top = int(np.searchsorted(cum, coverage * cum[-1]) + 1)
    top = [i for i in range(len(ex)) if i < min(max(n_top, 2), max(rivals, 2))
           and (i < 2 or prob[i] >= MIN_RIVAL_PROBABILITY)]
    K = len(top)
    missing = [ex[i].name for i in top if ex[i].payload is None]
    if missing:
        raise ValueError(f"plan_measurements needs each rival's fit (Explanation.payload); {missing[0]} has none: "
                         "weigh the FitResults of femcheck.diagnose.selection.fit_rivals")
    n_old = int(weighing.n_data)
    # -2 ln evidence of each rival with the weighing's approximation (Laplace or BIC); more data add k ln(N'/N) to
    # either (the Occam factor of a Laplace evidence grows as that of BIC once the data dominate the prior)
    method = getattr(weighing, "method", "bic")
    bic_old = np.array([e.score(n_old, method) - e.penalty for e in ex])
    kpar = np.array([e.n_params for e in ex], float)

    cand = candidate_poses(case, n_poses, seed=seed, box_m=box_m, tilt_rad=tilt_rad, max_condition=max_condition)
    U, ulab = unit_directions()
    P, D, L = len(cand.ids), len(U), len(levels)
    pi, di, li = (a.ravel() for a in np.meshgrid(np.arange(P), np.arange(D), np.arange(L), indexing="ij"))
    states = measurement_states(cand.poses[pi], U[di], np.asarray(levels)[li], preload)
    n_c = len(pi)
    sigma_state = float(readings.reading_sigma_m) / np.sqrt(trials)

    # weighted predictions and Jacobians of each top rival: at the candidates and (for H) at the old readings
    pred, G, H = [], [], []
    for i in top:
        fit = ex[i].payload
        y, J = rival_response(model, fit, states, sigma_state)
        pred.append(y.reshape(n_c, 12))
        G.append(J.reshape(n_c, 12, -1))
        _, Jo = rival_response(model, fit, readings, readings.sigma)
        H.append(Jo.T @ Jo)
    # per ordered pair (truth a, rival b): per-candidate e^T e, G_b^T e; per rival: G_b^T G_b
    M = [np.einsum("cik,cil->ckl", g, g) for g in G]
    s_ab, g_ab = {}, {}
    for a, b in itertools.permutations(range(K), 2):
        e = pred[a] - pred[b]
        s_ab[a, b] = np.einsum("ci,ci->c", e, e)
        g_ab[a, b] = np.einsum("cik,ci->ck", G[b], e)

    chosen: list[int] = []
    acc = {"A": [h.copy() for h in H], "b": {k: np.zeros(G[k[1]].shape[2]) for k in s_ab}, "ee": {k: 0.0 for k in s_ab}}
    p_top = prob[top] / prob[top].sum()

    def deltas(extra: bool):
        """D[a, b] for the chosen set (+ each candidate when ``extra``): (n_c, K, K) or (1, K, K)."""
        n = n_c if extra else 1
        out = np.zeros((n, K, K))
        for (a, b), s in s_ab.items():
            A, bb, ee = acc["A"][b], acc["b"][a, b], acc["ee"][a, b]
            if extra:
                Ac, bc, ec = A[None] + M[b], bb[None] + g_ab[a, b], ee + s
            else:
                Ac, bc, ec = A[None], bb[None], np.array([ee])
            ec = refit_separation(Ac, bc, ec)
            out[:, a, b] = np.maximum(ec, 0.0)
        return out

    def lnB_matrix(Dm, n_new):
        """(n, K, K) expected ln B of each top truth over each top rival after ``n_new`` more data."""
        n_tot = n_old + n_new
        bic_new = (bic_old + kpar * (np.log(n_tot) - np.log(n_old)))[top]
        return 0.5 * (bic_new[None, None, :] - bic_new[None, :, None]) + 0.5 * Dm

    def objective(lnB):
        z = np.exp(-np.clip(lnB, -700, 700))
        z[:, np.arange(K), np.arange(K)] = 0.0
        logp = -np.log1p(z.sum(axis=-1))                                 # (n, K)
        return logp @ p_top, logp

    obj_before = float(objective(lnB_matrix(deltas(False), 0))[0][0])
    taken = np.zeros(n_c, bool)
    measurements = []
    for step in range(budget):
        Dm = deltas(True)
        obj, _ = objective(lnB_matrix(Dm, 12 * (step + 1)))
        score = np.where(taken, -np.inf, obj)
        c = int(np.argmax(score))
        taken[c] = True
        chosen.append(c)
        for (a, b) in s_ab:
            acc["b"][a, b] = acc["b"][a, b] + g_ab[a, b][c]
            acc["ee"][a, b] += float(s_ab[a, b][c])
        for b in range(K):
            acc["A"][b] = acc["A"][b] + M[b][c]
        measurements.append(PlannedMeasurement(
            pose_id=cand.ids[pi[c]], pose=cand.poses[pi[c]].copy(), direction=U[di[c]].copy(),
            direction_label=ulab[di[c]], preload_N=preload, load_N=levels[li[c]], cond=float(cand.cond[pi[c]]),
            objective_after=float(obj[c])))
        log.info("plan step %d: %s %s %g N, objective %.4g", step + 1, cand.ids[pi[c]], ulab[di[c]], levels[li[c]], obj[c])
    Dm = deltas(False)
    lnB = lnB_matrix(Dm, 12 * len(chosen))
    obj_after, logp = objective(lnB)
    # expected posterior over the top rivals if rival a is true: softmax_j(-ln B_aj), ln B_aa = 0
    post = softmax(-lnB[0], axis=1)
    now = 0.5 * (bic_old[top[1]] - bic_old[top[0]]) if K > 1 else float("inf")
    lead_causes = {c: float(sum(post[0, j] for j in range(K) if c in ex[top[j]].ids)) for c in ex[top[0]].ids}
    if not ex[top[0]].ids:      # the leader is "no effect": its own expected posterior
        lead_causes = {"none": float(post[0, 0])}
    rivals_out = tuple({"ids": list(ex[i].ids) or ["none"], "probability": float(prob[i]),
                        "expected_posterior_if_true": float(post[a, a])} for a, i in enumerate(top))
    notes = ("forces only: the case states no fixture for applied moments and the reading model takes TCP forces",
             f"poses sampled in nominal +- {box_m * 1e3:.0f} mm and the case's orientation tilted by up to "
             f"+- {np.rad2deg(tilt_rad):.0f} deg about each axis, reachable, cond(J_h) <= {max_condition:g}",
             "the expected posteriors assume the rival's fitted parameters are the truth and refit the others linearly; "
             f"rivals: the {K} leading explanations ({100 * float(prob[top].sum()):.1f} % of the posterior); expected "
             "posteriors are over them",
             "off-cube pose ids (Q...) are not P0..P8: diagnose readings taken there with `femcheck diagnose CASE "
             "DATA.csv --pose-table PLAN.json` (this plan's --json; the ids are stable for the same --seed)")
    if prob[0] >= 0.99:
        notes += (f"the leading explanation already holds {prob[0]:.3f} of the posterior: these measurements "
                  "confirm more than they separate",)
    return Plan(measurements=tuple(measurements), rivals=rivals_out, objective_before=obj_before,
                objective_after=float(obj_after[0]),
                expected_log_bayes_factor_top2=float(lnB[0, 0, top[1]]) if K > 1 else float("inf"),
                expected_log_bayes_factor_top2_reverse=float(lnB[0, 1, top[0]]) if K > 1 else float("nan"),
                log_bayes_factor_top2_now=float(now), expected_posterior_leader=float(post[0, 0]),
                expected_cause_probability_leader=lead_causes, rival_mass=float(prob[top].sum()),
                sigma_state_m=sigma_state, trials=trials, n_candidate_poses=P, n_candidates=n_c,
                load_levels_N=levels, max_condition=float(max_condition), wall_s=time.perf_counter() - t0, notes=notes)


def read_pose_table(path, case) -> dict[str, np.ndarray]:
    """{pose id: (6,) pose} from a plan's JSON (``femcheck plan --json``: its ``measurements``, each with ``pose_id``,
    ``x_mm``, ``y_mm``, ``z_mm`` and ``rx_rad``, ``ry_rad``, ``rz_rad``), so that readings taken at a plan's off-cube
    poses can be diagnosed. Every pose must be reachable (:class:`~femcheck.errors.UnreachablePoseError` names it);
    any other problem is a :class:`~femcheck.errors.MeasuredDataError` naming the file and the key."""
    import json
    from pathlib import Path

    from femcheck.errors import MeasuredDataError
    from femcheck.kinematics.psu6 import leg_geometry

    try:
        doc = json.loads(Path(path).read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise MeasuredDataError(path, None, None, f"not a plan JSON ({exc}); expected the file of `femcheck plan "
                                "--json`") from None
    rows = doc.get("measurements") if isinstance(doc, dict) else None
    if not isinstance(rows, list) or not rows:
        raise MeasuredDataError(path, None, "measurements", "missing or empty; expected the file of `femcheck plan --json`")
    table: dict[str, np.ndarray] = {}
    for k, m in enumerate(rows):
        try:
            pid = str(m["pose_id"])
            pose = np.array([m["x_mm"] * 1e-3, m["y_mm"] * 1e-3, m["z_mm"] * 1e-3,
                             m.get("rx_rad", 0.0), m.get("ry_rad", 0.0), m.get("rz_rad", 0.0)], float)
        except (KeyError, TypeError, ValueError) as exc:
            raise MeasuredDataError(path, None, f"measurements[{k}]", f"lacks or mangles {exc}; expected pose_id, "
                                    "x_mm, y_mm, z_mm (and rx_rad, ry_rad, rz_rad)") from None
        if not np.all(np.isfinite(pose)):
            raise MeasuredDataError(path, None, f"measurements[{k}]", f"pose {pid} is not finite")
        if pid in table and not np.allclose(table[pid], pose, atol=1e-9):
            raise MeasuredDataError(path, None, f"measurements[{k}]", f"pose id {pid} names two different poses")
        table[pid] = pose
    ids = list(table)
    leg_geometry(case, np.array([table[i] for i in ids]), labels=ids)      # raises UnreachablePoseError
    return table
