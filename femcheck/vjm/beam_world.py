"""A beam finite-element "world" for a serial arm: the virtual experiment that stands in for seed 002's FE model.

Seed 002 identifies its extended VJM on deflections computed by a commercial FE model of the SHIR5 cobot
(sec. IV-A). femcheck has no such model, so this module builds one from femcheck's own beam elements
(:mod:`femcheck.fe.beam`) on the arm's DH geometry. It is *not* a VJM: the links bend, twist, shear and
stretch along their length, and every joint is a six-direction elastic coupling. That is what lets it judge
the conventional and the extended VJM from outside.

Structure (per configuration, built from the forward kinematics; standard DH only):

* **Bodies.** Body 0 is the base; body j (1..n) turns with joint j. Each body is a chain of straight hollow
  tubes (:class:`Tube`, Timoshenko beams) along the DH geometry: from bearing j along joint axis j to the
  foot of the common normal (``o_j + d_j z_j``), along the normal to the next joint-frame origin, then along
  joint axis j+1 to bearing j+1. The base runs from the frame-0 origin, which is clamped, to bearing 1. The
  last body ends at the flange, and a tool tube (``tool``) runs from the flange to the tool point (TCP).
  Where a body's tube turns, the corner is rigid (beam theory) or, with ``corners``, a mitred tube joint: the
  two tube ends there are coincident nodes joined by the corner's 6 x 6 compliance (:class:`BeamWorld`).
* **Joints.** Joint j is a pair of coincident nodes at the bearing point ``o_j + offset_j z_j`` (the last
  node of body j-1 and the first of body j). They are coupled by six springs in the joint frame
  (:class:`Bearing`): torsion about the axis (the drive), two tilts, two radial translations and the axial one
  (the bearing, its seat and housing). A direction of infinite stiffness is an exact constraint.
* **Loads.** A wrench at the TCP (base frame, N and N m), and optionally the self-weight of the tubes
  (lumped half to each element node) and of the drives (``Bearing.mass_kg``, at the joint).

Solution. The nodal displacements are ``u = T z``: z holds the free node DOFs and each joint's relative
motions in its finite directions. The distal node of a joint is its proximal node plus those relative
motions, and with ``rigid_links`` every node of a body follows the body's first node rigidly. Then
``K_z = T^T K_beam T + diag(joint springs)``. It is factorized once per configuration (Cholesky), with
all wrenches as right-hand sides. A drive with a piecewise-linear torsion law (``Bearing.torsion_curve``,
:mod:`femcheck.vjm.strain_wave_torsion`) makes the problem nonlinear; it is solved by secant iteration in the
drive torques, per load state (:func:`tcp_deflections`). With rigid links and joints rigid except in
torsion, ``T`` at the TCP is the geometric Jacobian and ``K_z = diag(k_torsion)``, so the world reduces
exactly to the conventional VJM (with piecewise drives: of their secant stiffnesses).
"""
from __future__ import annotations

import dataclasses
import logging
import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from femcheck.fe.beam import BeamSection, assemble_beam_stiffness, line_mesh
from femcheck.vjm.dh import DHChain, as_poses, forward_kinematics
from femcheck.vjm.mitre_corner import MIN_MITRE_ANGLE_RAD, corner_compliance
from femcheck.vjm.mitre_superelement import corner_excess_compliance
from femcheck.vjm.strain_wave_torsion import StrainWaveTorsion

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Tube:
    """A hollow circular tube: ``outer_diameter_m`` and ``wall_m`` (m), ``E_Pa``, Poisson's ``nu``,
    ``density_kg_m3``. The default material is cast aluminium (70 GPa, 0.33, 2700 kg/m³)."""

    outer_diameter_m: float
    wall_m: float
    E_Pa: float = 70e9
    nu: float = 0.33
    density_kg_m3: float = 2700.0

    def __post_init__(self):
        if not (self.outer_diameter_m > 0 and 0 < self.wall_m <= self.outer_diameter_m / 2):
            raise ValueError(f"Tube(outer_diameter_m={self.outer_diameter_m}, wall_m={self.wall_m}); "
                             "expected 0 < wall_m <= outer_diameter_m / 2")

    @property
    def section(self) -> BeamSection:
        return BeamSection.tube(self.outer_diameter_m, self.outer_diameter_m - 2 * self.wall_m, self.nu)

    @property
    def G_Pa(self) -> float:
        return self.E_Pa / (2 * (1 + self.nu))


