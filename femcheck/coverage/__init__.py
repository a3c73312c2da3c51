"""How much of the analytical model the FE verification actually checks (``femcheck coverage``)."""
from femcheck.coverage.element_coverage import CoverageResult, ElementCoverage, element_coverage

__all__ = ["CoverageResult", "ElementCoverage", "element_coverage"]
