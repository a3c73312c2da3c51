"""The corrected serial-tree case: a self-weight diagnosis' extended model written into a copy of the case file,
its predictions, and the compensation table a controller subtracts.

What the fit ("after", :func:`femcheck.robot.diagnosis.diagnose_tree`) holds becomes the rows' own keys:

* geometry corrections of every DH row: ``theta_offset_deg``, ``d_m``, ``a_m``, ``alpha_deg`` (nominal + fitted
  correction); declared static frames ``static_origin_m``, ``static_rpy_deg`` (S' = S [R(r) | p]);
* marker offsets ``offset_m`` (nominal + correction) and the sensor frame ``[sensor_frame]``
  (x_sensor = R p_base + t);
* the springs of the named causes: torsion ``stiffness_Nm_per_rad`` = 1/c, tilt ``tilt_stiffness_Nm_per_rad``,
  gear clearance ``backlash_rad`` with its take-up torque ``backlash_torque_Nm``, link bending ``bending_EI_Nm2`` =
  1/c, mass scale s on every row's ``mass_kg`` (the payload is not scaled, as in the fit).

Every written value carries a comment: its 95 % interval (1.96 standard errors of the linearized fit) and the
cause (or the nuisance calibration) that set it. The corrected case predicts the fit's readings to rounding: the
keys are the fitted parameters themselves and floats are written with ``repr``.

The compensation table is the elastic part of the corrected model: marker position with the springs under self
weight (and payload) minus the rigid position, at joint angles the user lists, in the robot's base frame, mm.
"""
from __future__ import annotations

import csv
import io
import math

import numpy as np

from femcheck.case.toml_edit import Edit, edited
from femcheck.errors import FemcheckError, MeasuredDataError
from femcheck.robot.elastic import ElasticParams, equilibrium
from femcheck.robot.tree import Geometry, forward, homogeneous, rotation

#: the cause behind each flat elastic kind (messages)
def rpy_of(R: np.ndarray) -> np.ndarray:
    """Roll, pitch, yaw (rad) of R = Rz(yaw) Ry(pitch) Rx(roll), the inverse of
    :func:`femcheck.robot.tree.rpy_matrix` (|pitch| < 90 deg)."""
    return np.array([math.atan2(R[2, 1], R[2, 2]), -math.asin(max(-1.0, min(1.0, R[2, 0]))), math.atan2(R[1, 0], R[0, 0])])


def rotation_vector(R: np.ndarray) -> np.ndarray:
    from femcheck.kinematics.frames import matrix_to_rotvec
    return np.asarray(matrix_to_rotvec(R), float)


def _ci(v: float, se: float, unit: str, cause: str, scale: float = 1.0) -> str:
    if not np.isfinite(se):
        return f"{cause} (on its bound: no interval)"
    return f"95 % [{(v - 1.96 * se) * scale:.6g}, {(v + 1.96 * se) * scale:.6g}] {unit} from {cause}"


def _inverse_ci(c: float, se: float, unit: str, cause: str) -> str:
    """Interval of a stiffness 1/c from the compliance's interval c +- 1.96 se."""
    lo, hi = c - 1.96 * se, c + 1.96 * se
    if not np.isfinite(se):
        return f"{cause} (on its bound: no interval)"
    top = "inf" if lo <= 0 else f"{1.0 / lo:.6g}"
    return f"95 % [{1.0 / hi:.6g}, {top}] {unit} from {cause}"


