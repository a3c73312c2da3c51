"""The one plugin-discovery helper and the one direction parser."""
import numpy as np
import pytest

from femcheck.kinematics.directions import direction_unit
from femcheck.registry import module_names, plugin, plugins


@pytest.mark.parametrize("text, axis, sign", [("+x", 0, 1), ("-y", 1, -1), ("z", 2, 1), (" -Z ", 2, -1)])
def test_direction_unit_is_a_signed_basis_vector(text, axis, sign):
    v = direction_unit(text)
    expected = np.zeros(3)
    expected[axis] = sign
    assert np.array_equal(v, expected)


@pytest.mark.parametrize("bad", ["w", "+xy", "--x", "", "x+"])
def test_direction_unit_rejects_non_axes(bad):
    with pytest.raises(ValueError, match="direction"):
        direction_unit(bad)


def test_direction_unit_sign_required():
    with pytest.raises(ValueError, match=r"\+x"):
        direction_unit("x", sign_required=True)


def test_every_discovery_site_finds_its_plugins():
    from femcheck.bench.__main__ import _areas
    from femcheck.case.registry import case_kind_module, case_kinds
    from femcheck.diagnose.effects import effects
    from femcheck.fe.checks import registry
    assert {"parallel_device", "serial_robot"} <= set(case_kinds()) and "haptic_6psu" not in case_kinds()
    assert case_kind_module("registry") is None  # a module without CASE_KIND/build is no kind
    assert "none" in effects() and "link_modulus" in effects()
    assert "cantilever-solid" in registry()
    assert all(not n.startswith("_") for n in module_names("femcheck.bench"))
    assert plugin("femcheck.case", "no_such_kind", ("build",)) is None
    assert all(hasattr(m, "register") for m in plugins("femcheck.cli", ("register",)))