@dataclass(frozen=True)
class Bearing:
    """The elastic coupling of a joint, in its joint frame (z = joint axis, x and y turn with the joint).

    ``torsion_Nm_per_rad``: the drive (about z). ``tilt_Nm_per_rad``: about x and y. ``radial_N_per_m``:
    along x and y. ``axial_N_per_m``: along z. ``math.inf`` makes a direction rigid. ``offset_m``: the
    bearing's place along the joint axis from the joint-frame origin, m. ``mass_kg``: the drive's mass,
    for the self-weight. ``torsion_curve``: when given, the drive's torsion follows this piecewise-linear law
    in its torque instead of the constant ``torsion_Nm_per_rad`` (which must then be the law's K3, the value
    the catalogues list alone); :func:`tcp_deflections` solves the equilibrium for it.
    """

    torsion_Nm_per_rad: float
    tilt_Nm_per_rad: float = math.inf
    radial_N_per_m: float = math.inf
    axial_N_per_m: float = math.inf
    offset_m: float = 0.0
    mass_kg: float = 0.0
    torsion_curve: StrainWaveTorsion | None = None

    def __post_init__(self):
        for name in ("torsion_Nm_per_rad", "tilt_Nm_per_rad", "radial_N_per_m", "axial_N_per_m"):
            if not getattr(self, name) > 0:
                raise ValueError(f"Bearing.{name} = {getattr(self, name)}; expected > 0 (math.inf = rigid)")
        k3 = None if self.torsion_curve is None else self.torsion_curve.high_torque_stiffness_Nm_per_rad
        if k3 is not None and self.torsion_Nm_per_rad != k3:
            raise ValueError(f"Bearing.torsion_Nm_per_rad = {self.torsion_Nm_per_rad} with a torsion_curve; expected "
                             f"its K3 = {self.torsion_curve.high_torque_stiffness_Nm_per_rad}")

    @classmethod
    def crossed_roller(cls, torsion_Nm_per_rad: float, pitch_diameter_m: float, axial_N_per_m: float,
                       radial_N_per_m: float, offset_m: float = 0.0, mass_kg: float = 0.0) -> "Bearing":
        """A crossed-roller output bearing seen as a ring of axial springs (total ``axial_N_per_m``) on the
        pitch circle of radius R = D/2. A tilt θ stretches the spring at angle φ by R θ cos φ, so
        M = (k_a / 2π) ∫ R² cos² φ dφ θ = k_a R² / 2 θ, i.e. ``tilt = axial D² / 8``."""
        return cls(torsion_Nm_per_rad=torsion_Nm_per_rad, tilt_Nm_per_rad=axial_N_per_m * pitch_diameter_m**2 / 8,
                   radial_N_per_m=radial_N_per_m, axial_N_per_m=axial_N_per_m, offset_m=offset_m, mass_kg=mass_kg)

    @property
    def local_stiffness(self) -> np.ndarray:
        """(6,) stiffness along (x, y, z, rot x, rot y, rot z) of the joint frame, N/m and N m/rad."""
        return np.array([self.radial_N_per_m, self.radial_N_per_m, self.axial_N_per_m,
                         self.tilt_Nm_per_rad, self.tilt_Nm_per_rad, self.torsion_Nm_per_rad], dtype=float)


