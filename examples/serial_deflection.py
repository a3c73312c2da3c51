"""Deflection of a serial robot (ABB IRB 120, conventional VJM after seed 003) through the Python API:
what ``femcheck deflect cases/irb120.toml --pose 0,30,-20,0,45,0 --deg --wrench 0,0,-100,0,0,0`` prints.

Run: ``python examples/serial_deflection.py`` from the repository root.
"""
import dataclasses

import numpy as np

import femcheck
from femcheck.vjm.serial_vjm import deflect

# The case holds the DH table and the drive trains; femcheck turns the drive-train components into one
# joint stiffness per axis (springs in series, seed 003 eq. 21).
case = femcheck.load_case("cases/irb120.toml")
model = case.vjm()                       # the case's model.vjm (conventional: one torsion spring per joint)
print("joint stiffness (N m/rad):", np.round(model.k_theta, 2))

# Joint angles (rad, one row per pose) and a 100 N downward force at the flange centre.
q = np.deg2rad([[0, 30, -20, 0, 45, 0]])
wrench = np.array([0.0, 0.0, -100.0, 0.0, 0.0, 0.0])
res = deflect(model, q, wrench, complementary=False)   # K_C off: seed 003 eq. 15
print("flange twist [dx, dy, dz] (mm):", np.round(res.twist[0, :3] * 1e3, 4))

# Checks: the conventional VJM (K_C off) is linear, t = J K_theta^-1 J^T w, so
# (1) the flange moves down under a downward push and (2) doubling the load doubles the twist;
# (3) a stiffer joint 2 (the shoulder, carrying the longest lever) can only reduce the deflection.
assert res.twist[0, 2] < 0
res2 = deflect(model, q, 2 * wrench, complementary=False)
assert np.allclose(res2.twist, 2 * res.twist, rtol=1e-12, atol=0)
k = np.array(model.k_theta, float)
k[1] *= 10
stiffer = deflect(dataclasses.replace(model, k_theta=tuple(k)), q, wrench, complementary=False)
assert np.linalg.norm(stiffer.twist[0, :3]) < np.linalg.norm(res.twist[0, :3])
print("serial_deflection: all checks passed")
