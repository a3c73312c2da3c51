"""Report of a serial-robot self-weight diagnosis: Markdown + self-contained HTML, verdict first, the named
causes with places and intervals, held-out marker errors before/after with the leave-one-group-out table, the
identifiability of the nuisance parameters, and the plot of the held-out error per pose before and after."""
from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from femcheck.report.sectioned import write_sectioned_report


def _plot(diag) -> bytes:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(1, 2, figsize=(11, 3.6), gridspec_kw={"width_ratios": [3, 1]})
    n = np.arange(len(diag.per_pose_error_mm_before))
    ax[0].plot(n, diag.per_pose_error_mm_before, ".", ms=3, color="#c44", label="before (model as given)")
    ax[0].plot(n, diag.per_pose_error_mm_after, ".", ms=3, color="#27a", label="after (named causes)")
    ax[0].set_xlabel("pose (measurement order)")
    ax[0].set_ylabel("held-out marker error, mm")
    ax[0].legend(fontsize=8)
    ax[0].set_title("held-out error per pose (K-fold over poses)", fontsize=9)
    hi = max(float(diag.per_pose_error_mm_before.max()), 1e-9)
    bins = np.linspace(0, hi, 30)
    ax[1].hist(diag.per_pose_error_mm_before, bins, color="#c44", alpha=0.6, label="before")
    ax[1].hist(diag.per_pose_error_mm_after, bins, color="#27a", alpha=0.6, label="after")
    ax[1].set_xlabel("mm")
    ax[1].set_title("distribution", fontsize=9)
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    plt.close(fig)
    return buf.getvalue()


def sections(diag, case, data_path) -> list:
    j = diag.as_json()
    r = j["residual"]
    verdict = (f"**{j['verdict']}**: chi2/dof {r['chi2_per_dof']:.2f} (p {r['p_value']:.2g}) with sigma "
               f"{r['sigma_m'] * 1e3:.3f} mm ({j['sigma_source']}); the model as given: chi2/dof {r['chi2_per_dof_none']:.2f}. "
               f"Unexplained share of the excess residual: {r['unexplained_fraction']:.2f}. Residual shape: {', '.join(r['shape'])}.")
    out = [("Verdict", [("p", verdict)] + ([("p", "Ambiguous: " + j["ambiguity"])] if j["ambiguous"] else []))]
    rows = [[c["id"], f"{c['probability']:.2f}", c["location"],
             "; ".join(f"{k} = {v:.4g} [{c['params_ci'][k][0]:.3g}, {c['params_ci'][k][1]:.3g}]" for k, v in c["params"].items())]
            for c in j["causes"]]
    out.append(("Causes" if j["verdict"] != "unexplained" else "Partial explanations (a significant residual remains)",
                [("table", ["cause", "probability", "where", "parameters (95 % interval)"], rows)]))
    alt = [["+".join(a["ids"]), f"{a['probability']:.3f}", f"{a['chi2']:.1f}", a["n_params"]] for a in j["alternatives"][:8]]
    out.append(("Alternatives", [("table", ["explanation", "probability", "chi2", "cause parameters"], alt)]))
    ho = [["mean", f"{j['heldout_mean_error_mm_before']:.3f}", f"{j['heldout_mean_error_mm_after']:.3f}"],
          ["median", f"{j['heldout_median_error_mm_before']:.3f}", f"{j['heldout_median_error_mm_after']:.3f}"],
          ["max", f"{j['heldout_max_error_mm_before']:.3f}", f"{j['heldout_max_error_mm_after']:.3f}"]]
    items = [("p", f"{j['heldout_folds']}-fold cross-validation over poses: every fold refits the nuisance parameters "
                   "(and the named causes) on the other poses."),
             ("table", ["held-out marker error (mm)", "before", "after"], ho)]
    if j["leave_one_out"]:
        items.append(("table", ["named explanation without", "held-out mean error (mm)", "held-out max error (mm)"],
                      [[l["id"], f"{l['heldout_mean_error_mm']:.3f}", f"{l['heldout_max_error_mm']:.3f}"] for l in j["leave_one_out"]]))
    items.append(("img", "heldout_error_per_pose.png"))
    out.append(("Held-out errors", items))
    idf = j["identifiability"]
    out.append(("Nuisance parameters", [("p", f"rank {idf['rank']} of {idf['n_params']}, condition number "
                                             f"{idf['condition_number']:.3g}; fixed at nominal (not identifiable): "
                                             f"{', '.join(idf['fixed']) or 'none'}. Prior: {idf['prior']}.")]))
    if j["not_applicable"] or j["warnings"]:
        out.append(("Notes", [("p", s) for s in j["not_applicable"] + j["warnings"]]))
    return out


def write_report(diag, case, data_path, out_dir) -> list[Path]:
    """report.md, report.html (verdict first) and the per-pose error plot, atomically."""
    return write_sectioned_report(f"femcheck diagnose: {case.meta.name} vs {data_path}", sections(diag, case, data_path),
                                  {"heldout_error_per_pose.png": _plot(diag)}, out_dir, "femcheck diagnose")