@dataclass(frozen=True)
class BeamWorld:
    """An immutable beam-FE model of a serial arm.

    ``chain`` (standard DH); ``bearings`` (n,); ``links`` (n + 1,): the base and bodies 1..n; ``tool`` the
    flange-to-TCP tube; ``rigid_links``: the tubes are rigid (only the joints deform); ``max_element_m``:
    the longest beam element (the element is nodally exact for end loads, so this only matters for the
    self-weight); ``shear``: Timoshenko (True) or Euler-Bernoulli; ``gravity_m_per_s2`` base frame;
    ``corners``: how a body's tube turns a corner (the same tube on both sides, by more than 3 degrees):
    ``"rigid"`` (beam theory: the two tube ends share one node), ``"solid"`` (the two ends are joined by the
    6 x 6 compliance of the mitred tube's solid FE superelement beyond the beam's,
    :func:`femcheck.vjm.mitre_superelement.corner_excess_compliance`) or ``"b31.3"`` (by ASME B31.3's
    single-mitre flexibility as a rotational compliance, :func:`femcheck.vjm.mitre_corner.corner_compliance`);
    ``corner_scale`` multiplies that compliance (a bracket, 1 as computed); both ignored with ``rigid_links``.
    """

    chain: DHChain
    bearings: tuple[Bearing, ...]
    links: tuple[Tube, ...]
    tool: Tube
    rigid_links: bool = False
    max_element_m: float = 0.05
    shear: bool = True
    gravity_m_per_s2: tuple[float, float, float] = (0.0, 0.0, -9.81)
    corners: str = "rigid"
    corner_scale: float = 1.0

    def __post_init__(self):
        n = self.chain.n_joints
        if self.chain.convention != "standard":
            raise ValueError(f"BeamWorld needs a standard DH chain; got {self.chain.convention!r}")
        if self.corners not in CORNER_MODELS:
            raise ValueError(f"BeamWorld.corners = {self.corners!r}; expected one of {', '.join(CORNER_MODELS)}")
        if not (self.corner_scale > 0 and math.isfinite(self.corner_scale)):
            raise ValueError(f"BeamWorld.corner_scale = {self.corner_scale}; expected a finite factor > 0")
        if len(self.bearings) != n or len(self.links) != n + 1:
            raise ValueError(f"BeamWorld: {len(self.bearings)} bearings and {len(self.links)} links; "
                             f"expected {n} and {n + 1} (base + one per joint)")

    def with_rigid_structure(self) -> "BeamWorld":
        """The same arm with rigid links and bearings: only the drives' torsion is left (the conventional VJM)."""
        return dataclasses.replace(self, rigid_links=True, corners="rigid", bearings=tuple(
            Bearing(torsion_Nm_per_rad=b.torsion_Nm_per_rad, offset_m=b.offset_m, mass_kg=b.mass_kg,
                    torsion_curve=b.torsion_curve)
            for b in self.bearings))


#: how a body's tube turns a corner (:class:`BeamWorld`)
CORNER_MODELS = ("rigid", "solid", "b31.3")


def corner_hinge_compliance(model: str, tube: Tube, t_in, t_out) -> np.ndarray:
    """(6, 6) compliance, base frame, [u; theta] per [F; M] at the corner, that joins the tube ends meeting where
    ``tube``'s axis turns from unit ``t_in`` to unit ``t_out``: the solid superelement's excess over the beam
    (``"solid"``, computed in the frame t_in = x, bend in x-y, and turned into the corner's frame) or B31.3's
    rotational compliance (``"b31.3"``, translations rigid)."""
    t_in, t_out = np.asarray(t_in, dtype=float), np.asarray(t_out, dtype=float)
    C = np.zeros((6, 6))
    if model == "b31.3":
        C[3:, 3:] = corner_compliance(tube, t_in, t_out)
        return C
    angle = math.acos(min(1.0, float(t_in @ t_out)))
    e2 = t_out - (t_in @ t_out) * t_in
    e2 /= np.linalg.norm(e2)
    R = np.c_[t_in, e2, np.cross(t_in, e2)]          # superelement frame -> base frame
    C[:3, :3], C[3:, 3:] = R, R
    return C @ corner_excess_compliance(tube, round(angle, 9)) @ C.T


