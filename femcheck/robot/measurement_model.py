"""Measurement model of absolute marker positions and its nuisance parameters.

A reading is the marker position in the sensor frame::

    x = R(omega) R0 p_marker(q; geometry, elastic) + t0 + t

with the sensor<-base frame (rotation vector omega, translation t, around the closed-form Kabsch/Horn alignment
R0, t0 of the nominal model to the data: Horn, J. Opt. Soc. Am. A 4 (1987) 629), one offset correction per
marker (3 each) and the geometric corrections (dtheta, dd, da, dalpha) of every DH row plus the 6 of every
declared static frame. These are *nuisance* parameters: every explanation fits them, none reports them as a
cause.

Prior. A weak Gaussian prior centred on the nominal values, sigma ``prior_length_m`` for lengths,
``prior_angle_deg`` for angles, ``prior_marker_m`` for marker offsets (case ``[diagnosis]``); the sensor frame has
none. It keeps directions the data barely see from drifting; directions the data do not see at all (e.g. the
first row's theta offset against the sensor frame's rotation about the base z), and directions the data pin down
less well than the prior does, are *fixed* at nominal and listed (column-pivoted QR of the prior-scaled,
sigma-weighted Jacobian: pivot < ``RANK_RTOL`` of the largest, or < ``MIN_INFORMATION``).
"""
from __future__ import annotations

import dataclasses

import numpy as np
import scipy.linalg

from femcheck.robot.elastic import ElasticParams, equilibrium, flat_layout
from femcheck.robot.positions import MarkerPositions
from femcheck.robot.tree import ROW_PARAMS, STATIC_PARAMS, Geometry, RobotTree, forward, gravity_wrenches, rotation

#: relative pivot of the column-pivoted QR below which a nuisance direction counts as not identifiable
RANK_RTOL = 1e-7
#: pivot (data information in prior units) below which a nuisance direction is fixed at nominal
MIN_INFORMATION = 1.0
#: finite-difference steps: angles (rad) and lengths (m); elastic flat parameters by kind
FD_ANGLE, FD_LENGTH = 1e-7, 1e-7
FD_ELASTIC = {"torsion": 1e-7, "tilt": 1e-7, "backlash": 1e-6, "bending": 1e-7, "guide": 1e-7, "mass_scale": 1e-4}


