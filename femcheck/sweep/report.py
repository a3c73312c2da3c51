"""Self-contained HTML summary of a sweep (PNG plots embedded as base64), written atomically.

Plots (matplotlib, Agg): worst-case stiffness per direction vs each parameter (scatter + binned mean),
global elasticities, Sobol' indices (where available), element shares vs each parameter, and the
mass-stiffness trade-off with its Pareto front. Stiffness is shown in N/mm, lengths in mm, moduli in
GPa (edges only; the store is SI).
"""
from __future__ import annotations

import base64
import html
import io
import json
import logging
from pathlib import Path

import numpy as np

from femcheck.report.atomic import write_text_atomic

log = logging.getLogger(__name__)

#: at most this many samples are drawn in a scatter plot (a random, seeded subset beyond it)
MAX_SCATTER = 4000


def _display(key: str, unit: str):
    """(scale, label unit) for showing a parameter: m -> mm, Pa -> GPa, else SI."""
    if unit == "m":
        return 1e3, "mm"
    if unit == "Pa":
        return 1e-9, "GPa"
    return 1.0, unit


def _png(fig) -> str:
    import matplotlib.pyplot as plt
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110, bbox_inches="tight")
    plt.close(fig)
    return base64.b64encode(buf.getvalue()).decode("ascii")


def _binned(x, y, bins):
    """Mean of y in ``bins`` quantile bins of x (or per distinct x for few levels): (xc, ym)."""
    ux = np.unique(x)
    if ux.size <= max(bins, 12):
        _, inv = np.unique(x, return_inverse=True)
        return ux, np.bincount(inv, weights=y) / np.bincount(inv)
    edges = np.quantile(x, np.linspace(0, 1, bins + 1))
    which = np.clip(np.searchsorted(edges, x, side="right") - 1, 0, bins - 1)
    cnt = np.bincount(which, minlength=bins)
    keep = cnt > 0
    return (np.bincount(which, weights=x, minlength=bins)[keep] / cnt[keep],
            np.bincount(which, weights=y, minlength=bins)[keep] / cnt[keep])