@dataclass(frozen=True)
class _Layout:
    """One configuration's mesh: nodes (N, 3) m; segments [(elements (e, 2), tube)]; body_nodes per body;
    joint_frames (n, 3, 3); tcp node index; corners {node: (corner node, (6, 6) compliance, base frame,
    [u; theta] per [F; M])}: a node
    that starts a tube after a mitred corner, coincident with the node that ends the tube before it."""

    nodes: np.ndarray
    segments: list
    body_nodes: list
    joint_frames: np.ndarray
    tcp: int
    corners: dict = dataclasses.field(default_factory=dict)


def _layout(world: BeamWorld, fk, i: int) -> _Layout:
    chain = world.chain
    n = chain.n_joints
    jf = fk.joint_frames[i]
    o, z = jf[:, :3, 3], jf[:, :3, 2]
    bearing_pt = o + np.array([b.offset_m for b in world.bearings])[:, None] * z
    foot = o + np.asarray(chain.d_m)[:, None] * z
    origin = fk.frames[i][:, :3, 3]                   # frame k origin; frame k < n is joint k+1's origin
    paths = [[(origin[0], bearing_pt[0], world.links[0])]]
    for j in range(n):
        pts = [bearing_pt[j], foot[j], origin[j + 1]] + ([bearing_pt[j + 1]] if j + 1 < n else [])
        segs = [(pts[k], pts[k + 1], world.links[j + 1]) for k in range(len(pts) - 1)]
        if j + 1 == n:
            segs.append((origin[n], fk.tcp[i], world.tool))
        paths.append(segs)
    nodes, segments, body_nodes, corners = [], [], [], {}
    for segs in paths:
        ids = [len(nodes)]
        nodes.append(np.asarray(segs[0][0], dtype=float))
        prev = None                                   # (direction, tube) of the body's last tube
        for a, b, tube in segs:
            L = float(np.linalg.norm(b - a))
            if L < 1e-12:
                continue
            t = (b - a) / L
            if (world.corners != "rigid" and not world.rigid_links and prev is not None and prev[1] == tube
                    and math.acos(min(1.0, float(prev[0] @ t))) > MIN_MITRE_ANGLE_RAD):
                corners[len(nodes)] = (ids[-1], world.corner_scale * corner_hinge_compliance(world.corners, tube, prev[0], t))
                nodes.append(nodes[ids[-1]])          # the next tube starts at a coincident node
                ids.append(len(nodes) - 1)
            prev = (t, tube)
            ne = max(1, math.ceil(L / world.max_element_m - 1e-9))
            pts, _ = line_mesh(a, b, ne)
            new = list(range(len(nodes), len(nodes) + ne))
            nodes.extend(pts[1:])
            segments.append((np.c_[[ids[-1]] + new[:-1], new], tube))
            ids.extend(new)
        body_nodes.append(ids)
    return _Layout(nodes=np.array(nodes), segments=segments, body_nodes=body_nodes,
                   joint_frames=jf[:, :3, :3], tcp=body_nodes[-1][-1], corners=corners)


def _skew(r):
    return np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])


