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


def machine() -> dict:
    """What the figures were measured on (named next to every quoted figure)."""
    import os
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return {"machine": cpu, "machine_cpus": os.cpu_count(), "machine_python": platform.python_version(),
            "machine_blas_threads": os.environ.get("OPENBLAS_NUM_THREADS", "default"),
            # 1-minute load average when the area finished: other jobs on the machine slow the figures down
            "load_average": round(os.getloadavg()[0], 2)}


def print_figures(figures: dict, table) -> None:
    """An area module run as a script (``python -m femcheck.bench.solvers``): its own ``table(figures)`` and the
    figures as JSON on stdout; nothing is written."""
    print(table(figures))
    json.dump(figures, sys.stdout, indent=1)


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    snapshot = "--snapshot" in argv
    argv = [a for a in argv if a != "--snapshot"]
    out_dir = Path("reports/bench")
    console = Console()
    for mod in _areas():
        if argv and mod.AREA not in argv:
            continue
        t0 = time.perf_counter()
        figures = mod.run()
        figures = {"bench_wall_s": round(time.perf_counter() - t0, 3), **machine(), **figures}
        table = Table(title=f"bench: {mod.AREA}")
        table.add_column("figure")
        table.add_column("value", justify="right")
        for k, v in figures.items():
            table.add_row(k, f"{v:.4g}" if isinstance(v, float) else str(v))
        console.print(table)
        if hasattr(mod, "table"):  # an area's own summary table (e.g. solvers: ratios to the best)
            console.print(mod.table(figures), markup=False, soft_wrap=True)
        path = out_dir / f"{mod.AREA}.json"
        # reports/bench/*.json are committed (docs/validation.md is built from them): an area that could not run
        # its comparison here (e.g. calculix without ccx) keeps the committed figures
        if figures.get("ccx_status", "ran") != "ran" and path.is_file():
            console.print(f"kept {path}: {figures['ccx_status']}")
            continue
        write_text_atomic(path, json.dumps(figures, indent=2) + "\n")
        console.print(f"wrote {path}")
    if snapshot:  # make bench: the generated page follows the figures
        from femcheck.bench import validation_page
        validation_page.main([])
    return 0


if __name__ == "__main__":
    sys.exit(main())
