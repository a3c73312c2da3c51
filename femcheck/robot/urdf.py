"""A URDF robot description as a ``serial_tree`` case document.

URDF (ROS, http://wiki.ros.org/urdf/XML): links with inertials, joints with an origin (xyz, rpy: roll, pitch, yaw
about fixed x, y, z), an axis in the joint frame, types ``revolute`` | ``continuous`` | ``prismatic`` | ``fixed``
(others are refused), and ``<mimic joint= multiplier= offset=>`` for coupled joints.

Mapping. A revolute joint with origin T_o and axis u turns its child link by T_o Rot(u, q). With R_u a rotation
that takes z onto u, Rot(u, q) = R_u Rz(q) R_u^T, so the joint is a ``serial_tree`` row with the standard
convention, all DH parameters zero, and the static frame S = (accumulated fixed transforms) T_o R_u; the child
link's frame is then the row frame times R_u^T. A prismatic joint moves its child by T_o Trans(u q) = S Tz(q)
R_u^T: a prismatic row with the same static frame (the carriage frame is the row frame). Fixed joints fold into the next row's static frame (and their
links' masses into the row that carries them). A mimic joint becomes ``coupling = {joint = multiplier}`` and its
offset the row's theta offset (its d offset, m, on a prismatic row). URDF carries no guide geometry: the
engaged length of a prismatic joint's guide at q = 0 is given per joint (``guide_overlap`` {joint: m}). Link masses and centres of mass (``<inertial><origin xyz>``) are carried to the
row frame; masses of links fixed to the base are carried by the base and dropped.

The geometry is then calibrated like any case (the static frames' 6 corrections and the rows' 4): URDF rows are
over-parametrized, and the identifiability report fixes the redundant directions.
"""
from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from femcheck.errors import CaseError
from femcheck.robot.tree import homogeneous, rpy_matrix


def _floats(text, n, where, path):
    try:
        v = [float(x) for x in (text or "").split()]
    except ValueError:
        raise CaseError(path, where, f"{text!r}; expected {n} numbers") from None
    if len(v) != n or not all(math.isfinite(x) for x in v):
        raise CaseError(path, where, f"{text!r}; expected {n} finite numbers")
    return np.array(v)


def _origin(el, where, path):
    o = el.find("origin")
    xyz = _floats(o.get("xyz", "0 0 0"), 3, f"{where}.origin.xyz", path) if o is not None else np.zeros(3)
    rpy = _floats(o.get("rpy", "0 0 0"), 3, f"{where}.origin.rpy", path) if o is not None else np.zeros(3)
    return homogeneous(rpy_matrix(rpy), xyz)


def matrix_rpy(R: np.ndarray) -> np.ndarray:
    """(roll, pitch, yaw) rad with R = Rz(yaw) Ry(pitch) Rx(roll) (the inverse of ``rpy_matrix``)."""
    pitch = math.asin(-max(-1.0, min(1.0, R[2, 0])))
    if abs(R[2, 0]) < 1 - 1e-12:
        return np.array([math.atan2(R[2, 1], R[2, 2]), pitch, math.atan2(R[1, 0], R[0, 0])])
    return np.array([math.atan2(-R[1, 2], R[1, 1]), pitch, 0.0])


def z_onto(u: np.ndarray) -> np.ndarray:
    """A rotation taking z onto the unit vector u (the shortest one; a half turn about x for u = -z)."""
    u = u / np.linalg.norm(u)
    z = np.array([0.0, 0.0, 1.0])
    c = float(z @ u)
    if c > 1 - 1e-12:
        return np.eye(3)
    if c < -1 + 1e-12:
        return np.diag([1.0, -1.0, -1.0])
    v = np.cross(z, u)
    s = np.linalg.norm(v)
    K = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]]) / s
    ang = math.atan2(s, c)
    return np.eye(3) + math.sin(ang) * K + (1 - math.cos(ang)) * K @ K