def _reduction(world: BeamWorld, lay: _Layout):
    """(T (6N, nz), spring stiffness (nz,) with 0 on node DOFs, torsion column of each joint (n,), -1 where
    the drive is rigid): u = T z (module docstring)."""
    N = len(lay.nodes)
    cap = 6 * N + 6 * len(world.bearings)
    T = np.zeros((N, 6, cap))
    spring = np.zeros(cap)
    torsion_col = np.full(len(world.bearings), -1)
    col = 0
    for b, ids in enumerate(lay.body_nodes):
        if b > 0:                                     # joint b: distal node = proximal node + relative motions
            dist, prox = ids[0], lay.body_nodes[b - 1][-1]
            R = lay.joint_frames[b - 1]
            Q = np.zeros((6, 6))
            Q[:3, :3] = Q[3:, 3:] = R                 # columns: the joint-frame directions in the base frame
            T[dist] = T[prox]
            for f, k in enumerate(world.bearings[b - 1].local_stiffness):
                if np.isfinite(k):
                    T[dist, :, col] += Q[:, f]
                    spring[col] = k
                    if f == 5:
                        torsion_col[b - 1] = col
                    col += 1
        # body 0's first node is the clamped base (T = 0)
        ref = ids[0]
        for node in ids[1:]:
            if node in lay.corners:                   # u = u_corner + relative motions along C's eigenvectors
                corner, C = lay.corners[node]
                lam, vec = np.linalg.eigh(C)
                T[node] = T[corner]
                for l, v in zip(lam, vec.T):
                    if l > 1e-12 * lam.max():         # a zero eigenvalue is a rigid direction
                        T[node, :, col] += v
                        spring[col] = 1.0 / l
                        col += 1
            elif world.rigid_links:                     # u = u_ref + theta_ref x (x - x_ref), theta = theta_ref
                G = np.eye(6)
                G[:3, 3:] = -_skew(lay.nodes[node] - lay.nodes[ref])
                T[node] = G @ T[ref]
            else:
                T[node, :, col:col + 6] = np.eye(6)
                col += 6
    return T[:, :, :col].reshape(6 * N, col), spring[:col], torsion_col


def _self_weight(world: BeamWorld, lay: _Layout) -> np.ndarray:
    """(6N,) nodal loads of the self-weight, N: each element's weight half to each end node; drives at the joint."""
    g = np.asarray(world.gravity_m_per_s2, dtype=float)
    f = np.zeros((len(lay.nodes), 6))
    for el, tube in lay.segments:
        L = np.linalg.norm(lay.nodes[el[:, 1]] - lay.nodes[el[:, 0]], axis=1)
        w = (tube.density_kg_m3 * tube.section.A * L)[:, None] * g / 2
        np.add.at(f, (el[:, 0], slice(0, 3)), w)
        np.add.at(f, (el[:, 1], slice(0, 3)), w)
    for j, b in enumerate(world.bearings):
        f[lay.body_nodes[j + 1][0], :3] += b.mass_kg * g
    return f.ravel()


def arm_mass_kg(world: BeamWorld) -> float:
    """Mass of the arm (tubes, tool and drives), kg; independent of the configuration."""
    lay = _layout(world, forward_kinematics(world.chain, np.zeros((1, world.chain.n_joints))), 0)
    tubes = sum(t.density_kg_m3 * t.section.A * np.linalg.norm(lay.nodes[el[:, 1]] - lay.nodes[el[:, 0]], axis=1).sum()
                for el, t in lay.segments)
    return float(tubes + sum(b.mass_kg for b in world.bearings))


@dataclass(frozen=True)
class WorldDeflections:
    """TCP deflections of a :class:`BeamWorld`: ``twist`` (m, p, 6) [dx, dy, dz, rx, ry, rz] in m and rad
    under each of the p wrenches (self-weight added when asked); ``self_weight`` (m, 6) the deflection
    under the self-weight alone (zeros when not asked); ``n_dof`` (m,) reduced unknowns per configuration.
    With piecewise drives: ``drive_torque_Nm`` (m, p + 1, n) each drive's torque, N m, under the self-weight
    alone (index 0) and under the self-weight plus wrench k (index k + 1), 0 for a drive without a curve;
    ``iterations`` (m,) secant iterations to equilibrium. Both are None with constant drives."""

    twist: np.ndarray
    self_weight: np.ndarray
    n_dof: np.ndarray
    drive_torque_Nm: np.ndarray | None = None
    iterations: np.ndarray | None = None


