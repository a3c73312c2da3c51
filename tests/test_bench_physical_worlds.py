"""The physical-worlds bench: its worlds are seeded random modified cases, and its scoring counts what it says."""
import numpy as np

from femcheck.bench.physical_worlds import (CHANGES, ELEMENT, TUBE_MATERIALS, changed_case, confusion_table, draw_world,
                                           leg_cases, score)


def test_worlds_are_seeded_random_and_physically_changed(case):
    """Same seed, same world; over 40 seeds both one-leg and all-leg changes, singles and pairs of different
    elements appear; every change weakens its element (factor < 1 on a modulus, a section or a radius)."""
    a, b = draw_world(5), draw_world(5)
    assert a == b
    worlds = [draw_world(s) for s in range(40)]
    assert {len(w["changes"]) for w in worlds} == {1, 2}
    assert {len(c["legs"]) for w in worlds for c in w["changes"]} == {1, 6}
    for w in worlds:
        els = [c["element"] for c in w["changes"]]
        assert len(set(els)) == len(els) and set(els) <= set(ELEMENT.values())
        # a section or radius at most 18 % smaller; a tube material at least glass-fibre polyamide's ~10 GPa
        assert all(0.1 < c["factor"] < 0.95 for c in w["changes"])


def test_a_change_is_written_into_the_case_of_its_legs_only(case):
    """A tube alloy of its own changes the proximal links' modulus and not the guideways' (both aluminium in the
    case); each change reaches exactly the legs it names, a pair's two changes meet in a leg they share, and legs
    alike share one case object (one FE solve of their parts)."""
    tube = case.with_params(**changed_case(case, "proximal_link_modulus", 0.5))
    assert tube.proximal_link.material.E_Pa == 0.5 * case.proximal_link.material.E_Pa
    assert tube.guideway.material.E_Pa == case.guideway.material.E_Pa
    mg = case.with_params(**changed_case(case, "proximal_link_modulus", 0.0, "magnesium_AZ31B"))
    assert (mg.proximal_link.material.E_Pa, mg.proximal_link.material.nu) == TUBE_MATERIALS["magnesium_AZ31B"][:2]
    for name in CHANGES:   # every change moves the case (no silent no-op)
        assert case.with_params(**changed_case(case, name, 0.8)).sha256 != case.sha256
    changes = [{"change": "cable_modulus", "factor": 0.6, "legs": [3]},
               {"change": "guideway_section", "factor": 0.85, "legs": list(range(6))}]
    legs = leg_cases(case, changes)
    cable = [c.actuation.cable_modulus_Pa for c in legs]
    assert cable == [case.actuation.cable_modulus_Pa * (0.6 if i == 3 else 1.0) for i in range(6)]
    assert all(c.guideway.width_radial_m == case.guideway.width_radial_m * 0.85 for c in legs)
    assert len({id(c) for c in legs}) == 2


def test_scoring_counts_elements_not_ids():
    """A whole-device cause is not the element; a whole-leg factor is counted; a pair needs both elements named."""
    changes = [{"element": "lg", "legs": list(range(6))}, {"element": "act", "legs": [2]}]
    good = score(changes, [{"id": "guideway_in_legs", "legs": list(range(6))}, {"id": "actuation_in_legs", "legs": [2]}])
    assert good["right_element_first"] and good["both_named"] and good["legs_right"] and not good["wrong_whole_leg"]
    bad = score(changes, [{"id": "link_modulus"}, {"id": "leg_softening", "legs": []}])
    assert not bad["right_element_first"] and not bad["both_named"] and bad["wrong_whole_leg"]
    one = score(changes[:1], [{"id": "actuation_compliance"}, {"id": "guideway_in_legs", "legs": [0, 1]}])
    assert not one["right_element_first"] and one["both_named"] and not one["legs_right"]


def test_alias_aware_scoring_needs_the_diagnosis_own_group():
    """A first named cause counts as right, alias-aware, only through an alias group the diagnosis reported for
    that very cause (same legs) holding the changed element; strictly it stays wrong; a group of another cause or
    another leg set does not count; a pair's second element can be named through a group member."""
    changes = [{"element": "uj", "legs": [1]}]
    causes = [{"id": "proximal_link_in_legs", "legs": [1]}]
    group = {"cause": "proximal_link_in_legs", "legs": [1],
             "members": [{"id": "proximal_link_in_legs"}, {"id": "universal_joint_in_legs"}]}
    r = score(changes, causes, [group])
    assert r["right_element_first"] and not r["right_element_first_strict"] and r["first_group"] == "prox\u2261uj"
    assert not score(changes, causes, [{**group, "legs": [2]}])["right_element_first"]
    assert not score(changes, causes, [])["right_element_first"]
    pair = [{"element": "act", "legs": [0]}, {"element": "uj", "legs": [1]}]
    two = score(pair, [{"id": "actuation_in_legs", "legs": [0]}] + causes, [group])
    assert two["both_named"] and not two["both_named_strict"]


def test_confusion_table_counts_the_single_changes():
    """Rows: changed element; columns: first named element; each single world counted once, pairs not at all."""
    rows = [{"changes": [{"element": "lg"}], "first_element": "lg"},
            {"changes": [{"element": "lg"}], "first_element": "act"},
            {"changes": [{"element": "act"}], "first_element": "act"},
            {"changes": [{"element": "act"}, {"element": "lg"}], "first_element": "lg"}]
    lines = [[x.strip() for x in ln.split("|")] for ln in confusion_table(rows).splitlines()]
    assert lines[0][1:] == ["act", "lg"]
    assert dict((ln[0], ln[1:]) for ln in lines[1:]) == {"act": ["1", "0"], "lg": ["1", "1"]}
    assert np.sum([int(x) for ln in lines[1:] for x in ln[1:]]) == 3


