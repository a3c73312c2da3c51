"""Figure of an identification: frequency–stiffness relation with the identified points, and the
preload law with its confidence band (matplotlib, Agg; returns PNG bytes, the caller writes them)."""
from __future__ import annotations

import io

import numpy as np


def identification_png(report, title: str = "") -> bytes:
    """PNG of ``report`` (:class:`femcheck.contact_id.workflow.ContactIdReport`). Units at the edge:
    stiffness in N/um, frequency in kHz, preload in N."""
    import matplotlib
    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    sym = "k_n" if report.kind == "normal" else "k_t"
    ncols = 2 if report.law is not None else 1
    fig, axes = plt.subplots(1, ncols, figsize=(6.2 * ncols, 4.6), squeeze=False)
    ax = axes[0, 0]
    k_um = report.relation_k_N_m * 1e-6
    for i in range(report.relation_f_Hz.shape[1]):
        ax.plot(k_um, report.relation_f_Hz[:, i] * 1e-3, lw=1.2, label=f"mode {i + 1}")
    cmap = plt.get_cmap("tab10")
    for j, r in enumerate(report.identifications):
        k = r.k_n_N_m if report.kind == "normal" else r.k_t_N_m
        lab = "identified" if report.preloads_N is None else f"P = {report.preloads_N[j]:g} N"
        ax.scatter(k * 1e-6, r.frequencies_Hz * 1e-3, marker="o", facecolor="none", edgecolor=cmap(j % 10), zorder=3, label=lab)
        ax.scatter([k[r.best] * 1e-6], [r.frequencies_Hz[r.best] * 1e-3], marker="x", color=cmap(j % 10), zorder=4)
    ax.set_xscale("log")
    ax.set_xlabel(f"{sym} per contact (N/um)")
    ax.set_ylabel("natural frequency (kHz)")
    ax.set_title(("1-D bar on normal spring (seed 004 eq. 30)" if report.kind == "normal"
                  else "specimen on tangential springs (seed 004 eq. 44, FE)"), fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="upper left")
    if report.law is not None:
        ax2 = axes[0, 1]
        P = report.preloads_N
        k = report.k_best_N_m
        yerr = np.vstack([k - k * np.exp(-report.sigma_ln_k), k * np.exp(report.sigma_ln_k) - k]) * 1e-6
        ax2.errorbar(P, k * 1e-6, yerr=yerr, fmt="o", capsize=3, label="identified (1 sigma)")
        Pg = np.geomspace(P.min() / 1.2, P.max() * 1.2, 100)
        ax2.plot(Pg, report.law(Pg) * 1e-6, "k-", label=f"{sym} = c P^m, m = {report.law.m:.3f}")
        if report.law.dof >= 1:
            lo, hi = report.law.band(Pg, level=report.confidence)
            ax2.fill_between(Pg, lo * 1e-6, hi * 1e-6, color="0.8", alpha=0.6, label=f"{report.confidence:.0%} band")
        ax2.set_xscale("log")
        ax2.set_yscale("log")
        ax2.set_xlabel("preload P (N)")
        ax2.set_ylabel(f"{sym} (N/um)")
        ax2.set_title("preload law", fontsize=10)
        ax2.grid(True, which="both", alpha=0.3)
        ax2.legend(fontsize=7)
    if title:
        fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=120)
    plt.close(fig)
    return buf.getvalue()
