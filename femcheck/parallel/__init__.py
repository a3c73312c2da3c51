"""Parallel devices described leg by leg: numeric inverse kinematics of any leg set, the general
compliance-chain model ``K_T = sum_i G_i^T K_i G_i`` and its beam FE, all from one ``parallel_device`` case.

- :mod:`femcheck.parallel.device`: the legs as arrays (joint screws, links, joint laws) and the test points;
- :mod:`femcheck.parallel.leg_kinematics`: inverse kinematics, joint twists, actuation Jacobian;
- :mod:`femcheck.parallel.chain_model`: ``evaluate`` (simplified / detailed, rigid / released, element scales);
- :mod:`femcheck.parallel.kernel_tables`, :mod:`femcheck.parallel.chain_kernel`, :mod:`femcheck.parallel.compiled`:
  the compiled (numba) path of the inverse kinematics and of the chain model, used by default (``backend``);
  the numpy functions above stay the reference the tests hold it to;
- :mod:`femcheck.parallel.beam_fe`: the same device as beams with idealized joints and a rigid platform;
- :mod:`femcheck.parallel.verification`: analytical vs beam FE at the test points (``femcheck verify``);
- :mod:`femcheck.parallel.stiffness_map`: the ``femcheck map`` slice.

The 6-PSU reference case (``cases/haptic_6psu.toml``) is a parallel device whose legs are the paper's layout
(:mod:`femcheck.case.psu_layout`); its five-element chain model ``femcheck.chain`` is this package's model on
those legs (:mod:`femcheck.chain.psu_view`).
"""
