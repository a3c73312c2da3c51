"""Shared fixtures. Tests run from the repository root (pytest's rootdir)."""
from __future__ import annotations

import os
from pathlib import Path

import pytest

os.environ.setdefault("MPLBACKEND", "Agg")
os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")

ROOT = Path(__file__).resolve().parents[1]
REFERENCE_CASE = ROOT / "cases" / "haptic_6psu.toml"
SHARED_REFERENCE = ROOT.parent / "shared" / "reference" / "haptic_6psu.toml"


@pytest.fixture(scope="session")
def case():
    import femcheck
    return femcheck.load_case(REFERENCE_CASE)


@pytest.fixture(scope="session")
def coarse_p0_fe_models(case):
    """The detailed device FE at P0 on the coarse mesh ({point: PointModel}: meshes and condensed
    super-elements), built once per session: the coverage and joint-law tests both solve on it (models are
    immutable; a law mutation or a joint law changes only the dense leg algebra solved on top)."""
    from femcheck.verify.fe import run_fe
    return run_fe(case, ("P0",), levels=("detailed",), mesh="coarse").models


@pytest.fixture(scope="session")
def rigid_chain(case):
    """The reference case's detailed analytical chain with rigid joint rotations, as a diagnosis's reading model."""
    from femcheck.diagnose import AnalyticalChainModel
    return AnalyticalChainModel(case, "detailed", "rigid")


@pytest.fixture(scope="session")
def points(case):
    import femcheck
    return femcheck.test_points(case)


@pytest.fixture(scope="session")
def isolated_mesh_cache(tmp_path_factory):
    """Mesh cache in a temporary folder, so geometry tests neither read nor fill the user's cache."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("FEMCHECK_CACHE", str(tmp_path_factory.mktemp("meshes")))
        yield


def assert_same_tables(t1, t2):
    """Two pyarrow result tables are equal column by column, bit for bit (identical inputs through the same
    deterministic code in any process must give identical results)."""
    import numpy as np
    a = {c: np.asarray(t1.column(c).to_numpy(zero_copy_only=False)) for c in t1.column_names}
    b = {c: np.asarray(t2.column(c).to_numpy(zero_copy_only=False)) for c in t2.column_names}
    assert a.keys() == b.keys()
    for c in a:
        np.testing.assert_array_equal(a[c], b[c], err_msg=c)


def sparse_actuation_readings():
    """(model, readings): the detailed rigid model and a sparse generated set (actuation compliance x 1.5, points P0 and
    P6, +z and +x, 3 trials, no sweep): sigma comes from the trial scatter (sigma_dof > 0) and the rivals' posterior is
    not all 0 or 1. Shared by the evidence tests that weigh one diagnosis several ways."""
    import dataclasses as dc

    import numpy as np

    import femcheck
    from femcheck.diagnose import AnalyticalChainModel
    from femcheck.experiment.simulate import simulate
    from femcheck.measured import process
    case = femcheck.load_case(REFERENCE_CASE)
    model = AnalyticalChainModel(case, "detailed", "rigid")
    data = simulate(case, [("actuation_compliance", {"scale": 1.5})], seed=4, directions=("+z", "+x"), sweep=False).data
    keep = np.isin(data.point, ["P0", "P6"])
    data = dc.replace(data, **{f: getattr(data, f)[keep] for f in
                               ("point", "direction", "trial", "phase", "load_N", "force", "disp", "row")})
    return model, process(data, case)


def clamped_steel_bar(n_along: int, n_across: int, order: int):
    """(basis, K, constraints) of a 100 x 20 x 20 mm steel bar (E = 210 GPa, nu = 0.3) clamped at x = 0: a tensor
    tetrahedral mesh with ``n_along`` x ``n_across`` x ``n_across`` nodes and Lagrange elements of ``order``. The
    linear-solver tests' symmetric positive definite system once reduced."""
    import numpy as np
    import skfem

    from femcheck.fe import constraints
    from femcheck.fe.elasticity import assemble_stiffness, vector_basis
    across = np.linspace(0, 0.02, n_across)
    basis = vector_basis(skfem.MeshTet.init_tensor(np.linspace(0, 0.1, n_along), across, across), order)
    K = assemble_stiffness(basis, 210e9, 0.3)
    return basis, K, constraints.clamp(basis.N, basis.get_dofs(lambda x: np.isclose(x[0], 0.0)).all())
