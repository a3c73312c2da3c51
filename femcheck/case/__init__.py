"""Case files: TOML -> validated, immutable model objects (one module per case kind)."""
from femcheck.case.registry import build_case, case_kinds, load_case, with_params
from femcheck.case.schema import Material

__all__ = ["load_case", "build_case", "case_kinds", "with_params", "Material"]
