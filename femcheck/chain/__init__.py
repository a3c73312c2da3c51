"""Analytical compliance-chain models of the 6-PSU device (seed 000 §3-4; docs/conventions.md §4-7)."""
from femcheck.chain.device_parameters import DeviceParameters, device_parameters
from femcheck.chain.haptic_6psu_model import (ELEMENT_NAMES, ELEMENTS, ChainAdjustments, ChainResult,
                                            chain_element_compliances, evaluate)

__all__ = ["DeviceParameters", "device_parameters", "ELEMENTS", "ELEMENT_NAMES", "ChainAdjustments", "ChainResult",
           "chain_element_compliances", "evaluate"]
