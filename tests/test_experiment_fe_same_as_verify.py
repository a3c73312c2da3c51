"""``femcheck experiment simulate --model fe`` reads the device FE of ``femcheck verify``: the same contact-FE joint
laws and measured tilt slip ratio, so its readings reproduce verify's eq. 1 deflections."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import femcheck

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.slow
def test_virtual_experiment_fe_pins_to_the_verify_fe():
    from femcheck.diagnose.fe_model import device_fe_reading_model
    from femcheck.fe_device.loads import direction_unit
    from femcheck.verify.fe import contact_joint_inputs, run_fe

    case = femcheck.load_case(ROOT / "cases" / "haptic_6psu.toml")
    # the reading model of `experiment simulate --model fe` (coarse meshes, beam parts to keep it short)
    model = device_fe_reading_model(case, ("P0",), "coarse", "beam", "coarse")
    assert model.fe.joint_law_sources == {"spherical": "contact_fe", "universal": "contact_fe"}
    # the device FE as `verify --joint-fe` builds it (run_verify: contact_joint_inputs, then run_fe)
    cj = contact_joint_inputs(case, "coarse")
    fe = run_fe(case, ("P0",), ("detailed",), "coarse", kind="beam", friction=cj.friction, joint_laws=cj.joint_laws)
    # the tilt study is solved afresh on each side; the contact solver repeats itself to ~1e-11 (measured 3e-12)
    assert model.fe.friction.tilt_slip_ratio == pytest.approx(cj.friction.tilt_slip_ratio, rel=1e-9)
    L = case.loads
    P0 = femcheck.test_points(case)[0]
    for d in L.directions:
        u = direction_unit(d)
        forces = np.outer([L.detailed_preload_N, L.detailed_preload_N + L.detailed_test_N], u)
        r = model.tcp_displacement(np.tile(P0, (2, 1)), forces, model.base_scale)
        # eq. 1 from two readings loaded from zero = verify's deflection (the same secant solves, the same joint
        # laws; the slip ratio to ~1e-11)
        assert float((r[1] - r[0]) @ u) == pytest.approx(fe.deflection("P0", d, "detailed", "contact"), rel=1e-9)
