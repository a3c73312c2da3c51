"""FE part of the verification: the device FE model (``femcheck.fe_device``) at the test points.

FE solves: one link super-element per run (all legs share it), one guideway super-element per (point,
leg) — 6 per point, run in ``jobs`` worker processes (``concurrent.futures``, spawn start method). After
each FE solve ``progress(description)`` is called (the CLI drives a rich progress bar with it). Timings
are split into meshing, assembly and solve (factorization + condensation) summed over the FE solves,
plus the small dense leg/platform/load-protocol algebra ("platform").
"""
from __future__ import annotations

import concurrent.futures as cf
import dataclasses
import logging
import multiprocessing as mp
import time

import numpy as np

from femcheck.fe_device.device_model import (build_link, guideway_task, point_model,
                                             solve_point)
from femcheck.fe_device.joints import FE_JOINTS, IDEALIZATIONS
from femcheck.fe_device.mesh_levels import MeshSizes, mesh_sizes
from femcheck.kinematics.points import as_point_set

log = logging.getLogger(__name__)


@dataclasses.dataclass(frozen=True)
class FEVerification:
    """FE results: ``results`` {point: PointResult}, ``models`` {point: PointModel}, ``mesh`` sizes,
    ``levels``, ``timings_s`` {meshing, assembly, solve, platform, total}, ``dofs`` {link, guideway_min,
    guideway_max}, ``tets`` {link, guideway_min, guideway_max}, ``fixed_point_iterations`` max over cases,
    ``linear_solver``."""

    points: tuple
    directions: tuple
    levels: tuple
    kind: str
    mesh: MeshSizes
    results: dict
    models: dict
    timings_s: dict
    dofs: dict
    tets: dict
    fixed_point_iterations: int
    linear_solver: str
    friction: object = None
    joint_laws: object = None

    @property
    def joint_law_sources(self) -> dict:
        """``{"spherical": "contact_fe" | "closed_form", "universal": …}`` of the detailed level."""
        from femcheck.fe_device.joint_laws import CLOSED_FORM
        return (self.joint_laws or CLOSED_FORM).sources()

    def deflection(self, point, direction, level, joints) -> float:
        return self.results[point].cases[(level, joints, direction)].deflection_m

    def mean_contributions(self, level: str, joints: str) -> np.ndarray:
        """(5,) mean FE element shares over points x directions (order lg, act, sp, prox, uj)."""
        return np.mean([r.cases[(level, joints, d)].contributions for r in self.results.values()
                        for d in self.directions], axis=0)


@dataclasses.dataclass(frozen=True)
class ContactJointInputs:
    """What the device FE takes from the joints' own contact FE: ``tilt`` the ball-tilt study
    (:func:`femcheck.verify.contact_joints.ball_tilt_study`), ``friction`` the joint friction data with its measured
    tilt slip ratio, ``joint_laws`` the contact-FE-measured joint laws
    (:func:`femcheck.fe_device.joint_laws.measure_joint_laws`), and their wall times ``tilt_s``, ``laws_s``."""

    tilt: dict
    friction: object
    joint_laws: object
    tilt_s: float
    laws_s: float


def contact_joint_inputs(case, joint_mesh: str = "coarse", progress=None) -> ContactJointInputs:
    """The contact-FE joint inputs of the detailed device FE at ``joint_mesh``: the one definition that
    ``femcheck verify`` (with the joint FE) and ``femcheck experiment simulate --model fe`` share, so both run the
    same device FE."""
    from femcheck.fe_device.joint_friction import joint_friction
    from femcheck.fe_device.joint_laws import measure_joint_laws
    from femcheck.verify.contact_joints import ball_tilt_study, tilt_slip_ratio
    t0 = time.perf_counter()
    tilt = ball_tilt_study(case, progress)
    friction = joint_friction(case, tilt_slip_ratio=tilt_slip_ratio(tilt))
    t1 = time.perf_counter()
    joint_laws = measure_joint_laws(case, joint_mesh, progress=progress)
    return ContactJointInputs(tilt, friction, joint_laws, t1 - t0, time.perf_counter() - t1)