def corrected_case_edits(case, diagnosis) -> list[Edit]:
    """The :class:`Edit` list that writes ``diagnosis``' extended model into ``case`` (module docstring)."""
    if case.meta.kind != "serial_tree":
        raise FemcheckError(f"--extended-case: a {case.meta.kind} case; the corrected case is written for serial_tree "
                            "cases (the rows' own keys): describe the robot as a serial_tree case")
    fit = diagnosis.fitted
    tree = case.tree
    x, params, kept, se_x = fit["x"], fit["params"], set(int(i) for i in fit["kept"]), fit["nuisance_se"]
    names = diagnosis_layout_names(case)
    edits: list[Edit] = []
    calib = "the nuisance calibration"
    pos = {n: i for i, n in enumerate(names)}
    J = case.joints
    for i, j in enumerate(J):
        # DH corrections of the row
        for p, key, nominal, to_unit, unit in (("theta", "theta_offset_deg", j.theta_offset_deg, math.degrees, "deg"),
                                               ("d", "d_m", j.d_m, float, "m"), ("a", "a_m", j.a_m, float, "m"),
                                               ("alpha", "alpha_deg", j.alpha_deg, math.degrees, "deg")):
            k = pos[f"geometry.{j.name}.{p}_{'rad' if p in ('theta', 'alpha') else 'm'}"]
            if k in kept and x[k] != 0.0:
                v = nominal + to_unit(x[k])
                edits.append(Edit("joints", key, v, _ci(to_unit(x[k]), to_unit(se_x[k]), unit, calib) + " (correction)",
                                  index=i))
        if tree.has_static[i]:
            ks = [pos[f"static.{j.name}.{c}_{'rad' if c.startswith('r') else 'm'}"] for c in ("x", "y", "z", "rx", "ry", "rz")]
            dv = np.array([x[k] if k in kept else 0.0 for k in ks])
            if np.any(dv):
                S = tree.static[i] @ homogeneous(rotation(dv[3:]), dv[:3])
                se_p = max(se_x[k] for k in ks[:3]) * 1e3
                se_r = math.degrees(max(se_x[k] for k in ks[3:]))
                edits.append(Edit("joints", "static_origin_m", [float(c) for c in S[:3, 3]],
                                  f"static frame corrected by [{', '.join(f'{c * 1e3:.4g}' for c in dv[:3])}] mm, "
                                  f"95 % +-{1.96 * se_p:.3g} mm, from {calib}", index=i))
                edits.append(Edit("joints", "static_rpy_deg", [float(c) for c in np.degrees(rpy_of(S[:3, :3]))],
                                  f"rotated by [{', '.join(f'{math.degrees(c):.4g}' for c in dv[3:])}] deg, "
                                  f"95 % +-{1.96 * se_r:.3g} deg, from {calib}", index=i))
    for m, mk in enumerate(case.markers):
        ks = [pos[f"marker.{mk.name}.{c}_m"] for c in "xyz"]
        dv = np.array([x[k] if k in kept else 0.0 for k in ks])
        if np.any(dv):
            ci = ", ".join(f"[{(d - 1.96 * se_x[k]) * 1e3:.4g}, {(d + 1.96 * se_x[k]) * 1e3:.4g}]" for d, k in zip(dv, ks))
            edits.append(Edit("markers", "offset_m", [float(a + b) for a, b in zip(mk.offset_m, dv)],
                              f"correction 95 % {ci} mm from {calib}", index=m))
    R, t = fit["R"], fit["t"]
    edits.append(Edit("sensor_frame", "rotation_vector_rad", [float(c) for c in rotation_vector(R)],
                      f"sensor <- base, from {calib} (95 % +-{1.96 * max(se_x[:3]):.3g} rad about the closed-form alignment)"))
    edits.append(Edit("sensor_frame", "translation_m", [float(c) for c in t],
                      f"from {calib} (95 % +-{1.96 * max(se_x[3:6]) * 1e3:.3g} mm)"))
    edits += _spring_edits(case, diagnosis, params)
    return edits


def diagnosis_layout_names(case) -> tuple[str, ...]:
    from femcheck.robot.measurement_model import NuisanceLayout
    return NuisanceLayout.of(case.tree, case.diagnosis).names


