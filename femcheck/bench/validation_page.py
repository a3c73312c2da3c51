"""docs/validation.md, generated from the committed bench figures reports/bench/<area>.json.

``python -m femcheck.bench.validation_page`` (``make validation``) writes the page; ``--check`` exits 1 when the
page on disk differs from what the JSON files give (tests/test_docs.py runs the same comparison). One section per
area: what the area measures (its module's first docstring paragraph), the command that measures it, the machine
it ran on and every figure, so a quoted number always has its command and machine beside it.
"""
from __future__ import annotations

import importlib
import json
import sys
from pathlib import Path

from femcheck.report.atomic import write_text_atomic

ROOT = Path(__file__).resolve().parents[2]
BENCH_DIR = ROOT / "reports" / "bench"
PAGE = ROOT / "docs" / "validation.md"

#: keys describing the machine, shown in the section's header line rather than in its table
#: figure/value pairs in one table row
FIGURES_PER_ROW = 4

MACHINE_KEYS = ("machine", "machine_cpus", "machine_python", "machine_blas_threads", "load_average", "bench_wall_s")


def format_value(value) -> str:
    """One figure as the page prints it: floats to 6 significant digits (the JSON keeps full precision)."""
    if isinstance(value, bool) or value is None:
        return json.dumps(value)
    if isinstance(value, float):
        return f"{value:.6g}"
    if isinstance(value, (int, str)):
        return str(value).replace("|", "/")
    return json.dumps(value, separators=(", ", ": ")).replace("|", "/")


#: what each area measures, in one sentence (an area not listed here shows its module's first docstring paragraph)
AREA_TEXT = {
    "analytical": "The analytical chain models of the reference case: batched throughput (poses/s, one core, compiled "
                  "kernel) and single-pose latency, per model level and joint idealization.",
    "calculix": "femcheck's contact FE and CalculiX side by side on one mesh: the Hertz sphere on a flat (15 N and 50 N, "
                "errors against Johnson's closed form) and a pin in a bore with 10 µm clearance (100 N, 400 N).",
    "contact_id": "Contact stiffness from natural frequencies: root finding of the bar's frequency equation and the FE "
                  "specimen's tangential identification (time, round-trip error).",
    "diagnose": "The diagnosis of the reference device: wall time of a diagnosis weighing every candidate pair, and the "
                "verdict rates on data inside and outside the effect vocabulary.",
    "early_stop": "Whether the early stops of the rival pair fits are safe: stops against full fits on generated sets.",
    "fe_contact": "The Hertz sphere-on-flat quarter model at three refinements: DOFs, times, approach and radius errors.",
    "fe_solver": "The P2 solid cantilever at four refinements: assembly, factorization and solve times with the "
                 "automatically chosen direct solver, AMG-preconditioned CG on the finest, tip error vs Timoshenko.",
    "geometry": "Meshing time and element counts per part, contact-refinement methods on the spherical-joint seat, and "
                "a check that two cold builds give the same mesh.",
    "joints": "The passive joints' contact FE at coarse, default and fine meshes: sizes, iterations, times, memory.",
    "monolithic_leg": "One complete leg as one contact FE model against the substructured leg.",
    "parallel_device": "The general parallel-device model on the 6-PSU, the hexapod and the Delta: throughput "
                       "of the compiled and numpy paths, against the retired 6-PSU kernel's recorded throughput.",
    "physical_worlds": "The diagnosis of the reference device against physically modified copies of its case "
                       "(material, section, pin radius, cable modulus; one leg or all; singles and pairs; the "
                       "world is the device FE of the modified case, coarse mesh), drawn until 30 worlds are "
                       "detectable (every change above 3 reading sigmas): element confusion and the rates of right "
                       "answers over those, the same over all draws, and the honesty of the undetectable draws.",
    "serial_diagnose": "The self-weight diagnosis of serial robots: wall time on a 19-joint tree and the rates of right "
                       "answers on generated robots.",
    "solvers": "Every available sparse direct solver on three of femcheck's own systems: time and residual, each as a "
               "ratio to the best.",
    "sweep": "Analytical sweep throughput, the local-pool overhead and the FE sweep wall time.",
    "vjm": "The virtual joint method: deflection throughput and latency of the IRB 120 case, extended-VJM batch, "
           "identification and configuration selection, the HISS stiffness and weight fit.",
}

