"""URDF import (femcheck import-urdf): the imported serial_tree reproduces the URDF's own kinematics.

The reference is a direct URDF forward kinematics written here from the URDF definition (child = parent *
origin(xyz, rpy) * Rot(axis, q)), independent of the DH-row mapping in femcheck.robot.urdf."""
from __future__ import annotations

import numpy as np
import pytest

from femcheck.case import load_case
from femcheck.robot.tree import forward, rotation, rpy_matrix


def _joint_xml(name: str, j: dict) -> str:
    """URDF text of joint ``name`` from its spec (type, parent, child, xyz, rpy, axis or None, mimic or None)."""
    xyz, rpy, axis, mimic = j["xyz"], j["rpy"], j["axis"], j["mimic"]
    ax = "" if axis is None else f'<axis xyz="{axis[0]} {axis[1]} {axis[2]}"/>'
    mm = "" if mimic is None else f'<mimic joint="{mimic[0]}" multiplier="{mimic[1]}" offset="{mimic[2]}"/>'
    return (f'<joint name="{name}" type="{j["type"]}"><parent link="{j["parent"]}"/><child link="{j["child"]}"/>'
            f'<origin xyz="{xyz[0]} {xyz[1]} {xyz[2]}" rpy="{rpy[0]} {rpy[1]} {rpy[2]}"/>{ax}{mm}</joint>')


def _urdf(rng) -> tuple[str, dict]:
    """A torso with two 3-joint arms (random origins and axes, one fixed joint in each arm, one mimic joint)."""
    joints, links = [], ["base_link"]
    spec = {}

    def add(name, jtype, parent, child, axis=None, mimic=None):
        xyz, rpy = rng.uniform(-0.2, 0.2, 3), rng.uniform(-1.5, 1.5, 3)
        spec[name] = dict(type=jtype, parent=parent, child=child, xyz=xyz, rpy=rpy, axis=axis, mimic=mimic)
        links.append(child)
        joints.append(_joint_xml(name, spec[name]))

    add("mount", "fixed", "base_link", "pedestal")
    add("torso_yaw", "revolute", "pedestal", "torso", (0, 0, 1))
    add("chest_fix", "fixed", "torso", "chest")
    for side in ("l", "r"):
        add(f"{side}_j1", "revolute", "chest", f"{side}_l1", tuple(rng.normal(size=3)))
        add(f"{side}_j2", "continuous", f"{side}_l1", f"{side}_l2", (0, 0, -1))
        add(f"{side}_fix", "fixed", f"{side}_l2", f"{side}_l2b")
        add(f"{side}_j3", "revolute", f"{side}_l2b", f"{side}_hand", (1, 0, 0),
            mimic=(f"{side}_j2", 0.5, 0.1) if side == "l" else None)
    text = "<robot name='t'>" + "".join(
        f'<link name="{l}"><inertial><origin xyz="0.01 0.02 -0.03"/><mass value="{1.0 + i * 0.1}"/></inertial></link>'
        for i, l in enumerate(links)) + "".join(joints) + "</robot>"
    return text, spec


def _urdf_fk(spec, q: dict, link: str) -> np.ndarray:
    by_child = {s["child"]: s for s in spec.values()}
    T = np.eye(4)
    chain = []
    while link in by_child:
        chain.append(by_child[link])
        link = by_child[link]["parent"]
    for s in reversed(chain):
        O = np.eye(4)
        O[:3, :3], O[:3, 3] = rpy_matrix(s["rpy"]), s["xyz"]
        T = T @ O
        if s["type"] != "fixed":
            name = next(n for n, v in spec.items() if v is s)
            angle = q[name] if s["mimic"] is None else s["mimic"][1] * q[s["mimic"][0]] + s["mimic"][2]
            u = np.asarray(s["axis"], float)
            R = np.eye(4)
            if s["type"] == "prismatic":         # child = parent * origin * Trans(axis q)
                R[:3, 3] = angle * u / np.linalg.norm(u)
            else:
                R[:3, :3] = rotation(angle * u / np.linalg.norm(u))
            T = T @ R
    return T


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_imported_tree_reproduces_urdf_kinematics(tmp_path, seed):
    """Marker positions of the imported case equal the direct URDF FK at random angles; 1e-12 m (round-off)."""
    from femcheck.cli import main
    rng = np.random.default_rng(seed)
    text, spec = _urdf(rng)
    (tmp_path / "r.urdf").write_text(text)
    out = tmp_path / "r.toml"
    assert main(["import-urdf", str(tmp_path / "r.urdf"), "--marker", "lh=l_hand@0.05,0,0.1", "--marker", "rh=r_l2b@0,0.03,0",
                 "--out", str(out), "--sigma-mm", "0.3"]) == 0
    case = load_case(out)
    tree = case.tree
    indep = list(tree.joint_names)
    assert "l_j3" not in indep and len(indep) == 6           # the mimic joint has no CSV column
    assert tree.branch[tree.names.index("r_j2")] == "r_j1"    # branches named after their first row
    qs = rng.uniform(-2, 2, (5, len(indep)))
    got = forward(tree, qs @ tree.coupling.T).markers
    for k in range(5):
        qd = dict(zip(indep, qs[k]))
        lh = _urdf_fk(spec, qd, "l_hand") @ np.array([0.05, 0, 0.1, 1.0])
        rh = _urdf_fk(spec, qd, "r_l2b") @ np.array([0, 0.03, 0, 1.0])
        assert np.abs(got[k, 0] - lh[:3]).max() < 1e-12 and np.abs(got[k, 1] - rh[:3]).max() < 1e-12
    # masses: every link below the first revolute joint is carried; the base and pedestal are not
    assert tree.mass.sum() == pytest.approx(sum(1.0 + i * 0.1 for i in range(2, 12)), rel=1e-12)
    assert case.measurement.sigma_m == pytest.approx(3e-4)


