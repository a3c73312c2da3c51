"""Serial robots as kinematic trees: kinematics, self-weight elastics, the absolute-position measurement model
and the self-weight diagnosis."""
