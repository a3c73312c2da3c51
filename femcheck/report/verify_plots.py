"""Plots of the verification run: deflection per test point and direction (seed 000 Figs. 9-11,
17-19 layout) and the element contributions (Fig. 23). Return PNG bytes; SI in, mm on the axes."""
from __future__ import annotations

import io

import numpy as np


def _png(fig) -> bytes:
    import matplotlib.pyplot as plt
    buf = io.BytesIO()
    fig.savefig(buf, format="png", bbox_inches="tight")
    plt.close(fig)
    return buf.getvalue()


def deflection_plot(points, series: dict[str, np.ndarray], direction: str, load_N: float) -> bytes:
    """Grouped bars: one group per test point, one bar per series (label -> (n_points,) deflection in m)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(8, 3.6), dpi=110)
    width = 0.8 / max(len(series), 1)
    x = np.arange(len(points))
    for j, (label, values) in enumerate(series.items()):
        ax.bar(x + (j - (len(series) - 1) / 2) * width, np.asarray(values) * 1e3, width, label=label)
    ax.set_xticks(x, points)
    ax.set_ylabel(f"deflection along {direction} (mm)")
    ax.set_title(f"TCP deflection under {load_N:g} N along {direction}")
    ax.legend(fontsize=8)
    ax.grid(axis="y", alpha=0.3)
    return _png(fig)


def contributions_plot(shares: dict[str, dict[str, float]]) -> bytes:
    """Bars of mean element shares (%) per idealization (seed 000 Fig. 23)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7, 3.6), dpi=110)
    names = list(next(iter(shares.values())))
    x = np.arange(len(names))
    width = 0.8 / len(shares)
    for j, (label, s) in enumerate(shares.items()):
        bars = ax.bar(x + (j - (len(shares) - 1) / 2) * width, [100 * s[n] for n in names], width, label=label)
        ax.bar_label(bars, fmt="%.1f", fontsize=7)
    ax.set_xticks(x, [n.replace("_", " ") for n in names])
    ax.set_ylabel("share of deflection energy (%)")
    ax.set_title("Contributions of the compliant elements (mean over points and directions)")
    ax.legend(fontsize=8)
    return _png(fig)
