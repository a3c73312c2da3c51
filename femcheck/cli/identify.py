"""``femcheck identify``: joint compliances of a serial robot from measured tool deflections (seed 002 eqs. 9-12),
or, on a ``parallel_vjm`` case (HISS), seed 001's weight fit with its Tables 2-4 (``femcheck.vjm.hiss_pipeline``).

With ``--world beam|bearings`` (serial robot) no DATA.csv is read: a beam-FE world of the arm makes the
measurements, both models are identified and compared with seed 002's published errors
(``femcheck.cli._identify_world``); with ``--make-data`` the world's measurements are written as DATA.csv
instead. ``beam`` is a check of the assembly, by construction (its joints are the extended model's springs at its
tilt places); ``bearings`` (``femcheck.vjm.bearing_world``) is built from catalogue drives and bearings and is
the test of the extended model.

DATA.csv: header ``set,q1..qn,fx,fy,fz,mx,my,mz,dx,dy,dz``; ``set`` is ``identification`` or ``verification``;
q in deg, wrench in N and N m at the tool point (base frame), deflection in m. Partial: no confidence
intervals beyond the classical LS standard error (1.96 s), kappa_inv uses the
configuration's own rows (3 per wrench), which is an assumed reading of seed 002's per-configuration index.
"""
from __future__ import annotations

from enum import Enum

import numpy as np
import typer

from femcheck.cli._common import emit_json, load_case_for
from femcheck.errors import FemcheckError
from femcheck.measured.csv_format import read_table_rows
from femcheck.report.atomic import write_text_atomic
from femcheck.vjm.extended_vjm import identification_matrix, identify_compliances, virtual_jacobian


class IdentifyDataError(FemcheckError, ValueError):
    """DATA.csv of `femcheck identify` is malformed (message names the file and what was expected)."""


class VJMModel(str, Enum):
    conventional = "conventional"
    extended = "extended"


def read_data(path: str, n: int):
    """(set (m,), q (m, n) rad, W (m, 6), dX (m, 3) m) from DATA.csv; errors name the file and row."""
    cols = ["set"] + [f"q{j + 1}" for j in range(n)] + ["fx", "fy", "fz", "mx", "my", "mz", "dx", "dy", "dz"]
    rows = read_table_rows(path, cols, IdentifyDataError)
    try:
        num = np.array([[float(r[c]) for c in cols[1:]] for r in rows])
    except ValueError as e:
        raise IdentifyDataError(f"{path}: non-numeric value ({e})") from None
    sets = np.array([r["set"] for r in rows])
    if not np.isin(sets, ["identification", "verification"]).all():
        raise IdentifyDataError(f"{path}: column set must be 'identification' or 'verification'")
    return sets, np.deg2rad(num[:, :n]), num[:, n:n + 6], num[:, n + 6:]


def make_data(case, path: str, noise_rel: float = 0.0, seed: int = 0, world=None, noise_mm: float = 0.0) -> int:
    """Write DATA.csv from the case's own VJM (identification plan + verification set, every wrench at every
    configuration), optional Gaussian noise of ``noise_rel`` times each deflection's norm. ``world`` (a
    :class:`femcheck.vjm.beam_world.BeamWorld`) makes the deflections instead of the VJM; ``noise_mm`` adds
    Gaussian noise of that sigma (mm) to each component. Returns the rows."""
    from femcheck.vjm.serial_vjm import deflect
    p = case.identification
    if p is None:
        raise IdentifyDataError(f"{case.source}: [identification] is required to make data")
    qid, qver = np.array(p.configurations_deg, float), np.array(p.verification_configurations_deg, float).reshape(-1, case.n_joints)
    nw = len(p.wrenches)
    qdeg = np.vstack([np.repeat(qid, nw, 0), np.repeat(qver, nw, 0)])
    W = np.tile(np.array(p.wrenches), (len(qid) + len(qver), 1))
    if world is None:
        dX = deflect(case.vjm(), np.deg2rad(qdeg), W, complementary=False).twist[:, :3]
    else:
        from femcheck.vjm.beam_world import tcp_deflections
        q = np.deg2rad(np.vstack([qid, qver]))
        dX = tcp_deflections(world, q, np.array(p.wrenches)).twist[:, :, :3].reshape(-1, 3)
    rng = np.random.default_rng(seed)
    dX = dX + noise_rel * np.linalg.norm(dX, axis=1, keepdims=True) * rng.standard_normal(dX.shape) / np.sqrt(3)
    dX = dX + 1e-3 * noise_mm * rng.standard_normal(dX.shape)
    n = case.n_joints
    lines = [",".join(["set"] + [f"q{j + 1}" for j in range(n)] + ["fx", "fy", "fz", "mx", "my", "mz", "dx", "dy", "dz"])]
    for i in range(len(qdeg)):
        tag = "identification" if i < len(qid) * nw else "verification"
        lines.append(",".join([tag] + [repr(float(v)) for v in (*qdeg[i], *W[i], *dX[i])]))
    write_text_atomic(path, "\n".join(lines) + "\n")
    return len(qdeg)


