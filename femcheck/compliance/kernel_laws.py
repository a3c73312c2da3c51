"""The element laws as the compiled chain kernels call them: one implementation of each law, in its module.

The numba chain kernels (:mod:`femcheck.parallel.chain_kernel`) evaluate
two laws inside their per-pose loops: the Hertz point-contact tangent stiffness (inside the linearization fixed
point, at forces known only there) and the cantilever tip compliance (per leg and pose). They do not hold copies
of them: they take the laws as first-class function arguments (numba ``cfunc`` pointers), compiled here from the
function each module holds *when the kernel is called*:

* :func:`femcheck.compliance.hertz_point_contact.hertz_tangent_stiffness` (F, E*, R*) -> k;
* :func:`femcheck.compliance.cantilever_beam.cantilever_terms` (L, E, G, A, Ix, Iy, Jt, κ, shear) -> 8 entries.

Replacing either module attribute (a corrected law, or a mutation that breaks it on purpose) therefore moves
the compiled and the numpy chain models alike, in the same process. The kernels themselves are compiled once
(their signature holds the function type, not the function), so a new law costs only its own small compile.
The other laws (cable, motor shaft, line contact, pin bending, sections, E*, R*) enter the kernels as
per-pose parameters computed in numpy by :func:`femcheck.chain.device_parameters` and
:func:`femcheck.parallel.device.build_device` through their modules.

:func:`law_functions` returns the current law functions, for caches whose values depend on the laws.
"""
from __future__ import annotations

import warnings

from numba import cfunc, types
from numba.core.errors import NumbaExperimentalFeatureWarning

from femcheck.compliance import actuation, cantilever_beam, hertz_line_contact, hertz_point_contact, sections

_F8 = types.float64
HERTZ_SIGNATURE = _F8(_F8, _F8, _F8)
CANTILEVER_SIGNATURE = types.UniTuple(_F8, 8)(_F8, _F8, _F8, _F8, _F8, _F8, _F8, _F8, types.boolean)

#: the laws whose module attribute is read each time (module, attribute)
LAWS = ((hertz_point_contact, "hertz_tangent_stiffness"), (hertz_point_contact, "effective_modulus"),
        (hertz_point_contact, "effective_radius"), (cantilever_beam, "cantilever_terms"),
        (hertz_line_contact, "line_contact_stiffness"), (hertz_line_contact, "pin_bending_stiffness"),
        (actuation, "cable_stiffness"), (actuation, "motor_stiffness_at_cable"),
        (sections, "rectangle_section"), (sections, "tube_section"))

_ORIGINAL = {(m.__name__, a): getattr(m, a) for m, a in LAWS}
_compiled: dict = {}

# the kernels take the laws as first-class functions, a numba feature it marks experimental
warnings.filterwarnings("ignore", message="First-class function type feature is experimental",
                        category=NumbaExperimentalFeatureWarning)


def law_functions() -> tuple:
    """The law functions the modules hold now (for cache keys of values derived from the laws)."""
    return tuple(getattr(m, a) for m, a in LAWS)


def _compile(fn, signature):
    key = (fn, signature)
    if key not in _compiled:
        original = any(fn is f for f in _ORIGINAL.values())
        # the module's own law is cached on disk (keyed on its source); a replacement is compiled in memory
        _compiled[key] = cfunc(signature, cache=original)(fn)
    return _compiled[key]


def kernel_laws() -> tuple:
    """(hertz, cantilever): the compiled laws the chain kernels take as arguments, from the functions
    :mod:`.hertz_point_contact` and :mod:`.cantilever_beam` hold now (module doc)."""
    return (_compile(hertz_point_contact.hertz_tangent_stiffness, HERTZ_SIGNATURE),
            _compile(cantilever_beam.cantilever_terms, CANTILEVER_SIGNATURE))