def run_fe(case, points, levels=("simplified", "detailed"), mesh: str = "default", jobs: int = 1,
           kind: str = "solid", progress=None, friction=None, joint_laws=None) -> FEVerification:
    """Build and solve the device FE model at ``points`` for ``levels`` (module docstring).

    ``friction``: joint friction data of the ``contact`` joints (default: the case's, tilt slip ratio 1;
    the verification passes the ratio measured by the contact FE of the spherical joint); ``joint_laws``
    (:class:`femcheck.fe_device.joint_laws.JointLaws`): the contact-FE-measured joint laws of the detailed
    level (None: the closed forms).
    """
    t0 = time.perf_counter()
    pts = as_point_set(case, points)      # the run's PointSet: no second inverse kinematics
    points, legs = pts.labels, pts.legs
    sizes = mesh_sizes(case, mesh)
    note = progress or (lambda desc: None)
    tasks = [(k, i, float(legs.slider[k, i])) for k in range(len(points)) for i in range(6)]
    got: dict = {}
    link = None
    if jobs > 1 and kind == "solid":
        # super-elements already in the result cache are read here: a worker process costs more to start
        from femcheck.fe_device.parts import superelement_cached
        if superelement_cached(case, "link", sizes.link_m):
            link = build_link(case, kind, sizes.link_m)
            note("link")
        for k, i, s in [t for t in tasks if superelement_cached(case, "guideway", sizes.guideway_m, t[2])]:
            got[(k, i)] = guideway_task(case, s, kind, sizes.guideway_m)
            note(f"{points[k]} guideway {i}")
        tasks = [t for t in tasks if (t[0], t[1]) not in got]
    if jobs > 1 and (tasks or link is None):
        ctx = mp.get_context("spawn")
        with cf.ProcessPoolExecutor(max_workers=jobs, mp_context=ctx) as ex:
            futs = {} if link is not None else {ex.submit(build_link, case, kind, sizes.link_m): "link"}  # biggest first
            futs.update({ex.submit(guideway_task, case, s, kind, sizes.guideway_m): (k, i) for k, i, s in tasks})
            for f in cf.as_completed(futs):
                key = futs[f]
                if key == "link":
                    link = f.result()
                    note("link")
                    continue
                got[key] = f.result()
                note(f"{points[key[0]]} guideway {key[1]}")
    elif jobs <= 1:
        link = build_link(case, kind, sizes.link_m)
        note("link")
        for k, i, s in tasks:
            got[(k, i)] = guideway_task(case, s, kind, sizes.guideway_m)
            note(f"{points[k]} guideway {i}")
    t_fe = time.perf_counter()
    results, models = {}, {}
    for k, p in enumerate(points):
        m = point_model(case, legs, k, p, [got[(k, i)] for i in range(6)], link)
        models[p] = m
        results[p] = solve_point(case, m, levels, FE_JOINTS, friction=friction, joint_laws=joint_laws)
    t_end = time.perf_counter()
    ses = [link] + list(got.values())
    timings = {"meshing": sum(s.mesh_s for s in ses), "assembly": sum(s.assembly_s for s in ses),
               "solve": sum(s.solve_s for s in ses), "platform": t_end - t_fe, "wall": t_end - t0}
    gdofs = [g.dofs for g in got.values()]
    gtets = [g.n_tets for g in got.values()]
    iters = max(c.iterations for r in results.values() for c in r.cases.values())
    return FEVerification(points=points, directions=tuple(case.loads.directions), levels=tuple(levels), kind=kind,
                          mesh=sizes, results=results, models=models,
                          timings_s={k: round(v, 3) for k, v in timings.items()},
                          dofs={"link": link.dofs, "guideway_min": min(gdofs), "guideway_max": max(gdofs)},
                          tets={"link": link.n_tets, "guideway_min": min(gtets), "guideway_max": max(gtets)},
                          fixed_point_iterations=int(iters), linear_solver=link.solver or "dense",
                          friction=friction, joint_laws=joint_laws)
