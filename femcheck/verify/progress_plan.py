"""The steps of a verification run and what each is expected to cost, for the progress bar's ETA.

A run reports a step after each of: the ball tilt contact FE (frictionless, with friction), the joint laws
(spherical, universal), the joint table (build and solve of each joint), the device FE (the link and six
guideways per point, in any order when ``--jobs`` > 1), the tables, plots and VTU, the diagnosis of the contact
FE, the coverage, each mesh of the convergence study and the report files. :class:`VerifyWork` gives each reported step its expected
cost (:data:`COLD_S`; ``CACHED_SHARE`` of it for a step read from the result caches), so the ETA counts work,
not steps (:class:`femcheck.cli._progress.StageProgress`); tests/test_progress.py keeps it within 3x of the time
left after the first tenth of the work on the stage costs measured on cold and warm runs.

Cache state is predicted before the run: the tilt study, the joint laws and the joint table from their cache
entries; the device FE's super-elements are taken as cached when the joint table is (the same earlier run
wrote both; a run whose meshes changed but whose joints did not gets an ETA that is low at first).
"""
from __future__ import annotations

import dataclasses

#: expected wall time (s) per reported step, cold caches, ``--jobs 2``: the stage times of ``make verify`` (manifest.json
#: timings_s of a cold default-mesh run of the nine points on the 2-core machine at load average 3-6: tilt study 7.6 s,
#: joint laws 57 s, joint table 20.5 s, device FE wall 63.5 s for the link and 54 guideways, tables/plots/VTU 8.1 s,
#: contact diagnosis 28.7 s, coverage 3.8 s, convergence 33.4 s for the coarse and fine meshes at P0), split over the
#: stage's steps by their sizes (the universal joint ~60 % of the laws; the link ~8 guideways). Only ratios matter.
COLD_S = {
    "tilt": 3.8,
    "law:spherical": 23.0, "law:universal": 34.0,
    # the table re-meshes the ball (graded on the point's load) and reuses the universal joint's condensed model
    "table:spherical:build": 17.0, "table:spherical:solve": 2.0,
    "table:universal:build": 0.5, "table:universal:solve": 1.0,
    "link:coarse": 1.0, "guideway:coarse": 0.33,
    "link:default": 8.0, "guideway:default": 1.03,
    "link:fine": 12.0, "guideway:fine": 3.0,
    # tables, plots, VTU and PNGs of the first point, per mesh level
    "figures:coarse": 4.0, "figures:default": 8.1, "figures:fine": 20.0,
    "diagnosis": 28.7, "coverage:per_point": 0.42, "report": 1.0,
}
#: a step read from a cache costs this share of its cold time (a pickle or npz read; the analytical column)
CACHED_SHARE = 0.02


@dataclasses.dataclass
class VerifyWork:
    """Reported step -> expected cost. ``phases``: (name, steps, cost of each step as a function of its
    description) in the order the run reports them; ``weights``: one per step (their sum is the total work)."""

    phases: list

    @property
    def weights(self) -> list[float]:
        out = []
        for name, n, cost in self.phases:
            if name.startswith("fe:"):   # link first, then the guideways (any order: costs come from descriptions)
                out += [cost("link")] + [cost("guideway")] * (n - 1)
            else:
                out += [cost(None)] * n
        return out

    def __post_init__(self):
        self._seen = 0

    def __call__(self, description: str) -> float:
        """The expected cost of the step just reported (by its place in the run and its description)."""
        k = self._seen
        self._seen += 1
        for _name, n, cost in self.phases:
            if k < n:
                return cost(description)
            k -= n
        return 0.0


def _const(v: float):
    return lambda desc: v


def plan(case, points, levels, mesh: str, joint_fe: bool, joint_mesh: str, convergence_point) -> VerifyWork:
    """The steps of ``run_verify`` with these options (module doc)."""
    from femcheck.fe_device.joint_laws import cached as laws_cached
    from femcheck.verify.contact_joints import tilt_cached

    n_points = len(points)
    detailed = "detailed" in levels
    contact = bool(joint_fe and detailed)
    phases = []
    warm_fe = False
    if contact:
        tilt_hit = tilt_cached(case)
        laws_hit = laws_cached(case, joint_mesh)
        table_hit = joint_table_cached(case, joint_mesh)
        warm_fe = all(table_hit.values())
        phases.append(("tilt", 2, _const(COLD_S["tilt"] * (CACHED_SHARE if tilt_hit else 1.0))))
        for j in ("spherical", "universal"):
            phases.append((f"law:{j}", 1, _const(COLD_S[f"law:{j}"] * (CACHED_SHARE if laws_hit[j] else 1.0))))
        for j in ("spherical", "universal"):
            share = CACHED_SHARE if table_hit[j] else 1.0
            phases.append((f"table:{j}", 1, _const(COLD_S[f"table:{j}:build"] * share)))
            phases.append((f"table:{j}", 1, _const(COLD_S[f"table:{j}:solve"] * share)))
    if levels:
        fe_share = CACHED_SHARE if warm_fe else 1.0   # a super-element read: a pickle, no mesh, no solve

        def fe_cost(m):
            return lambda desc: fe_share * COLD_S[("link:" if desc == "link" else "guideway:") + m]
        phases.append((f"fe:{mesh}", 1 + 6 * n_points, fe_cost(mesh)))
        phases.append(("figures", 1, _const(COLD_S[f"figures:{mesh}"])))
        if contact and n_points == 9:
            phases.append(("diagnosis", 1, _const(COLD_S["diagnosis"])))
        if contact:
            phases.append(("coverage", 1, _const(COLD_S["coverage:per_point"] * n_points)))
        if convergence_point:
            for m in ("coarse", "default", "fine"):
                if m == mesh and convergence_point in points:
                    continue   # the run's own FE at this mesh is reused
                phases.append((f"fe:{m}", 7, fe_cost(m)))
    phases.append(("report", 1, _const(COLD_S["report"])))
    return VerifyWork(phases)


def joint_table_cached(case, joint_mesh: str) -> dict[str, bool]:
    """{joint: whether its joint-table contact FE is in the result cache}."""
    from femcheck.fe import result_cache
    from femcheck.fe_device.joint_check import joint_table_key
    return {j: result_cache.has("joint_check", joint_table_key(case, j, joint_mesh, "P0")) for j in ("spherical", "universal")}