def figures(outcome, an) -> dict[str, str]:
    """{title: base64 PNG} of the summary plots."""
    import matplotlib
    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt
    ranges, d = outcome.ranges, len(outcome.ranges)
    good = np.flatnonzero(an.ok)
    rng = np.random.default_rng(0)
    show = good if good.size <= MAX_SCATTER else np.sort(rng.choice(good, MAX_SCATTER, replace=False))
    figs = {}
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]

    fig, axes = plt.subplots(1, d, figsize=(4.2 * d, 3.4), squeeze=False)
    for j, r in enumerate(ranges):
        ax = axes[0, j]
        sc, un = _display(r.key, r.unit)
        for c, (dname, k) in enumerate(an.k_min.items()):
            ax.scatter(an.params[show, j] * sc, k[show] / 1e3, s=6, alpha=0.35, color=colors[c % 10])
            xb, yb = _binned(an.params[good, j], k[good], 10)
            ax.plot(xb * sc, yb / 1e3, "-o", ms=3, color=colors[c % 10], label=f"{dname}")
        ax.set_xlabel(f"{r.key} ({un})")
        ax.set_ylabel("min over points k (N/mm)")
        if r.log:
            ax.set_xscale("log")
        ax.grid(alpha=0.3)
    axes[0, 0].legend(title="load", fontsize=8)
    fig.suptitle("worst-case stiffness per load direction vs each parameter (dots: samples, line: binned mean)")
    figs["Stiffness vs parameters"] = _png(fig)

    fig, ax = plt.subplots(figsize=(max(5, 1.6 * d + 2), 3.4))
    outs = list(an.elasticity)
    w = 0.8 / len(outs)
    for c, name in enumerate(outs):
        ax.bar(np.arange(d) + (c - (len(outs) - 1) / 2) * w, an.elasticity[name], w, label=name, color=colors[c % 10])
    ax.axhline(0, color="k", lw=0.8)
    ax.set_xticks(np.arange(d), [r.key for r in ranges], rotation=15, ha="right", fontsize=8)
    ax.set_ylabel("d ln k_min / d ln p")
    ax.legend(fontsize=8, title="load")
    ax.grid(alpha=0.3, axis="y")
    ax.set_title("global elasticities (log-log least squares over the box)")
    figs["Elasticities"] = _png(fig)

    if an.sobol_first is not None:
        fig, ax = plt.subplots(figsize=(max(5, 1.6 * d + 2), 3.4))
        w = 0.8 / len(an.sobol_first)
        for c, name in enumerate(an.sobol_first):
            x = np.arange(d) + (c - (len(an.sobol_first) - 1) / 2) * w
            ax.bar(x, an.sobol_first[name], w, label=f"S_i {name}", color=colors[c % 10])
            if an.sobol_total is not None:
                ax.plot(x, an.sobol_total[name], "k_", ms=12, mew=2)
        ax.set_xticks(np.arange(d), [r.key for r in ranges], rotation=15, ha="right", fontsize=8)
        ax.set_ylabel("Sobol' index of k_min")
        ax.legend(fontsize=8)
        ax.grid(alpha=0.3, axis="y")
        ax.set_title("variance-based sensitivity (bars: first order; black ticks: total)")
        figs["Sobol' indices"] = _png(fig)

    fig, axes = plt.subplots(1, d, figsize=(4.2 * d, 3.4), squeeze=False)
    for j, r in enumerate(ranges):
        ax = axes[0, j]
        sc, un = _display(r.key, r.unit)
        for c, (name, s) in enumerate(an.shares.items()):
            xb, yb = _binned(an.params[good, j], s[good], 10)
            ax.plot(xb * sc, 100 * yb, "-o", ms=3, color=colors[c % 10], label=name)
        ax.set_xlabel(f"{r.key} ({un})")
        ax.set_ylabel("share of deflection energy (%)")
        ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=7)
    fig.suptitle("element contributions across the sweep (docs/conventions.md §7; mean over points and load directions)")
    figs["Element contributions"] = _png(fig)

    fig, ax = plt.subplots(figsize=(5.5, 4))
    ax.scatter(an.mass_kg[show], an.k_min_all[show] / 1e3, s=6, alpha=0.4, label="samples")
    pf = an.pareto
    ax.plot(an.mass_kg[pf], an.k_min_all[pf] / 1e3, "r-o", ms=3, label="Pareto front")
    ax.set_xlabel("mass of the sized elements (kg)")
    ax.set_ylabel("min over points and directions k (N/mm)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title("mass-stiffness trade-off")
    figs["Mass-stiffness trade-off"] = _png(fig)
    return figs


def _table(header, rows) -> str:
    h = "".join(f"<th>{html.escape(str(c))}</th>" for c in header)
    body = "".join("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in row) + "</tr>" for row in rows)
    return f"<table><thead><tr>{h}</tr></thead><tbody>{body}</tbody></table>"


def _f(v, fmt="{:.3g}"):
    return "–" if v is None or not np.isfinite(v) else fmt.format(v)


def render_html(outcome, an, local: dict | None = None) -> str:
    """The HTML text of the summary."""
    man = outcome.manifest
    t = man.get("timing", {})
    ranges = outcome.ranges
    parts = [f"<h1>femcheck sweep — {html.escape(man['case'].get('name') or man['case']['source'])}</h1>",
             f"<p>case <code>{html.escape(man['case']['source'])}</code> (sha256 {man['case']['sha256'][:16]}…), "
             f"model <b>{man['options']['model']}</b>, joints <b>{man['options']['joints']}</b>, "
             f"points {', '.join(man['options']['points'])}, loads {', '.join(man['options']['directions'])}; "
             f"design <b>{man['design']['kind']}</b>, {man['design']['samples']} samples "
             f"({man['sample_points']} sample-points, seed {man['design']['seed']}); "
             f"{an.ok.sum()} samples evaluated without failure. Code {html.escape(man['code_version'])}.</p>",
             f"<p>Timing: {_f(t.get('compute_wall_s'), '{:.2f}')} s compute on {t.get('backend')} "
             f"({t.get('workers')} workers), {_f(t.get('sample_points_per_s'), '{:.3g}')} sample-points/s "
             f"this run; {man.get('resumed_with_finished_samples', 0)} samples reused from an earlier run.</p>"]
    parts.append("<h2>Parameters</h2>" + _table(
        ["key", "unit", "nominal", "low", "high", "scale", "how varied"],
        [[r.key, r.unit, f"{r.nominal:.4g}", f"{r.lo:.4g}", f"{r.hi:.4g}", "log" if r.log else "linear",
          "vectorized array" if r.kind == "array" else "case variant"] for r in ranges]))
    rows = []
    for name in an.elasticity:
        row = [name] + [_f(v) for v in an.elasticity[name]] + [_f(an.elasticity_r2[name])]
        if local is not None:
            row += [" / ".join(_f(v) for v in local[name])]
        rows.append(row)
    parts.append("<h2>Elasticities d ln k_min / d ln p</h2><p>Global: least squares of ln k_min on ln p over all "
                 "samples (R² tells how well a power law fits). Local: central difference at the case's nominal "
                 "values (in parameter order).</p>"
                 + _table(["load"] + [r.key for r in ranges] + ["R²"] + (["local"] if local is not None else []), rows))
    parts.append(f"<h2>Variance-based sensitivity</h2><p>{html.escape(an.sobol_method)}</p>")
    if an.sobol_first is not None:
        rows = [[name] + [_f(v, "{:.3f}") for v in an.sobol_first[name]]
                + ([_f(v, "{:.3f}") for v in an.sobol_total[name]] if an.sobol_total is not None else [])
                for name in an.sobol_first]
        head = ["output"] + [f"S {r.key}" for r in ranges] + ([f"ST {r.key}" for r in ranges] if an.sobol_total is not None else [])
        parts.append(_table(head, rows))
    k_rows = [[name, _f(s["min"] / 1e3 if s["min"] else None), _f(s["mean"] / 1e3 if s["mean"] else None),
               _f(s["max"] / 1e3 if s["max"] else None)] for name, s in an.summary()["k_min_N_per_m"].items()]
    parts.append("<h2>Worst-case stiffness over the sweep (N/mm)</h2>" + _table(["load", "min", "mean", "max"], k_rows))
    parts.append("<h2>Element shares across the sweep (%)</h2>" + _table(
        ["element", "min", "mean", "max"],
        [[e, _f(100 * v[an.ok].min()), _f(100 * v[an.ok].mean()), _f(100 * v[an.ok].max())] for e, v in an.shares.items()]
        if an.ok.any() else []))
    pf = an.pareto
    parts.append("<h2>Mass-stiffness Pareto front</h2><p>Mass of the sized elements (guideways over the rail length, "
                 "link tubes, balls, U-joint pins; not the device mass).</p>" + _table(
        ["sample", "mass (kg)", "k_min (N/mm)"] + [r.key for r in ranges],
        [[int(i), f"{an.mass_kg[i]:.4g}", f"{an.k_min_all[i] / 1e3:.4g}"] + [f"{v:.4g}" for v in an.params[i]]
         for i in pf[:30]]))
    for title, png in figures(outcome, an).items():
        parts.append(f"<h2>{html.escape(title)}</h2><img alt='{html.escape(title)}' src='data:image/png;base64,{png}'/>")
    parts.append("<h2>Manifest</h2><pre>" + html.escape(json.dumps(man, indent=1, default=str)) + "</pre>")
    style = ("body{font-family:sans-serif;max-width:1400px;margin:1em auto;padding:0 1em}table{border-collapse:collapse;"
             "margin:.5em 0}td,th{border:1px solid #bbb;padding:2px 8px;text-align:right}th{background:#eee}"
             "img{max-width:100%}pre{font-size:11px;background:#f6f6f6;padding:.5em;overflow:auto}")
    return (f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>femcheck sweep</title><style>{style}</style>"
            f"</head><body>{''.join(parts)}</body></html>")


def write_report(outcome, an, local: dict | None = None, path=None) -> Path:
    """Write ``summary.html`` (and ``analysis.json``) into the sweep folder atomically; returns the HTML path."""
    root = outcome.store.root
    path = Path(path) if path else root / "summary.html"
    write_text_atomic(root / "analysis.json", json.dumps(
        an.summary() | ({"elasticity_local": {k: [float(x) for x in v] for k, v in local.items()}} if local else {}),
        indent=2) + "\n")
    write_text_atomic(path, render_html(outcome, an, local))
    log.info("wrote %s", path)
    return path
