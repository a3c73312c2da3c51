"""``femcheck identify`` on a ``parallel_vjm`` case: seed 001's workflow and its Tables 2-4 (HISS haptic master).

DATA.csv format, steps and assumptions: :mod:`femcheck.vjm.hiss_pipeline`. The published tables are printed
beside femcheck's (``femcheck.vjm.hiss_published``); they come from the paper's own measurements, which it
does not publish, so on other data they are a reference for the layout and order of magnitude only.
"""
from __future__ import annotations

import os

import numpy as np
import typer

from femcheck.cli._common import emit_json
from femcheck.vjm.hiss_pipeline import HissDataError


def _true_weights(text: str, n: int) -> np.ndarray:
    from femcheck.vjm.hiss_published import TABLE2
    named = {"table2-df": "D/F", "table2-fd": "F/D"}
    if text.lower() in named:
        return np.array(TABLE2[named[text.lower()]][0], dtype=float)
    try:
        w = np.array([float(v) for v in text.split(",")])
    except ValueError:
        raise HissDataError(f"--true-weights: {text!r}; expected table2-df, table2-fd or {n} positive numbers") from None
    if len(w) != n or not np.all(np.isfinite(w)) or np.any(w <= 0):
        raise HissDataError(f"--true-weights: {text!r}; expected table2-df, table2-fd or {n} positive numbers")
    return w


def _fmt(v, width=8, prec=3):
    if v is None or not np.isfinite(v):
        return "inf".rjust(width)
    return f"{v:{width}.{prec}g}" if abs(v) >= 1e4 or (0 < abs(v) < 1e-3) else f"{v:{width}.{prec}f}"


def format_tables(results: dict, noise_mm: float, noise_deg: float) -> str:
    """Seed 001 Tables 2, 3 and 4 for every fitted setup, with the published values where the paper has them."""
    from femcheck.vjm.hiss_published import COMPONENTS, TABLE2, TABLE3, TABLE4
    unit = {"dx": "mm", "dy": "mm", "dz": "mm", "dalpha": "deg", "dbeta": "deg", "dgamma": "deg",
            "norm_xyz": "mm", "norm_abg": "deg"}
    out = []
    for name, g in results.items():
        pub = name in TABLE2
        out.append(f"{name}: {g['n']} measurements; {g['restarts']} starts, {g['equivalent_runs']} as good as the best; "
                   f"E = {g['cost']:.4g} (residuals in units of {noise_mm:g} mm / {noise_deg:g} deg)")
        out.append(f"  Table 2   fit      95 % interval         variance  not identified because"
                   + ("                     | paper: fit  variance" if pub else ""))
        for k, w in enumerate(g["weights"]):
            wn = f"W{k + 1}"
            flagged = wn in g["unidentifiable"]
            why = ", ".join(g["reasons"].get(wn, [])) if flagged else ""
            # a flagged weight's best-fit value is one of many that fit: shown in parentheses, never as identified
            val = f"({_fmt(w, 6)})" if flagged else _fmt(w)
            line = (f"  {wn:<8}{val}  [{_fmt(g['ci95_low'][k])}, {_fmt(g['ci95_high'][k])}]  {_fmt(g['variance'][k])}"
                    f"  {why:<42}")
            if pub:
                line += f"|  {_fmt(TABLE2[name][0][k])} {_fmt(TABLE2[name][1][k])}"
            out.append(line.rstrip())
        out.append("  Table 3   x' = a x + b        a        b" + ("   | paper: a        b" if pub else ""))
        for j, c in enumerate(COMPONENTS):
            ab = g["correction"][c]
            line = f"  {c + ' (' + unit[c] + ')':<24}{_fmt(ab['a'])} {_fmt(ab['b'])}"
            if pub:
                line += f"   |  {_fmt(TABLE3[name][j][0])} {_fmt(TABLE3[name][j][1])}"
            out.append(line)
        out.append("  Table 4   fitted: RMS     Std       M      AM | fine-tuned: RMS  Std       M      AM"
                   + ("  | paper fitted / fine-tuned RMS" if pub else ""))
        for j, c in enumerate(COMPONENTS):
            s = g["statistics"][c]
            vals = [s[lvl][k] for lvl in ("fitted", "fine_tuned") for k in ("rms", "std", "mean", "abs_mean")]
            line = f"  {c:<14}" + " ".join(_fmt(v) for v in vals[:4]) + "  | " + " ".join(_fmt(v) for v in vals[4:])
            if pub:
                line += f"  |  {TABLE4[name][j][0][0]:.2f} / {TABLE4[name][j][1][0]:.2f}"
            out.append(line)
    out.append("  weights in parentheses are not identified: their 95 % profile-likelihood interval spans more than a "
               "factor 4 (or they are structural, at a bound, or spread over the restarts), whatever their variance")
    return "\n".join(out)


