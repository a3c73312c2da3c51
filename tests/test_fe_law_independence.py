"""The FE checks the analytical laws without borrowing from them: every input of the contact FE and of the device
FE (mesh grading, candidate band, initial gap, penetration tolerance, closed-form springs, slip moments, the
joint-law cache key) is the same whether or not an analytical law is broken, while the analytical model moves."""
from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

import femcheck
import femcheck.chain
from femcheck.compliance import actuation, cantilever_beam, hertz_line_contact, hertz_point_contact, sections
from tests.test_kernel_laws import _cantilever_2x_softer, _hertz_3x_compliant

ROOT = Path(__file__).resolve().parents[1]
CASE = ROOT / "cases" / "haptic_6psu.toml"
JOINTS = ("spherical", "universal")


def fe_inputs(case) -> dict:
    """Every FE set-up quantity derived from a contact law or spring (repr: compared bit for bit)."""
    from femcheck.fe_device.contact_scales import device_springs
    from femcheck.fe_device.joint_check import joint_loads, joint_table_key
    from femcheck.fe_device.joint_fe import contact_start
    from femcheck.fe_device.joint_friction import joint_friction
    from femcheck.fe_device.joint_laws import _cache_key, force_ladder
    from femcheck.fe_device.mesh_levels import joint_mesh_sizes

    loads = joint_loads(case, "P0")
    ladder = force_ladder(case)
    fr = joint_friction(case)
    out = {"springs": repr(device_springs(case)), "friction": repr(fr), "loads": repr(loads),
           "slip": repr([m.tolist() for m in fr.slip_moments(np.array(loads))])}
    for j in JOINTS:
        out[f"{j} mesh"] = repr(joint_mesh_sizes(case, j, "coarse", max(loads)))
        out[f"{j} start"] = repr(contact_start(case, j, loads))
        out[f"{j} ladder start"] = repr(contact_start(case, j, (ladder[0], ladder[-1])))
        out[f"{j} law cache key"] = _cache_key(case, j, "coarse", ladder)
        out[f"{j} joint table cache key"] = joint_table_key(case, j, "coarse", "P0")
    return out


# Each factory takes the module's law and returns the broken law (the kernels' two laws: as in test_kernel_laws)
def _swapped(f):
    def broken(b, h):
        s = f(b, h)
        return dataclasses.replace(s, Ix=s.Iy, Iy=s.Ix)
    return broken


def _e_star_through_device_parameters(f):
    def broken(case, overrides=None):
        p = f(case, overrides)
        return dataclasses.replace(p, E_star_sp=p.E_star_sp * 3.0 ** -1.5)
    return broken


# (module, attribute, factory): the five mutations of the analytical laws, and E* broken in three other places
MUTATIONS = {
    "cable 5x softer": (actuation, "cable_stiffness", lambda f: lambda E, d, l: f(0.2 * E, d, l)),
    "pin bending 10x softer": (hertz_line_contact, "pin_bending_stiffness", lambda f: lambda E, r, L: f(0.1 * E, r, L)),
    "Hertz 3x compliant via E*": (hertz_point_contact, "hertz_tangent_stiffness", _hertz_3x_compliant),
    "motor shaft 5x softer": (actuation, "motor_stiffness_at_cable", lambda f: lambda G, d, L, r: f(0.2 * G, d, L, r)),
    "guideway second moments swapped": (sections, "rectangle_section", _swapped),
    "E* of every contact 3x lower": (hertz_point_contact, "effective_modulus",
                                     lambda f: lambda E1, nu1, E2, nu2: f(E1 / 3.0, nu1, E2 / 3.0, nu2)),
    "cantilever 2x softer": (cantilever_beam, "cantilever_terms", _cantilever_2x_softer),
    "E* in device_parameters": (femcheck.chain, "device_parameters", _e_star_through_device_parameters),
}


@pytest.fixture(scope="module")
def case():
    return femcheck.load_case(CASE)


@pytest.fixture(scope="module")
def reference(case):
    P0 = femcheck.test_points(case)[:1]
    return fe_inputs(case), femcheck.chain.evaluate(case, P0, [20.0, 0, 0, 0, 0, 0]).twist[0]


@pytest.mark.parametrize("name", list(MUTATIONS))
def test_fe_inputs_unchanged_by_a_broken_analytical_law(name, case, reference, monkeypatch):
    module, attr, make = MUTATIONS[name]
    monkeypatch.setattr(module, attr, make(getattr(module, attr)))
    fe_ref, twist_ref = reference
    twist = femcheck.chain.evaluate(case, femcheck.test_points(case)[:1], [20.0, 0, 0, 0, 0, 0]).twist[0]
    # the mutation reaches the analytical model: the P0 twist under 20 N along x moves by > 0.1 % of its largest
    # component (the chain model reads device_parameters from its own module, not the package attribute)
    if name != "E* in device_parameters":
        assert np.abs(twist - twist_ref).max() > 1e-3 * np.abs(twist_ref).max()
    # ... and leaves every FE input bit for bit as it was (the FE checks the law, it does not use it)
    assert fe_inputs(case) == fe_ref


@pytest.mark.parametrize("law", ["sp", "uj", "act", "lg", "prox"])
def test_fe_inputs_unchanged_by_law_scale(law, case, reference):
    """``[model.law_scale]`` scales the analytical laws only (coverage mutations)."""
    variant = case.with_params(**{f"model.law_scale.{law}": 3.0})
    assert fe_inputs(variant) == reference[0]