def _spring_edits(case, diagnosis, params: ElasticParams) -> list[Edit]:
    """Springs of the named causes, one comment per row: the fitted value's interval and its cause."""
    tree, fit = case.tree, diagnosis.fitted
    # per flat unit: (cause id, standard error of its group's increment, probability)
    source: dict[tuple[str, int], tuple[str, float, float]] = {}
    for cid, kind, groups, vals, ses, prob in fit["units"]:
        for g, s in zip(groups, ses):
            for u in g:
                source[(kind, int(u))] = (cid, float(s), prob)
    edits = []
    J = case.joints

    def why(kind, u):
        cid, s, p = source[(kind, u)]
        return cid, s, f"{cid}, p = {p:.2f}"

    def inverse_edit(kind, unit, row, c, key, si_unit, word):
        """key = 1/c, refused where the fit leaves the element rigid (a rigid spring is an absent key)."""
        cid, s, text = why(kind, unit)
        if c <= 0:
            raise FemcheckError(f"--extended-case: {cid} leaves {word} {J[row].name} rigid; the case holds a "
                                f"rigid element as an absent key, remove {key} by hand")
        return Edit("joints", key, 1.0 / c, _inverse_ci(c, s, si_unit, text), index=row)

    for r in range(tree.n_rows):
        if ("torsion", r) in source:      # a row's own spring: the drive's, a coupled row's series one, or axial
            if tree.prismatic[r]:
                edits.append(inverse_edit("torsion", r, r, float(params.torsion[r]), "axial_stiffness_N_per_m", "N/m",
                                          "the slide of"))
            else:
                edits.append(inverse_edit("torsion", r, r, float(params.torsion[r]), "stiffness_Nm_per_rad", "N m/rad",
                                          "joint"))
        if ("guide", r) in source:
            g = float(params.guide[r])
            _, s, text = why("guide", r)
            edits.append(Edit("joints", "guide_clearance_m", g, _ci(g, s, "m", text), index=r))
    for k, r in enumerate(tree.independent):
        r = int(r)
        if ("backlash", k) in source:
            b = float(params.backlash[k])
            _, s, text = why("backlash", k)
            edits.append(Edit("joints", "backlash_rad", b, _ci(b, s, "rad", text), index=r))
            edits.append(Edit("joints", "backlash_torque_Nm", float(fit["backlash_width"][k]),
                              "take-up torque of the tanh law the fit used", index=r))
    for r in range(tree.n_rows):
        if ("tilt", r) in source:
            c = params.tilt[r]
            _, s, text = why("tilt", r)
            if np.any(c <= 0):
                raise FemcheckError(f"--extended-case: joint_tilt_compliance leaves a tilt axis of row {J[r].name} rigid "
                                    "beside a compliant one; tilt_stiffness_Nm_per_rad holds two finite springs")
            edits.append(Edit("joints", "tilt_stiffness_Nm_per_rad", [float(1.0 / c[0]), float(1.0 / c[1])],
                              f"x: {_inverse_ci(float(c[0]), s, 'N m/rad', text)}; y: {_inverse_ci(float(c[1]), s, 'N m/rad', text)}",
                              index=r))
        if ("bending", r) in source:
            edits.append(inverse_edit("bending", r, r, float(params.bending[r]), "bending_EI_Nm2", "N m^2", "the link of row"))
    if ("mass_scale", 0) in source:
        sc = float(params.mass_scale)
        _, s, text = why("mass_scale", 0)
        for r, j in enumerate(J):
            if j.mass_kg > 0:
                edits.append(Edit("joints", "mass_kg", j.mass_kg * sc,
                                  f"{j.mass_kg:g} kg x mass scale {sc:.6g}, {_ci(sc, s, '', text)}", index=r))
    return edits


def corrected_case(case, case_text: str, diagnosis):
    """(text, case object) of the corrected case (the object is the text loaded, as a user would)."""
    from femcheck.case.registry import build_case
    import tomllib
    text = edited(case_text, corrected_case_edits(case, diagnosis), "--extended-case")
    return text, build_case(tomllib.loads(text), case.source)


def marker_positions(case, q: np.ndarray, payload_kg: np.ndarray | None = None, *, elastic: bool = True) -> np.ndarray:
    """(m, n_markers, 3) marker positions (m) in the robot's base frame at independent joint angles ``q`` (m, n_ind)
    rad, under self weight (and ``payload_kg`` (m,)) with the case's springs (``elastic``) or rigid; the case's
    ``[diagnosis] fixed_point_passes`` passes of the equilibrium, as in the fit."""
    tree = case.tree
    q = np.atleast_2d(np.asarray(q, float))
    if not elastic:
        return forward(tree, q @ tree.coupling.T, Geometry.nominal(tree)).markers
    open_width = (tree.backlash > 0) & ~np.isfinite(tree.backlash_width)
    if np.any(open_width):
        row = case.joints[int(tree.independent[np.flatnonzero(open_width)[0]])].name
        raise FemcheckError(f"{case.source}: joints {row}: backlash_rad without backlash_torque_Nm; expected both")
    bw = np.where(np.isfinite(tree.backlash_width), tree.backlash_width, 1.0)   # 1 N m where no backlash acts
    return equilibrium(tree, q, None, ElasticParams.nominal(tree), case.diagnosis.fixed_point_passes,
                       payload_kg, bw).markers


