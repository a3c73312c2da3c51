"""The actuation FE (femcheck/fe_device/actuation_fe.py): shaft + capstan + cable strands condensed to the slider."""
from __future__ import annotations

import math

import numpy as np
import pytest

import femcheck
from femcheck.fe_device.actuation_fe import actuation_springs, leg_actuation


@pytest.fixture(scope="module")
def ref():
    """The reference device with the FE actuation options these tests vary set explicitly (the case file itself
    selects elements in the single-strand layout): eq. 44's spring in the device FE, a closed cable loop."""
    return femcheck.load_case("cases/haptic_6psu.toml").with_params(
        **{"actuation.fe.model": "law", "actuation.fe.layout": "closed_loop"})


def _eq44(case):
    from femcheck.chain import device_parameters
    return 1.0 / float(np.squeeze(device_parameters(case).c_act))


def _parts(case):
    a = case.actuation
    EA = a.cable_modulus_Pa * math.pi * a.cable_diameter_m**2 / 4
    k_motor = a.shaft_G_Pa * math.pi * a.shaft_diameter_m**4 / 32 / a.shaft_length_m / a.capstan_radius_m**2
    return EA, k_motor


def test_single_strand_reproduces_eq44(ref):
    """Eq. 44's layout (one strand of length l, shaft in series through the capstan) from elements: the same
    spring to round-off, at any slider position (the strand's free length is constant)."""
    case = ref.with_params(**{"actuation.fe.layout": "single_strand"})
    for s in (0.1, 0.2, 0.3):
        assert leg_actuation(case, s).k_axial == pytest.approx(_eq44(case), rel=1e-12)


def test_closed_loop_is_the_two_strands_in_parallel_in_series_with_the_shaft(ref):
    """Closed loop: 1 / k = 1 / (EA (1/l1 + 1/l2)) + r² / K_rotor with l1 = s - z_c, l2 = l - l1, and
    z_c = rail_length - l / 2 (idler at the rail's end); at least 4x the single strand's cable stiffness."""
    EA, k_motor = _parts(ref)
    l = ref.actuation.cable_length_m
    z_c = ref.geometry.rail_length_m - l / 2
    for s in (0.162, 0.2, 0.26):
        l1 = s - z_c
        k_cable = EA * (1 / l1 + 1 / (l - l1))
        r = leg_actuation(ref, s)
        assert r.k_axial == pytest.approx(1 / (1 / k_cable + 1 / k_motor), rel=1e-12)
        assert k_cable >= 4 * EA / l
        assert r.k_shaft_at_cable == pytest.approx(k_motor, rel=1e-12)
        assert sum(r.strand_lengths[:2]) + r.strand_lengths[2] == pytest.approx(l)
        # strand tensions: the pulled strand gains, the return strand loses; the changes carry the load
        assert r.dT_dF[0] - r.dT_dF[1] == pytest.approx(1.0, rel=1e-12)
        assert r.dT_dF[1] == pytest.approx(r.dT_dF[2], rel=1e-12)           # frictionless idler
        # pretension: transverse geometric stiffness tau (1/l1 + 1/l2a) at the slider, decoupled from the axis
        tau = ref.actuation.fe.cable_pretension_N
        assert r.K_slider[0, 0] == pytest.approx(tau * (1 / l1 + 1 / r.strand_lengths[1]), rel=1e-12)
        assert abs(r.K_slider[0, 2]) < 1e-9 * r.k_axial
        assert r.slack_force_N() == pytest.approx(tau / np.abs(r.dT_dF).max())   # a load of either sign


def test_element_springs_do_not_read_the_analytical_law(ref):
    """law_scale.act mutates eq. 44 (the analytical side) and not the elements: what lets coverage detect it."""
    v = ref.with_params(**{"model.law_scale.act": 3.0})
    s = np.array([0.17, 0.25])
    assert np.array_equal(actuation_springs(ref, s), actuation_springs(v, s))
    assert _eq44(v) == pytest.approx(_eq44(ref) / 3)


def test_slider_outside_the_cable_run_is_refused(ref):
    with pytest.raises(ValueError, match="outside the cable run"):
        leg_actuation(ref, ref.geometry.rail_length_m + 0.01)


def test_device_fe_uses_the_elements_and_checks_the_strands(ref):
    """With [actuation.fe] model = "elements" the device FE takes its actuation springs from the elements (one
    per leg, from its slider position) and adds the pretension's transverse geometric stiffness to the guideway
    tip across the rail (frame A x, y); model = "law" keeps eq. 44 and the guideways as they are."""
    from types import SimpleNamespace
    from femcheck.fe_device.device_model import actuation_at, point_geometry, point_model
    legs = point_geometry(ref, ("P5",))
    gw = tuple(SimpleNamespace(K=np.eye(6) * (k + 1.0)) for k in range(6))   # stand-ins: the springs need no mesh
    m = point_model(ref, legs, 0, "P5", gw, None)
    k0, K0 = actuation_at(ref, m)
    assert k0 is None and np.array_equal(K0, m.K_lg)
    v = ref.with_params(**{"actuation.fe.model": "elements"})
    k, K = actuation_at(v, m)
    s = (m.B - m.A) @ np.array([0.0, 0.0, 1.0])
    assert np.allclose(k, actuation_springs(v, s), rtol=1e-14) and np.ptp(k) > 0   # sliders differ at P5
    dK = K - m.K_lg
    tau = v.actuation.fe.cable_pretension_N
    for i, si in enumerate(s):
        g = leg_actuation(v, si)
        assert dK[i, 0, 0] == dK[i, 1, 1] == pytest.approx(tau * (1 / g.strand_lengths[0] + 1 / g.strand_lengths[1]))
        dK[i, 0, 0] = dK[i, 1, 1] = 0.0
    assert not dK.any()                                          # nothing along the rail, no rotations
