"""The contact-stiffness identification case (seed 004 §4): the 1-D bar of Fig. 7 for the normal
contact stiffness and the 5 x 3 x 0.75 in specimen of Fig. 16 for the tangential one.

Each TOML table becomes one frozen dataclass; :class:`ContactSpecimenCase` holds them. SI units
(m, Pa, kg/m^3, N/m, Hz). Errors name the file and the dotted key.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from femcheck.case.solver_options import SolverOptions
from femcheck.case.schema import CaseMeta as Meta, CaseRecord, Material, build_sectioned, option, quantity

CASE_KIND = "contact_specimen"

_FACES = ("x-", "x+", "y-", "y+", "z-", "z+")


@dataclass(frozen=True)
class BarSection:
    """Uniform bar on a normal contact spring at one end (seed 004 Fig. 7, eqs. 20–31)."""
    material: Material = option(doc="material name")
    length_m: float = quantity("m", doc="l, bar length (free end to contact end)")
    area_m2: float = quantity("m^2", doc="A, cross-section area")
    contact_area_m2: float = quantity("m^2", doc="nominal contact area of the bar end (k_n per area = k_n / A_c)")


@dataclass(frozen=True)
class SpecimenSection:
    """Rectangular block with contact springs on two faces (seed 004 §4.3, Fig. 16, eq. 44)."""
    material: Material = option(doc="material name")
    length_m: float = quantity("m", doc="edge along x")
    width_m: float = quantity("m", doc="edge along y")
    thickness_m: float = quantity("m", doc="edge along z")
    contact_faces: tuple[str, ...] = option(("z-", "z+"), doc="faces carrying contact springs (x-, x+, y-, y+, z-, z+)")
    contact_size_m: tuple[float, float] | None = quantity(
        "m", default=None, doc="size of the centred contact patch on each face (in-face axes in x, y, z order); omit = whole face")
    normal_contact: Literal["stick", "spring"] = option(
        "stick", doc="stick: u.n = 0 on the patch (seed 004: k_n -> inf); spring: finite normal_stiffness_N_per_m")
    normal_stiffness_N_per_m: float = quantity("N/m", default=1.0e10, doc="k_n per patch when normal_contact = 'spring'")

    def __post_init__(self):
        bad = [f for f in self.contact_faces if f not in _FACES]
        if bad:
            raise ValueError(f"contact_faces: {bad[0]!r}; expected one of {list(_FACES)}")
        if len(set(self.contact_faces)) != len(self.contact_faces):
            raise ValueError(f"contact_faces: {list(self.contact_faces)} names a face twice")
        if self.contact_size_m is not None:
            axes = {f[0] for f in self.contact_faces}
            if len(axes) != 1:
                raise ValueError("contact_size_m: a patch size needs all contact faces normal to the same axis")
            if min(self.contact_size_m) <= 0:
                raise ValueError(f"contact_size_m: {list(self.contact_size_m)}; expected sizes > 0")
            dims = {"x": self.length_m, "y": self.width_m, "z": self.thickness_m}
            inface = [a for a in "xyz" if a not in axes]
            for a, s in zip(inface, self.contact_size_m):
                if s > dims[a] * (1 + 1e-12):
                    raise ValueError(f"contact_size_m: {s} m along {a} exceeds the specimen edge {dims[a]} m")

    @property
    def dims_m(self) -> tuple[float, float, float]:
        return (self.length_m, self.width_m, self.thickness_m)


@dataclass(frozen=True)
class FEOptions:
    element: Literal["hex1", "hex2"] = option("hex2", doc="hexahedral Q1 or Q2 (27-node) elements")
    divisions: tuple[int, int, int] = quantity("-", default=(8, 6, 2), doc="elements along x, y, z")
    n_modes: int = quantity("-", default=6, doc="number of modes in the frequency-stiffness relation")


@dataclass(frozen=True)
class Identification:
    frequency_sigma_Hz: float = quantity("Hz", check="nonnegative", default=1.0,
                                         doc="absolute 1-sigma of a measured frequency (e.g. FFT line spacing)")
    frequency_rel_sigma: float = quantity("-", check="nonnegative", default=1.0e-3,
                                          doc="relative 1-sigma of a measured frequency")
    k_t_min_N_per_m: float = quantity("N/m", default=1.0e6, doc="lower end of the tangential sweep")
    k_t_max_N_per_m: float = quantity("N/m", default=1.0e11, doc="upper end of the tangential sweep")
    sweep_points: int = quantity("-", default=21, doc="points of the tangential sweep (log spaced)")
    confidence: float = quantity("-", check="fraction", default=0.95, doc="level of the preload-law band")

    def __post_init__(self):
        if self.k_t_max_N_per_m <= self.k_t_min_N_per_m:
            raise ValueError("k_t_max_N_per_m: must exceed k_t_min_N_per_m")
        if self.sweep_points < 3:
            raise ValueError(f"sweep_points: = {self.sweep_points}; expected >= 3")
        if self.frequency_sigma_Hz == 0 and self.frequency_rel_sigma == 0:
            raise ValueError("frequency_rel_sigma: frequency_sigma_Hz and frequency_rel_sigma are both 0; expected one > 0")


@dataclass(frozen=True)
class ContactSpecimenCase(CaseRecord):
    """A validated contact-identification case. Immutable; variants via :meth:`with_params`."""

    materials: tuple[Material, ...]
    bar: BarSection
    specimen: SpecimenSection
    fe: FEOptions = FEOptions()
    identification: Identification = Identification()
    solver: SolverOptions = SolverOptions()

    kind = CASE_KIND



SECTIONS = {"solver": SolverOptions, "meta": Meta, "bar": BarSection, "specimen": SpecimenSection, "fe": FEOptions,
            "identification": Identification}
OPTIONAL_SECTIONS = ("solver", "meta", "fe", "identification")


def build(raw: dict, path) -> ContactSpecimenCase:
    """Validate a parsed TOML document into a :class:`ContactSpecimenCase` (errors name file and key)."""
    return build_sectioned(ContactSpecimenCase, raw, path, SECTIONS, OPTIONAL_SECTIONS)
