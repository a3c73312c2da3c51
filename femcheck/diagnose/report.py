"""Diagnosis report: Markdown + self-contained HTML (PNG plots embedded as base64), written atomically.

Contents: the named causes with parameters and 95 % intervals, held-out errors before/after (and of the
seed 001 weight-fit baseline), the before/after error tables in seed 000 Table 2/3 layout (rows x, y, z;
columns P0..P8, Average; along-load relative error %), the residual signatures, the selection steps,
the preload identification, and the plots: residual maps and measured vs model per direction.
"""
from __future__ import annotations

import io
import logging
from pathlib import Path

import numpy as np

from femcheck.diagnose import residuals
from femcheck.report.sectioned import write_sectioned_report

log = logging.getLogger(__name__)


def _pct(v) -> str:
    return f"{100 * v:.1f}"




def seed_table(readings, delta_model) -> tuple[list, list]:
    """Header and rows of a seed 000 Table 2/3: along-load relative error (%) per axis and point."""
    t = residuals.error_table(readings, delta_model, "along")
    pts = readings.points
    header = ["Rel. error %"] + pts + ["Average"]
    rows = [[a.upper()] + [f"{t[a].get(p, float('nan')):.0f}" for p in pts] + [f"{t[a]['Average']:.1f}"] for a in t]
    return header, rows


def _plots(readings, diag) -> dict[str, bytes]:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = {}
    axes = list(dict.fromkeys(readings.case_axis().tolist()))
    pts = readings.points
    fig, axs = plt.subplots(1, 2, figsize=(11, 3.2), constrained_layout=True)
    for ax, (title, delta) in zip(axs, (("model as given", diag.cv_before.delta), ("extended model (held out)", diag.cv_after.delta))):
        u = readings.case_unit
        rel = np.einsum("ij,ij->i", delta - readings.delta, u) / np.einsum("ij,ij->i", readings.delta, u)
        grid = np.full((len(axes), len(pts)), np.nan)
        for i, a in enumerate(axes):
            for j, p in enumerate(pts):
                s = (readings.case_axis() == a) & (readings.case_point == p)
                if s.any():
                    grid[i, j] = 100 * rel[s].mean()
        lim = max(5.0, np.nanmax(np.abs(grid)))
        im = ax.imshow(grid, cmap="RdBu_r", vmin=-lim, vmax=lim, aspect="auto")
        ax.set_xticks(range(len(pts)), pts)
        ax.set_yticks(range(len(axes)), [a.upper() for a in axes])
        for i in range(grid.shape[0]):
            for j in range(grid.shape[1]):
                if np.isfinite(grid[i, j]):
                    ax.text(j, i, f"{grid[i, j]:.0f}", ha="center", va="center", fontsize=8)
        ax.set_title(f"residual map, {title}: (model - measured)/measured %", fontsize=9)
        fig.colorbar(im, ax=ax, shrink=0.8)
    out["residual_map.png"] = _png(fig, plt)

    fig, axs = plt.subplots(1, len(axes), figsize=(4 * len(axes), 3.2), constrained_layout=True, squeeze=False)
    for ax, a in zip(axs[0], axes):
        x = np.arange(len(pts))
        for label, delta, style in (("measured", readings.delta, "ko"), ("model as given", diag.cv_before.delta, "r^--"),
                                    ("extended (held out)", diag.cv_after.delta, "bs:")):
            vals = []
            for p in pts:
                s = (readings.case_axis() == a) & (readings.case_point == p)
                vals.append(np.mean(np.abs(np.einsum("ij,ij->i", delta[s], readings.case_unit[s]))) * 1e3 if s.any() else np.nan)
            ax.plot(x, vals, style, label=label, ms=5)
        ax.set_xticks(x, pts)
        ax.set_title(f"load along {a}", fontsize=9)
        ax.set_ylabel("deflection along the load, mm")
        ax.grid(alpha=0.3)
    axs[0][0].legend(fontsize=7)
    out["measured_vs_model.png"] = _png(fig, plt)
    return out


def _png(fig, plt) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    plt.close(fig)
    return buf.getvalue()


