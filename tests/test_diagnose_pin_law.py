"""The U joint's pin law over its bending compliance, and the FE-anchored model that carries it.

Light tests use synthetic laws (power laws, so every expected value is a closed form) and the light device FE (beam
parts, closed-form frictional joints); the slow one the U joint's contact FE of the reference case.
"""
import dataclasses

import numpy as np
import pytest

from femcheck.diagnose.pin_law import PinLawTable, link_forces


@dataclasses.dataclass(frozen=True)
class PowerLaw:
    """δ(F) = a F^p (m, F in N): a Hertz-like contact law with a closed form."""
    a: float
    p: float

    def approach(self, F):
        return self.a * np.asarray(F, float) ** self.p


def _table():
    # the case's pin, and two thinner ones that stiffen more with load (smaller p): X = 0.75^-4, 0.5^-4
    return PinLawTable((1.0, 0.75 ** -4, 16.0), (PowerLaw(1e-6, 0.9), PowerLaw(3e-6, 0.8), PowerLaw(12e-6, 0.6)))


def test_extra_deflection_is_zero_for_the_case_pin_exact_at_the_nodes_and_linear_between():
    """e(F; 1) = 0 for every load (the case's pin adds nothing); at a node e is that law minus the case's to
    round-off; halfway between two nodes it is their mean (linear in the bending compliance, which is ∝ r^-4); below
    X = 1 the first segment continues (a stiffer pin takes deflection away)."""
    t = _table()
    F = np.geomspace(0.5, 30.0, 9)
    base = 1e-6 * F ** 0.9
    np.testing.assert_allclose(t.extra_approach(F, 1.0), 0.0, atol=1e-18)
    np.testing.assert_allclose(t.extra_approach(F, 16.0), 12e-6 * F ** 0.6 - base, rtol=1e-12)
    X1 = 0.75 ** -4
    np.testing.assert_allclose(t.extra_approach(F, X1), 3e-6 * F ** 0.8 - base, rtol=1e-12)
    mid = t.extra_approach(F, 0.5 * (X1 + 16.0))
    np.testing.assert_allclose(mid, 0.5 * (t.extra_approach(F, X1) + t.extra_approach(F, 16.0)), rtol=1e-12)
    below = t.extra_approach(F, 0.5)
    np.testing.assert_allclose(below, -0.5 / (X1 - 1.0) * t.extra_approach(F, X1), rtol=1e-12)
    # broadcasting: (m, 6) loads with (m, 6) factors, as the anchored model calls it
    X = np.tile([1.0, 16.0, X1, 2.0, 1.0, 30.0], (4, 1))
    Fm = np.tile(F[:4, None], (1, 6))
    assert t.extra_approach(Fm, X).shape == (4, 6)


def test_a_table_must_start_at_the_case_pin():
    with pytest.raises(ValueError, match="start at 1"):
        PinLawTable((2.0, 3.0), (PowerLaw(1e-6, 1.0), PowerLaw(2e-6, 1.0)))
    with pytest.raises(ValueError, match="laws"):
        PinLawTable((1.0, 3.0), (PowerLaw(1e-6, 1.0),))


def test_link_forces_balance_the_tcp_force(case):
    """The released statics: at random reachable poses and forces, the six link forces along u_i sum to the TCP force
    and their moments about the TCP to zero (1e-9 relative: one 6 x 6 solve per pose)."""
    from femcheck.kinematics.psu6 import leg_geometry, test_points
    rng = np.random.default_rng(5)
    P = test_points(case)[rng.integers(0, 9, 12)].copy()
    P[:, :3] += rng.uniform(-0.004, 0.004, (12, 3))
    W = rng.normal(0.0, 10.0, (12, 3))
    f = link_forces(case, P, W)
    legs = leg_geometry(case, P)
    force = np.einsum("ni,nij->nj", f, legs.u)
    moment = np.einsum("ni,nij->nj", f, np.cross(legs.C - legs.tcp[:, None, :], legs.u))
    np.testing.assert_allclose(force, W, atol=1e-9 * np.abs(W).max())
    np.testing.assert_allclose(moment, 0.0, atol=1e-9 * np.abs(W).max())


