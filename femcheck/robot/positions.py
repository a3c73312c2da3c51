"""Measured absolute marker positions: the long-form CSV, one row per pose and marker.

Columns: ``pose`` (label), ``marker`` (a name defined in the case), optional ``fold`` (integer), ``q1_rad`` ..
``qN_rad`` (the case's independent joints in order; a prismatic joint's column is ``qK_m``, metres), ``x_mm``, ``y_mm``, ``z_mm`` (in the sensor frame), optional
``payload_kg``. Lines starting with ``#`` are comments. A row whose x, y or z is empty or ``nan`` is an occluded
marker: it is left out and counted (``missing``), not refused. Every marker row of a pose must repeat the pose's joint
angles, fold and payload. Poses keep the order of their first row: that is the measurement order that a drift
check uses.
"""
from __future__ import annotations

import csv
import dataclasses
import io

import numpy as np

from femcheck.errors import MeasuredDataError


@dataclasses.dataclass(frozen=True)
class MarkerPositions:
    """``pose_labels`` (P,); ``q`` (P, n) rad; ``payload_kg`` (P,); ``fold`` (P,) int or None;
    per reading (R rows): ``pose`` (R,) index, ``marker`` (R,) index into the case's markers, ``xyz`` (R, 3) m."""

    source: str
    pose_labels: tuple[str, ...]
    q: np.ndarray
    payload_kg: np.ndarray
    fold: np.ndarray | None
    pose: np.ndarray
    marker: np.ndarray
    xyz: np.ndarray
    missing: int = 0

    @property
    def n_poses(self) -> int:
        return len(self.pose_labels)

    @property
    def n_readings(self) -> int:
        return len(self.pose)

    def subset(self, poses: np.ndarray) -> "MarkerPositions":
        """The readings of the poses ``poses`` (indices), re-indexed."""
        poses = np.asarray(poses)
        new = -np.ones(self.n_poses, int)
        new[poses] = np.arange(len(poses))
        keep = np.isin(self.pose, poses)
        return MarkerPositions(self.source, tuple(self.pose_labels[i] for i in poses), self.q[poses],
                               self.payload_kg[poses], None if self.fold is None else self.fold[poses],
                               new[self.pose[keep]], self.marker[keep], self.xyz[keep], 0)


def q_column(k: int, prismatic: bool = False) -> str:
    """CSV column of joint k (0-based): ``q{k+1}_rad``, or ``q{k+1}_m`` for a prismatic joint."""
    return f"q{k + 1}_{'m' if prismatic else 'rad'}"