def _errors(A, c, dX):
    pred = (A @ c).reshape(-1, 3)
    e = 100 * np.linalg.norm(pred - dX, axis=1) / np.linalg.norm(dX, axis=1)
    return {"mean": float(e.mean()), "max": float(e.max())} if len(e) else {"mean": None, "max": None}


def register(app: typer.Typer) -> None:
    @app.command("identify")
    def identify_cmd(
        case_path: str = typer.Argument(..., metavar="CASE", help="serial_robot or parallel_vjm case file (TOML), e.g. cases/cobot7.toml, cases/hiss.toml"),
        data_path: str = typer.Argument(None, metavar="[DATA.csv]", help="measurements (format in the module doc / docs/vjm.md); not used with --world unless --make-data"),
        model: VJMModel = typer.Option(VJMModel.extended, "--model", help="conventional (torsion only) or extended (3 springs per joint)"),
        json_out: str = typer.Option(None, "--json", help="write the result as JSON to OUT ('-' = stdout)"),
        make: bool = typer.Option(False, "--make-data", help="write DATA.csv from the case's own model (plan + verification set) and stop"),
        noise: float = typer.Option(0.0, "--noise", help="with --make-data: relative Gaussian noise on each deflection (serial robots)"),
        noise_mm: float = typer.Option(None, "--noise-mm", help="HISS: translation noise sigma, mm (default 0.02; weights the fit, L = 1/sigma^2; added by --make-data). --world: noise sigma on each measured translation, mm (default 0)"),
        noise_deg: float = typer.Option(0.02, "--noise-deg", help="HISS: rotation noise sigma, deg (as --noise-mm)"),
        true_weights: str = typer.Option("table2-df", "--true-weights", help="HISS --make-data: W1..W11 as 11 numbers, or table2-df | table2-fd (seed 001 Table 2)"),
        seed: int = typer.Option(0, "--seed", help="HISS: seed of --make-data and of the fit's restarts; --world: seed of the noise and the random poses"),
        world: str = typer.Option(None, "--world", help="serial robot, no DATA.csv: measure on a beam-FE world of the arm and compare both models with seed 002. 'bearings' = catalogue drives and output bearings at their real places (the test of the extended model); 'beam' = joints made of the extended model's own springs, a check of the assembly by construction"),
        drives: str = typer.Option("nominal", "--drives", help="--world bearings: 'nominal' = each drive a constant spring of its catalogue stiffness (seed 002's linear FE, sec. IV-A); 'catalogue' = the catalogue's piecewise torsion law, loaded by the arm's weight"),
        gravity: bool = typer.Option(False, "--gravity", help="--world: the measurements include the self-weight deflection"),
        random_poses: int = typer.Option(0, "--random-poses", help="--world: extra verification poses, uniform within the iiwa 7's joint limits"),
        restarts: int = typer.Option(None, "--restarts", help="HISS: starts of the weight fit (default: the case's [fitting] restarts)"),
        extended_case: str = typer.Option(None, "--extended-case", metavar="OUT.toml",
                                          help="write a copy of CASE with the identified joint stiffnesses (serial robot) or weights (parallel_vjm)"),
    ):
        """Identify joint compliances by least squares (seed 002 eq. 10) and report the deflection errors;
        on a parallel_vjm (HISS) case, fit seed 001's weights and print its Tables 2-4 (--model is not used)."""
        case = load_case_for(case_path, "identify", kinds=("serial_robot", "parallel_vjm"))
        if extended_case and (make or world is not None):
            raise IdentifyDataError("--extended-case writes the springs identified from DATA.csv; not with "
                                    "--make-data or --world")
        if extended_case:
            from femcheck.report.atomic import check_output_file, refuse_input_overwrite
            refuse_input_overwrite(extended_case, [case_path, data_path])
            check_output_file(extended_case, "--extended-case")
        if world is not None and case.kind != "serial_robot":
            raise IdentifyDataError(f"--world {world}: only for serial_robot cases; {case_path} is {case.kind!r}")
        if world is not None and not make:
            if data_path is not None:
                raise IdentifyDataError(f"{data_path}: --world makes its own measurements; give DATA.csv only with --make-data")
            from femcheck.cli._identify_world import identify_world
            identify_world(case, case_path, world=world, json_out=json_out, noise_mm=0.0 if noise_mm is None else noise_mm,
                           seed=seed, gravity=gravity, random_poses=random_poses, drives=drives)
            return
        if data_path is None:
            raise IdentifyDataError("DATA.csv is required (or --world bearings|beam on a serial_robot case)")
        if case.kind == "parallel_vjm":
            noise_mm = 0.02 if noise_mm is None else noise_mm
            from femcheck.cli._identify_hiss import identify_hiss
            identify_hiss(case, case_path, data_path, json_out=json_out, make=make, noise_rel=noise,
                          noise_mm=noise_mm, noise_deg=noise_deg, true_weights=true_weights, seed=seed,
                          restarts=restarts, extended_case=extended_case)
            return
        if make:
            import os
            if os.path.exists(data_path):
                raise IdentifyDataError(f"{data_path}: exists; --make-data never overwrites a file")
            w = None
            if world is not None:
                from femcheck.cli._identify_world import DRIVES, WORLD_ROLE, make_world
                if world not in WORLD_ROLE:
                    raise IdentifyDataError(f"--world {world!r}; expected 'beam' or 'bearings'")
                if drives not in DRIVES:
                    raise IdentifyDataError(f"--drives {drives!r}; expected one of {', '.join(DRIVES)}")
                w = make_world(case, world, drives)
            nmm = 0.0 if noise_mm is None else noise_mm
            if not np.isfinite(nmm) or nmm < 0:
                raise IdentifyDataError(f"--noise-mm {nmm:g}; expected a finite sigma >= 0 (mm)")
            typer.echo(f"wrote {make_data(case, data_path, noise, seed=seed, world=w, noise_mm=nmm)} rows to {data_path}"
                       + (f" ({world} world)" if w is not None else ""))
            return
        vjm = case.vjm()
        ext = model is VJMModel.extended
        sets, q, W, dX = read_data(data_path, case.n_joints)
        J = virtual_jacobian(vjm.chain, q, ext, vjm.tilt_offset_m if ext else None)
        ident = sets == "identification"
        res = identify_compliances(J[ident], W[ident], dX[ident])
        A = identification_matrix(J, W).reshape(len(q), 3, -1)
        k = A.shape[2]
        tors = slice(0, k, 3) if ext else slice(0, k)
        dt = np.einsum("mrk,k->mr", A[:, :, tors], res.compliance[tors])
        dall = np.einsum("mrk,k->mr", A, res.compliance)
        # the projection of the torsion part on the total (femcheck/vjm/torsion_share.py): additive, torsion + tilt = 1
        share = np.einsum("mr,mr->m", dt, dall) / np.einsum("mr,mr->m", dall, dall)
        # kappa_inv per configuration (unique joint vector, in file order): sigma_min / sigma_max of that
        # configuration's stacked rows of A (3 per wrench); sigma_min over the min(rows, k) singular values
        _, first, inv = np.unique(np.round(q, 12), axis=0, return_index=True, return_inverse=True)
        kinv = []
        for g in np.argsort(first):
            sv = np.linalg.svd(A[inv.ravel() == g].reshape(-1, k), compute_uv=False)
            kinv.append(float(sv[-1] / sv[0]))
        out = {"model": model.value, "compliances": res.compliance.tolist(),
               "compliances_ci": (1.96 * res.standard_error).tolist(), "cond_A": res.condition_number,
               "kappa_inv": kinv,
               "torsion_share": float(share[ident].mean()),
               "error_identification_pct": _errors(A[ident].reshape(-1, k), res.compliance, dX[ident]),
               "error_verification_pct": _errors(A[~ident].reshape(-1, k), res.compliance, dX[~ident])}
        if extended_case:
            from pathlib import Path
            from femcheck.vjm.identified_case import identified_case_text
            write_text_atomic(extended_case, identified_case_text(case, Path(case_path).read_text(), res.compliance,
                                                                  res.standard_error, ext, data_path))
        if json_out:
            emit_json(out, json_out, inputs=[case_path, data_path])
        if json_out != "-":
            typer.echo(f"{model.value}: cond(A) {out['cond_A']:.3g}, torsion share {100 * out['torsion_share']:.1f} %, "
                       f"error identification {out['error_identification_pct']['mean']:.2f} % mean / "
                       f"{out['error_identification_pct']['max']:.2f} % max, verification "
                       + (f"{out['error_verification_pct']['mean']:.2f} % mean / {out['error_verification_pct']['max']:.2f} % max"
                          if out['error_verification_pct']['mean'] is not None else "none"))
