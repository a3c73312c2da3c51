"""What each joint of a leg does with the six relative DOFs between the two nodes it joins.

A joint between node a and node b (both at the same point) is written in a joint frame R (3 x 3,
columns = axes in U) through its relative twist r: u_b = u_a + Rot(R) r (docs/conventions.md §4, Rot =
blockdiag(R, R)). Every component of r is either *tied* (r_k = 0, a coupling), *free* (no stiffness, a
released joint rotation) or a *spring* of stiffness k (N/m), so a joint is the selection E (6 x k) of the
non-tied components. Per docs/conventions.md §5:

=========  ===============  ===================================================================
joint      frame            simplified level / detailed level
=========  ===============  ===================================================================
act        A_i (z = rail)   tied (actuation rigid) / spring 1/c_act along z, rest tied
sp         U                translations tied / springs k_sp (Hertz); rotations tied (``rigid``)
                            or free (``released``: all three)
uj         B_i (z = u_i)    translations tied / springs (K_UC, K_UC, 1/(1/K_UC + 1/K_UB));
                            rotations tied (``rigid``) or free about x_B = a1, y_B = a2 (``released``)
=========  ===============  ===================================================================

The detailed FE also has ``contact`` joints (:data:`FE_JOINTS`): the joints as the contact FE of each
joint alone finds them — translations as above, the rotations that an ideal joint releases (sp: all
three, uj: a1 and a2) carry the frictional stick/slip law of :mod:`.joint_friction` as secant springs.

(x_B = unit(z x u_i) is the a1 of docs/conventions.md §5 at the test points, y_B = u_i x a1 = a2.)
"""
from __future__ import annotations

import dataclasses

import numpy as np

LEVELS = ("simplified", "detailed")
IDEALIZATIONS = ("rigid", "released")
#: joint settings of the FE: the two analytical idealizations, and the frictional contact joints
#: (detailed level only)
FE_JOINTS = IDEALIZATIONS + ("contact",)


@dataclasses.dataclass(frozen=True)
class JointLayout:
    """Non-tied components of the three joints for one (level, idealization).

    ``act``, ``sp``, ``uj``: tuples of component indices 0..5 (u_x, u_y, u_z, θ_x, θ_y, θ_z in the joint
    frame) that are not tied; ``*_springs``: the subset of those that carry a spring (the others are free).
    """

    level: str
    joints: str
    act: tuple[int, ...]
    sp: tuple[int, ...]
    uj: tuple[int, ...]
    act_springs: tuple[int, ...]
    sp_springs: tuple[int, ...]
    uj_springs: tuple[int, ...]

    @staticmethod
    def selection(components) -> np.ndarray:
        """E (6, k): columns = unit vectors of ``components``."""
        return np.eye(6)[:, list(components)]


def joint_layout(level: str, joints: str) -> JointLayout:
    """The :class:`JointLayout` of ``level`` ('simplified' | 'detailed') and ``joints`` ('rigid' | 'released' | 'contact')."""
    if level not in LEVELS:
        raise ValueError(f"level = {level!r}; expected one of {', '.join(LEVELS)}")
    if joints not in FE_JOINTS:
        raise ValueError(f"joints = {joints!r}; expected one of {', '.join(FE_JOINTS)}")
    detailed = level == "detailed"
    if joints == "contact" and not detailed:
        raise ValueError("joints = 'contact' exists for the detailed level only (the simplified level has no joint model)")
    released = joints == "released"
    contact = joints == "contact"
    act_springs = (2,) if detailed else ()
    sp_springs = (0, 1, 2, 3, 4, 5) if contact else (0, 1, 2) if detailed else ()
    uj_springs = (0, 1, 2, 3, 4) if contact else (0, 1, 2) if detailed else ()
    sp_free = (3, 4, 5) if released else ()
    uj_free = (3, 4) if released else ()
    return JointLayout(level, joints, act=act_springs, sp=sp_springs + sp_free, uj=uj_springs + uj_free,
                       act_springs=act_springs, sp_springs=sp_springs, uj_springs=uj_springs)