def test_floating_joint_is_refused(tmp_path, capsys):
    from femcheck.cli import main
    (tmp_path / "p.urdf").write_text("<robot name='p'><link name='a'/><link name='b'/><joint name='slide' type='floating'>"
                                     "<parent link='a'/><child link='b'/></joint></robot>")
    assert main(["import-urdf", str(tmp_path / "p.urdf"), "--marker", "m=b", "--out", str(tmp_path / "p.toml")]) == 2
    err = capsys.readouterr().err
    assert "joint slide: type 'floating'" in err and err.count("\n") == 1
    assert not (tmp_path / "p.toml").exists()


def _column_urdf(rng, telescope: bool = True) -> tuple[str, dict]:
    """A robot on a lifting column: prismatic column (axis tilted a little off z), a torso yaw, two 3-joint arms
    whose third joint is a parallelogram mimic of the second (multiplier -1), and (``telescope``) a prismatic
    mimic: a telescoping second stage moving half as far as the column (multiplier 0.5)."""
    joints, links, spec = [], ["base_link"], {}

    def add(name, jtype, parent, child, axis=None, mimic=None, xyz=None, rpy=None):
        xyz = rng.uniform(-0.1, 0.1, 3) if xyz is None else np.asarray(xyz, float)
        rpy = rng.uniform(-0.5, 0.5, 3) if rpy is None else np.asarray(rpy, float)
        spec[name] = dict(type=jtype, parent=parent, child=child, xyz=xyz, rpy=rpy, axis=axis, mimic=mimic)
        links.append(child)
        joints.append(_joint_xml(name, spec[name]))

    add("lift", "prismatic", "base_link", "column", (0.02, -0.01, 1.0), xyz=(0, 0, 0.3), rpy=(0, 0, 0))
    if telescope:
        add("stage2", "prismatic", "column", "upper", (0, 0, 1), mimic=("lift", 0.5, 0.01), xyz=(0, 0, 0.2), rpy=(0, 0, 0))
    add("torso_yaw", "revolute", "upper" if telescope else "column", "torso", (0, 0, 1), xyz=(0, 0, 0.15), rpy=(0, 0, 0))
    for side, sg in (("l", 1), ("r", -1)):
        add(f"{side}_j1", "revolute", "torso", f"{side}_l1", (0, 1, 0), xyz=(0, sg * 0.2, 0.1), rpy=(0, 0, 0))
        add(f"{side}_j2", "revolute", f"{side}_l1", f"{side}_l2", (0, 1, 0), xyz=(0.3, 0, 0), rpy=(0, 0, 0))
        add(f"{side}_j3", "revolute", f"{side}_l2", f"{side}_hand", (0, 1, 0), mimic=(f"{side}_j2", -1.0, 0.0),
            xyz=(0.25, 0, 0), rpy=(0, 0, 0))
    masses = {"column": 8.0, "upper": 4.0, "torso": 6.0}
    text = "<robot name='lifter'>" + "".join(
        f'<link name="{l}"><inertial><origin xyz="{0.1 if "_l" in l or "hand" in l else 0.0} 0 0.02"/>'
        f'<mass value="{masses.get(l, 1.5)}"/></inertial></link>' for l in links) + "".join(joints) + "</robot>"
    return text, spec


def _import_column(tmp_path, rng, overlap="0.6", telescope=True):
    from femcheck.cli import main
    text, spec = _column_urdf(rng, telescope)
    (tmp_path / "c.urdf").write_text(text)
    out = tmp_path / "c.toml"
    assert main(["import-urdf", str(tmp_path / "c.urdf"), "--marker", "lh=l_hand@0.08,0,0", "--marker",
                 "rh=r_hand@0.08,0,0", "--guide-overlap", f"lift={overlap}", "--out", str(out), "--sigma-mm", "0.2"]) == 0
    return load_case(out), spec, out


