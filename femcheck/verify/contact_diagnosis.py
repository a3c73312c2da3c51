"""The contact FE as a virtual experiment, diagnosed against the paper's rigid model.

``femcheck verify`` (detailed level, all 9 points) turns its detailed FE with contact joints into the
readings of the paper's protocol (:func:`femcheck.experiment.simulate.simulate` with
:class:`femcheck.diagnose.fe_model.DeviceFEReadingModel`: 9 points, ±x ±y ±z, preload, 3 trials, noise
and 0.01 mm dials) and diagnoses them against the detailed analytical model with ``rigid`` joints (the
paper's) and with ``released`` joints. Expected: the rigid diagnosis names ``joint_rotation_release``
and its extended model reaches the held-out error of the released model.
"""
from __future__ import annotations

import dataclasses

#: seed of the reading noise of the virtual experiment (fixed: the verification is deterministic)
NOISE_SEED = 2026


@dataclasses.dataclass(frozen=True)
class ContactDiagnosis:
    """``csv_text`` readings, ``truth`` dict, ``rigid`` and ``released`` diagnosis JSON objects."""

    csv_text: str
    truth: dict
    rigid: dict
    released: dict

    def summary_rows(self) -> list[dict]:
        rows = []
        for name, d in (("detailed rigid (paper)", self.rigid), ("detailed released", self.released)):
            rows.append({"model diagnosed": name, "causes named": ", ".join(c["id"] for c in d["causes"]) or "none",
                         "held-out error before %": 100 * d["heldout_error_before"]["overall"],
                         "held-out error after %": 100 * d["heldout_error_after"]["overall"]})
        return rows


def _diagnosed(case, joints: str, readings) -> dict:
    """The diagnosis JSON of ``readings`` against the detailed analytical model with ``joints``."""
    from femcheck.diagnose import AnalyticalChainModel, diagnose
    return diagnose(AnalyticalChainModel(case, "detailed", joints), readings).as_json()


def diagnose_contact_fe(case, fe, friction=None, jobs: int = 1) -> ContactDiagnosis:
    """Virtual experiment from the contact FE of ``fe`` (a detailed-level ``FEVerification`` at P0..P8) and
    its diagnosis against the rigid and the released detailed analytical models. ``jobs`` >= 2: the released
    diagnosis runs in a second process beside the rigid one (the two are independent and each takes tens of
    seconds of model evaluations)."""
    import concurrent.futures as cf
    import multiprocessing

    from femcheck.diagnose.fe_model import DeviceFEReadingModel
    from femcheck.experiment.simulate import simulate
    from femcheck.measured.protocol import process
    from femcheck.sweep.executor import pool_start_method

    ve = simulate(case, (), seed=NOISE_SEED, model=DeviceFEReadingModel(case, fe, friction=friction))
    readings = process(ve.data, case)
    if jobs >= 2:
        with cf.ProcessPoolExecutor(max_workers=1, mp_context=multiprocessing.get_context(pool_start_method())) as ex:
            released = ex.submit(_diagnosed, case, "released", readings)
            rigid = _diagnosed(case, "rigid", readings)
            released = released.result()
    else:
        rigid, released = (_diagnosed(case, j, readings) for j in ("rigid", "released"))
    return ContactDiagnosis(ve.csv_text, ve.truth, rigid, released)
