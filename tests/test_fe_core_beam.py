"""3D beam elements vs closed forms: Timoshenko cantilever, axial, torsion, rigid modes, mass, modal."""
import numpy as np
import pytest

from femcheck.fe import constraints as C
from femcheck.fe.beam import (BeamSection, assemble_beam_mass, assemble_beam_stiffness, beam_dofs, line_mesh,
                              local_frames)
from femcheck.fe.linear_solver import solve
from femcheck.fe.modal import natural_frequencies

E, NU = 210e9, 0.3
G = E / (2 * (1 + NU))
SEC = BeamSection.rectangle(0.03, 0.02, NU)
AXIS = np.array([2.0, -1.0, 2.0]) / 3.0


def _tip_response(n, shear, length=0.2):
    nodes, el = line_mesh([0.1, 0.2, 0.3], np.array([0.1, 0.2, 0.3]) + length * AXIS, n)
    orient = [0.0, 0.0, 1.0]
    R = local_frames(nodes, el, orient)[0][0]
    K = assemble_beam_stiffness(nodes, el, E, G, SEC, orientation=orient, shear=shear)
    c = C.clamp(K.shape[0], beam_dofs([0]))
    tip = beam_dofs([n])[0]
    out = []
    for vec in (R[0], R[1]):
        u = c.expand(solve(c.reduce_matrix(K), c.reduce_vector(C.nodal_wrench(K.shape[0], tip[:3], 100.0 * vec))).x)
        out.append(u[tip[:3]] @ vec)
    return np.array(out)


@pytest.mark.parametrize("n", [1, 3, 10])
def test_cantilever_timoshenko_and_euler_bernoulli(n):
    L, P = 0.2, 100.0
    shear = np.array([P * L / (SEC.kappa_x * G * SEC.A), P * L / (SEC.kappa_y * G * SEC.A)])
    bend = np.array([P * L**3 / (3 * E * SEC.Iy), P * L**3 / (3 * E * SEC.Ix)])
    # nodally exact element: round-off only, for any number of elements
    assert _tip_response(n, True) == pytest.approx(bend + shear, rel=1e-10)
    assert _tip_response(n, False) == pytest.approx(bend, rel=1e-10)


def test_rigid_body_modes_have_no_energy_and_mass_is_exact():
    nodes, el = line_mesh([0, 0, 0], 0.5 * AXIS, 5)
    K = assemble_beam_stiffness(nodes, el, E, G, SEC)
    M = assemble_beam_mass(nodes, el, 7800.0, SEC)
    rb = np.zeros((K.shape[0], 6))
    for i, x in enumerate(nodes):
        d = beam_dofs([i])[0]
        for k in range(3):
            w = np.eye(3)[k]
            rb[d[k], k] = 1.0
            rb[d[:3], 3 + k] = np.cross(w, x)
            rb[d[3:], 3 + k] = w
    assert np.abs(K @ rb).max() <= 1e-12 * abs(K).max()  # round-off
    for k in range(3):  # translational mass ρ A L, exact for the consistent matrix
        assert rb[:, k] @ M @ rb[:, k] == pytest.approx(7800.0 * SEC.A * 0.5, rel=1e-12)


def test_cantilever_first_bending_frequency():
    """Euler–Bernoulli cantilever: ω1 = (1.875104)² sqrt(E I / (ρ A L⁴)) (Timoshenko, Vibration Problems)."""
    L, rho = 1.0, 7800.0
    sec = BeamSection.circle(0.01, NU)
    nodes, el = line_mesh([0, 0, 0], [0, 0, L], 20)
    K = assemble_beam_stiffness(nodes, el, E, G, sec, shear=False)
    M = assemble_beam_mass(nodes, el, rho, sec)
    c = C.clamp(K.shape[0], beam_dofs([0]))
    f = natural_frequencies(c.reduce_matrix(K), c.reduce_matrix(M), 2).frequencies_Hz
    ref = 1.8751040687**2 * np.sqrt(E * sec.Ix / (rho * sec.A * L**4)) / (2 * np.pi)
    # the two bending planes are degenerate; 20 cubic elements converge as h^4: < 1e-6
    assert f == pytest.approx([ref, ref], rel=1e-6)


def test_bad_orientation_is_rejected():
    nodes, el = line_mesh([0, 0, 0], [0, 0, 1], 2)
    with pytest.raises(ValueError, match="parallel"):
        local_frames(nodes, el, [0, 0, 1])
