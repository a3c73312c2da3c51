"""``actuation_in_legs``: the actuation compliance is wrong (or missing) in some legs only, e.g. a slack cable, a worn
joint or a loose clamp in those legs: S_act,i -> leg_i S_act,i for the legs i named (see
:mod:`femcheck.diagnose.effects._located`; the diagnosis finds the legs by
:func:`femcheck.diagnose.placement.screen_placements`).
"""
from femcheck.diagnose.effects._located import ElementInLegs

EFFECT = ElementInLegs("act", "actuation_in_legs", uniform_cause="actuation_compliance")
