"""Measured data -> what the model gets wrong, why, the extended model and the gain.

``diagnose(model, readings)`` fits the library of physical effects (``effects``), selects up to two by
information criterion and leave-points-out cross-validation (``selection``) and reports the held-out
error before and after; ``residuals`` gives the residual signatures, ``baseline`` seed 001's generic
weight-matrix correction, ``report`` the Markdown/HTML report.
"""
from femcheck.diagnose.model import AnalyticalChainModel, predict_readings
from femcheck.diagnose.selection import Diagnosis, diagnose

__all__ = ["AnalyticalChainModel", "predict_readings", "Diagnosis", "diagnose"]
