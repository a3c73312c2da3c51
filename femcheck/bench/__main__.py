"""Run every bench area (or those named on the command line) and write reports/bench/<area>.json."""
from __future__ import annotations

import json
import platform
import sys
import time
from pathlib import Path

from rich.console import Console
from rich.table import Table

from femcheck.report.atomic import write_text_atomic


def _areas():
    from femcheck.registry import plugins
    return plugins("femcheck.bench", ("run", "AREA"))


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    out_dir = Path("reports/bench")
    console = Console()
    for mod in _areas():
        if argv and mod.AREA not in argv:
            continue
        t0 = time.perf_counter()
        figures = mod.run()
        figures = {"bench_wall_s": round(time.perf_counter() - t0, 3), "machine": platform.processor() or platform.machine(), **figures}
        table = Table(title=f"bench: {mod.AREA}")
        table.add_column("figure")
        table.add_column("value", justify="right")
        for k, v in figures.items():
            table.add_row(k, f"{v:.4g}" if isinstance(v, float) else str(v))
        console.print(table)
        if hasattr(mod, "table"):  # an area's own summary table (e.g. solvers: ratios to the best)
            console.print(mod.table(figures), markup=False)
        write_text_atomic(out_dir / f"{mod.AREA}.json", json.dumps(figures, indent=2) + "\n")
        console.print(f"wrote {out_dir / (mod.AREA + '.json')}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
