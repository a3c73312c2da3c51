"""Structured, graded tetrahedral meshes of extruded sections (deterministic, exact on analytic surfaces).

A plane section (triangles) is built from nested star-shaped rings (a disk, an annulus, a rectangle with
a bore); it is extruded through layers whose height may vary with (x, y) (a spherical socket under a
flat top); each triangular prism is split into three tetrahedra by the global-index rule (diagonal of a
side quad from its lowest-numbered bottom node), which is conforming across neighbouring prisms
(Dompierre et al. 1999, "How to subdivide pyramids, prisms and hexahedra into tetrahedra"). Ring
nodes lie exactly on the circles and planes of the geometry, so contact surfaces carry no meshing
error. Grading (finer toward a contact) is a geometric progression of ring radii / layer heights.
"""
from __future__ import annotations

import math
from typing import Callable

import numpy as np

TWO_PI = 2.0 * math.pi


def graded_levels(a: float, b: float, h_a: float, h_b: float, h_max: float | None = None) -> np.ndarray:
    """Levels from a to b (a < b) with spacing growing linearly from about h_a at a to h_b at b.

    The spacing h(x) = min(h_max, h_a + (h_b - h_a) (x - a) / (b - a)) is integrated and rounded to a
    whole number of cells; returns the (k,) increasing array including a and b exactly.
    """
    if not b > a:
        raise ValueError(f"graded_levels: expected a < b, got a={a}, b={b}")
    h_max = max(h_a, h_b) if h_max is None else h_max
    xs = np.linspace(a, b, 2001)
    h = np.minimum(h_max, h_a + (h_b - h_a) * (xs - a) / (b - a))
    cum = np.concatenate([[0.0], np.cumsum(np.diff(xs) / (0.5 * (h[1:] + h[:-1])))])
    n = max(1, int(round(cum[-1])))
    return np.interp(np.linspace(0.0, cum[-1], n + 1), cum, xs)


def symmetric_levels(a: float, b: float, h_end: float, h_mid: float) -> np.ndarray:
    """Levels from a to b, fine (h_end) at both ends and coarser (h_mid) in the middle."""
    m = 0.5 * (a + b)
    lo = graded_levels(a, m, h_end, h_mid)
    hi = m + (m - lo[::-1])
    return np.concatenate([lo, hi[1:]])


def levels_with_zones(a: float, b: float, zones: list[tuple[float, float]], h_fine: float, h: float, grading: float) -> np.ndarray:
    """Levels on [a, b] with spacing h_fine inside the zones [(lo, hi), ...] and growing by ``grading``
    (dh/dx) away from them up to h. Zone ends are levels exactly."""
    breaks = sorted({a, b, *[max(a, min(b, v)) for z in zones for v in z]})
    out = [np.array([a])]
    for lo, hi in zip(breaks[:-1], breaks[1:]):
        mid = 0.5 * (lo + hi)
        inside = any(z0 - 1e-15 <= mid <= z1 + 1e-15 for z0, z1 in zones)
        if inside:
            n = max(1, math.ceil((hi - lo) / h_fine - 1e-9))
            seg = np.linspace(lo, hi, n + 1)
        else:
            lo_fine = any(abs(lo - v) < 1e-15 for z in zones for v in z)
            hi_fine = any(abs(hi - v) < 1e-15 for z in zones for v in z)
            length = hi - lo
            if lo_fine and hi_fine:
                seg = symmetric_levels(lo, hi, h_fine, min(h, h_fine + grading * length / 2))
            elif lo_fine:
                seg = graded_levels(lo, hi, h_fine, min(h, h_fine + grading * length), h)
            elif hi_fine:
                seg = hi - graded_levels(0.0, length, h_fine, min(h, h_fine + grading * length), h)[::-1]
                seg[0] = lo
            else:
                seg = np.linspace(lo, hi, max(1, math.ceil(length / h - 1e-9)) + 1)
        out.append(seg[1:])
    return np.concatenate(out)


