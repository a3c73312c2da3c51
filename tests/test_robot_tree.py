"""Kinematic trees, gravity and the self-weight elastics: against the independent DH chain
code, against energy, and against femcheck's FE beam model."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from femcheck.case import load_case
from femcheck.case.registry import build_case
from femcheck.robot.beam_check import chain_tip_deflection, fe_tip_deflection, two_link_document
from femcheck.robot.elastic import ElasticParams, equilibrium, joint_torques
from femcheck.robot.serial_case import as_tree_case
from femcheck.robot.simulate import humanoid_case, industrial_case, to_toml
from femcheck.robot.tree import forward, gravity_wrenches
from femcheck.vjm.dh import forward_kinematics


@pytest.mark.parametrize("path", ["cases/irb120.toml", "cases/cobot7.toml"])
def test_serial_robot_cases_load_through_the_tree(path):
    """The tree's forward kinematics of a serial_robot case equals the DH chain code's tool point.
    Tolerance 1e-12 m: the same products in a different order (round-off only)."""
    import tomllib
    raw = tomllib.loads(open(path).read())
    for j in raw["joints"]:
        j["mass_kg"] = 1.0    # kinematics only; the case files carry no masses
    case = build_case(raw, path)
    tree = as_tree_case(case).tree
    q = np.random.default_rng(0).uniform(-2, 2, (25, case.n_joints))
    tcp = forward_kinematics(case.chain, q).tcp
    assert np.abs(forward(tree, q @ tree.coupling.T).markers[:, 0] - tcp).max() < 1e-12


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_gravity_torque_is_minus_the_gradient_of_potential_energy(seed):
    """tau_j = -dV/dq_j with V = -sum m g.c (virtual work), by central differences on a generated humanoid
    (with a payload); tolerance 1e-6 relative: O(h^2) of the difference quotient with h = 1e-5 rad."""
    case, _ = humanoid_case(seed)
    tree = case.tree
    rng = np.random.default_rng(seed)
    q = rng.uniform(-1.5, 1.5, (4, tree.n_joints))
    pay = np.array([0.0, 1.0, 2.0, 0.5])

    def V(q):
        fk = forward(tree, q @ tree.coupling.T)
        com = np.einsum("mnij,nj->mni", fk.frames, np.append(tree.com, np.ones((tree.n_rows, 1)), axis=1))[..., :3]
        return -(tree.mass[None, :, None] * com * tree.gravity).sum(axis=(1, 2))

    fk = forward(tree, q @ tree.coupling.T)
    _, M = gravity_wrenches(tree, fk)
    tau = joint_torques(tree, fk, M)
    h = 1e-5
    for j in range(tree.n_joints):
        e = np.zeros(tree.n_joints)
        e[j] = h
        num = -(V(q + e) - V(q - e)) / (2 * h)
        assert np.allclose(tau[:, j], num, rtol=1e-6, atol=1e-6 * np.abs(tau).max())


def test_coupled_passive_joint_follows_and_passes_its_torque_on():
    """A passive row coupled as q_k = 0.5 q_2 - q_1: its angle follows, and the independent joints' torques equal
    -dV/dq_ind (virtual work through the coupling). Tolerance as the test above."""
    _, raw = industrial_case(0)
    raw["joints"][4]["coupling"] = {"j2": 0.5, "j1": -1.0}
    case = build_case(raw, "<coupled>")
    tree = case.tree
    assert tree.n_joints == 5 and np.allclose(tree.coupling[4], [-1.0, 0.5, 0, 0, 0])
    q = np.random.default_rng(3).uniform(-1, 1, (3, 5))
    fk = forward(tree, q @ tree.coupling.T)
    _, M = gravity_wrenches(tree, fk)
    tau = joint_torques(tree, fk, M)

    def V(q):
        f = forward(tree, q @ tree.coupling.T)
        com = np.einsum("mnij,nj->mni", f.frames, np.append(tree.com, np.ones((tree.n_rows, 1)), axis=1))[..., :3]
        return -(tree.mass[None, :, None] * com * tree.gravity).sum(axis=(1, 2))

    for j in range(5):
        e = np.zeros(5)
        e[j] = 1e-5
        assert np.allclose(tau[:, j], -(V(q + e) - V(q - e)) / 2e-5, rtol=1e-6, atol=1e-6 * np.abs(tau).max())


@pytest.mark.parametrize("tip_mass", [0.0, 1.0])
@pytest.mark.parametrize("q", [(0.3, -0.7), (0.0, 0.0), (1.2, 0.5), (-0.8, 1.4)])
def test_two_link_self_weight_deflection_matches_the_fe_beam_model(q, tip_mass):
    """Issue 23 item 2: joint springs + link bending of a two-link arm under self-weight (and a tip payload)
    against femcheck's FE beam model (8 Euler-Bernoulli elements per link, exact at nodes for nodal loads).
    Within 1 % with one equilibrium pass (the residue is the chain's exact finite rotation, which the linear FE
    lacks); the linear parts (springs scaled by 1e-4, response scaled back) within 1e-5 relative."""
    EI = 800.0
    case = build_case(two_link_document(EI=EI, tip_mass=tip_mass), "<two-link>")
    q = np.array(q)
    fe = fe_tip_deflection(case, q, EI, tip_mass=tip_mass)
    ch = chain_tip_deflection(case, q, passes=1, tip_mass=tip_mass)
    assert np.linalg.norm(ch - fe) < 0.01 * np.linalg.norm(fe)
    stiff = build_case(two_link_document(EI=EI * 1e4, k1=2000.0e4, k2=1000.0e4, tip_mass=tip_mass), "<stiff>")
    fe_s = fe_tip_deflection(stiff, q, EI * 1e4, tip_mass=tip_mass) * 1e4
    ch_s = chain_tip_deflection(stiff, q, passes=1, tip_mass=tip_mass) * 1e4
    assert np.linalg.norm(ch_s - fe_s) < 1e-5 * np.linalg.norm(fe_s)
    assert np.linalg.norm(fe_s - fe) < 0.02 * np.linalg.norm(fe)   # the two scalings describe the same arm


def test_two_link_check_fails_when_a_load_is_left_out():
    """Mutation: dropping the link's own weight from its bending (the second term of link_bending) must break
    the FE agreement by more than the 1 % tolerance."""
    import femcheck.robot.elastic as el
    case = build_case(two_link_document(m2=0.01, k1=1e9, k2=1e9), "<bending only>")
    q = np.array([0.2, -0.3])
    fe = fe_tip_deflection(case, q, 800.0)
    good = chain_tip_deflection(case, q)
    assert np.linalg.norm(good - fe) < 0.01 * np.linalg.norm(fe)
    mutated = dataclasses.replace(case.tree, mass=case.tree.mass * np.array([0.0, 1.0]))
    fk0 = forward(mutated, q[None] @ mutated.coupling.T)
    Ft, Mt = gravity_wrenches(mutated, fk0, strict=True)
    b_mut = el.link_bending(mutated, fk0, Ft, Mt, mutated.compliance_bending)
    full = forward(mutated, q[None] @ mutated.coupling.T, None, None, b_mut).markers[0, 0] - fk0.markers[0, 0]
    assert np.linalg.norm(full - fe) > 0.05 * np.linalg.norm(fe)


def test_fixed_point_passes_converge():
    """Each further pass changes the deflection less (contraction of the torque equilibrium); on a soft humanoid
    pass 4 differs from pass 3 by < 1 % of the deflection."""
    case, _ = humanoid_case(4)
    tree = case.tree
    p = dataclasses.replace(ElasticParams.nominal(tree), torsion=np.full(tree.n_joints, 5e-4))
    q = np.random.default_rng(1).uniform(-1, 1, (20, tree.n_joints))
    rigid = forward(tree, q @ tree.coupling.T).markers
    d = [equilibrium(tree, q, None, p, k, None, np.ones(tree.n_joints)).markers - rigid for k in (1, 2, 3, 4)]
    steps = [np.abs(d[k + 1] - d[k]).max() for k in range(3)]
    assert steps[2] < steps[1] < steps[0]
    assert steps[2] < 0.01 * np.abs(d[3]).max()


def test_generated_case_round_trips_through_toml(tmp_path):
    """The generator's document written as TOML loads back into the same tree (the case template in the docs)."""
    case, raw = humanoid_case(5)
    p = tmp_path / "h.toml"
    p.write_text(to_toml(raw))
    back = load_case(p).tree
    assert back.names == case.tree.names and np.allclose(back.d, case.tree.d) and np.allclose(back.static, case.tree.static)


