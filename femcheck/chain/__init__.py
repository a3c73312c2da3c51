"""The 6-PSU device's compliance chain in the paper's five elements (seed 000 §3-4; docs/conventions.md §4-7),
computed by the general parallel-device model (:mod:`femcheck.chain.psu_view`)."""
from femcheck.chain.device_parameters import DeviceParameters, device_parameters
from femcheck.chain.psu_view import (ELEMENT_NAMES, ELEMENTS, MODEL_ELEMENTS, ChainAdjustments, ChainResult,
                                     chain_element_compliances, evaluate)

__all__ = ["DeviceParameters", "device_parameters", "ELEMENTS", "ELEMENT_NAMES", "MODEL_ELEMENTS", "ChainAdjustments",
           "ChainResult", "chain_element_compliances", "evaluate"]