# -- plane sections --------------------------------------------------------------------------------
def ring_angles(n: int, extra: np.ndarray | None = None) -> np.ndarray:
    """n equally spaced angles in [0, 2 pi) starting at 0, merged with ``extra`` angles (e.g. corners);
    uniform angles closer than 0.3 steps to an extra one are dropped (no slivers, no duplicates)."""
    th = np.arange(n) * (TWO_PI / n)
    if extra is None or not len(extra):
        return th
    ex = np.mod(np.asarray(extra, float), TWO_PI)
    d = np.abs((th[:, None] - ex[None, :] + math.pi) % TWO_PI - math.pi)
    th = th[(d >= 0.3 * TWO_PI / n).all(axis=1) | (th == 0.0)]
    ex = ex[np.abs((ex + math.pi) % TWO_PI - math.pi) > 1e-12]  # angle 0 is always the first node
    return np.sort(np.concatenate([th, ex]))


def zip_rings(ia: np.ndarray, ta: np.ndarray, ib: np.ndarray, tb: np.ndarray) -> np.ndarray:
    """Triangles filling the band between two closed rings, each given by node ids and sorted angles
    starting at 0. Advances along whichever ring has the next smaller angle (merge of the two
    angle sequences), vectorized. Returns (k, 3) node ids (orientation fixed later)."""
    na, nb = len(ia), len(ib)
    ta_next = np.append(ta[1:], TWO_PI)
    tb_next = np.append(tb[1:], TWO_PI)
    ev_t = np.concatenate([ta_next, tb_next])
    ev_is_a = np.concatenate([np.ones(na, bool), np.zeros(nb, bool)])
    order = np.lexsort((~ev_is_a, ev_t))  # by angle, ring a first on ties
    is_a = ev_is_a[order]
    i = np.concatenate([[0], np.cumsum(is_a)[:-1]])
    j = np.concatenate([[0], np.cumsum(~is_a)[:-1]])
    a0, a1 = ia[i % na], ia[(i + 1) % na]
    b0, b1 = ib[j % nb], ib[(j + 1) % nb]
    return np.where(is_a[:, None], np.stack([a0, a1, b0], 1), np.stack([a0, b1, b0], 1))


def ring_section(inner: Callable[[np.ndarray], np.ndarray] | None, outer: Callable[[np.ndarray], np.ndarray],
                 t_levels: np.ndarray, counts: list[int], extra_angles: np.ndarray | None = None):
    """A plane section between an inner closed curve (None: a point at the origin, i.e. a disk) and an
    outer one, both star-shaped about the origin and given as functions angle (k,) -> points (k, 2).

    Ring j (t = t_levels[j], 0 = inner, 1 = outer) is the blend (1 - t) inner(theta) + t outer(theta)
    sampled at ``counts[j]`` angles (plus ``extra_angles``, e.g. corners, on rings with t > 1/2). Returns
    (points (n, 2), triangles (m, 3) counter-clockwise, ring_ids list of node-id arrays).
    """
    pts, rings, angs = [], [], []
    start = 0
    if inner is None:
        pts.append(np.zeros((1, 2)))
        rings.append(np.array([0]))
        angs.append(np.array([0.0]))
        start = 1
        t_levels = t_levels[1:] if t_levels[0] == 0.0 else t_levels
        counts = counts[1:] if len(counts) == len(t_levels) + 1 else counts
    n0 = start
    for t, n in zip(t_levels, counts):
        th = ring_angles(n, extra_angles if t > 0.5 else None)  # corners only where the ring is near the outline
        p_in = np.zeros((len(th), 2)) if inner is None else inner(th)
        p = (1.0 - t) * p_in + t * outer(th)
        pts.append(p)
        rings.append(np.arange(n0, n0 + len(th)))
        angs.append(th)
        n0 += len(th)
    points = np.vstack(pts)
    tris = []
    for k in range(len(rings) - 1):
        if len(rings[k]) == 1:  # fan around the centre
            r = rings[k + 1]
            tris.append(np.stack([np.full(len(r), rings[k][0]), r, np.roll(r, -1)], 1))
        else:
            tris.append(zip_rings(rings[k], angs[k], rings[k + 1], angs[k + 1]))
    tris = np.vstack(tris)
    a, b, c = points[tris[:, 0]], points[tris[:, 1]], points[tris[:, 2]]
    area2 = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    tris = np.where((area2 < 0)[:, None], tris[:, [0, 2, 1]], tris)
    tris = tris[np.abs(area2) > 1e-30 * max(1.0, np.abs(points).max() ** 2)]
    return points, tris, rings


def circle(r: float) -> Callable[[np.ndarray], np.ndarray]:
    return lambda th: r * np.stack([np.cos(th), np.sin(th)], 1)


