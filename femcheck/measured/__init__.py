"""Measured TCP deflections of a device: the CSV format (docs/conventions.md §10) and the test protocol
(seed 000 §3.1.3, §4.3.2: trials, preload subtraction by eq. 1, preload identification, uncertainty)."""
from femcheck.measured.csv_format import COLUMNS, OPTIONAL_COLUMNS, PHASES, MeasuredData, read_measured_csv, write_measured_csv
from femcheck.measured.protocol import PreloadIdentification, Readings, identify_preload, process

__all__ = ["COLUMNS", "OPTIONAL_COLUMNS", "PHASES", "MeasuredData", "read_measured_csv", "write_measured_csv",
           "Readings", "process", "PreloadIdentification", "identify_preload"]
