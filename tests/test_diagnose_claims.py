"""A diagnosis claims only what its data give: causes in importance order, collinear causes sharing their mass,
the scale of the readings checked before a verdict, dimensions judged against the device, and verdicts on dial
readings made without the effect code (:mod:`femcheck.experiment.dial_gauge`)."""
import json

import numpy as np
import pytest

import femcheck
from femcheck.cli import main
from femcheck.diagnose import diagnose, predict_readings
from femcheck.diagnose import evidence
from femcheck.diagnose.effects.link_modulus import LinkModulus
from femcheck.diagnose.fitting import fit_effects
from femcheck.diagnose.selection import collinear_causes, share_collinear
from femcheck.experiment.dial_gauge import dial_campaign
from femcheck.experiment.simulate import simulate
from femcheck.measured import process

FAST = ("+x", "+y", "+z")


@pytest.fixture(scope="module")
def model(rigid_chain):
    return rigid_chain


def test_causes_come_in_order_of_heldout_loss(case, model):
    """Friction of 1.5 N moves every unload reading (a hysteresis band of 3 N) and wins the first greedy round on
    chi^2; a dial frame rotated by ~8 deg changes the deflection along the load (cos) and across it. Left out of the
    named pair, the rotation costs the held-out deflection error several points, friction below the preload hardly
    any: sensor_misalignment goes first, though it comes after friction in the vocabulary and in the greedy path."""
    c = dial_campaign(case, {"friction": 1.5, "sensor_misalignment": [0.1, 0.1, 0.05]}, seed=3)
    j = diagnose(model, process(c.data, case), with_baseline=False,
                 candidates=("friction_hysteresis", "link_modulus", "sensor_misalignment", "actuation_compliance")).as_json()
    assert j["rank_by"] == "heldout_loss"
    steps = [s["effects"] for s in j["steps"] if s["accepted"]]
    assert steps[0] == ["friction_hysteresis"]   # the greedy path named friction first
    ids = [x["id"] for x in j["causes"]]
    assert ids == ["sensor_misalignment", "friction_hysteresis"], j["causes"]
    loss = [x["heldout_loss_pct"] for x in j["causes"]]
    # measured 9.3 and 0.02 points (seed 3): the margins leave room for the fit's scatter
    assert loss[0] > 3.0 and loss[1] < 1.0, loss


class _TwinModulus(LinkModulus):
    """The link modulus again under another name: a cause whose parameter is collinear with link_modulus's."""

    id = "link_modulus_twin"


def test_collinear_pair_shares_its_probability(case, model):
    """Two causes built to act alike: their joint fit correlates the parameters at -1, and the explanation holding
    both cannot hand each a marginal of 0.9 or more."""
    r = process(simulate(case, [("link_modulus", {"E_factor": 0.6})], seed=4, directions=FAST, sweep=False).data, case)
    pair = fit_effects(model, r, [LinkModulus(), _TwinModulus()])
    found = collinear_causes(pair)
    assert [(a, b) for a, b, _ in found] == [("link_modulus", "link_modulus_twin")]
    assert abs(found[0][2]) > 0.95   # the same column of the Jacobian twice: |corr| 1 up to the fit's rounding
    none = fit_effects(model, r, [])
    single = fit_effects(model, r, [LinkModulus()])
    # the pair weighed as if it won (its chi^2 lowered by hand): the raw marginals are both ~1
    ex = [evidence.Explanation((), none.chi2, 0), evidence.Explanation(("link_modulus",), single.chi2 + 30.0, 1),
          evidence.Explanation(("link_modulus_twin",), single.chi2 + 30.0, 1),
          evidence.Explanation(("link_modulus", "link_modulus_twin"), single.chi2, 2)]
    w = evidence.weigh(ex, 3 * r.n_states)
    raw = {i: sum(p for e, p in zip(w.explanations, w.probability) if i in e.ids)
           for i in ("link_modulus", "link_modulus_twin")}
    assert min(raw.values()) > 0.99
    shared = share_collinear(raw, w, found)
    assert max(shared.values()) < 0.9 and sum(shared.values()) <= 1.0 + 1e-12   # mass split, never duplicated
    assert shared["link_modulus"] == pytest.approx(shared["link_modulus_twin"], abs=1e-12)   # symmetric by construction
    assert collinear_causes(single) == []


def _scaled_csv(tmp_path, case, factor):
    from femcheck.measured.csv_format import format_measured_csv
    ve = simulate(case, [], seed=1, directions=FAST, sweep=False)
    d = ve.data
    text = format_measured_csv(d.point, d.direction, d.trial, d.phase, d.load_N, d.force, d.disp * factor,
                               resolution_m=1e-5)
    p = tmp_path / f"readings_x{factor:g}.csv"
    p.write_text(text)
    return p


