"""The README's Python API, narrated, ending in checks.

Run: ``python examples/python_api.py`` from the repository root (SI units throughout).
"""
import numpy as np

import femcheck

# A case file is validated into an immutable model object; the 9 test points of seed 000 are poses
# [x, y, z, rx, ry, rz] (m, rad; rotation vector): P0 the centre of the workspace cube, P1..P8 its corners.
case = femcheck.load_case("cases/haptic_6psu.toml")
poses = femcheck.test_points(case)

# 15 N along +x at every pose: the TCP twist [dx, dy, dz, rx, ry, rz] (m, rad) of the detailed model
# (guideways, actuation, Hertz spherical joints, proximal links, universal joints).
wrench = np.array([15.0, 0, 0, 0, 0, 0])
t = femcheck.deflection(case, poses, wrench, model="detailed")
print("deflection along +x at P0..P8 (um):", np.round(t[:, 0] * 1e6, 2))

# The tangent stiffness, linearized at the same wrench (the Hertz contacts make the model load-dependent),
# and the share of each element in the deflection energy (seed 000 Fig. 23).
K = femcheck.stiffness(case, poses, model="detailed", wrench=wrench)
shares = femcheck.contributions(case, poses, wrench)
print("mean shares:", {k: round(float(v.mean()), 3) for k, v in shares.items()})

# A design variant: a wider guideway, re-validated like the original file.
variant = case.with_params(**{"guideway.width_radial_m": 0.016})
t_wide = femcheck.deflection(variant, poses, wrench, model="detailed")

# Checks (physics, not numbers copied from a run):
# the platform yields along the push, at every pose
assert np.all(t[:, 0] > 0)
# the simplified model is linear: K t = w exactly (round-off)
Ks = femcheck.stiffness(case, poses, model="simplified")
ts = femcheck.deflection(case, poses, wrench, model="simplified")
assert np.allclose(np.einsum("nij,nj->ni", Ks, ts), wrench, rtol=0, atol=1e-9 * 15)
# a stiffness matrix is symmetric positive definite
assert np.allclose(K, np.swapaxes(K, 1, 2), rtol=1e-9, atol=1e-6 * np.abs(K).max())
assert np.all(np.linalg.eigvalsh(0.5 * (K + np.swapaxes(K, 1, 2))) > 0)
# element shares of the energy are fractions summing to one
assert np.allclose(sum(shares.values()), 1.0) and all(np.all(v >= -1e-12) for v in shares.values())
# a wider guideway cannot make the device softer along x
assert np.all(t_wide[:, 0] <= t[:, 0] * (1 + 1e-12))
print("python_api: all checks passed")
