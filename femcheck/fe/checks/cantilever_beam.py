"""``cantilever-beam``: 3D Timoshenko beam elements vs Timoshenko beam theory.

Rectangular steel beam 30 × 20 mm (local x × y), L = 200 mm, laid along the skew direction (1, 2, 2)/3 so
that the element frames and the global transformation are exercised; clamped at node 0, a 100 N tip
force along local x (bending about local y, the stiffer axis here: I_y = h b³/12).
Reference: δ = P L³/(3 E I_y) + P L/(κ G A), κ = 10(1+ν)/(12+11ν) (Cowper). The two-node Timoshenko
element is nodally exact for end loads, so the error is round-off at any number of elements; the
detail also reports the other bending plane, the axial and the torsional tip displacements.
"""
from __future__ import annotations

import time

import numpy as np

from femcheck.fe import constraints
from femcheck.fe.beam import BeamSection, assemble_beam_stiffness, beam_dofs, line_mesh, local_frames
from femcheck.fe.checks import CheckResult
from femcheck.fe.linear_solver import factorize

NAME = "cantilever-beam"
#: relative error accepted at each mesh level (``femcheck check-solver`` fails above it)
TOLERANCE = {"coarse": 1e-10, "default": 1e-10, "fine": 1e-10}
TOLERANCE_REASON = "cubic Hermite beam elements are exact for a tip load: round-off only"
E, NU, L, P = 210e9, 0.3, 0.200, 100.0
AXIS = np.array([1.0, 2.0, 2.0]) / 3.0
ORIENT = np.array([0.0, 0.0, 1.0])
MESHES = {"coarse": 2, "default": 8, "fine": 32}


def run(mesh: str = "default") -> CheckResult:
    t0 = time.perf_counter()
    n = MESHES[mesh]
    G = E / (2 * (1 + NU))
    sec = BeamSection.rectangle(0.030, 0.020, NU)
    nodes, el = line_mesh([0, 0, 0], L * AXIS, n)
    R = local_frames(nodes, el, ORIENT)[0][0]
    K = assemble_beam_stiffness(nodes, el, E, G, sec, orientation=ORIENT)
    c = constraints.clamp(K.shape[0], beam_dofs([0]))
    fac = factorize(c.reduce_matrix(K))
    tip = beam_dofs([n])[0]
    loads = np.zeros((K.shape[0], 4))
    loads[tip[:3], 0] = P * R[0]            # local x force
    loads[tip[:3], 1] = P * R[1]            # local y force
    loads[tip[:3], 2] = P * R[2]            # axial force
    loads[tip[3:], 3] = 10.0 * R[2]         # 10 N·m torque about the axis
    U = c.expand(fac.solve(c.T.T @ loads))
    got = np.array([U[tip[:3], 0] @ R[0], U[tip[:3], 1] @ R[1], U[tip[:3], 2] @ R[2], U[tip[3:], 3] @ R[2]])
    ref = np.array([P * L**3 / (3 * E * sec.Iy) + P * L / (sec.kappa_x * G * sec.A),
                    P * L**3 / (3 * E * sec.Ix) + P * L / (sec.kappa_y * G * sec.A),
                    P * L / (E * sec.A), 10.0 * L / (G * sec.J)])
    rel = np.abs(got - ref) / np.abs(ref)
    return CheckResult(name=NAME, quantity="tip deflection along local x (m)", computed=float(got[0]),
                       reference=float(ref[0]), dofs=K.shape[0], iterations=fac.iterations,
                       seconds=time.perf_counter() - t0,
                       detail={"solver": fac.method, "elements": n,
                               "rel_error_local_y": float(rel[1]), "rel_error_axial": float(rel[2]),
                               "rel_error_torsion": float(rel[3])})
