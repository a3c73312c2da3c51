"""Beam FE of a parallel device from its case description.

Every link is meshed with 3D two-node beams (:mod:`femcheck.fe.beam`, Euler-Bernoulli unless the case asks
for shear), split at the middle where a P joint sits in it. Each joint is a pair of nodes at its centre
whose twists differ by ``B y``: the columns of B are the joint's released freedoms (unit twists ``[0; w]`` of
its rotations, ``[u; 0]`` of a slide; free, only with ``released`` joints), its drive (``detailed``: a spring
of stiffness 1/c on the actuated freedom) and its contact law (``detailed``: translational springs, Hertz
point contact at the analytical model's linearization, or line contact + pin bending in the link frame; an
FE-measured law as six springs along the eigen-twists of its 6 x 6 compliance in the link frame);
every other relative motion is locked. The base side of the first joint is fixed; the platform is rigid, so
the platform side of each last joint moves with the TCP twist (``G_i t_T``). The nodes are expressed by a
master-slave transformation (exact, no penalty) and everything but the TCP twist is condensed out:
``K_T = K_tt - K_to K_oo^-1 K_ot``.

With ``fe_laws`` (:class:`FeLaws`) the FE takes nothing from the laws it checks: each passive joint with a
contact FE (:mod:`femcheck.parallel.joint_specimen`) is three translational springs along its joint frame (the
ball: isotropic, the contact FE's axial stick tangent K_zz(F); the U joint: the frame of its loaded link yoke, z
along that link, y its pin, x = y x z, the diagonal K_xx, K_yy, K_zz(F) of the contact FE's stick tangent) at
the joint force F the FE itself carries under the pose's wrench (fixed point, as the analytical model's Hertz
linearization), its rotations as the joint's idealization (released: free; else locked); the drive is the
spring condensed from its elements (:mod:`femcheck.parallel.drive_fe`).

With the analytical model's element laws this reproduces :func:`femcheck.parallel.chain_model.evaluate`
exactly in exact arithmetic (a cantilever's tip compliance is exact for beam elements), so the test asks
1e-8; what it checks is the chain algebra (carrying compliances, the null-space treatment of released
joints, the rigid platform sum) by an independent route.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from femcheck.fe.beam import BeamSection, assemble_beam_stiffness
from femcheck.parallel.leg_kinematics import DeviceState, solve_legs


#: fixed point on the contact-FE joints' force: relative change of every joint force below this
FORCE_TOL = 1e-10
MAX_FORCE_ITER = 60


@dataclasses.dataclass(frozen=True)
class FeLaws:
    """What the FE uses instead of the analytical laws: ``joints`` {(``[[legs]]`` index, joint index): (kind
    'spherical' | 'universal', :class:`~femcheck.fe_device.joint_laws.MeasuredJointLaw`)} and ``drives``
    {``[[legs]]`` index: stiffness of the drive's elements (N/m or N m/rad)}."""

    joints: dict = dataclasses.field(default_factory=dict)
    drives: dict = dataclasses.field(default_factory=dict)


def fe_laws_of(case, joint_fe: bool = True, joint_mesh: str = "coarse", progress=None) -> FeLaws:
    """The FE's own laws of a ``parallel_device`` case: each drive the case describes by its parts condensed from
    its elements, and (``joint_fe``) every joint with a contact FE measured at ``joint_mesh`` (cached)."""
    from femcheck.parallel.drive_fe import drive_stiffness, has_elements
    drives = {i: drive_stiffness(j.drive) for i, leg in enumerate(case.legs) for j in leg.joints
              if j.drive is not None and has_elements(j.drive)}
    joints = {}
    if joint_fe:
        from femcheck.parallel.joint_specimen import measure_device_joint_laws
        joints = measure_device_joint_laws(case, joint_mesh, progress=progress).laws
    return FeLaws(joints=joints, drives=drives)


class _Model:
    """Nodes as linear expressions of master coordinates ({first master index: (6, k) matrix})."""

    def __init__(self):
        self.n_master = 6  # the TCP twist
        self.nodes: list[tuple[np.ndarray, dict]] = []
        self.springs: list[tuple[int, np.ndarray]] = []
        self.beams: list[tuple] = []  # (node a, node b, E, G, section, orientation, shear)
        self.solids: list[tuple] = []  # (node a, node b, K (12, 12) in the global frame): condensed solid links

    def master(self, k: int) -> int:
        s = self.n_master
        self.n_master += k
        return s

    def node(self, pos, expr: dict) -> int:
        self.nodes.append((np.asarray(pos, float), expr))
        return len(self.nodes) - 1

    def master_node(self, pos) -> int:
        return self.node(pos, {self.master(6): np.eye(6)})

    def stiffness(self) -> np.ndarray:
        T = np.zeros((6 * len(self.nodes), self.n_master))
        for i, (_, expr) in enumerate(self.nodes):
            for s, M in expr.items():
                T[6 * i:6 * i + 6, s:s + M.shape[1]] += M
        K = np.zeros((self.n_master, self.n_master))
        for a, b, E, G, sec, orient, shear in self.beams:
            pts = np.array([self.nodes[a][0], self.nodes[b][0]])
            Ke = assemble_beam_stiffness(pts, [[0, 1]], E, G, sec, orientation=orient, shear=shear).toarray()
            Te = np.vstack([T[6 * a:6 * a + 6], T[6 * b:6 * b + 6]])
            K += Te.T @ Ke @ Te
        for a, b, Kg in self.solids:
            Te = np.vstack([T[6 * a:6 * a + 6], T[6 * b:6 * b + 6]])
            K += Te.T @ Kg @ Te
        for s, k in self.springs:
            K[s:s + len(k), s:s + len(k)] += np.diag(k)
        return K


def _plus(expr: dict, s: int, B: np.ndarray, sign: float = 1.0) -> dict:
    out = dict(expr)
    if B.shape[1]:  # a joint with no columns is welded
        out[s] = out.get(s, 0.0) + sign * B
    return out


def _contact_springs(leg, k, p, s, kind, law, F):
    """(3, 6) translational columns and (3,) stiffnesses of a contact-FE joint law at joint force F (module doc)."""
    if kind == "spherical":
        frame = np.eye(3)
        kk = np.full(3, law.component_stiffness(F)[2])
    else:
        # the contact FE's frame is its loaded link yoke's: z along that link, y its pin (a2), x = y x z. The yoke is
        # on the link after the joint (its last axis), at the platform end on the link before (its first axis)
        c = int(leg.joint_centre[k])
        after = c < len(leg.links)
        z = s.link_R[p, c if after else c - 1][:, 2]
        axes = [s.twists[p, d, 3:] for d in np.flatnonzero(leg.dof_joint == k)]   # an R joint: its one pin
        y = axes[-1] if after else axes[0]
        y = y - (y @ z) * z
        y /= np.linalg.norm(y)
        frame = np.array([np.cross(y, z), y, z]).T
        kk = law.component_stiffness(F)[:3]
    return np.vstack([frame, np.zeros((3, 3))]).T, kk


def _joint_columns(leg, li, k, p, state: DeviceState, model, joints, hertz_stiffness, fe_laws=None, forces=None):
    """(6, m) relative-twist columns of joint k at its centre, their stiffnesses (m,) (0: free) and the number of
    trailing contact-FE columns (their springs carry the joint force)."""
    s = state.legs[li]
    cols, ks = [], []
    key = (leg.case_index, k)
    measured = fe_laws is not None and model == "detailed" and key in fe_laws.joints
    for d in np.flatnonzero(leg.dof_joint == k):
        tw = s.twists[p, d]
        col = np.concatenate([np.zeros(3), tw[3:]]) if leg.dof_kind[d] == "R" else np.concatenate([tw[:3], np.zeros(3)])
        if d == leg.actuated_dof:
            if model == "detailed":
                k_drive = (fe_laws.drives[leg.case_index] if fe_laws is not None and leg.case_index in fe_laws.drives
                           else 1.0 / leg.drive_compliance)
                cols.append(col), ks.append(k_drive)
        elif joints == "released":
            cols.append(col), ks.append(0.0)
    if measured:
        kind, law = fe_laws.joints[key]
        C, kk = _contact_springs(leg, k, p, s, kind, law, forces[li, k])
        cols.extend(C), ks.extend(kk)
        return np.array(cols).T, np.array(ks), 3
    if model == "detailed" and k in leg.hertz_point:
        kh = hertz_stiffness[li, k][p]
        for a in range(3):
            cols.append(np.eye(6)[a]), ks.append(kh)
    if model == "detailed" and k in leg.hertz_line:
        c_uc, c_ub, m = leg.hertz_line[k]
        R = s.link_R[p, m]
        for a, c in enumerate((c_uc, c_uc, c_uc + c_ub)):
            cols.append(np.concatenate([R[:, a], np.zeros(3)])), ks.append(1.0 / c)
    if model == "detailed" and k in leg.measured_law:
        # S_J = V diag(c) V^T in the link frame: one spring 1/c_a per eigen-twist, turned into frame U
        S_J, _, m = leg.measured_law[k]
        if k in leg.measured_ladder:   # the axial tangent of the chain model's fixed point (hertz_stiffness)
            d = np.ones(6)
            d[2] = np.sqrt(1.0 / (hertz_stiffness[li, k][p] * S_J[2, 2]))
            S_J = S_J * d[:, None] * d[None, :]
        R = s.link_R[p, m]
        c, V = np.linalg.eigh(S_J)
        for a in range(6):
            cols.append(np.concatenate([R @ V[:3, a], R @ V[3:, a]])), ks.append(1.0 / c[a])
    if not cols:
        return np.zeros((6, 0)), np.zeros(0), 0
    return np.array(cols).T, np.array(ks), 0


def _beam_section(ln) -> BeamSection:
    sec = ln.section
    return BeamSection(A=float(sec.A), Ix=float(sec.Ix), Iy=float(sec.Iy), J=float(sec.Jt),
                       kappa_x=float(sec.shear_factor), kappa_y=float(sec.shear_factor))


def _segment(fe: _Model, a: int, b: int, ln, orient, n_el: int, shear: bool, parts: str = "beam",
             mesh: str = "default") -> None:
    if ln.section is None:
        raise NotImplementedError(f"link {ln.name!r} is rigid; the beam FE meshes only tube and bar links")
    pa, pb = fe.nodes[a][0], fe.nodes[b][0]
    if parts == "solid":
        from femcheck.fe.beam import _to_global, local_frames
        from femcheck.parallel.solid_links import link_stiffness
        R, L = local_frames(np.array([pa, pb]), [[0, 1]], orient)
        fe.solids.append((a, b, _to_global(link_stiffness(ln.spec, float(L[0]), mesh)[None], R)[0]))
        return
    ids = [a] + [fe.master_node(pa + (pb - pa) * t) for t in np.arange(1, n_el) / n_el] + [b]
    sec = _beam_section(ln)
    for i, j in zip(ids[:-1], ids[1:]):
        fe.beams.append((i, j, ln.E, ln.G, sec, orient, shear))


def _assemble(device, state: DeviceState, p: int, model, joints, hertz_stiffness, elements_per_link, parts, mesh,
              fe_laws, forces):
    """The FE model of pose p and its contact-FE joint springs [(leg, joint, first master, B, stiffnesses)]."""
    fe = _Model()
    contacts = []
    for li, leg in enumerate(device.legs):
        s = state.legs[li]
        G = state.G(li)[p]
        last = len(leg.centres) - 1
        cursor, link = None, 0
        for k, jt in enumerate(leg.joint_types):
            B, kk, n_contact = _joint_columns(leg, li, k, p, state, model, joints, hertz_stiffness, fe_laws, forces)
            y = fe.master(B.shape[1])
            if kk.size:
                fe.springs.append((y, kk))
            if n_contact:
                contacts.append((li, k, y + B.shape[1] - n_contact, B[:3, -n_contact:], kk[-n_contact:]))
            ln = leg.links[min(link, len(leg.links) - 1)]
            orient = s.link_R[p, min(link, len(leg.links) - 1), :, 0]
            if jt == "P":
                mid = 0.5 * (s.centres[p, ln.start] + s.centres[p, ln.end])
                before = fe.master_node(mid)
                _segment(fe, cursor, before, ln, orient, elements_per_link, device.beam_shear, parts, mesh)
                cursor = fe.node(mid, _plus(fe.nodes[before][1], y, B))
                continue
            c = int(leg.joint_centre[k])
            pos = s.centres[p, c]
            if c == 0:
                cursor = fe.node(pos, _plus({}, y, B))
            elif c < last:
                before = fe.master_node(pos)
                _segment(fe, cursor, before, ln, orient, elements_per_link, device.beam_shear, parts, mesh)
                cursor = fe.node(pos, _plus(fe.nodes[before][1], y, B))
                link = c
            else:
                before = fe.node(pos, _plus({0: G}, y, B, -1.0))
                _segment(fe, cursor, before, ln, orient, elements_per_link, device.beam_shear, parts, mesh)
    return fe, contacts


def device_fe_stiffness(device, poses, *, model: str = "detailed", joints: str = "released",
                        hertz_stiffness: dict | None = None, elements_per_link: int = 2,
                        state: DeviceState | None = None, parts: str = "beam", mesh: str = "default",
                        fe_laws: FeLaws | None = None, wrench=None) -> np.ndarray:
    """(n, 6, 6) TCP stiffness of the beam FE of ``device`` at TCP poses (n, 6) (m, rad).

    ``hertz_stiffness``: {(leg, joint): (n,)} N/m of the Hertz point contacts (``ParallelResult.hertz_stiffness``);
    required for a detailed model with Hertz point contacts the FE takes as closed forms. ``parts``: ``"beam"``
    (beam elements: the analytical cantilever, a check of the chain algebra) or ``"solid"`` (each link meshed and
    condensed, :mod:`femcheck.parallel.solid_links`, at ``mesh`` level: a check of the link laws too).
    ``fe_laws``: the FE's own joint and drive laws (:class:`FeLaws`, module doc); its contact-FE joints need the
    TCP ``wrench`` (6,) or (n, 6) (N, N m) whose joint forces linearize them.
    """
    if parts not in ("beam", "solid"):
        raise ValueError(f"parts = {parts!r}; expected beam or solid")
    state = state if state is not None else solve_legs(device, poses)
    laws = fe_laws.joints if fe_laws is not None and model == "detailed" else {}
    closed = [leg for leg in device.legs if leg.measured_ladder or any((leg.case_index, k) not in laws for k in leg.hertz_point)]
    if model == "detailed" and closed and hertz_stiffness is None:
        raise ValueError("hertz_stiffness: required for the detailed model (the Hertz contacts' linearization)")
    if laws and wrench is None:
        raise ValueError("wrench: required with contact-FE joint laws (they are linearized at the joint force)")
    W = np.broadcast_to(np.asarray(wrench, float), (state.n, 6)) if laws else None
    n_joints = max(len(leg.joint_types) for leg in device.legs)
    out = np.empty((state.n, 6, 6))
    for p in range(state.n):  # one FE model per pose (each pose is a different mesh)
        # joint forces of the contact-FE laws: start mid-ladder, then the force the FE carries (fixed point)
        forces = np.full((device.n_legs, n_joints), np.nan)
        for li, leg in enumerate(device.legs):
            for k in range(len(leg.joint_types)):
                if (leg.case_index, k) in laws:
                    F = laws[leg.case_index, k][1].loads_N
                    forces[li, k] = np.sqrt(F[0] * F[-1])
        for _ in range(MAX_FORCE_ITER):
            fe, contacts = _assemble(device, state, p, model, joints, hertz_stiffness, elements_per_link, parts,
                                     mesh, fe_laws, forces)
            K = fe.stiffness()
            Ktt, Kto, Koo = K[:6, :6], K[:6, 6:], K[6:, 6:]
            Koo_Kot = np.linalg.solve(Koo, Kto.T)
            KT = Ktt - Kto @ Koo_Kot
            if not contacts:
                break
            t = np.linalg.solve(KT, W[p])
            u = np.concatenate([t, -Koo_Kot @ t])
            new = forces.copy()
            for li, k, y, D, kk in contacts:   # joint force = its springs' forces along their directions
                new[li, k] = np.linalg.norm(D @ (kk * u[y:y + kk.size]))
            done = np.nanmax(np.abs(new - forces) / np.maximum(np.abs(new), 1e-300)) < FORCE_TOL
            forces = new
            if done:
                break
        out[p] = 0.5 * (KT + KT.T)
    return out
