"""Alias groups: a named cause that the readings cannot separate from another element type on its legs is reported
with it as one group; a placement the readings do separate is not grouped."""
import numpy as np
import pytest

import femcheck
from femcheck.diagnose import AnalyticalChainModel, diagnose
from femcheck.diagnose.selection import ALIAS_CHI2
from femcheck.experiment.simulate import simulate
from femcheck.measured import process

#: the element types of one leg's link line and a rival of the whole device (a short vocabulary keeps it fast)
CANDIDATES = ["proximal_link_in_legs", "universal_joint_in_legs", "guideway_in_legs", "actuation_compliance"]


@pytest.fixture(scope="module")
def case():
    return femcheck.load_case("cases/haptic_6psu.toml")


def _softer_tube_in_leg1(case, joints: str):
    """Readings of the chain with ``joints`` whose leg-1 proximal tube is 3x as compliant, diagnosed against it."""
    ve = simulate(case, [("proximal_link_in_legs", {"leg1": 3.0})], seed=3, joints=joints,
                  directions=("+x", "+y", "+z"))
    return diagnose(AnalyticalChainModel(case, "detailed", joints), process(ve.data, case), candidates=CANDIDATES,
                    with_baseline=False)


def _swap_chi2(d, element_id: str, legs: tuple) -> float:
    """chi^2 of the weighed single explanation that holds ``element_id`` on ``legs``."""
    return next(ex.chi2 for ex in d.weighing.explanations if ex.payload is not None and len(ex.payload.effects) == 1
                and ex.payload.effects[0].id == element_id and getattr(ex.payload.effects[0], "legs", ()) == legs)


def test_tube_and_u_joint_in_series_are_one_alias_group(case):
    """With the joints released the leg carries its load along the link, where the tube's axial compliance and the
    U joint's are two springs in series: their leg-1 scales move the readings along one column, so the U joint in
    the tube's place fits the same readings to round-off and the two are reported as one group, not one at random."""
    d = _softer_tube_in_leg1(case, "released")
    first = d.causes[0]
    assert first.id in ("proximal_link_in_legs", "universal_joint_in_legs") and first.legs == (1,)
    assert len(d.alias_groups) == 1
    g = d.alias_groups[0]
    assert {m["label"] for m in g["members"]} == {"proximal_link_in_legs[1]", "universal_joint_in_legs[1]"}
    # series springs: the same column up to scale, so the swap's chi^2 equals the named one's to fit tolerance
    assert abs(g["members"][1]["delta_chi2"]) < 1e-3 * d.fit.chi2
    assert "cannot separate" in d.weighing.ambiguity and d.weighing.ambiguous
    # the shared mass: neither placement can hold 0.9 alone
    assert first.probability < 0.9


def test_a_separable_placement_is_not_grouped(case):
    """With rigid joints the tube also bends under the moments the joints pass, which the pin's line contact does
    not: the U joint of leg 1 in the tube's place leaves more than ALIAS_CHI2 (3 reading sigmas) unexplained, so the
    tube is named alone with no alias group."""
    d = _softer_tube_in_leg1(case, "rigid")
    assert d.causes[0].id == "proximal_link_in_legs" and d.causes[0].legs == (1,)
    assert d.alias_groups == ()
    # the separation is in the data, not at the threshold's edge: well beyond 3 sigmas
    assert _swap_chi2(d, "universal_joint_in_legs", (1,)) - d.fit.chi2 > 3 * ALIAS_CHI2
    assert np.isfinite(d.fit.chi2)