def rectangle(x0: float, x1: float, y0: float, y1: float) -> tuple[Callable[[np.ndarray], np.ndarray], np.ndarray]:
    """Boundary of the rectangle [x0, x1] x [y0, y1] (contains the origin) as a function of the angle seen
    from the origin (ray intersection), and its corner angles."""
    def f(th):
        c, s = np.cos(th), np.sin(th)
        with np.errstate(divide="ignore"):
            tx = np.where(c > 0, x1 / np.where(c == 0, 1, c), np.where(c < 0, x0 / np.where(c == 0, 1, c), np.inf))
            ty = np.where(s > 0, y1 / np.where(s == 0, 1, s), np.where(s < 0, y0 / np.where(s == 0, 1, s), np.inf))
        t = np.minimum(tx, ty)
        return np.stack([t * c, t * s], 1)
    corners = np.arctan2([y0, y0, y1, y1], [x1, x0, x0, x1])
    return f, corners


def rect_grid(x: np.ndarray, y: np.ndarray):
    """Structured triangulation of the grid x (i,) by y (j,): points (i j, 2), triangles (2 (i-1)(j-1), 3)."""
    X, Y = np.meshgrid(x, y, indexing="ij")
    pts = np.stack([X.ravel(), Y.ravel()], 1)
    ni, nj = len(x), len(y)
    idx = np.arange(ni * nj).reshape(ni, nj)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    tris = np.vstack([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    return pts, tris


# -- extrusion -------------------------------------------------------------------------------------
def extrude(points2: np.ndarray, tris: np.ndarray, zeta: np.ndarray,
            z_bottom: Callable[[np.ndarray], np.ndarray] | float, z_top: Callable[[np.ndarray], np.ndarray] | float):
    """Extrude a plane section (points (n, 2), triangles (m, 3)) into tetrahedra.

    Layer k sits at z = z_b(x, y) + zeta[k] (z_t(x, y) - z_b(x, y)), zeta increasing from 0 to 1, so the
    bottom and top may be curved (z_t > z_b required). Returns (points (n K, 3), tets (3 m (K-1), 4)),
    tets positively oriented.
    """
    n, K = len(points2), len(zeta)
    zb = z_bottom(points2) if callable(z_bottom) else np.full(n, float(z_bottom))
    zt = z_top(points2) if callable(z_top) else np.full(n, float(z_top))
    if np.any(zt <= zb):
        raise ValueError("extrude: top surface must lie above the bottom surface everywhere")
    z = zb[None, :] + np.asarray(zeta)[:, None] * (zt - zb)[None, :]
    pts = np.concatenate([np.repeat(points2[None], K, 0), z[:, :, None]], axis=2).reshape(-1, 3)
    s = np.sort(tris, axis=1)  # A < B < C by global id (same order in every layer)
    A, B, C = s[:, 0], s[:, 1], s[:, 2]
    layers = np.arange(K - 1)[:, None] * n
    A0, B0, C0 = A[None] + layers, B[None] + layers, C[None] + layers
    A1, B1, C1 = A0 + n, B0 + n, C0 + n
    tets = np.concatenate([np.stack([A0, B0, C0, C1], -1).reshape(-1, 4),
                           np.stack([A0, B0, B1, C1], -1).reshape(-1, 4),
                           np.stack([A0, A1, B1, C1], -1).reshape(-1, 4)])
    return pts, orient_positive(pts, tets)


def orient_positive(points: np.ndarray, tets: np.ndarray) -> np.ndarray:
    """Swap two nodes of every negatively oriented tetrahedron."""
    a, b, c, d = (points[tets[:, i]] for i in range(4))
    vol = np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a)
    return np.where((vol < 0)[:, None], tets[:, [0, 2, 1, 3]], tets)


def box(x: np.ndarray, y: np.ndarray, z: np.ndarray):
    """Tetrahedra of the box grid x by y by z (each a sorted level array): (points, tets)."""
    p2, t2 = rect_grid(x, y)
    return extrude(p2, t2, (z - z[0]) / (z[-1] - z[0]), float(z[0]), float(z[-1]))


def n_around(radius: float, h: float, minimum: int = 48) -> int:
    """Angular node count on a circle of ``radius`` for edge length about h; at least ``minimum`` so that
    the polygon area is within (2 pi / n)^2 / 6 = 0.29 % (n = 48) of the circle's."""
    return max(minimum, int(math.ceil(TWO_PI * radius / h)))


# -- ball: cubed sphere with refining transition layers ----------------------------------------------
def prism_tets(tris: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Tetrahedra of the prisms between a triangulated layer and the next one (same triangles).

    tris : (k, 3) local node indices of the layer; lo, hi : local index -> node id in the lower / upper layer.
    Each prism is split into three tetrahedra by the global-index rule on the *local* index (the diagonal of
    a side quad starts at its lower-index bottom node), so neighbouring prisms agree on every side quad.
    Orientation is not fixed here (see :func:`orient_positive`)."""
    s = np.sort(tris, axis=1)
    A, B, C = s[:, 0], s[:, 1], s[:, 2]
    A0, B0, C0, A1, B1, C1 = lo[A], lo[B], lo[C], hi[A], hi[B], hi[C]
    return np.vstack([np.stack([A0, B0, C0, C1], 1), np.stack([A0, B0, B1, C1], 1), np.stack([A0, A1, B1, C1], 1)])


def red_refine(tris: np.ndarray, n_nodes: int):
    """Split every triangle (local indices < n_nodes) into four at its edge midpoints.

    Returns (edges (e, 2) sorted node pairs, mids (k, 3) local index of the midpoint of edges 01, 12, 20 of
    each triangle (n_nodes + edge number), fine triangles (4 k, 3) with the orientation of their parent)."""
    k = len(tris)
    e = np.sort(np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]]), axis=1)
    edges, inv = np.unique(e, axis=0, return_inverse=True)
    inv = np.asarray(inv).ravel()
    m01, m12, m20 = n_nodes + inv[:k], n_nodes + inv[k:2 * k], n_nodes + inv[2 * k:]
    fine = np.vstack([np.stack([tris[:, 0], m01, m20], 1), np.stack([tris[:, 1], m12, m01], 1),
                      np.stack([tris[:, 2], m20, m12], 1), np.stack([m01, m12, m20], 1)])
    return edges, np.stack([m01, m12, m20], 1), fine


def transition_tets(tris: np.ndarray, mids: np.ndarray, lo: np.ndarray, hi: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Tetrahedra of a 1:2 transition layer: each coarse triangle abc (ids ``lo``) below its red refinement
    (ids ``hi``; ``mids`` from :func:`red_refine`) above. Seven tets per cell: three corner tets
    (a, a', m_ab', m_ca') and the octahedron a b c | m_ab' m_bc' m_ca', split along its shortest
    vertex-to-opposite-midpoint diagonal. Each side face (a, b | a', m_ab', b') is split as the fan from
    m_ab', whichever cell it belongs to, so neighbouring cells conform."""
    corners = [np.stack([lo[tris[:, i]], hi[tris[:, i]], hi[mids[:, i]], hi[mids[:, (i + 2) % 3]]], 1) for i in range(3)]
    opposite = (1, 2, 0)  # vertex 0 faces the midpoint of edge 12, 1 of 20, 2 of 01
    diag = np.stack([np.linalg.norm(points[lo[tris[:, i]]] - points[hi[mids[:, opposite[i]]]], axis=1) for i in range(3)], 1)
    k = np.argmin(diag, axis=1)
    rot = (k[:, None] + np.arange(3)[None]) % 3
    a, b, c = (lo[np.take_along_axis(tris, rot[:, [j]], 1)[:, 0]] for j in range(3))
    mab, mbc, mca = (hi[np.take_along_axis(mids, rot[:, [j]], 1)[:, 0]] for j in range(3))
    octahedron = [np.stack([a, b, mab, mbc], 1), np.stack([a, mbc, mab, mca], 1), np.stack([a, c, mbc, mca], 1),
                  np.stack([a, b, mbc, c], 1)]
    return np.vstack(corners + octahedron)


#: layers of the ball shell from the core surface (t = 0) to the sphere (t = 1): prism layer ("p") or
#: 1:2 refining transition ("r"), each with the t where it ends. Chosen for the minimum dihedral angle
#: (about 25 deg before contact refinement) at the fewest tetrahedra.
BALL_SHELL = (("p", 0.35), ("r", 0.6), ("p", 0.8), ("r", 1.0))


def cubed_ball(radius: float, n_core: int, *, core_fraction: float = 0.4, inflate: float = 0.55,
               shell=BALL_SHELL) -> tuple[np.ndarray, np.ndarray]:
    """Structured tetrahedral mesh of the ball |x| <= radius (centre at the origin), deterministic.

    Core: a box of half side ``core_fraction * radius`` with ``n_core`` cells per edge at equiangular
    positions (a tan(xi)), split by :func:`box`, inflated toward a sphere by ``inflate`` (0: cube, 1: sphere)
    so that the shell is not thin at the cube corners. Shell: the core's boundary triangles are carried
    outward along the rays from the centre through ``shell`` (prism layers and 1:2 transition layers, see
    :data:`BALL_SHELL`), so the surface has ``n_core * 2**(number of transitions)`` cells per cube-face
    edge, every surface node lies exactly on the sphere (up to round-off), and the cubed-sphere face of -z
    is centred on (0, 0, -radius). Returns (points (n, 3), tets (m, 4)) positively oriented; raises
    ValueError if a tetrahedron would be degenerate or the mesh folds over itself."""
    if n_core < 1:
        raise ValueError(f"cubed_ball: n_core = {n_core}; expected >= 1")
    a = core_fraction * radius
    u = a * np.tan(np.linspace(-math.pi / 4, math.pi / 4, n_core + 1))
    u[0], u[-1] = -a, a
    if n_core % 2 == 0:
        u[n_core // 2] = 0.0
    pc, tc = box(u, u, u)
    n_inf = np.abs(pc).max(axis=1)
    n_2 = np.linalg.norm(pc, axis=1)
    safe = np.where(n_2 > 0, n_2, 1.0)
    pc = pc * np.where(n_2 > 0, (1.0 - inflate) + inflate * n_inf / safe, 1.0)[:, None]
    tc = orient_positive(pc, tc)
    from geometry.regions import boundary_facets
    bf = boundary_facets(tc)
    bnodes = np.unique(bf)
    local = np.full(len(pc), -1)
    local[bnodes] = np.arange(len(bnodes))
    tris, base = local[bf], pc[bnodes]  # triangles of the core surface; their nodes (the rays' feet)

    def layer(feet, t):
        r0 = np.linalg.norm(feet, axis=1)
        return (r0 + t * (radius - r0))[:, None] * (feet / r0[:, None])

    points, tets = [pc], [tc]
    lo, n_id = bnodes, len(pc)
    for kind, t in shell:
        if kind == "r":
            edges, mids, fine = red_refine(tris, len(base))
            base = np.vstack([base, 0.5 * (base[edges[:, 0]] + base[edges[:, 1]])])
        hi = np.arange(n_id, n_id + len(base))
        n_id += len(base)
        points.append(layer(base, t))
        if kind == "p":
            tets.append(prism_tets(tris, lo, hi))
        else:
            tets.append(transition_tets(tris, mids, lo, hi, np.vstack(points)))
            tris = fine
        lo = hi
    p, t = np.vstack(points), np.vstack(tets)
    t = orient_positive(p, t)
    check_covering(p, t, "cubed_ball")
    return p, t


def check_covering(points: np.ndarray, tets: np.ndarray, what: str = "mesh") -> None:
    """Raise ValueError unless the (positively oriented) tets are non-degenerate and cover the solid bounded
    by their boundary exactly once: the sum of their volumes equals the volume enclosed by the boundary
    facets (divergence theorem). A folded or overlapping mesh fails the second test."""
    from geometry.regions import boundary_facets
    a, b, c, d = (points[tets[:, i]] for i in range(4))
    vol = np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a) / 6.0
    scale = float(np.abs(points).max()) ** 3
    if np.any(vol <= 1e-14 * scale):
        raise ValueError(f"{what}: {(vol <= 1e-14 * scale).sum()} degenerate tetrahedra")
    f = boundary_facets(tets)
    x, y, z = (points[f[:, i]] for i in range(3))
    enclosed = float(np.einsum("ij,ij->i", x, np.cross(y, z)).sum() / 6.0)
    if abs(vol.sum() - enclosed) > 1e-9 * max(abs(enclosed), scale):
        raise ValueError(f"{what}: the tetrahedra fold over each other (volume {vol.sum():.6g} vs enclosed {enclosed:.6g})")