def test_prismatic_column_and_mimics_reproduce_urdf_kinematics(tmp_path):
    """A lifting column (prismatic, with a prismatic mimic stage) and parallelogram mimics import into one case:
    markers equal the direct URDF FK at random heights and angles, 1e-12 m (round-off)."""
    rng = np.random.default_rng(4)
    case, spec, out = _import_column(tmp_path, rng)
    tree = case.tree
    assert list(tree.joint_names) == ["lift", "torso_yaw", "l_j1", "l_j2", "r_j1", "r_j2"]
    assert tree.prismatic[tree.names.index("lift")] and tree.prismatic[tree.names.index("stage2")]
    assert tree.guide_overlap[tree.names.index("lift")] == pytest.approx(0.6)
    assert "q1_m = lift" in out.read_text() and "q2_rad = torso_yaw" in out.read_text()
    qs = rng.uniform(-1.5, 1.5, (6, 6))
    qs[:, 0] = rng.uniform(0.0, 0.4, 6)
    got = forward(tree, qs @ tree.coupling.T).markers
    for k in range(6):
        qd = dict(zip(tree.joint_names, qs[k]))
        for i, link in enumerate(("l_hand", "r_hand")):
            ref = _urdf_fk(spec, qd, link) @ np.array([0.08, 0, 0, 1.0])
            assert np.abs(got[k, i] - ref[:3]).max() < 1e-12


def test_hidden_column_guide_clearance_is_found(tmp_path):
    """Generated data on the imported column robot over heights 0..0.4 m (guide overlap 0.6 m at q = 0, so
    L = 0.6..0.2 m), with a hidden diametral column clearance moving the markers 6 sigma RMS, written as a CSV
    (q1_m column) and diagnosed by the CLI as one case: guide_clearance is named at the column, and its value is
    within 3 standard errors of the truth (linearized intervals)."""
    import json

    from femcheck.cli import main
    from femcheck.robot.positions import format_marker_csv
    from femcheck.robot.simulate import scaled, simulate_positions
    rng = np.random.default_rng(4)
    # no telescoping stage here: its axis misalignment (a nuisance) trades against the play's 1/L(q) growth over
    # this stroke, and the refit from the rigid calibration then needs more than its few modified-Newton steps
    case, _, out = _import_column(tmp_path, rng, telescope=False)
    eff = scaled(case, {"guide_clearance": {"lift": 1.0}}, 6 * 2e-4)
    assert 1e-5 < eff["guide_clearance"]["lift"] < 1e-2          # a clearance of a real guide: 10 um .. 10 mm
    data, _ = simulate_positions(case, 150, effects=eff, sigma_m=2e-4, seed=3)
    tree = case.tree
    (tmp_path / "d.csv").write_text(format_marker_csv(data, tree.marker_names, prismatic=tree.prismatic[tree.independent]))
    assert main(["diagnose", str(out), str(tmp_path / "d.csv"), "--json", str(tmp_path / "j.json")]) == 0
    j = json.loads((tmp_path / "j.json").read_text())
    assert j["verdict"] == "explained", j["causes"]
    c = j["causes"][0]
    assert [x["id"] for x in j["causes"]] == ["guide_clearance"] and c["joints"] == ["lift"], c
    (name, v), = c["params"].items()
    lo, hi = c["params_ci"][name]
    assert abs(v - eff["guide_clearance"]["lift"]) < 1.5 * (hi - lo), (v, eff, lo, hi)


def test_a_slide_beyond_the_guide_overlap_is_bad_input(tmp_path, capsys):
    """A pose whose column height leaves no guide engagement (q >= guide_overlap_m): exit 2, one line naming the
    file, the q1_m column and the pose, no traceback."""
    from femcheck.cli import main
    from femcheck.robot.positions import format_marker_csv
    from femcheck.robot.simulate import simulate_positions
    case, _, out = _import_column(tmp_path, np.random.default_rng(4), overlap="0.3", telescope=False)
    data, _ = simulate_positions(case, 20, sigma_m=2e-4, seed=1)       # heights up to 0.4 m > 0.3 m
    tree = case.tree
    (tmp_path / "d.csv").write_text(format_marker_csv(data, tree.marker_names, prismatic=tree.prismatic[tree.independent]))
    assert main(["diagnose", str(out), str(tmp_path / "d.csv")]) == 2
    err = capsys.readouterr().err
    assert "d.csv" in err and "q1_m" in err and "beyond its guide overlap" in err and err.count("\n") == 1, err
