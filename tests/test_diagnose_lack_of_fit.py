"""The structured lack-of-fit test of ``femcheck.diagnose.lack_of_fit``: a compliance-shaped
residual per (point, direction) against the pure error of the same subspace."""
import numpy as np
import pytest

from femcheck.diagnose.effects import get_effect
from femcheck.diagnose.fitting import fit_effects
from femcheck.diagnose.lack_of_fit import discrepancy_basis, structured_lack_of_fit
from femcheck.diagnose.model import predict_readings
from femcheck.experiment.simulate import simulate
from femcheck.measured import process

FAST = ("+x", "+y", "+z")


@pytest.fixture(scope="module")
def model(rigid_chain):
    return rigid_chain


@pytest.fixture(scope="module")
def clean(case):
    return process(simulate(case, [], seed=2, directions=FAST).data, case)


def test_projection_of_one_column_is_its_chi2(clean):
    # a residual that is exactly one discrepancy column (group 0, axis x: c |F| / sigma) projects onto itself:
    # T = the sum of its squares (exact projection)
    B = discrepancy_basis(clean, "case")
    resid = 3.0 * B[:, :, 0] / clean.sigma
    lof = structured_lack_of_fit(clean, clean.disp + resid * clean.sigma)
    assert lof.chi2 == pytest.approx(float(np.sum(resid ** 2)), rel=1e-10)
    assert lof.n_columns == 3 * len(set(zip(clean.point, clean.direction)))   # 3 axes per (point, direction)
    # the smooth space: 5 functions of the pose per direction and axis (9 poses, 3 directions: 45 columns)
    sm = structured_lack_of_fit(clean, clean.disp + resid * clean.sigma, kind="smooth")
    assert sm.n_columns == 3 * 3 * 5 and sm.chi2 <= lof.chi2 * (1 + 1e-12)   # a projection on a smaller space


def test_the_fit_absorbs_exactly_the_columns_its_jacobian_spans(clean):
    # a Jacobian spanning two discrepancy columns: tr(P_S H) = 2, so dof = m_S - 2 (hat-matrix trace, exact)
    B = discrepancy_basis(clean, "case") / clean.sigma[:, :, None]
    J = np.column_stack([B[:, :, 3].ravel(), 5.0 * B[:, :, 7].ravel()])   # any scale
    lof = structured_lack_of_fit(clean, clean.disp, jacobian=J)
    assert lof.dof == pytest.approx(lof.n_columns - 2, abs=1e-9)
    # a Jacobian orthogonal to every column (an offset on the 0 N unload states) absorbs nothing
    J0 = np.repeat(np.linalg.norm(clean.force, axis=1) == 0, 3).astype(float)[:, None]
    assert structured_lack_of_fit(clean, clean.disp, jacobian=J0).dof == pytest.approx(lof.n_columns, abs=1e-9)


def test_true_model_passes_and_pure_error_sees_the_quantization(case, model):
    # the model that made the data: the test must not fire (alpha 1e-3) on any of 4 seeds; kappa (the pure error
    # of the subspace over what the pooled sigma predicts) stays within a factor 2 of 1 (81 dof: +- 0.16 sd)
    for seed in range(4):
        r = process(simulate(case, [], seed=seed, directions=FAST).data, case)
        pred = fit_effects(model, r, []).predicted
        for kind in ("case", "smooth"):
            lof = structured_lack_of_fit(r, pred, sigma_dof=r.sigma_dof, kind=kind)
            assert lof.p_value > 1e-3, (seed, lof)
            assert 0.5 < lof.pure_error_ratio < 2.0 and lof.pure_error_dof == lof.n_columns   # 3 trials: 1 dof/column


def test_a_missing_compliance_is_a_structured_lack_of_fit(case, model):
    # the drive 12 % softer than modelled, diagnosed with nothing: a load-proportional misfit, p << 1e-3;
    # the right cause fitted leaves noise
    r = process(simulate(case, [("actuation_compliance", {"scale": 1.12})], seed=3, directions=FAST).data, case)
    none = structured_lack_of_fit(r, fit_effects(model, r, []).predicted, sigma_dof=r.sigma_dof)
    f = fit_effects(model, r, [get_effect("actuation_compliance")])
    right = structured_lack_of_fit(r, f.predicted, jacobian=f.jacobian, n_params=1, sigma_dof=r.sigma_dof)
    assert none.p_value < 1e-6
    assert right.p_value > 1e-3
    assert right.dof == pytest.approx(right.n_columns - 1, abs=0.1)   # one linear-elastic parameter: ~1 column
