"""``sensor_misalignment``: the three dials are not aligned with U. The readings are the TCP translation
seen in a dial frame rotated by the small rotation vector theta (rad): ``d_read = R(theta) d``
(Rodrigues). Signature: axis cross-talk, i.e. a load along x gives readings along y and z that the model
does not predict, and a cos(theta) loss along the load.
"""
import numpy as np

from femcheck.diagnose.effects import Effect, Param
from femcheck.kinematics.frames import rotvec_to_matrix


class SensorMisalignment(Effect):
    id = "sensor_misalignment"
    stage = 9
    params = tuple(Param(f"theta_{a}_rad", -0.6, 0.6, 0.0, typical=0.05, neutral=0.0, prior_sd=3.0, doc=f"dial frame rotation about {a}")
                   for a in "xyz")

    def neutral(self, model):
        return np.zeros(3)

    def apply(self, model, readings, values, state):
        state.sensor = rotvec_to_matrix(np.asarray(values, float)) @ state.sensor

    def location(self, values, lo, hi):
        deg = np.rad2deg(values)
        return f"dial frame rotated by [{deg[0]:.1f}, {deg[1]:.1f}, {deg[2]:.1f}] deg"

    def sample_truth(self, rng, case):
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        ang = np.deg2rad(rng.uniform(12.0, 20.0))
        return {f"theta_{a}_rad": float(v) for a, v in zip("xyz", ang * axis)}


EFFECT = SensorMisalignment()