@pytest.mark.parametrize("edit, key", [
    (lambda r: r["joints"][3].update(parent="nowhere"), "joints[3].parent"),
    (lambda r: r["markers"][0].update(link="x9"), "markers[0].link"),
    (lambda r: r["joints"][4].update(coupling={"r9": 1.0}), "joints[4].coupling.r9"),
    (lambda r: r["joints"][2].update(name="t1"), "joints[2].name"),
    (lambda r: [j.update(mass_kg=0.0) for j in r["joints"]], "joints"),
    (lambda r: r["joints"][0].update(mass_kg=-1.0), "joints[0].mass_kg"),
    (lambda r: r["joints"][0].update(type="spherical"), "joints[0].type"),
    (lambda r: r["joints"][0].update(type="prismatic", stiffness_Nm_per_rad=1e3), "joints[0].stiffness_Nm_per_rad"),
    (lambda r: r["joints"][1].update(guide_overlap_m=0.4), "joints[1].guide_overlap_m"),
])
def test_bad_tree_cases_name_the_key(edit, key):
    from femcheck.errors import CaseError
    _, raw = humanoid_case(0)
    edit(raw)
    with pytest.raises(CaseError) as e:
        build_case(raw, "bad.toml")
    assert f"bad.toml: {key}" in str(e.value)