def test_anchored_model_moves_each_leg_by_its_pin_deflection(case):
    """With the pin laws the U-joint column is the pin's bending compliance: at the case's pin (X = 1) the model reads
    exactly what it reads without them; with a thinner pin in leg 2 only the TCP moves by J^-T Δl, Δl_2 = e(|f_2|)
    sign(f_2) along that leg's link and nothing in the others (released joints: each link a two-force member, so
    the leg's axial deflection maps to the TCP through the statics alone; 1e-6 relative, the chain's own solve).
    Below the floor F_min a leg keeps its secant at F_min, as the device FE does."""
    from femcheck.diagnose import AnalyticalChainModel
    from femcheck.diagnose.fe_model import FEAnchoredChainModel
    from femcheck.diagnose.model import UJ
    from femcheck.experiment.device_fe_world import DeviceFEWorld
    from femcheck.kinematics.psu6 import leg_geometry, test_points
    device = DeviceFEWorld(case, (case,) * 6, kind="beam", joint_fe=False, tilt_slip_ratio=1.0)
    chain = AnalyticalChainModel(case, "detailed", "released")
    plain = FEAnchoredChainModel(chain, device)
    pinned = FEAnchoredChainModel(chain, device, _table())
    P = test_points(case)[[0, 3, 5, 7, 1]]
    # the last force leaves leg 2 below F_min
    W = np.array([[20.0, 0, 0], [0, -20.0, 0], [0, 0, 20.0], [-5.0, 0, 0], [0, 0.7, 0]])
    base = np.array(chain.base_scale, float)
    np.testing.assert_allclose(pinned.tcp_displacement(P, W, base), plain.tcp_displacement(P, W, base), rtol=0,
                               atol=1e-18)
    thin = np.tile(base, (len(P), 1, 1))
    thin[:, 2, UJ] = 16.0
    got = pinned.tcp_displacement(P, W, thin) - pinned.tcp_displacement(P, W, base)
    f = link_forces(case, P, W)
    F = np.maximum(np.abs(f[:, 2]), float(case.spherical_joint.min_contact_force_N))
    dl = np.zeros((len(P), 6))
    dl[:, 2] = _table().extra_approach(F, 16.0) * np.abs(f[:, 2]) / F * np.sign(f[:, 2])
    legs = leg_geometry(case, P)
    J = np.concatenate([legs.u, np.cross(legs.C - legs.tcp[:, None, :], legs.u)], axis=2)   # (n, leg, 6)
    want = np.linalg.solve(J, dl[..., None])[..., 0][:, :3]
    np.testing.assert_allclose(got, want, rtol=1e-6, atol=1e-6 * np.abs(want).max())
    assert np.abs(want).max() > 1e-6   # the change is well above round-off
    assert np.abs(f[-1, 2]) < float(case.spherical_joint.min_contact_force_N)


@pytest.mark.slow
def test_the_case_thin_pins_stiffen_inside_the_test_loads(case):
    """The contact FE of the reference U joint for its Ø2 mm pin and the Ø1.5 / Ø1 mm pins (coarse mesh, cached):
    the thinner pin adds deflection at every load, and its extra tangent compliance falls with the load (a thin pin's
    ends come to bear on the opposite line of the bore; the case's pin stays a near-linear spring there). Ratios of
    the measured increments, not of the laws' secants, so the 20 um clearance take-up cancels."""
    from femcheck.diagnose.pin_law import pin_law_table
    t = pin_law_table(case, "coarse")
    F = np.asarray(t.laws[0].loads_N, float)
    ref = np.diff(t.laws[0].approach(F))
    for law in t.laws[1:]:
        ratio = np.diff(law.approach(F)) / ref
        assert np.all(ratio > 1.3), ratio                 # a thinner pin is softer at every load step
        assert ratio[-1] < 0.8 * ratio[0], ratio          # ... and stiffens within the ladder
    assert np.all(np.diff(np.asarray(t.factors)) > 0) and t.factors[0] == 1.0


@pytest.mark.slow
@pytest.mark.parametrize("legs, second", [([3], None), ([1], {"change": "guideway_section", "element": "lg",
                                                              "factor": 0.86, "legs": [4]})])
def test_a_thin_pin_in_the_device_fe_is_named_the_u_joint_not_the_ball(legs, second):
    """A Ø1 mm pin (half the case's radius) in one leg of the device FE world, alone and beside a thinner guideway
    in another leg: the diagnosis through the FE-anchored chain with the pin laws names the U joint of that leg,
    not the ball, with a bending-compliance factor near 0.5^-4 = 16 (10-25: the nodes 0.6 and 0.45 x r
    are interpolated), and the guideway when it is changed. Without the pin laws the same readings were named the
    ball (spherical_joint_in_legs x4.5-4.9)."""
    from femcheck.bench.physical_worlds import run_world
    changes = [{"change": "pin_radius", "element": "uj", "factor": 0.5, "legs": legs}] + ([second] if second else [])
    row = run_world(0, world={"changes": changes, "data_seed": 7})
    causes = {c["id"]: c for c in row["causes"]}
    uj = causes.get("universal_joint_in_legs")
    assert uj is not None and "spherical_joint_in_legs" not in causes, row["causes"]
    factor = uj["params"][f"leg{legs[0]}"] if f"leg{legs[0]}" in uj["params"] else uj["params"]["all_legs"]
    assert 10.0 < factor < 25.0, uj
    if second:
        assert row["both_named_strict"], row["causes"]