def urdf_document(path, markers: dict[str, tuple[str, tuple[float, float, float]]], root: str | None = None,
                  name: str | None = None, guide_overlap: dict[str, float] | None = None) -> dict:
    """The ``serial_tree`` document of the URDF at ``path``; ``markers`` {name: (link, offset in the link frame)};
    ``guide_overlap`` {prismatic joint: guide engagement at q = 0, m}."""
    path = Path(path)
    try:
        tree = ET.parse(path)
    except (ET.ParseError, OSError) as exc:
        raise CaseError(path, "", f"not a readable URDF (XML) file: {exc}") from None
    robot = tree.getroot()
    if robot.tag != "robot":
        raise CaseError(path, "", f"root element <{robot.tag}>; expected <robot>")
    links = {}
    for L in robot.findall("link"):
        inert = L.find("inertial")
        m, c = 0.0, np.zeros(3)
        if inert is not None:
            me = inert.find("mass")
            m = float(me.get("value", "0")) if me is not None else 0.0
            c = _origin(inert, f"link {L.get('name')}.inertial", path)[:3, 3]
        links[L.get("name")] = (m, c)
    joints, children = {}, {}
    for J in robot.findall("joint"):
        jn, jt = J.get("name"), J.get("type")
        parent, child = J.find("parent").get("link"), J.find("child").get("link")
        if jt not in ("revolute", "continuous", "prismatic", "fixed"):
            raise CaseError(path, f"joint {jn}", f"type {jt!r}; femcheck's trees take revolute, continuous, prismatic and fixed joints")
        axis = J.find("axis")
        u = _floats(axis.get("xyz"), 3, f"joint {jn}.axis.xyz", path) if axis is not None else np.array([1.0, 0.0, 0.0])
        if jt != "fixed" and np.linalg.norm(u) == 0:
            raise CaseError(path, f"joint {jn}.axis.xyz", "is zero; expected a direction")
        mimic = J.find("mimic")
        mim = None if mimic is None else (mimic.get("joint"), float(mimic.get("multiplier", "1")), float(mimic.get("offset", "0")))
        joints[jn] = {"type": jt, "parent": parent, "child": child, "T": _origin(J, f"joint {jn}", path), "axis": u, "mimic": mim}
        children.setdefault(parent, []).append(jn)
    child_links = {j["child"] for j in joints.values()}
    roots = [l for l in links if l not in child_links]
    root = root or (roots[0] if len(roots) == 1 else None)
    if root is None or root not in links:
        raise CaseError(path, "--root", f"{root!r}; expected one of the links {roots if len(roots) > 1 else list(links)}")
    rows: list[dict] = []
    mass: dict[int, list] = {}
    row_of_joint: dict[str, str] = {}
    link_place: dict[str, tuple[int, np.ndarray]] = {}

    def visit(link, row, T_acc):
        link_place[link] = (row, T_acc)
        m, c = links.get(link, (0.0, np.zeros(3)))
        if row >= 0 and m > 0:
            mass.setdefault(row, []).append((m, (T_acc @ np.append(c, 1.0))[:3]))
        for jn in children.get(link, []):
            j = joints[jn]
            T = T_acc @ j["T"]
            if j["type"] == "fixed":
                visit(j["child"], row, T)
                continue
            Ru = z_onto(j["axis"])
            S = T @ homogeneous(Ru, np.zeros(3))
            r = {"name": jn, "parent": rows[row]["name"] if row >= 0 else "base",
                 **({"type": "prismatic"} if j["type"] == "prismatic" else {}),
                 "a_m": 0.0, "alpha_deg": 0.0, "d_m": 0.0,
                 "static_origin_m": [float(x) for x in S[:3, 3]],
                 "static_rpy_deg": [float(math.degrees(a)) for a in matrix_rpy(S[:3, :3])]}
            rows.append(r)
            row_of_joint[jn] = jn
            visit(j["child"], len(rows) - 1, homogeneous(Ru.T, np.zeros(3)))

    visit(root, -1, np.eye(4))
    if not rows:
        raise CaseError(path, "", f"no revolute or prismatic joint below link {root!r}")
    for i, r in enumerate(rows):
        ms = mass.get(i, [])
        tot = sum(m for m, _ in ms)
        r["mass_kg"] = float(tot)
        r["com_m"] = [float(x) for x in (sum(m * c for m, c in ms) / tot if tot > 0 else np.zeros(3))]
        j = joints[r["name"]]
        if j["mimic"] is not None:
            src, mult, off = j["mimic"]
            while joints.get(src, {}).get("mimic") is not None:     # a mimic of a mimic: to the independent joint
                s2, m2, o2 = joints[src]["mimic"]
                src, mult, off = s2, mult * m2, off + mult * o2
            if src not in row_of_joint:
                raise CaseError(path, f"joint {r['name']}.mimic", f"joint {src!r} is not a revolute joint of this tree")
            r["coupling"] = {src: mult}
            if j["type"] == "prismatic":
                r["d_m"] = off
            else:
                r["theta_offset_deg"] = math.degrees(off)
    for jn, L0 in (guide_overlap or {}).items():
        row = next((r for r in rows if r["name"] == jn), None)
        if row is None or joints[jn]["type"] != "prismatic":
            raise CaseError(path, f"--guide-overlap {jn}", "is not a prismatic joint of this tree")
        if not (math.isfinite(L0) and L0 > 0):
            raise CaseError(path, f"--guide-overlap {jn}", f"{L0}; expected a positive length in m")
        row["guide_overlap_m"] = float(L0)
    mk = []
    for mname, (link, off) in markers.items():
        if link not in link_place:
            raise CaseError(path, f"--marker {mname}", f"link {link!r} is not in the tree below {root!r}")
        row, T = link_place[link]
        if row < 0:
            raise CaseError(path, f"--marker {mname}", f"link {link!r} is fixed to the base: it does not move")
        mk.append({"name": mname, "link": rows[row]["name"], "offset_m": [float(x) for x in (T @ np.append(off, 1.0))[:3]]})
    if not mk:
        raise CaseError(path, "--marker", "at least one marker is needed: NAME=LINK[@x,y,z]")
    # branches: a row whose parent (row or base) carries several rows starts a branch named after it
    n_children: dict[str, int] = {}
    for r in rows:
        n_children[r["parent"]] = n_children.get(r["parent"], 0) + 1
    branch_of: dict[str, str] = {"base": "main"}
    for r in rows:
        branch_of[r["name"]] = r["name"] if n_children[r["parent"]] > 1 else branch_of[r["parent"]]
        r["branch"] = branch_of[r["name"]]
    return {"meta": {"name": name or robot.get("name", path.stem), "kind": "serial_tree",
                     "reference": f"imported from {path.name} by femcheck import-urdf"},
            "kinematics": {"convention": "standard"}, "gravity": {"vector_m_per_s2": [0.0, 0.0, -9.81]},
            "joints": rows, "markers": mk}
