"""No scikit-fem "Transforming over 1000 vertices/elements to C_CONTIGUOUS" warning from femcheck's meshes.

scikit-fem logs it (``skfem.mesh.mesh``, WARNING) whenever a mesh is built from arrays that are not in C order
and have more than 1000 columns. ``make verify`` printed it from the ball's graded bisection
(geometry.subdivision, where scikit-fem's own adaptive refinement slices its work arrays); the meshes femcheck
builds itself pass C-ordered arrays. Each test builds meshes above the 1000 threshold and fails on the notice.
"""
from __future__ import annotations

import logging

import numpy as np
import pytest
import skfem

NOTICE = "C_CONTIGUOUS"


def _notices(caplog):
    return [r.getMessage() for r in caplog.records if NOTICE in r.getMessage()]


@pytest.fixture
def grid():
    """(points (n, 3), tets (m, 4)) of a 12³-cell box: 2197 vertices, 10368 tets (over the 1000 threshold)."""
    x = np.linspace(0.0, 1.0, 13)
    m = skfem.MeshTet.init_tensor(x, x, x)
    return np.ascontiguousarray(m.p.T), np.ascontiguousarray(m.t.T).astype(np.int64)


def test_bare_scikit_fem_bisection_does_log_the_notice(grid, caplog):
    """The detector works: scikit-fem's adaptive refinement called directly logs the notice (scikit-fem 12)."""
    p, t = grid
    with caplog.at_level(logging.WARNING):
        skfem.MeshTet(np.ascontiguousarray(p.T), np.ascontiguousarray(t.T)).refined(np.arange(0, t.shape[0], 2))
    if not _notices(caplog):
        pytest.skip("this scikit-fem version does not log the notice on adaptive refinement")


def test_femcheck_bisection_logs_no_notice_and_refines(grid, caplog):
    from geometry.subdivision import bisect, refine_to_size
    p, t = grid
    marked = np.arange(0, t.shape[0], 2)
    with caplog.at_level(logging.WARNING):
        m = bisect(p, t, marked)
        p2, t2 = refine_to_size(p, t, lambda c: np.where(c[:, 0] < 0.3, 0.05, 1.0), part="test", parameters={})
    assert _notices(caplog) == []
    assert m.t.shape[1] > t.shape[0] and len(t2) > len(t)
    # the filter is scoped to the call: the logger is left as it was
    assert logging.getLogger("skfem.mesh.mesh").filters == []


def test_ball_mesh_logs_no_notice(case, caplog, isolated_mesh_cache):
    """The mesh that printed the notice in ``make verify``: the graded cubed-sphere ball of the spherical joint."""
    from geometry import spherical_joint
    with caplog.at_level(logging.WARNING):
        pm = spherical_joint.build(case, 0.0015, use_cache=False)
        mesh = pm.to_skfem()
    assert mesh.p.shape[1] > 1000
    assert _notices(caplog) == []


def test_fe_check_meshes_log_no_notice(caplog):
    from femcheck.fe.checks import contact_patch, hertz_sphere
    from femcheck.fe.checks._graded_mesh import radial_box, radial_slab
    with caplog.at_level(logging.WARNING):
        meshes = [hertz_sphere.make_mesh("coarse", g)[0] for g in hertz_sphere.GEOMETRIES]
        meshes += [contact_patch.two_blocks(8)[0], radial_box(1.0, 12, 0.01, 3), radial_slab(1.0, 40, 0.01, 5, 0.01)]
    assert max(m.p.shape[1] for m in meshes) > 1000
    assert _notices(caplog) == []