def build_sections(diag, readings, case, data_path) -> list[tuple[str, list]]:
    """Report content as (title, [("p", text) | ("table", header, rows) | ("img", name)]) sections."""
    before, after = diag.cv_before.error, diag.cv_after.error
    keys = [k for k in before if k != "overall"] + ["overall"]
    err_rows = [["model as given"] + [_pct(before[k]) for k in keys],
                ["extended model (named causes)"] + [_pct(after[k]) for k in keys]]
    if diag.baseline_error:
        err_rows.append(["seed 001 weight fit + fine-tuning"] + [_pct(diag.baseline_error.get(k, np.nan)) for k in keys])
    causes = [[c.id, c.location, ", ".join(f"{k} = {v:.4g}" for k, v in c.params.items()),
               ", ".join(f"{k}: [{a:.3g}, {b:.3g}]" for k, (a, b) in c.params_ci.items())] for c in diag.causes]
    sec = [("Summary", [
        ("p", f"Case `{case.source}` ({case.meta.name}), measured data `{data_path}`: {readings.n_cases} point/direction "
              f"cases, {readings.n_states} reading states, reading uncertainty {readings.reading_sigma_m * 1e6:.2f} um "
              f"(dial resolution {readings.resolution_m * 1e3:.3g} mm)."),
        ("p", f"Model checked: **{diag.model_name}**. Significant: **{diag.significant}** "
              f"(held-out chi^2 {diag.cv_before.chi2:.1f} -> {diag.cv_after.chi2:.1f}; noise threshold {diag.noise_threshold:.1f})."),
        ("table", ["cause", "location", "parameters", "95 % interval"], causes),
        ("p", "Held-out mean relative error of the deflection vector |delta_model - delta_meas| / |delta_meas| (%), "
              f"leave-points-out folds {[list(f) for f in diag.folds]}:"),
        ("table", ["model"] + keys, err_rows),
    ])]
    if diag.warnings:
        sec.append(("Fit warnings (identifiability)", [("p", w) for w in diag.warnings]))
    hb, rb = seed_table(readings, diag.cv_before.delta)
    ha, ra = seed_table(readings, diag.cv_after.delta)
    sec.append(("Error tables (seed 000 Table 2/3 layout, along-load relative error %)", [
        ("p", "Model as given:"), ("table", hb, rb),
        ("p", "Extended model, each point predicted with its fold held out:"), ("table", ha, ra)]))
    sec.append(("Plots", [("img", "residual_map.png"), ("img", "measured_vs_model.png")]))
    pred_after = diag.fit.predicted
    sig_rows = []
    for sb, sa in zip(residuals.signatures(readings, diag.base.predicted), residuals.signatures(readings, pred_after)):
        sig_rows.append([sb.name, f"{sb.value:.3g} {sb.unit}", f"{sb.z:.1f}", "yes" if sb.flagged else "",
                         f"{sa.value:.3g}", f"{sa.z:.1f}", sb.meaning])
    sec.append(("Residual signatures", [("p", "z = value / noise; |z| > 3 is flagged."),
                                        ("table", ["signature", "before", "z", "flag", "after", "z after", "meaning"], sig_rows)]))
    step_rows = [[s["round"], "+".join(s["effects"]), f"{s['chi2']:.1f}", f"{s['delta_bic']:.1f}",
                  f"{s['heldout_chi2']:.1f}" if "heldout_chi2" in s else "", _pct(s["heldout_error"]) if "heldout_error" in s else "",
                  "yes" if s["accepted"] else ""] for s in diag.steps]
    sec.append(("Model selection steps", [("table", ["round", "effects", "chi^2", "Delta BIC", "held-out chi^2",
                                                     "held-out error %", "accepted"], step_rows)]))
    pre = []
    from femcheck.measured.protocol import identify_preload
    for d in dict.fromkeys(readings.direction[readings.phase == "sweep"].tolist()):
        try:
            pid = identify_preload(readings, d)
        except Exception as exc:  # a report never fails on the optional sweep
            pre.append([d, "-", "-", str(exc)])
            continue
        pre.append([d, f"{pid.preload_N:.0f}", f"{pid.stiffness_N_per_m / 1e3:.2f}",
                    ", ".join(f"{v * 100:.1f}" for v in pid.spread[np.isfinite(pid.spread)])])
    if pre:
        sec.append(("Preload identification (seed 000 Fig. 8)", [
            ("p", "Smallest staircase load above which (F_k - P_p)/(delta_k - delta_p) is constant:"),
            ("table", ["direction", "preload N", "stiffness N/mm", "spread of ratios above each level %"], pre)]))
    return sec


def write_report(diag, readings, case, data_path, out_dir) -> list[Path]:
    """Write ``report.md``, ``report.html`` and the PNG plots into ``out_dir`` (atomically). Returns the paths."""
    paths = write_sectioned_report(f"femcheck diagnose: {case.meta.name}", build_sections(diag, readings, case, data_path),
                                   _plots(readings, diag), out_dir, "femcheck diagnose")
    log.info("report written to %s", out_dir)
    return paths
