"""VTU output (meshio round trip) and the off-screen picture helper."""
import meshio
import numpy as np
import pytest
import skfem

from femcheck.fe.elasticity import vector_basis
from femcheck.fe.results import ElasticResult, write_point_cloud_vtu


def _uniaxial():
    mesh = skfem.MeshTet.init_tensor(np.linspace(0, 1, 5), np.linspace(0, 0.2, 2), np.linspace(0, 0.2, 2))
    basis = vector_basis(mesh, 2)
    strain = 1e-3
    u = np.zeros(basis.N)
    u[0::3] = strain * basis.doflocs[0, 0::3]  # u_x = ε x, ν = 0: uniaxial stress E ε
    return mesh, basis, u, 200e9 * strain


def test_vtu_round_trip(tmp_path):
    mesh, basis, u, sigma = _uniaxial()
    status = np.arange(mesh.p.shape[1]) % 3
    res = ElasticResult(basis, u, 200e9, 0.0, point_data={"contact_status": status})
    path = res.write_vtu(tmp_path / "r.vtu")
    back = meshio.read(path)
    assert back.points.shape == (mesh.p.shape[1], 3)
    assert np.allclose(back.point_data["displacement_m"][:, 0], 1e-3 * mesh.p[0], rtol=0, atol=1e-15)
    # uniform uniaxial stress: von Mises = σ everywhere, to round-off
    assert np.allclose(back.cell_data["von_mises_Pa"][0], sigma, rtol=1e-9)
    assert np.array_equal(back.point_data["contact_status"], status)
    assert not list(tmp_path.glob(".*"))  # no temporary left behind (atomic write)
    with pytest.raises(ValueError, match="vertices"):
        ElasticResult(basis, u, 200e9, 0.0, point_data={"p": np.zeros(3)}).to_meshio()


def test_point_cloud(tmp_path):
    p = write_point_cloud_vtu(tmp_path / "gp.vtu", np.random.rand(7, 3), {"contact_pressure_Pa": np.arange(7.0)})
    assert np.array_equal(meshio.read(p).point_data["contact_pressure_Pa"], np.arange(7.0))


def test_png(tmp_path):
    from femcheck.fe.picture import render_png
    mesh, basis, u, _ = _uniaxial()
    vtu = ElasticResult(basis, u, 200e9, 0.0).write_vtu(tmp_path / "r.vtu")
    pic = render_png(vtu, tmp_path / "r.png", warp=50.0, title="uniaxial")
    data = pic.path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 5000
    assert pic.renderer in ("pyvista", "matplotlib")
    with pytest.raises(ValueError, match="not in the result"):
        render_png(vtu, tmp_path / "x.png", scalars="nope")