def sensor_readings(case, q, payload_kg=None) -> np.ndarray:
    """(m, n_markers, 3) readings (m) in the case's ``[sensor_frame]`` (x = R p + t) of the elastic model."""
    sf = case.sensor_frame
    R = rotation(np.asarray(sf.rotation_vector_rad, float))
    return marker_positions(case, q, payload_kg) @ R.T + np.asarray(sf.translation_m, float)


def elastic_deflection(case, q, payload_kg=None) -> np.ndarray:
    """(m, n_markers, 3) elastic deflection (m) of each marker in the base frame: elastic minus rigid position."""
    return marker_positions(case, q, payload_kg) - marker_positions(case, q, elastic=False)


def read_poses_csv(path, n_joints: int) -> tuple[tuple[str, ...], np.ndarray, np.ndarray]:
    """(labels, q (m, n_joints) rad, payload_kg (m,)) of a pose list: columns q1_rad..qN_rad, optional ``pose`` and
    ``payload_kg``; ``#`` lines are comments."""
    from femcheck.measured.csv_format import read_data_text
    lines = [l for l in read_data_text(path).splitlines() if l.strip() and not l.lstrip().startswith("#")]
    if not lines:
        raise MeasuredDataError(path, None, None, "no header row; expected q1_rad..qN_rad (pose, payload_kg optional)")
    rows = list(csv.reader(io.StringIO("\n".join(lines))))
    header = [h.strip() for h in rows[0]]
    qcols = [f"q{i + 1}_rad" for i in range(n_joints)]
    for c in qcols:
        if c not in header:
            raise MeasuredDataError(path, 1, c, f"required column is missing (the case has {n_joints} independent joints)")
    unknown = [h for h in header if h not in set(qcols) | {"pose", "payload_kg"}]
    if unknown:
        raise MeasuredDataError(path, 1, unknown[0], f"unknown column; expected pose, {', '.join(qcols)}, payload_kg")
    col = {h: i for i, h in enumerate(header)}
    labels, q, pay = [], [], []
    for k, row in enumerate(rows[1:]):
        if len(row) != len(header):
            raise MeasuredDataError(path, k + 2, None, f"has {len(row)} fields; the header has {len(header)}")

        def num(c):
            try:
                v = float(row[col[c]])
            except ValueError:
                raise MeasuredDataError(path, k + 2, c, f"{row[col[c]]!r} is not a number") from None
            if not math.isfinite(v):
                raise MeasuredDataError(path, k + 2, c, f"{row[col[c]]!r}; expected a finite number")
            return v
        labels.append(row[col["pose"]].strip() if "pose" in col else f"p{k + 1}")
        q.append([num(c) for c in qcols])
        p = num("payload_kg") if "payload_kg" in col else 0.0
        if p < 0:
            raise MeasuredDataError(path, k + 2, "payload_kg", f"{p}; expected >= 0")
        pay.append(p)
    if not q:
        raise MeasuredDataError(path, None, None, "no poses")
    return tuple(labels), np.array(q, float), np.array(pay, float)


def compensation_csv(case, labels, q, payload_kg) -> str:
    """CSV text: pose, marker, dx_mm, dy_mm, dz_mm (elastic deflection in the base frame, to subtract)."""
    tree = case.tree
    d = elastic_deflection(case, q, payload_kg)
    out = io.StringIO()
    out.write(f"# elastic deflection of each marker under self weight by the corrected case {case.meta.name}; base "
              "frame, mm; a controller subtracts it\n")
    w = csv.writer(out, lineterminator="\n")
    w.writerow(["pose", "marker", "dx_mm", "dy_mm", "dz_mm"])
    for i, lab in enumerate(labels):
        for k, m in enumerate(tree.marker_names):
            w.writerow([lab, m, *(f"{v * 1e3:.6f}" for v in d[i, k])])
    return out.getvalue()

