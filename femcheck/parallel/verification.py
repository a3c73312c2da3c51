"""Analytical chain model vs beam FE of a parallel device at its test points (what ``femcheck verify`` runs for a
``parallel_device`` case): the deflection along each load direction under the case's test force, for each
model level and joint idealization, and their relative error.

Two FE routes from the same description (:mod:`femcheck.parallel.beam_fe`): ``parts="beam"`` meshes the links with
beam elements, which reproduce the analytical cantilevers exactly, so analytical vs beam FE checks the chain
algebra (carrying, releases, the platform sum) to round-off; ``parts="solid"`` meshes every link as a solid
(:mod:`femcheck.parallel.solid_links`) and condenses it, which checks the link laws as well. With ``fe_laws``
(:func:`femcheck.parallel.beam_fe.fe_laws_of`: the drives' elements and the joints' contact FE) the detailed FE
takes none of the analytical drive and joint laws; without, it takes them as they are (the beam route then checks
the chain algebra to round-off).
"""
from __future__ import annotations

import dataclasses

import numpy as np

from femcheck.kinematics.directions import direction_unit
from femcheck.parallel.beam_fe import device_fe_stiffness
from femcheck.parallel.chain_model import evaluate
from femcheck.kinematics.points import POINT_LABELS, test_poses
from femcheck.parallel.leg_kinematics import solve_legs

COLUMNS = ("level", "joints", "point", "direction", "analytical_mm", "fe_mm", "rel_error_pct")


@dataclasses.dataclass(frozen=True)
class VerificationRows:
    """One row per (level, joints, point, direction): deflection along the direction (mm) and the relative
    error 100 (analytical - FE) / FE (%)."""

    rows: tuple[dict, ...]

    @property
    def max_abs_error_pct(self) -> float:
        return max(abs(r["rel_error_pct"]) for r in self.rows)

    def to_csv(self) -> str:
        lines = [",".join(COLUMNS)]
        for r in self.rows:
            lines.append(",".join(f"{r[c]:.9g}" if isinstance(r[c], float) else str(r[c]) for c in COLUMNS))
        return "\n".join(lines) + "\n"

    def to_markdown(self) -> str:
        head = "| " + " | ".join(COLUMNS) + " |\n| " + " | ".join("---" for _ in COLUMNS) + " |\n"
        body = "".join("| " + " | ".join(f"{r[c]:.6g}" if isinstance(r[c], float) else str(r[c]) for c in COLUMNS)
                       + " |\n" for r in self.rows)
        return head + body


def verify_device(case, labels=None, levels=("simplified", "detailed"), joints=("rigid", "released"),
                  elements_per_link: int = 2, parts: str = "beam", mesh: str = "default",
                  progress=None, fe_laws=None) -> VerificationRows:
    """Analytical vs FE deflections of ``case`` at the test points ``labels`` (default P0..P8); ``parts``
    beam | solid, ``mesh`` the solid links' mesh level; ``fe_laws`` the detailed FE's own drive and joint laws
    (module doc); ``progress(description)`` after each FE model."""
    labels = tuple(labels or POINT_LABELS)
    P = test_poses(case, labels)
    dev = case.device
    state = solve_legs(dev, P)
    rows = []
    for level in levels:
        for jt in joints:
            for d in case.loads.directions:
                u = direction_unit(d)
                W = np.concatenate([case.loads.test_N * u, np.zeros(3)])
                r = evaluate(dev, P, W, model=level, joints=jt, state=state)
                K_fe = device_fe_stiffness(dev, P, model=level, joints=jt, hertz_stiffness=r.hertz_stiffness,
                                           state=state, elements_per_link=elements_per_link, parts=parts, mesh=mesh,
                                           fe_laws=fe_laws if level == "detailed" else None, wrench=W)
                if progress:
                    progress(f"{parts} FE {level} {jt} {d}")
                t_fe = np.linalg.solve(K_fe, np.broadcast_to(W, (len(P), 6))[..., None])[..., 0]
                for k, label in enumerate(labels):
                    a, f = float(r.twist[k, :3] @ u) * 1e3, float(t_fe[k, :3] @ u) * 1e3
                    rows.append({"level": level, "joints": jt, "point": label, "direction": d, "analytical_mm": a,
                                 "fe_mm": f, "rel_error_pct": 100.0 * (a - f) / f})
    return VerificationRows(rows=tuple(rows))