class _LinearWorld:
    """A world whose TCP moves ``c`` m/N along the force at every point (a closed form for the signal)."""

    def __init__(self, c: float):
        self.c = c

    def tcp_displacement(self, pose, force):
        return self.c * np.asarray(force, float)


def test_change_signal_is_the_rms_of_the_total_minus_preload_change(case):
    """Against a reference of 1e-5 m/N, a world of 1.02e-5 m/N changes every total - preload reading (20 N - 5 N
    along its direction) by 2e-7 m/N x 15 N = 3 um: RMS 3 um exactly (rounding only); the reference against itself
    has no signal."""
    from femcheck.experiment.dial_gauge import device_change_rms
    rms = device_change_rms(case, [_LinearWorld(1e-5), _LinearWorld(1.02e-5)], _LinearWorld(1e-5),
                            directions=("+x", "-y", "+z"))
    np.testing.assert_allclose(rms, [0.0, 2e-7 * 15.0], rtol=1e-9, atol=1e-15)


def _row(seed, elements, detectable, causes, groups=()):
    """A scored row as run_world writes it (changes in one leg each), from the causes the diagnosis named."""
    changes = [{"element": e, "legs": [0], "snr": 5.0 if detectable else 1.0} for e in elements]
    return {"seed": seed, "changes": changes, "verdict": "explained", "detectable": detectable, "cpu_s": 1.0,
            "world_cpu_s": 0.5, **score(changes, causes, list(groups))}


def test_headline_rates_are_over_the_detectable_worlds_and_honesty_over_the_rest():
    """Headline rates count only the detectable worlds; *_all_draws every scored draw; a failed world is neither;
    an undetectable draw is honest when it names nothing, the changed element, or a group holding it, and not when
    it names an unchanged element (here 2 of 3)."""
    from femcheck.bench.physical_worlds import summarize
    uj1 = {"id": "universal_joint_in_legs", "legs": [0]}
    pr1 = {"id": "proximal_link_in_legs", "legs": [0]}
    group = {"cause": "proximal_link_in_legs", "legs": [0],
             "members": [{"id": "proximal_link_in_legs"}, {"id": "universal_joint_in_legs"}]}
    rows = [_row(1, ["act"], True, [{"id": "actuation_in_legs", "legs": [0]}]),          # right
            _row(2, ["lg"], True, [{"id": "actuation_in_legs", "legs": [0]}]),           # wrong
            _row(3, ["uj", "act"], True, [pr1, {"id": "actuation_compliance"}], [group]),  # both, by the group
            _row(4, ["prox"], False, []),                                                # honest: none
            _row(5, ["uj"], False, [pr1], [group]),                                      # honest: group has uj
            _row(6, ["prox"], False, [{"id": "guideway_in_legs", "legs": [0]}]),        # not honest
            {"seed": 7, "changes": [{"element": "lg", "legs": [0]}], "world_failed": "x", "cpu_s": 1.0}]
    f = summarize(rows)
    assert (f["worlds_drawn"], f["worlds_detectable"], f["worlds_undetectable"], f["worlds_failed"]) == (7, 3, 3, 1)
    assert f["right_element_first_count"] == 2 and f["right_element_first_rate"] == round(2 / 3, 4)
    assert f["right_element_first_count_strict"] == 1   # seed 3's first named cause is the tube, by its group only
    assert f["both_changes_named_rate"] == 1.0 and f["both_changes_named_rate_strict"] == 0.0
    assert f["pairs_all_draws"] == 1 and f["right_element_first_count_all_draws"] == 3   # + seed 5 by its group
    assert f["honesty_count_undetectable"] == 2 and f["honesty_rate_undetectable"] == round(2 / 3, 4)
    assert f["worlds_failed_seeds"] == "7"
    assert "lg>act 1" in f["confusion_singles_changed_to_first_named"]
    assert "prox>lg 1" in f["confusion_singles_changed_to_first_named_all_draws"]
    assert "prox>" not in f["confusion_singles_changed_to_first_named"]   # undetectable draws stay out


def _fake_world(seed):
    """Every third seed undetectable (module level: picklable for the process pool)."""
    return {"seed": seed, "detectable": seed % 3 != 0}


def test_draws_stop_at_the_detectable_count_whatever_the_jobs():
    """Seeds 10, 11 (detectable), 12 (not), 13, 14 (detectable), 15 (not), 16: the fifth detectable world is seed 16;
    the same prefix with one process or two, and the cap stops short of the count."""
    from femcheck.bench.physical_worlds import draw_until
    one = [r["seed"] for r in draw_until(_fake_world, 10, 5, 100, jobs=1)]
    two = [r["seed"] for r in draw_until(_fake_world, 10, 5, 100, jobs=2)]
    assert one == two == list(range(10, 17))
    assert [r["seed"] for r in draw_until(_fake_world, 10, 5, 4)] == [10, 11, 12, 13]


def test_pin_worlds_draw_the_standard_dowel_pins_below_the_case(case):
    """The reference Ø2 mm pin (radius 1 mm) gives way to Ø1.5 and Ø1 mm (ISO 8734 / ISO 2338 sizes): factors 0.75 and
    0.5 exactly; every pin world over 60 seeds is one of them."""
    from femcheck.bench.physical_worlds import pin_factors
    assert case.universal_joint.pin_radius_m == 1e-3
    assert pin_factors(case) == (0.75, 0.5)
    drawn = {c["factor"] for s in range(60) for c in draw_world(s, case)["changes"] if c["change"] == "pin_radius"}
    assert drawn == {0.75, 0.5}