def parse_marker_csv(text: str, source: str, marker_names, n_joints: int, independent_rows=None,
                     prismatic_rows=None) -> MarkerPositions:
    """Parse the CSV text. ``independent_rows`` (n_joints,): the row indices of the independent joints when the
    tree has coupled rows; a file that gives every row's angle (q1..q_rows) is then read at those columns, and
    the coupled rows' angles are not used (the coupling gives them). ``prismatic_rows`` (n_rows,) bool: rows whose
    column is in metres (``qK_m``)."""
    lines = text.splitlines()
    first = next((i for i, line in enumerate(lines) if line.strip() and not line.lstrip().startswith("#")), None)
    if first is None:
        raise MeasuredDataError(source, None, None, "no header row; expected pose,marker,q1_rad..,x_mm,y_mm,z_mm")
    reader = csv.reader(io.StringIO("\n".join(lines[first:])))
    header = [h.strip() for h in next(reader)]
    rows = np.arange(n_joints) if independent_rows is None else np.asarray(independent_rows)
    slide = np.zeros(int(rows.max()) + 1, bool) if prismatic_rows is None else np.asarray(prismatic_rows, bool)
    qcols = [q_column(i, slide[r]) for i, r in enumerate(rows)]
    given = [h for h in header if h.startswith("q") and (h.endswith("_rad") or h.endswith("_m"))]
    extra_q = []
    if independent_rows is not None and len(given) > n_joints and len(given) > max(independent_rows) and \
            set(given) == {q_column(i, i < len(slide) and slide[i]) for i in range(len(given))}:
        extra_q = [c for c in given if c not in {q_column(r, slide[r]) for r in independent_rows}]
        qcols = [q_column(r, slide[r]) for r in independent_rows]
    need = ["pose", "marker", *qcols, "x_mm", "y_mm", "z_mm"]
    if "pose" not in header and "point" in header:
        raise MeasuredDataError(source, first + 1, "pose", "required column is missing: this is a dial-readings CSV "
                                "(point, direction, ...); a serial robot takes marker positions: pose, marker, q1_rad.., "
                                "x_mm, y_mm, z_mm")
    for c in need:
        if c not in header:
            extra = given
            hint = f" (the case has {n_joints} independent joints; the file has {len(extra)} q columns)" if c in qcols else ""
            raise MeasuredDataError(source, first + 1, c, f"required column is missing{hint}")
    known = set(need) | {"fold", "payload_kg"} | set(extra_q)
    unknown = [h for h in header if h not in known]
    if unknown:
        raise MeasuredDataError(source, first + 1, unknown[0], f"unknown column; expected {need + ['fold', 'payload_kg']}")
    col = {h: i for i, h in enumerate(header)}
    mk_index = {m: i for i, m in enumerate(marker_names)}
    poses: dict[str, int] = {}
    pq, pf, pp = [], [], []
    r_pose, r_mk, r_xyz = [], [], []
    seen = set()
    missing = 0
    for k, row in enumerate(reader):
        line = first + 2 + k
        if not row or all(not c.strip() for c in row):
            continue
        if len(row) != len(header):
            raise MeasuredDataError(source, line, None, f"has {len(row)} fields; the header has {len(header)}")

        def num(c):
            try:
                v = float(row[col[c]])
            except ValueError:
                raise MeasuredDataError(source, line, c, f"{row[col[c]]!r} is not a number") from None
            if not np.isfinite(v):
                raise MeasuredDataError(source, line, c, f"{row[col[c]]!r}; expected a finite number")
            return v

        if any(row[col[c]].strip().lower() in ("", "nan") for c in ("x_mm", "y_mm", "z_mm")):
            missing += 1        # an occluded marker (motion capture): the reading is absent, not bad
            continue
        label, mk = row[col["pose"]].strip(), row[col["marker"]].strip()
        if not label:
            raise MeasuredDataError(source, line, "pose", "is empty")
        if mk not in mk_index:
            raise MeasuredDataError(source, line, "marker", f"{mk!r} is not a marker of the case; expected one of {list(mk_index)}")
        if (label, mk) in seen:
            raise MeasuredDataError(source, line, "marker", f"pose {label!r} has marker {mk!r} twice")
        seen.add((label, mk))
        q = [num(c) for c in qcols]
        fold = None
        if "fold" in col:
            f = num("fold")
            if f != int(f):
                raise MeasuredDataError(source, line, "fold", f"{row[col['fold']]!r}; expected an integer")
            fold = int(f)
        pay = num("payload_kg") if "payload_kg" in col else 0.0
        if pay < 0:
            raise MeasuredDataError(source, line, "payload_kg", f"{pay}; expected >= 0")
        if label not in poses:
            poses[label] = len(poses)
            pq.append(q), pf.append(fold), pp.append(pay)
        else:
            i = poses[label]
            for c, a, b in (("q", pq[i], q), ("fold", pf[i], fold), ("payload_kg", pp[i], pay)):
                if not np.allclose(a, b, rtol=0, atol=1e-12) if c == "q" else a != b:
                    raise MeasuredDataError(source, line, c if c != "q" else "q1_rad",
                                            f"pose {label!r} repeats with a different {c}; every marker row of a pose must agree")
        r_pose.append(poses[label]), r_mk.append(mk_index[mk]), r_xyz.append([num("x_mm"), num("y_mm"), num("z_mm")])
    if not r_pose:
        raise MeasuredDataError(source, None, None, "no data rows")
    return MarkerPositions(source, tuple(poses), np.array(pq, float), np.array(pp, float),
                           np.array(pf, int) if "fold" in col else None, np.array(r_pose), np.array(r_mk),
                           np.array(r_xyz) * 1e-3, missing)


def read_marker_csv(path, marker_names, n_joints: int, independent_rows=None, prismatic_rows=None) -> MarkerPositions:
    """Read and validate a marker-position CSV (opened read-only)."""
    from femcheck.measured.csv_format import read_data_text
    text = read_data_text(path)
    return parse_marker_csv(text, str(path), marker_names, n_joints, independent_rows, prismatic_rows)


def format_marker_csv(data: MarkerPositions, marker_names, meta: dict | None = None, prismatic=None) -> str:
    """CSV text of ``data`` (positions printed in mm with 4 decimals: 0.1 um); ``prismatic`` (n_joints,) bool:
    joints whose column is ``qK_m``."""
    out = io.StringIO()
    for k, v in (meta or {}).items():
        out.write(f"# {k}: {v}\n")
    w = csv.writer(out, lineterminator="\n")
    n = data.q.shape[1]
    w.writerow(["pose", "marker", *(["fold"] if data.fold is not None else []), *[q_column(i, prismatic is not None and prismatic[i]) for i in range(n)],
                "x_mm", "y_mm", "z_mm", "payload_kg"])
    for r in range(data.n_readings):
        p = data.pose[r]
        w.writerow([data.pose_labels[p], marker_names[data.marker[r]], *([int(data.fold[p])] if data.fold is not None else []),
                    *(f"{v:.9f}" for v in data.q[p]), *(f"{v * 1e3:.4f}" for v in data.xyz[r]), f"{data.payload_kg[p]:g}"])
    return out.getvalue()
