"""The physical-worlds bench: its worlds are seeded random modified cases, and its scoring counts what it says."""
import numpy as np

from femcheck.bench.physical_worlds import ELEMENT, draw_world, score


def test_worlds_are_seeded_random_and_physically_changed(case):
    """Same seed, same world; over 40 seeds both one-leg and all-leg changes, singles and pairs of different
    elements appear; a thinner pin or a softer cable in one leg scales that leg's element up (compliance > 1)."""
    a, b = draw_world(5, case), draw_world(5, case)
    assert a["changes"] == b["changes"] and a["data_seed"] == b["data_seed"]
    worlds = [draw_world(s, case) for s in range(40)]
    sizes = {len(w["changes"]) for w in worlds}
    legs = {len(c["legs"]) for w in worlds for c in w["changes"]}
    assert sizes == {1, 2} and legs == {1, 6}
    for w in worlds:
        els = [c["element"] for c in w["changes"]]
        assert len(set(els)) == len(els) and set(els) <= set(ELEMENT.values())
        for c in w["changes"]:
            if len(c["legs"]) == 1:
                assert c["factor"] > 1.2   # every change softens its element: 1.7-2.2 for the tube, ~2 for the bar


def test_scoring_counts_elements_not_ids():
    """A whole-device cause is not the element; a whole-leg factor is counted; a pair needs both elements named."""
    changes = [{"element": "lg", "legs": list(range(6))}, {"element": "act", "legs": [2]}]
    good = score(changes, [{"id": "guideway_in_legs", "legs": list(range(6))}, {"id": "actuation_in_legs", "legs": [2]}])
    assert good["right_element_first"] and good["both_named"] and good["legs_right"] and not good["wrong_whole_leg"]
    bad = score(changes, [{"id": "link_modulus"}, {"id": "leg_softening", "legs": []}])
    assert not bad["right_element_first"] and not bad["both_named"] and bad["wrong_whole_leg"]
    one = score(changes[:1], [{"id": "actuation_compliance"}, {"id": "guideway_in_legs", "legs": [0, 1]}])
    assert not one["right_element_first"] and one["both_named"] and not one["legs_right"]
