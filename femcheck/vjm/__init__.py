"""Virtual joint method (VJM) stiffness models of serial and parallel robots (seeds 001, 002, 003).

Modules, one concept each:

* :mod:`~femcheck.vjm.dh` -- Denavit-Hartenberg chains (standard and modified/Craig), forward
  kinematics and the geometric Jacobian at the tool point, vectorized over poses.
* :mod:`~femcheck.vjm.cartesian_stiffness` -- C = J K_theta^-1 J^T, K = J^-T (K_theta - K_C) J^-1,
  the complementary stiffness K_C of the external wrench, deflections (seed 002 eqs. 4-5, seed 003 eqs. 12-15).
* :mod:`~femcheck.vjm.serial_vjm` -- a serial robot's VJM model (chain + springs) and its deflection under a wrench.
* :mod:`~femcheck.vjm.drive_train` -- joint stiffness from motor, harmonic reducer and timing belt in series (seed 003 sec. 3).
* :mod:`~femcheck.vjm.extended_vjm` -- three virtual joints per actuated joint and the least-squares identification
  of their compliances (seed 002 eqs. 9-12), with configurations scored by the condition number.
* :mod:`~femcheck.vjm.parallel_vjm` -- leg stiffness from the bordered compliance matrix, legs summed (seed 001 eqs. 2-6).
* :mod:`~femcheck.vjm.rcube_geometry` -- the (assumed) R-CUBE leg geometry of the HISS haptic device (seed 001 sec. 2).
* :mod:`~femcheck.vjm.weight_fitting` -- K' = W K W^T model fitting with restarts, identifiability and intervals,
  and the linear fine-tuning and error statistics (seed 001 sec. 3, Tables 2-4).
* :mod:`~femcheck.vjm.rcube_weight_model` -- the HISS platform twist as a function of the weights, with its exact Jacobian.
* :mod:`~femcheck.vjm.hole_twist` -- platform twist from three measured holes (seed 001 sec. 4.2).
* :mod:`~femcheck.vjm.hiss_pipeline` -- seed 001's measured-data workflow (CSV, twists, fits, Tables 2-4, virtual experiments).
* :mod:`~femcheck.vjm.hiss_published` -- seed 001's Tables 2-4 as printed.
* :mod:`~femcheck.vjm.beam_world` -- a beam-FE "world" of a serial arm (tubes, six-spring joints, self-weight) that
  makes virtual measurements no VJM made; reduces exactly to the conventional / extended VJM in its rigid limits.
* :mod:`~femcheck.vjm.world_identification` -- seed 002's identification workflow (conventional vs extended) on such a world.

Importing the package does no work.
"""
