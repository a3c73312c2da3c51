"""Contact between deformable bodies: pairing, penalty with friction, augmented Lagrangian.

Modules (one concept each): :mod:`.pairing` (Gauss-point-to-surface pairing, gap/slip operators),
:mod:`.normal_penalty`, :mod:`.coulomb_friction`, :mod:`.augmented_lagrangian` (Uzawa), :mod:`.status`
(open / stick / slide), :mod:`.half_space` (Hertz / Boussinesq closed forms for verification).
The solver entry point is :func:`femcheck.fe.newton.solve_contact`; see docs/fe_solver.md.
"""