def format_consistency(cc: dict, iso: dict) -> str:
    """The column-consistency table (1 kg deflections of the three Table 2 columns under both eq. 10 readings)
    and TP3's isotropy ratio."""
    cols = list(next(iter(cc["readings"].values()))["columns"])
    out = [f"eq. 10 reading vs seed 001's own Table 2: largest deflection under {cc['load']}, mm (test point)",
           "  reading     " + "".join(f"{c:>18}" for c in cols) + "   largest/smallest"]
    for r, v in cc["readings"].items():
        out.append(f"  {r:<11} " + "".join(f"{v['columns'][c]['max_mm']:>11.2f} ({v['columns'][c]['at']:>4})" for c in cols)
                   + f"   {v['spread']:>8.2f}")
    out.append(f"  the columns agree best under the {cc['supported']} reading; this case uses {cc['case_reading']}")
    n = iso["nominal"]
    out.append(f"TP3 translational compliance, largest / smallest: {n['ratio']:.2f} with nominal weights (1 = isotropic, "
               "as seed 001 states); with the Table 2 weights: "
               + "; ".join(f"{r}: " + ", ".join(f"{c} {iso[r][c]:.2f}" for c in cols) for r in cc["readings"]))
    return "\n".join(out)


def identify_hiss(case, case_path: str, data_path: str, *, json_out, make: bool, noise_rel: float, noise_mm: float,
                  noise_deg: float, true_weights: str, seed: int, restarts, extended_case=None) -> None:
    from femcheck.vjm import hiss_pipeline as hp

    if noise_rel:
        raise HissDataError("--noise: relative noise is for serial robots; on a parallel_vjm case use --noise-mm and --noise-deg")
    if not (np.isfinite(noise_mm) and np.isfinite(noise_deg)) or noise_mm < 0 or noise_deg < 0 or (not make and (noise_mm == 0 or noise_deg == 0)):
        raise HissDataError(f"--noise-mm {noise_mm:g} / --noise-deg {noise_deg:g}: expected finite sigmas, "
                            "> 0 for a fit (they weight its residuals)")
    if restarts is not None and restarts < 1:
        raise HissDataError(f"--restarts: {restarts}; expected at least 1")
    if make:
        if os.path.exists(data_path):
            raise HissDataError(f"{data_path}: exists; --make-data never overwrites a file")
        w = _true_weights(true_weights, case.fitting.n_weights)
        data = hp.virtual_experiment(case, w, noise_mm=noise_mm, noise_deg=noise_deg, seed=seed)
        hp.write_csv(data_path, case, data)
        typer.echo(f"wrote {len(data.setup)} rows to {data_path} ({int(np.sum(data.setup == 'D/F'))} D/F, "
                   f"{int(np.sum(data.setup == 'F/D'))} F/D; noise {noise_mm:g} mm / {noise_deg:g} deg)")
        return
    from femcheck.vjm.hiss_column_consistency import column_consistency, isotropy_table
    data = hp.read_csv(data_path, case)
    results = hp.run(case, data, noise_mm=noise_mm, noise_deg=noise_deg, restarts=restarts, seed=seed)
    cc, iso = column_consistency(case), isotropy_table(case)
    if extended_case:
        from pathlib import Path
        from femcheck.report.atomic import write_text_atomic
        from femcheck.vjm.identified_case import weights_case_text
        write_text_atomic(extended_case, weights_case_text(case, Path(case_path).read_text(), results, data_path))
    if json_out:
        emit_json({"kind": "parallel_vjm", "units": {"translation": "mm", "rotation": "deg"},
                   "noise": {"mm": noise_mm, "deg": noise_deg}, "stiffness_scaling": case.fitting.stiffness_scaling,
                   "setups": results, "column_consistency": cc, "tp3_isotropy": iso}, json_out,
                  inputs=[case_path, data_path])
    if json_out != "-":
        typer.echo(format_tables(results, noise_mm, noise_deg) + "\n" + format_consistency(cc, iso))
