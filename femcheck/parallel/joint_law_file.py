"""Law files for the ``measured_law`` joint element of parallel devices.

Two kinds of file carry a joint's contact-FE law (SI, joint frame x, y lateral, z axial; rotations tilt, tilt,
spin):

* the JSON of ``femcheck check-joints --json`` as it is: its ``fe_compliance`` (6 x 6, the secant of the eq. 1
  load increment between its two ``loads_N`` levels) is a constant law;
* a force-ladder file written here from a :class:`femcheck.fe_device.joint_laws.MeasuredJointLaw` (the contact FE
  over a ladder of axial forces, cached on disk): ``loads_N`` (k,) and ``approach_m`` (k,) make the axial entry
  load-dependent (the tangent of the piecewise power law, :func:`femcheck.parallel.chain_model.ladder_compliance`),
  and ``fe_compliance`` is the inverse of the stick tangent stiffness at one ladder level (the other entries).

``python -m femcheck.parallel.joint_law_file CASE --joint spherical --mesh coarse --out FILE`` measures (or reads
from the cache) the ladder of a 6-PSU case's joint and writes the file.
"""
from __future__ import annotations

import json

import numpy as np


def ladder_law_document(law, at_N: float | None = None) -> dict:
    """The law file of ``law`` (:class:`~femcheck.fe_device.joint_laws.MeasuredJointLaw`) as a JSON-ready dict.

    ``at_N``: the force (N) whose nearest ladder level gives ``fe_compliance`` = K_k^-1 (default: the ladder's
    geometric middle). The axial entry of that matrix is replaced by the ladder's law in the model."""
    F = np.asarray(law.loads_N, float)
    at = float(np.sqrt(F[0] * F[-1])) if at_N is None else float(at_N)
    k = int(np.argmin(np.abs(np.log(F) - np.log(at))))
    K = 0.5 * (law.stiffness[k] + law.stiffness[k].T)
    S = np.linalg.inv(K)
    return {"joint": law.joint, "mesh": law.mesh, "kind": "force_ladder",
            "loads_N": [float(v) for v in F], "approach_m": [float(v) for v in law.approach_m],
            "fe_compliance": [[float(v) for v in row] for row in 0.5 * (S + S.T)],
            "fe_compliance_at_N": float(F[k]), "dofs": int(law.dofs), "contact_iterations": int(law.iterations),
            "seconds": round(float(law.seconds), 2)}


def write_ladder_law(case, joint: str, path, mesh: str = "coarse", at_N: float | None = None) -> dict:
    """Measure (or read from the cache) ``joint``'s force ladder on ``case`` (a 6-PSU case) and write its law file."""
    from femcheck.fe_device.joint_laws import measure_joint_law
    from femcheck.report.atomic import write_text_atomic
    doc = ladder_law_document(measure_joint_law(case, joint, mesh), at_N)
    write_text_atomic(path, json.dumps(doc, indent=2) + "\n")
    return doc


def main(argv=None) -> int:
    import argparse
    from femcheck.case import load_case
    from femcheck.errors import FemcheckError
    ap = argparse.ArgumentParser(prog="python -m femcheck.parallel.joint_law_file", description=__doc__.split("\n")[0])
    ap.add_argument("case")
    ap.add_argument("--joint", choices=("spherical", "universal"), required=True)
    ap.add_argument("--mesh", choices=("coarse", "default", "fine"), default="coarse")
    ap.add_argument("--at-N", type=float, default=None, help="ladder level of the constant entries (N)")
    ap.add_argument("--out", required=True)
    a = ap.parse_args(argv)
    try:
        doc = write_ladder_law(load_case(a.case), a.joint, a.out, a.mesh, a.at_N)
    except FemcheckError as exc:
        print(f"error: {exc}")
        return 2
    print(f"wrote {a.out}: {a.joint} ladder {doc['loads_N'][0]:.3g}..{doc['loads_N'][-1]:.3g} N, "
          f"{len(doc['loads_N'])} levels, {doc['dofs']} DOFs")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