def _solve_piecewise_drives(world: BeamWorld, lay: _Layout, T, Kz, spring, torsion_col, W, tol: float = 1e-8,
                            max_iter: int = 50):
    """Equilibrium of one configuration whose drives follow their ``torsion_curve`` (:func:`tcp_deflections`).

    Load states: the self-weight alone (s = 0) and the self-weight plus each wrench (s = 1..p). Secant
    fixed point, all states at once: each curved drive's spring is its secant from zero torque,
    ``k = T / phi(T)`` at the torque of the previous solve (K1 to start); the solve gives the torques
    ``k z``; repeat until they change by less than ``tol`` of the largest (K_z's condition number, up to
    about 1e7, times the round-off leaves ~1e-9). The arm is statically determinate, so the torques are
    exact after the first solve and the second confirms them. Returns z (p + 1, nz), the
    torques (p + 1, n) and the iterations."""
    n = len(world.bearings)
    curved = np.array([j for j, b in enumerate(world.bearings) if b.torsion_curve is not None and torsion_col[j] >= 0],
                      dtype=int)
    cols = torsion_col[curved]
    curves = [world.bearings[j].torsion_curve for j in curved]
    f_sw = T.T @ _self_weight(world, lay)
    Tt = T[6 * lay.tcp:6 * lay.tcp + 6]
    F = np.c_[f_sw, f_sw[:, None] + Tt.T @ W.T].T                  # (p + 1, nz)
    K_lin = Kz.copy()
    K_lin[cols, cols] -= spring[cols]                                # the curved drives enter per state
    Ks = np.repeat(K_lin[None], len(F), axis=0)
    k = np.array([[c.stiffness_Nm_per_rad[0] for c in curves]] * len(F))
    tau_prev = None
    for it in range(1, max_iter + 1):
        Ks[:, cols, cols] = K_lin[cols, cols] + k
        z = np.linalg.solve(Ks, F[:, :, None])[:, :, 0]
        tau = k * z[:, cols]
        k = np.stack([c.secant(0.0, tau[:, a]) for a, c in enumerate(curves)], axis=1)
        if tau_prev is not None and np.abs(tau - tau_prev).max() <= tol * max(np.abs(tau).max(), 1.0):
            break
        tau_prev = tau
    else:
        raise RuntimeError(f"piecewise drives: no equilibrium after {max_iter} secant iterations")
    torque = np.zeros((len(F), n))
    torque[:, curved] = tau
    return z, torque, it


def tcp_deflections(world: BeamWorld, q, wrenches, gravity: bool = False) -> WorldDeflections:
    """TCP deflections at configurations ``q`` (m, n) rad under ``wrenches`` (p, 6) N, N m (base frame, at the
    TCP). One Cholesky factorization per configuration; the p wrenches (and the self-weight) are its
    right-hand sides. ``gravity`` adds the self-weight's deflection to every wrench's.

    Drives with a ``torsion_curve`` make the world nonlinear, and the arm's own weight sets their operating
    torque: every configuration is then solved under the self-weight alone and under the self-weight plus
    each wrench (:func:`_solve_piecewise_drives`), and a wrench's deflection is the difference of the two
    states, what a measurement zeroed in the pose sees; each drive gives the secant of its law between its
    torque under the self-weight and under the self-weight plus the wrench. ``gravity`` adds the
    self-weight state's own deflection (from the unloaded arm), as before."""
    q = as_poses(world.chain, q)
    W = np.atleast_2d(np.asarray(wrenches, dtype=float))
    if W.shape[1] != 6:
        raise ValueError(f"wrenches have shape {W.shape}; expected (p, 6)")
    fk = forward_kinematics(world.chain, q)
    out = np.empty((len(q), len(W), 6))
    sw = np.zeros((len(q), 6))
    ndof = np.empty(len(q), dtype=int)
    piecewise = any(b.torsion_curve is not None for b in world.bearings)
    torque = np.zeros((len(q), len(W) + 1, len(world.bearings))) if piecewise else None
    iterations = np.zeros(len(q), dtype=int) if piecewise else None
    for i in range(len(q)):
        lay = _layout(world, fk, i)
        T, spring, torsion_col = _reduction(world, lay)
        Kz = np.diag(spring)
        if not world.rigid_links:
            for el, tube in lay.segments:
                K = assemble_beam_stiffness(lay.nodes, el, tube.E_Pa, tube.G_Pa, tube.section, shear=world.shear)
                Kz += T.T @ (K @ T)
        Tt = T[6 * lay.tcp:6 * lay.tcp + 6]           # (6, nz): TCP twist from z
        ndof[i] = Kz.shape[0]
        if piecewise:
            z, torque[i], iterations[i] = _solve_piecewise_drives(world, lay, T, Kz, spring, torsion_col, W)
            u = z @ Tt.T                              # (p + 1, 6)
            out[i] = u[1:] - u[0]                     # the wrenches' part: loaded minus self-weight state
            if gravity:
                sw[i] = u[0]
                out[i] += sw[i]
            continue
        rhs = Tt.T @ W.T
        if gravity:
            rhs = np.c_[rhs, T.T @ _self_weight(world, lay)]
        u = Tt @ sla.cho_solve(sla.cho_factor(Kz), rhs)
        out[i] = u[:, :len(W)].T
        if gravity:
            sw[i] = u[:, -1]
            out[i] += sw[i]
    log.debug("beam world: %d configurations, %d-%d unknowns", len(q), ndof.min(), ndof.max())
    return WorldDeflections(twist=out, self_weight=sw, n_dof=ndof, drive_torque_Nm=torque, iterations=iterations)