#: figures measured by a command other than the area's own: (command, condition), e.g. the make targets timed by an area
FIGURE_COMMAND = {
    "install_s": ("make venv", "fresh clone"),
    "make_verify_cold_s": ("make verify", "empty caches"),
    "make_verify_warm_s": ("make verify", "second run, same case"),
    "make_verify_nomkl_s": ("make verify", "without pypardiso"),
    "nomkl_peak_gb": ("make verify", "without pypardiso"),
    "test_suite_s": ("make test", "after the install"),
}


def _cell(key: str, value) -> str:
    """``| `key` | value |`` cells of one figure; a figure with its own command names it after the value."""
    text = format_value(value)
    if key in FIGURE_COMMAND:
        command, condition = FIGURE_COMMAND[key]
        text += f" (`{command}`, {condition})"
    return f"`{key}` | {text}"


def _summary(area: str) -> str:
    """What the area measures: :data:`AREA_TEXT`, else the module docstring's first paragraph on one line."""
    if area in AREA_TEXT:
        return AREA_TEXT[area]
    try:
        doc = importlib.import_module(f"femcheck.bench.{area}").__doc__ or ""
    except ImportError:
        return ""
    para = doc.strip().split("\n\n")[0]
    return " ".join(para.split())


def load_figures(bench_dir: Path = BENCH_DIR) -> dict[str, dict]:
    """{area: figures} of every reports/bench/<area>.json, sorted by area."""
    return {p.stem: json.loads(p.read_text(encoding="utf-8")) for p in sorted(bench_dir.glob("*.json"))}


def is_figure(value) -> bool:
    """A figure the page shows: a number, a flag or a short text (lists and tables of cases stay in the JSON)."""
    return not isinstance(value, (dict, list, tuple))


def render(figures: dict[str, dict]) -> str:
    """The page's Markdown text for ``{area: figures}``."""
    lines = [
        "# Validation: measured accuracy and speed",
        "",
        "Generated by `python -m femcheck.bench.validation_page` (`make validation`) from `reports/bench/*.json`;",
        "do not edit it by hand. `make bench` measures every area again, rewrites the JSON files and this page.",
        "Each section names the command that measured its figures and the machine they were measured on.",
        "Units are in the key names (`_s` seconds, `_pct` per cent, `_per_s` per second, `_um` micrometres).",
        "",
    ]
    for area, fig in figures.items():
        machine = f"{fig.get('machine', 'unknown')}, {fig.get('machine_cpus', '?')} CPUs"
        if "machine_python" in fig:
            machine += f", Python {fig['machine_python']}"
        if "machine_blas_threads" in fig:
            machine += f", BLAS threads {fig['machine_blas_threads']}"
        if "load_average" in fig:
            machine += f", load average {format_value(fig['load_average'])}"
        lines += [f"## {area}", ""]
        summary = _summary(area)
        lines += [(summary + " " if summary else "") + f"Command: `python -m femcheck.bench {area}`. Machine: {machine}."
                  + (f" Wall time of the area: {format_value(fig['bench_wall_s'])} s." if "bench_wall_s" in fig else ""),
                  "", "| figure | value " * FIGURES_PER_ROW + "|", "| --- | --- " * FIGURES_PER_ROW + "|"]
        cells = [_cell(k, v) for k, v in fig.items() if k not in MACHINE_KEYS and is_figure(v)]
        detail = [k for k, v in fig.items() if k not in MACHINE_KEYS and not is_figure(v)]
        # several figures per row, in the JSON's order down the rows: the page stays short for the big areas
        n = FIGURES_PER_ROW
        lines += ["| " + " | ".join(group) + " | |" * (n - len(group)) + " |"
                  for group in (cells[i:i + n] for i in range(0, len(cells), n))]
        if detail:
            lines += ["", "Per-case detail in the JSON: " + ", ".join(f"`{k}`" for k in detail) + "."]
        lines.append("")
    return "\n".join(lines)


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    text = render(load_figures())
    if "--check" in argv:
        if not PAGE.is_file() or PAGE.read_text(encoding="utf-8") != text:
            print(f"error: {PAGE.relative_to(ROOT)} differs from reports/bench/*.json; "
                  "run: python -m femcheck.bench.validation_page", file=sys.stderr)
            return 1
        return 0
    write_text_atomic(PAGE, text)
    print(f"wrote {PAGE.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