@pytest.mark.parametrize("factor, unit", [(1000.0, "µm written as mm"), (1e-3, "m written as mm")])
def test_readings_off_the_models_scale_exit_2_naming_the_unit(tmp_path, case, capsys, factor, unit):
    csv = _scaled_csv(tmp_path, case, factor)
    assert main(["diagnose", "cases/haptic_6psu.toml", str(csv)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and unit in err[0] and "--force" in err[0], err


def test_scale_check_passes_the_case_own_readings(case, model):
    from femcheck.cli.diagnose import _refuse_implausible_scale
    r = process(simulate(case, [("link_modulus", {"E_factor": 0.5})], seed=2, directions=FAST, sweep=False).data, case)
    _refuse_implausible_scale(model, r, "m.csv")   # twice as soft is a finding, not a unit slip: no error


def test_implausible_dimension_warns_on_the_first_line(tmp_path, case, capsys):
    text = open("cases/haptic_6psu.toml").read()
    import re
    # every leg's proximal tube (the case is written leg by leg): a mm value in a metre key
    bad, n = re.subn(r"outer_diameter_m\s*=\s*0\.006", "outer_diameter_m = 6.0", text)
    assert n == 6
    p = tmp_path / "mm_as_m.toml"
    p.write_text(bad)
    csv = _scaled_csv(tmp_path, case, 1000.0)   # stops at the scale check: the warning must already be out
    assert main(["diagnose", str(p), str(csv)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert "legs[0].links[1].outer_diameter_m = 6 m" in err[0] and "larger than the device" in err[0], err
    from femcheck.case.plausibility import dimension_warnings
    assert dimension_warnings(case) == []   # the reference case itself is plausible


def test_dial_readings_calibrate_the_true_model(case, model):
    """Readings of 10 um dials, 3 trials, scatter 1-3 um, made from the device model (not the effect code): the true
    model's residual, weighted by the readings' sigma, has chi^2 / N near 1 on the state axes that read anything
    (measured 0.90 / 1.11 / 1.09 at 1 / 2 / 3 um). With the scatter pooled over every axis (those reading zero
    throughout hide theirs) and sigma_r / sqrt(n) for a state (no rounding error shared by the trials), it was
    2.06 / 1.93 / 1.60: the verdict's over-strictness."""
    for scatter in (1e-6, 2e-6, 3e-6):
        z2 = []
        for seed in (11, 12, 13):
            c = dial_campaign(case, {}, seed=seed, scatter_m=scatter)
            r = process(c.data, case)
            pred = predict_readings(model, r)
            live = np.zeros(r.disp.shape, bool)
            np.logical_or.at(live, r.row_state, r.row_disp != 0.0)
            z2.append((((r.disp - pred) / r.sigma) ** 2)[live])
        mean = float(np.mean(np.concatenate(z2)))
        # ~700 live state axes over three seeds: chi^2 / N has a standard error ~0.05-0.1 (non-Gaussian rounding)
        assert 0.75 < mean < 1.25, (scatter, mean)


FOUR = {   # the four sets whose causes are in the vocabulary (issue text): magnitudes at SNR 3 where it says so
    "sensor_misalignment": ({"sensor_misalignment": [0.3, -0.5, 0.2]}, 3.0, {"sensor_misalignment"}),
    "weak_guideway": ({"weak_guideway": 2.0, "weak_guideway_leg": 2}, 3.0, {"guideway_in_legs"}),
    "friction_link_modulus": ({"friction": 8.0, "link_modulus": 0.6}, None, {"friction_hysteresis", "link_modulus"}),
    "guideway_friction": ({"weak_guideway": 2.5, "weak_guideway_leg": 4, "friction": 8.0}, None,
                          {"guideway_in_legs", "friction_hysteresis"}),
}


@pytest.mark.slow
@pytest.mark.parametrize("seed", [21, 22])
@pytest.mark.parametrize("name", list(FOUR))
def test_in_vocabulary_dial_data_are_explained(case, model, name, seed):
    causes, snr, want = FOUR[name]
    c = dial_campaign(case, causes, seed=seed, snr=snr)
    j = diagnose(model, process(c.data, case), with_baseline=False).as_json()
    assert {x["id"] for x in j["causes"]} == want, (j["causes"], c.truth)
    assert j["verdict"] == "explained", (j["residual"]["chi2_per_dof"], j["residual"]["p_value"])


def test_single_trial_sigma_comes_from_the_richest_rival(case, model):
    """One reading per state: no scatter to pool, only the dial step's floor q/sqrt(12) = 2.9 um, well below the
    6 um scatter. Sigma is estimated once, before the search, from the held-out residual of all candidates fitted
    jointly (dof counted), and the verdict says so; the model as given then fits within that noise."""
    c = dial_campaign(case, {}, seed=5, trials=1, scatter_m=6e-6)
    j = diagnose(model, process(c.data, case), with_baseline=False,
                 candidates=("friction_hysteresis", "link_modulus", "sensor_misalignment", "actuation_compliance")).as_json()
    res = j["residual"]
    true = np.sqrt(6e-6 ** 2 + 1e-5 ** 2 / 12)   # one rounded reading: scatter and rounding add
    # ~370 dof: the estimate's relative standard error is ~4 %; 15 % is > 3 of them
    assert res["sigma_m"] == pytest.approx(true, rel=0.15)
    assert "most flexible rival" in res["sigma_source"] and j["sigma_dof"] == 3 * 126 - 6
    assert j["verdict"] == "none"


def test_parallel_device_readings_off_scale_exit_2_and_force_goes_on(tmp_path, capsys):
    """The same check on a general parallel device (the delta): micrometres in the mm columns stop it, --force runs."""
    from femcheck.measured.csv_format import write_measured_csv
    from femcheck.parallel.diagnosis import simulate as simulate_parallel
    path = "cases/delta_3ruu.toml"
    dev = femcheck.load_case(path).device
    point, direction, trial, phase, load, force, disp = simulate_parallel(
        femcheck.load_case(path), np.ones((dev.n_legs, len(dev.element_names))), noise_m=2e-7)
    csv = tmp_path / "um_as_mm.csv"
    write_measured_csv(csv, point, direction, trial, phase, load, force, disp * 1000.0, resolution_m=1e-7)
    assert main(["diagnose", path, str(csv)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "µm written as mm" in err[0], err
    assert main(["diagnose", path, str(csv), "--force", "--json", str(tmp_path / "d.json")]) == 0
