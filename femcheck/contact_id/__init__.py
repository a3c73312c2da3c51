"""Contact stiffness from natural frequencies (seed 004 §4): the 1-D bar on a normal contact spring,
the preload law of the identified stiffness, and the FE specimen on tangential contact springs.
"""
