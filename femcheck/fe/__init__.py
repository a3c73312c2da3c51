"""Finite-element solver on scikit-fem: elasticity, beams, couplings, penalty contact, modal analysis."""