def cobot7_world(case, **overrides) -> BeamWorld:
    """The beam world femcheck uses for ``cases/cobot7.toml`` (KUKA LBR iiwa 7 R800 geometry, standing in for
    seed 002's SHIR5). Values are femcheck's choice for a 7-kg-payload cobot of about 24 kg, not measured:

    * links: cast-aluminium tubes, Ø140 x 6 mm (base, links 1-2), Ø120 x 5 mm (links 3-4), Ø100 x 4 mm
      (links 5-6), Ø80 x 4 mm (flange body); the tool: steel Ø50 x 10 mm, flange to TCP;
    * drives: the case's torsion stiffnesses (``stiffness_Nm_per_rad``);
    * bearings: crossed-roller output bearings of the seed's three joint sizes (its Joint32, Joint25, Joint17:
      pitch diameters 110, 90 and 70 mm), with *effective* axial and radial stiffnesses of the bearing with its
      seat and thin-walled housing (1.0e8, 0.6e8, 0.3e8 N/m; tilt 151, 61, 18 kN m/rad). A catalogue bearing
      alone is stiffer. This one scale is the world's free parameter: it is set so that the torsion springs
      give about three quarters of the deflection over Table I, as seed 002 sec. IV-B reports (76.5 %);
    * bearing places: the case's ``tilt_offset_m`` (the case calls them the bearing seats);
    * drive masses 3, 3, 2.5, 2.5, 1.5, 1.5, 0.5 kg (with the tubes and tool, 24.3 kg; the iiwa 7 weighs 23.9 kg).

    ``overrides`` replace :class:`BeamWorld` fields (e.g. ``rigid_links=True``).
    """
    size = {0: (0.110, 1.0e8), 1: (0.110, 1.0e8), 2: (0.090, 0.6e8), 3: (0.090, 0.6e8),
            4: (0.070, 0.3e8), 5: (0.070, 0.3e8), 6: (0.070, 0.3e8)}
    mass = (3.0, 3.0, 2.5, 2.5, 1.5, 1.5, 0.5)
    if case.n_joints != 7:
        raise ValueError(f"cobot7_world: the case has {case.n_joints} joints; expected 7")
    bearings = tuple(Bearing.crossed_roller(j.torsional_stiffness, size[i][0], size[i][1], size[i][1],
                                            offset_m=j.tilt_offset_m, mass_kg=mass[i])
                     for i, j in enumerate(case.joints))
    t140, t120, t100 = Tube(0.140, 0.006), Tube(0.120, 0.005), Tube(0.100, 0.004)
    links = (t140, t140, t140, t120, t120, t100, t100, Tube(0.080, 0.004))
    tool = Tube(0.050, 0.010, E_Pa=210e9, nu=0.3, density_kg_m3=7850.0)
    world = BeamWorld(chain=case.chain, bearings=bearings, links=links, tool=tool,
                      gravity_m_per_s2=tuple(case.gravity_m_per_s2))
    return dataclasses.replace(world, **overrides) if overrides else world
