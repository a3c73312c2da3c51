"""Verification problems cantilever-solid, cantilever-beam, bar-modal and the check-solver CLI."""
import json

import numpy as np
import pytest
import typer
from typer.testing import CliRunner

from femcheck.cli import check_solver
from femcheck.fe.checks import bar_modal, cantilever_beam, cantilever_solid
from femcheck.fe.modal import bar_on_spring_roots


def _app():
    app = typer.Typer()

    @app.callback()
    def _root():  # keep subcommand mode even if this is the only command
        pass

    check_solver.register(app)
    return app


@pytest.mark.parametrize("mesh", ["coarse", "default"])
def test_cantilever_solid_within_1_percent_of_timoshenko(mesh):
    r = cantilever_solid.run(mesh)
    # acceptance: P2 solid within 1 % of Timoshenko (shear included); measured 0.11 % / 0.011 %
    assert r.rel_error < 0.01
    assert r.dofs > 1000 and r.detail["solver"] in ("pardiso", "cholmod", "umfpack", "superlu")


def test_cantilever_solid_p1_is_too_stiff():
    """Sanity in the other direction: P1 tets lock in bending, so the same mesh is clearly too stiff."""
    uy, *_ = cantilever_solid.solve_cantilever(10, 2, order=1)
    assert uy < 0.7 * cantilever_solid.reference_deflection()


def test_cantilever_beam_exact():
    r = cantilever_beam.run("coarse")
    # nodally exact element: round-off only
    assert r.rel_error < 1e-10
    assert max(r.detail[k] for k in ("rel_error_local_y", "rel_error_axial", "rel_error_torsion")) < 1e-10


def test_bar_modal_seed004_eq29():
    r = bar_modal.run("default")
    # acceptance: the four frequencies within 1 %; P2 with 12 elements along the bar gives 2e-4 on f4
    assert r.detail["max_rel_error"] < 0.01
    assert r.rel_error < 0.01


@pytest.mark.parametrize("beta", [0.1, 10.0])
def test_bar_modal_other_stiffness_ratios(beta):
    f, _ = bar_modal.bar_frequencies(12, beta=beta, n_modes=3)
    ref = bar_modal.reference_frequencies(beta, 3)
    assert f == pytest.approx(ref, rel=0.01)  # same 1 % acceptance over the seed's β range 0.1..10


def test_bar_on_spring_roots_limits():
    # β → 0: free–free bar, λl → (i−1)π; β → ∞: fixed–free bar, λl → (i − ½)π
    small = bar_on_spring_roots(1e-8, 3)
    assert small[1:] == pytest.approx([np.pi, 2 * np.pi], rel=1e-7) and small[0] < 1e-3
    assert bar_on_spring_roots(1e8, 3) == pytest.approx([0.5 * np.pi, 1.5 * np.pi, 2.5 * np.pi], rel=1e-7)
    x = bar_on_spring_roots(1.0, 4)
    assert np.tan(x) == pytest.approx(1.0 / x, rel=1e-9)  # eq. 30 itself


def test_cli_table_and_json():
    runner = CliRunner()
    res = runner.invoke(_app(), ["check-solver", "cantilever-beam", "bar-modal", "--mesh", "coarse", "--json", "-"])
    assert res.exit_code == 0, res.output
    data = json.loads(res.stdout)   # the JSON is stdout; progress lines go to stderr
    assert [d["name"] for d in data] == ["cantilever-beam", "bar-modal"]
    for d in data:
        assert {"name", "computed", "reference", "rel_error", "dofs", "iterations", "seconds"} <= set(d)
        assert d["rel_error"] < 0.01
    res = runner.invoke(_app(), ["check-solver", "cantilever-beam"])
    assert res.exit_code == 0 and "cantilever-beam" in res.output and "rel. error" in res.output


def test_cli_unknown_check_is_a_clear_error():
    from femcheck.errors import FemcheckError
    with pytest.raises(FemcheckError, match="unknown check 'nope'"):
        check_solver.run_checks(["nope"])
    with pytest.raises(FemcheckError, match="--mesh"):
        check_solver.run_checks(["bar-modal"], mesh="huge")


@pytest.mark.slow
@pytest.mark.parametrize("name", ["cantilever-solid", "cantilever-beam", "bar-modal"])
def test_fine_meshes(name):
    from femcheck.fe.checks import registry
    r = registry()[name].run("fine")
    assert r.rel_error < 0.01  # acceptance tolerance on the fine mesh too