def kabsch(p: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """R, t minimizing sum |R p + t - x|^2 over rotations (p, x (N, 3))."""
    pc, xc = p.mean(0), x.mean(0)
    H = (p - pc).T @ (x - xc)
    U, _, Vt = np.linalg.svd(H)
    S = np.diag([1.0, 1.0, np.sign(np.linalg.det(Vt.T @ U.T))])
    R = Vt.T @ S @ U.T
    return R, xc - R @ pc


@dataclasses.dataclass(frozen=True)
class NuisanceLayout:
    """Names, units, prior sigmas (inf = no prior) and FD steps of the nuisance vector."""

    names: tuple[str, ...]
    prior_sigma: np.ndarray
    step: np.ndarray
    group: tuple[str, ...]

    @classmethod
    def of(cls, tree: RobotTree, opts) -> "NuisanceLayout":
        L, A, Mk = opts.prior_length_m, np.deg2rad(opts.prior_angle_deg), opts.prior_marker_m
        names, sig, step, grp = [], [], [], []

        def add(name, s, h, g):
            names.append(name), sig.append(s), step.append(h), grp.append(g)

        for k, c in enumerate(("rx", "ry", "rz")):
            add(f"frame.{c}_rad", np.inf, FD_ANGLE, "frame")
        for c in ("x", "y", "z"):
            add(f"frame.{c}_m", np.inf, FD_LENGTH, "frame")
        for m in tree.marker_names:
            for c in ("x", "y", "z"):
                add(f"marker.{m}.{c}_m", Mk, FD_LENGTH, "marker")
        for i, r in enumerate(tree.names):
            for p in ROW_PARAMS:
                ang = p in ("theta", "alpha")
                add(f"geometry.{r}.{p}_{'rad' if ang else 'm'}", A if ang else L, FD_ANGLE if ang else FD_LENGTH, "geometry")
            if tree.has_static[i]:
                for p in STATIC_PARAMS:
                    ang = p.startswith("r")
                    add(f"static.{r}.{p}_{'rad' if ang else 'm'}", A if ang else L, FD_ANGLE if ang else FD_LENGTH, "static")
        return cls(tuple(names), np.array(sig), np.array(step), tuple(grp))

    @property
    def size(self) -> int:
        return len(self.names)


class MeasurementModel:
    """Predicts sensor-frame readings of ``data`` for a nuisance vector and elastic parameters (module docstring)."""

    def __init__(self, tree: RobotTree, data: MarkerPositions, opts, passes: int, backlash_width: np.ndarray,
                 guide_width: np.ndarray | None = None):
        self.tree, self.data, self.passes = tree, data, passes
        self.layout = NuisanceLayout.of(tree, opts)
        self.backlash_width, self.guide_width = backlash_width, guide_width
        self.R0, self.t0 = np.eye(3), np.zeros(3)
        static_rows = np.flatnonzero(tree.has_static)
        self._static_rows = static_rows

    def geometry(self, x: np.ndarray) -> Geometry:
        t = self.tree
        k = 6
        nm = len(t.marker_names)
        marker = x[k:k + 3 * nm].reshape(nm, 3)
        k += 3 * nm
        row = np.zeros((t.n_rows, 4))
        static = np.zeros((t.n_rows, 6))
        for i in range(t.n_rows):
            row[i] = x[k:k + 4]
            k += 4
            if t.has_static[i]:
                static[i] = x[k:k + 6]
                k += 6
        return Geometry(row=row, static=static, marker=marker)

    def base_positions(self, x: np.ndarray, params: ElasticParams, data: MarkerPositions | None = None,
                       start: tuple | None = None) -> np.ndarray:
        d = data or self.data
        fk = equilibrium(self.tree, d.q, self.geometry(x), params, self.passes, d.payload_kg, self.backlash_width,
                         self.guide_width, start)
        return fk.markers[d.pose, d.marker]

    def predict(self, x: np.ndarray, params: ElasticParams, data: MarkerPositions | None = None,
                start: tuple | None = None) -> np.ndarray:
        """(R, 3) sensor-frame positions, m (``start``: see :func:`equilibrium`)."""
        p = self.base_positions(x, params, data, start)
        R = rotation(x[:3]) @ self.R0
        return p @ R.T + self.t0 + x[3:6]

    def align(self, params: ElasticParams) -> None:
        """Closed-form sensor<-base frame of the nominal model (the starting point of every fit)."""
        x = np.zeros(self.layout.size)
        self.R0, self.t0 = kabsch(self.base_positions(x, params), self.data.xyz)

    def jacobian(self, x: np.ndarray, params: ElasticParams, cols=None, base=None) -> np.ndarray:
        """(3R, len(cols)) d predict / d x by forward differences (one prediction per column)."""
        cols = np.arange(self.layout.size) if cols is None else np.asarray(cols)
        f0 = self.predict(x, params).ravel() if base is None else base
        J = np.empty((f0.size, len(cols)))
        for j, c in enumerate(cols):
            h = self.layout.step[c]
            xp = x.copy()
            xp[c] += h
            J[:, j] = (self.predict(xp, params).ravel() - f0) / h
        return J

    def elastic_jacobian(self, x: np.ndarray, params: ElasticParams, base=None) -> np.ndarray:
        """(3R, n_flat) d predict / d (flat elastic parameters) by forward differences at ``params``."""
        t = self.tree
        lay = flat_layout(t)
        n_flat = lay["mass_scale"].stop
        f0 = self.predict(x, params).ravel() if base is None else base
        J = np.zeros((f0.size, n_flat))
        steps = np.empty(n_flat)
        for kind, sl in lay.items():
            steps[sl] = FD_ELASTIC[kind]
        guided = t.prismatic & np.isfinite(t.guide_overlap)
        # every column starts from the same undeflected poses and weights: computed once
        fk0 = forward(t, self.data.q @ t.coupling.T, self.geometry(x))
        F0, M0 = gravity_wrenches(t, fk0, self.data.payload_kg, params.mass_scale)
        start = (fk0, F0, M0, params.mass_scale)
        for j in range(n_flat):
            if lay["guide"].start <= j < lay["guide"].stop and not guided[j - lay["guide"].start]:
                continue        # no guide geometry: the column stays zero (the cause does not apply there)
            dlt = np.zeros(n_flat)
            dlt[j] = steps[j]
            J[:, j] = (self.predict(x, params.shifted(t, dlt), start=start).ravel() - f0) / steps[j]
        return J


def identifiable_columns(J_w: np.ndarray, prior_sigma: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """(kept, fixed, condition number of the kept columns) of a sigma-weighted Jacobian; columns are scaled by
    their prior sigma (1 for those without a prior) so that lengths and angles compare."""
    scale = np.where(np.isfinite(prior_sigma), prior_sigma, 1.0)
    Js = J_w * scale
    _, R, piv = scipy.linalg.qr(Js, mode="economic", pivoting=True)
    d = np.abs(np.diag(R))
    # kept: directions the data pin down better than the prior does (pivot > 1 in prior units: the data-only
    # standard error is below the prior sigma) and not numerically null; the others stay at nominal, since a
    # direction the prior rules would wander by up to its prior sigma and break the linearization
    rank = int(np.sum((d > RANK_RTOL * d[0]) & (d > MIN_INFORMATION))) if d.size and d[0] > 0 else 0
    kept, fixed = np.sort(piv[:rank]), np.sort(piv[rank:])
    sv = np.linalg.svd(Js[:, kept], compute_uv=False) if rank else np.array([1.0])
    return kept, fixed, float(sv[0] / sv[-1]) if sv[-1] > 0 else float("inf")
