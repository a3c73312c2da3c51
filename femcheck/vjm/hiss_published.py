"""The published outcome tables of seed 001 (Gorgulu, Dede, Carbone 2021, HISS haptic master), as printed.

Used by ``femcheck identify`` on a ``parallel_vjm`` case to print the paper's figures beside femcheck's, and by
the tests. The paper does not publish its 65 D/F and 30 F/D measurements, so Tables 3 and 4 cannot be
recomputed from their inputs; the tests check what can be checked: that the printed Table 4 obeys the
identities of the statistics femcheck computes (``RMS^2 = Std^2 (n-1)/n + M^2`` with MATLAB's n-1 standard
deviation, a zero mean after the least-squares correction, the correction never raising the RMS error).

Reading notes: the fourth rows of Tables 3 and 4 are printed as a second "Delta_x"; they are Delta_alpha (the
order is x, y, z, alpha, beta, gamma, |.|_xyz, |.|_abg). Table 4's third group is headed "F/D + D/F" and
Table 2's "D/F + F/D": the same combined set. Units of Tables 3-4: mm and deg (Fig. 10 axes).
"""
from __future__ import annotations

#: setup names in the order of the paper's columns
SETUPS = ("D/F", "F/D", "D/F + F/D")

#: number of measurements per setup (sec. 4.2: 13 TPs x 5; sec. 4.3: 10 TPs x 3; their union)
N_MEASUREMENTS = {"D/F": 65, "F/D": 30, "D/F + F/D": 95}

#: Table 2: (fit, variance) of W1..W11 per setup
TABLE2 = {
    "D/F": ((0.884, 0.038, 0.941, 0.991, 0.866, 0.258, 0.977, 0.978, 0.054, 0.020, 0.125),
            (0.197, 0.000, 0.030, 0.000, 0.009, 0.003, 0.226, 0.000, 0.001, 0.000, 0.148)),
    "F/D": ((0.003, 0.052, 3.954, 0.947, 3.457, 19.46, 0.021, 1.139, 55.50, 0.035, 0.074),
            (0.000, 0.000, 2.056, 0.015, 3.786, 77.27, 0.000, 0.247, 916.5, 0.000, 0.000)),
    "D/F + F/D": ((2.123, 3.650, 6.467, 1.029, 0.004, 0.165, 1.534, 0.994, 0.043, 0.034, 0.066),
                  (113.2, 2.450, 272.3, 6.117, 0.000, 0.000, 59.04, 33.93, 0.000, 0.000, 0.000)),
}

#: rows of Tables 3 and 4
COMPONENTS = ("dx", "dy", "dz", "dalpha", "dbeta", "dgamma", "norm_xyz", "norm_abg")

#: Table 3: (a, b) of x' = a x + b per component and setup
TABLE3 = {
    "D/F": ((0.883, 0.017), (0.970, -0.369), (0.863, 0.014), (0.914, 0.328), (1.102, -0.190), (0.978, -0.111),
            (0.992, 0.170), (0.935, 0.322)),
    "F/D": ((0.956, 0.037), (1.086, -0.131), (1.396, 0.625), (0.348, 0.157), (1.219, -0.296), (2.085, -0.153),
            (0.909, 0.315), (1.087, 0.160)),
    "D/F + F/D": ((0.784, -0.125), (0.885, -0.346), (0.778, 0.011), (0.627, 0.185), (0.801, -0.287),
                  (0.857, -0.155), (0.982, 0.236), (1.020, 0.260)),
}

#: Table 4: per setup and component, (fitted (RMS, Std, M, AM), fine-tuned (RMS, Std, M, AM))
TABLE4 = {
    "D/F": (((0.64, 0.65, -0.04, 0.42), (0.61, 0.62, 0, 0.39)),
            ((0.63, 0.52, 0.37, 0.49), (0.51, 0.52, 0, 0.41)),
            ((0.43, 0.43, -0.03, 0.31), (0.38, 0.38, 0, 0.28)),
            ((0.59, 0.49, -0.33, 0.44), (0.49, 0.49, 0, 0.35)),
            ((0.56, 0.53, 0.19, 0.44), (0.52, 0.53, 0, 0.45)),
            ((0.43, 0.42, 0.11, 0.33), (0.41, 0.42, 0, 0.31)),
            ((0.45, 0.45, 0.04, 0.36), (0.35, 0.35, 0, 0.27)),
            ((0.47, 0.37, -0.30, 0.39), (0.33, 0.34, 0, 0.27))),
    "F/D": (((0.41, 0.41, -0.09, 0.30), (0.40, 0.41, 0, 0.30)),
            ((0.60, 0.57, 0.21, 0.47), (0.56, 0.57, 0, 0.45)),
            ((0.49, 0.43, -0.25, 0.37), (0.39, 0.39, 0, 0.31)),
            ((0.38, 0.37, -0.12, 0.30), (0.35, 0.35, 0, 0.26)),
            ((0.50, 0.42, 0.27, 0.40), (0.41, 0.42, 0, 0.36)),
            ((0.38, 0.37, 0.08, 0.25), (0.32, 0.33, 0, 0.23)),
            ((0.45, 0.44, -0.13, 0.33), (0.41, 0.42, 0, 0.32)),
            ((0.53, 0.40, -0.35, 0.41), (0.40, 0.41, 0, 0.32))),
    "D/F + F/D": (((0.74, 0.74, 0.04, 0.50), (0.65, 0.66, 0, 0.45)),
                  ((0.71, 0.64, 0.31, 0.55), (0.62, 0.62, 0, 0.47)),
                  ((0.59, 0.59, -0.09, 0.44), (0.49, 0.50, 0, 0.38)),
                  ((0.54, 0.52, -0.16, 0.41), (0.48, 0.48, 0, 0.37)),
                  ((0.62, 0.54, 0.32, 0.51), (0.52, 0.52, 0, 0.45)),
                  ((0.48, 0.44, 0.19, 0.37), (0.43, 0.43, 0, 0.32)),
                  ((0.64, 0.63, 0.12, 0.51), (0.50, 0.50, 0, 0.38)),
                  ((0.42, 0.41, -0.08, 0.32), (0.41, 0.41, 0, 0.33))),
}

#: sec. 3.3, Fig. 6: RMS error of an example data set before and after the correction
FIG6_RMS = (0.634, 0.513)
