"""URDF import (femcheck import-urdf): the imported serial_tree reproduces the URDF's own kinematics.

The reference is a direct URDF forward kinematics written here from the URDF definition (child = parent *
origin(xyz, rpy) * Rot(axis, q)), independent of the DH-row mapping in femcheck.robot.urdf."""
from __future__ import annotations

import numpy as np
import pytest

from femcheck.case import load_case
from femcheck.robot.tree import forward, rotation, rpy_matrix


def _urdf(rng) -> tuple[str, dict]:
    """A torso with two 3-joint arms (random origins and axes, one fixed joint in each arm, one mimic joint)."""
    joints, links = [], ["base_link"]
    spec = {}

    def add(name, jtype, parent, child, axis=None, mimic=None):
        xyz, rpy = rng.uniform(-0.2, 0.2, 3), rng.uniform(-1.5, 1.5, 3)
        spec[name] = dict(type=jtype, parent=parent, child=child, xyz=xyz, rpy=rpy, axis=axis, mimic=mimic)
        links.append(child)
        ax = "" if axis is None else f'<axis xyz="{axis[0]} {axis[1]} {axis[2]}"/>'
        mm = "" if mimic is None else f'<mimic joint="{mimic[0]}" multiplier="{mimic[1]}" offset="{mimic[2]}"/>'
        joints.append(f'<joint name="{name}" type="{jtype}"><parent link="{parent}"/><child link="{child}"/>'
                      f'<origin xyz="{xyz[0]} {xyz[1]} {xyz[2]}" rpy="{rpy[0]} {rpy[1]} {rpy[2]}"/>{ax}{mm}</joint>')

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


def test_prismatic_joint_is_refused(tmp_path, capsys):
    from femcheck.cli import main
    (tmp_path / "p.urdf").write_text("<robot name='p'><link name='a'/><link name='b'/><joint name='slide' type='prismatic'>"
                                     "<parent link='a'/><child link='b'/></joint></robot>")
    assert main(["import-urdf", str(tmp_path / "p.urdf"), "--marker", "m=b", "--out", str(tmp_path / "p.toml")]) == 2
    err = capsys.readouterr().err
    assert "joint slide: type 'prismatic'" in err and err.count("\n") == 1
    assert not (tmp_path / "p.toml").exists()