def test_serial_robot_without_masses_is_refused_for_self_weight(tmp_path, capsys):
    """`femcheck diagnose` on a serial_robot case without link masses: exit 2, one line naming the file and key."""
    from femcheck.cli import main
    csv = tmp_path / "d.csv"
    csv.write_text("pose,marker,q1_rad,q2_rad,q3_rad,q4_rad,q5_rad,q6_rad,x_mm,y_mm,z_mm\n")
    assert main(["diagnose", "cases/irb120.toml", str(csv)]) == 2
    err = capsys.readouterr().err
    assert "cases/irb120.toml: joints: no row has mass_kg > 0" in err and err.count("\n") == 1


def test_coupled_row_own_spring_is_the_stationary_point_of_the_total_potential():
    """A parallelogram row q5 = -(q2 + q3) with its own series spring, beside independent springs: the converged
    self-weight equilibrium is where the total potential V_grav(q + E dq + e_5 s) + dq^2/(2 c) + s^2/(2 c_5) is
    stationary. The reference solves that by fixed-point iteration on finite differences of the potential energy
    alone (no wrench or coupling code). Tolerance 1e-9 m: central differences, h = 1e-6 rad, on ~1e-3 m moves."""
    _, raw = industrial_case(0, springs=True)
    raw["joints"][4]["coupling"] = {"j2": -1.0, "j3": -1.0}
    raw["joints"][4]["stiffness_Nm_per_rad"] = 20.0
    case = build_case(raw, "<parallelogram>")
    tree = case.tree
    assert tree.coupled[4] and tree.compliance_torsion[4] == pytest.approx(1 / 20.0)
    q = np.random.default_rng(5).uniform(-1, 1, (3, tree.n_joints))
    got = equilibrium(tree, q, None, ElasticParams.nominal(tree), passes=40).markers
    c_ind, c_own = tree.compliance_torsion[tree.independent], tree.compliance_torsion[4]

    def V(q_rows):
        f = forward(tree, q_rows)
        com = np.einsum("mnij,nj->mni", f.frames, np.append(tree.com, np.ones((tree.n_rows, 1)), axis=1))[..., :3]
        return -(tree.mass[None, :, None] * com * tree.gravity).sum(axis=(1, 2))

    E, e5, h = tree.coupling, np.eye(tree.n_rows)[4], 1e-6
    dq, s = np.zeros_like(q), np.zeros(len(q))
    for _ in range(40):
        base = (q + dq) @ E.T + s[:, None] * e5
        tau = np.stack([-(V(base + h * E[:, j]) - V(base - h * E[:, j])) / (2 * h) for j in range(tree.n_joints)], axis=1)
        tau5 = -(V(base + h * e5) - V(base - h * e5)) / (2 * h)
        dq, s = c_ind * tau, c_own * tau5
    ref = forward(tree, (q + dq) @ E.T + s[:, None] * e5).markers
    assert np.abs(s).max() > 1e-3                      # the own spring really moves the row
    assert np.abs(got - ref).max() < 1e-9


def test_guide_play_tilts_the_stage_by_clearance_over_overlap():
    """A lifting column (prismatic row, guide overlap L0 = 0.5 m) with an overhanging mass: once the moment is well
    over the take-up width, the stage tilts by delta / (L0 - q) about the carriage, so a marker 1 m above it moves by
    the chord 2 sin(phi / 2) * 1 m, towards the moment. Closed form; tolerance 1e-12 m (round-off)."""
    raw = {"meta": {"kind": "serial_tree", "name": "column"}, "kinematics": {"convention": "standard"},
           "joints": [{"name": "lift", "type": "prismatic", "a_m": 0.0, "alpha_deg": 0.0, "d_m": 0.0,
                       "guide_overlap_m": 0.5, "mass_kg": 20.0, "com_m": [0.3, 0.0, 0.0]}],
           "markers": [{"name": "top", "link": "lift", "offset_m": [0.0, 0.0, 1.0]}]}
    tree = build_case(raw, "<column>").tree
    q = np.array([[0.0], [0.2], [0.4]])
    delta = 1e-3
    p = dataclasses.replace(ElasticParams.rigid(tree), guide=np.array([delta]))
    rigid = forward(tree, q).markers[:, 0]
    moved = equilibrium(tree, q, None, p, passes=2, guide_width=np.array([1e-9])).markers[:, 0]
    phi = delta / (0.5 - q[:, 0])
    assert np.allclose(np.linalg.norm(moved - rigid, axis=1), 2 * np.sin(phi / 2), rtol=0, atol=1e-12)
    assert np.all(moved[:, 0] > rigid[:, 0])       # the overhang at +x leans the top towards +x
