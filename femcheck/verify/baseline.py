"""Regression check against a committed baseline (``reports/baseline/*.json``).

The baseline stores flat {key: value} numbers; ``compare`` returns readable lines for every key
that moved by more than its relative tolerance, or is missing on either side.
"""
from __future__ import annotations

import json
from pathlib import Path

from femcheck.report.atomic import write_text_atomic


def load_baseline(path) -> dict[str, float] | None:
    p = Path(path)
    return json.loads(p.read_text()) if p.is_file() else None


def save_baseline(path, values: dict[str, float]) -> None:
    write_text_atomic(path, json.dumps(values, indent=1, sort_keys=True) + "\n")


def compare(current: dict[str, float], baseline: dict[str, float], rtol: float) -> list[str]:
    """Readable diff lines (empty = no drift)."""
    lines = []
    for k in sorted(set(current) | set(baseline)):
        if k not in baseline:
            lines.append(f"{k}: new value {current[k]:.6g} (not in baseline)")
        elif k not in current:
            lines.append(f"{k}: missing (baseline {baseline[k]:.6g})")
        else:
            a, b = current[k], baseline[k]
            rel = abs(a - b) / max(abs(b), 1e-300)
            if rel > rtol:
                lines.append(f"{k}: {a:.6g} vs baseline {b:.6g} (drift {100*rel:.3g} % > {100*rtol:.3g} %)")
    return lines
