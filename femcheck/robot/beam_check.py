"""Independent check of the self-weight elastics: a two-link arm as femcheck's FE beam model.

The arm (two links in a vertical plane, horizontal joint axes) is meshed with the 3D Euler-Bernoulli beam
elements of :mod:`femcheck.fe.beam`; each joint is a pair of coincident nodes tied by a stiff penalty in five
DOFs and by the joint's torsion spring about its axis; the root joint's spring goes to ground. The link masses
hang at mid-link nodes (lumped weights), and the tip node is the marker. The linear FE solve gives the marker's
deflection, compared with :func:`femcheck.robot.elastic.equilibrium` (one pass: the linear response) on the same
arm written as a ``serial_tree`` case.

What agrees by construction and what does not: both use Euler-Bernoulli bending and linear springs; the FE
assembles element matrices and solves the coupled structure, the chain model adds closed-form cantilever and
joint-rotation contributions link by link. A wrong lever arm, a load left out of a link's tip load or a wrong
sign in the cantilever formulas shows up as a disagreement.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from femcheck.fe.beam import BeamSection, assemble_beam_stiffness, line_mesh


def two_link_document(L1=0.40, L2=0.30, m1=2.0, m2=1.5, k1=2000.0, k2=1000.0, EI=800.0, tip_mass=0.0) -> dict:
    """A planar two-link arm (joint axes horizontal) as a serial_tree document; ``EI`` N m^2 of both links."""
    rows = [{"name": "shoulder", "a_m": L1, "alpha_deg": 0.0, "d_m": 0.0, "static_rpy_deg": [90.0, 0.0, 0.0],
             "mass_kg": m1, "com_m": [-L1 / 2, 0.0, 0.0], "stiffness_Nm_per_rad": k1, "bending_EI_Nm2": EI},
            {"name": "elbow", "a_m": L2, "alpha_deg": 0.0, "d_m": 0.0, "mass_kg": m2, "com_m": [-L2 / 2, 0.0, 0.0],
             "stiffness_Nm_per_rad": k2, "bending_EI_Nm2": EI}]
    doc = {"meta": {"name": "two_link_arm", "kind": "serial_tree"}, "kinematics": {"convention": "standard"},
           "gravity": {"vector_m_per_s2": [0.0, 0.0, -9.81]}, "joints": rows,
           "markers": [{"name": "tip", "link": "elbow", "offset_m": [0.0, 0.0, 0.0]}]}
    if tip_mass:
        doc["payload"] = {"link": "elbow", "com_m": [0.0, 0.0, 0.0]}
    return doc


def fe_tip_deflection(case, q: np.ndarray, EI: float, n_el: int = 8, tip_mass: float = 0.0) -> np.ndarray:
    """(3,) marker deflection, m, of the two-link ``case`` at joint angles ``q`` (2,) rad by the FE beam model."""
    from femcheck.robot.tree import forward
    tree = case.tree
    fk = forward(tree, np.atleast_2d(q) @ tree.coupling.T)
    o = fk.origins[0]                  # joint origins (2, 3)
    tip = fk.link_tip[0]               # link tips (2, 3)
    axis = fk.joint_frames[0, :, :3, 2]
    # section with the requested EI about every transverse axis (circle), huge EA and GJ: bending only
    I = EI / 200e9
    sec = BeamSection(A=1e6 * I / 0.01 ** 2, Ix=I, Iy=I, J=1e6 * I)
    n1, e1 = line_mesh(o[0], tip[0], n_el)
    n2, e2 = line_mesh(o[1], tip[1], n_el)
    nodes = np.vstack([n1, n2])
    elements = np.vstack([e1, e2 + len(n1)])
    ndof = 6 * len(nodes)
    K = assemble_beam_stiffness(nodes, elements, 200e9, 80e9, sec, shear=False, ndof=ndof).tolil()
    big = 1e6 * max(EI, 1.0) / min(np.linalg.norm(tip - o, axis=1).min(), 1.0) ** 3
    # joint 2: nodes n_el (end of link 1) and n_el+1 (start of link 2) share translations and rotations except the
    # rotation about the joint axis, which carries the torsion spring
    a, b = n_el, n_el + 1
    u = axis[1] / np.linalg.norm(axis[1])
    P = np.eye(3) - np.outer(u, u)
    tie = sp.lil_matrix((ndof, ndof))
    for blk, kk in ((slice(0, 3), big * np.eye(3)), (slice(3, 6), big * P + tree.compliance_torsion[1] ** -1 * np.outer(u, u))):
        ia = np.arange(6 * a, 6 * a + 6)[blk]
        ib = np.arange(6 * b, 6 * b + 6)[blk]
        for i in range(3):
            for j in range(3):
                K[ia[i], ia[j]] += kk[i, j]
                K[ib[i], ib[j]] += kk[i, j]
                K[ia[i], ib[j]] -= kk[i, j]
                K[ib[i], ia[j]] -= kk[i, j]
    # root: translations fixed, rotations held by a stiff penalty except about the joint axis (the torsion spring)
    u0 = axis[0] / np.linalg.norm(axis[0])
    Kr = big * (np.eye(3) - np.outer(u0, u0)) + tree.compliance_torsion[0] ** -1 * np.outer(u0, u0)
    for i in range(3):
        for j in range(3):
            K[3 + i, 3 + j] += Kr[i, j]
    f = np.zeros(ndof)
    g = tree.gravity
    for link, (nn, off) in enumerate(((n1, 0), (n2, len(n1)))):
        mid = off + n_el // 2   # n_el even: the mid-link node carries the link's weight
        f[6 * mid:6 * mid + 3] += tree.mass[link] * g
    if tip_mass:
        f[6 * (len(nodes) - 1):6 * (len(nodes) - 1) + 3] += tip_mass * g
    free = np.arange(3, ndof)
    Kf = K.tocsr()[free][:, free]
    x = np.zeros(ndof)
    x[free] = spla.spsolve(Kf.tocsc(), f[free])
    return x[6 * (len(nodes) - 1):6 * (len(nodes) - 1) + 3]


def chain_tip_deflection(case, q: np.ndarray, passes: int = 1, tip_mass: float = 0.0) -> np.ndarray:
    """(3,) marker deflection, m, of the chain model (``equilibrium``) at ``q`` (2,) rad."""
    from femcheck.robot.elastic import ElasticParams, equilibrium
    from femcheck.robot.tree import forward
    tree = case.tree
    q = np.atleast_2d(q)
    pay = np.array([tip_mass])
    rigid = forward(tree, q @ tree.coupling.T).markers[0, 0]
    flex = equilibrium(tree, q, None, ElasticParams.nominal(tree), passes, pay, np.ones(tree.n_joints)).markers[0, 0]
    return flex - rigid
