"""``femcheck contact-id CASE --frequencies f1,f2,... [--json OUT]``: contact stiffness from measured natural
frequencies (seed 004 §4). Normal (1-D bar, eqs. 20–31) or tangential (FE specimen, eq. 44). ``--json`` takes
an argument: a file, or ``-`` for one object on standard output."""
from __future__ import annotations

import math
from pathlib import Path
from typing import Optional

import typer

from femcheck.cli._common import JSON_HELP, emit_json

from femcheck.contact_id.bar_on_spring import ContactIdError


def _numbers(text: str, option: str) -> list[float]:
    vals = []
    for tok in text.split(","):
        tok = tok.strip()
        if not tok:
            raise ContactIdError(f"{option} {text!r}: empty entry; expected comma-separated numbers")
        try:
            v = float(tok)
        except ValueError:
            raise ContactIdError(f"{option} {text!r}: {tok!r} is not a number") from None
        if not math.isfinite(v) or v <= 0:
            raise ContactIdError(f"{option} {text!r}: {tok} must be a finite number > 0")
        vals.append(v)
    return vals


def parse_frequency_groups(text: str, n_preloads: int) -> list[list[float]]:
    """``"f1,f2;f1,f2"`` -> one group per preload. Without ';' and with as many values as preloads
    (>= 2), each value is one preload's frequency (of the single mode given by --modes, default 1)."""
    groups = [_numbers(g, "--frequencies") for g in text.split(";")]
    if len(groups) == 1 and n_preloads >= 2 and len(groups[0]) == n_preloads:
        return [[f] for f in groups[0]]
    if n_preloads and len(groups) != n_preloads:
        raise ContactIdError(f"--frequencies has {len(groups)} group(s) but --preloads has {n_preloads} values; "
                             "expected one group per preload, groups separated by ';' (e.g. \"f1,f2;f1,f2\")")
    return groups


def _clean(obj):
    """JSON-safe: NaN/inf -> None."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: _clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_clean(v) for v in obj]
    return obj


def register(app: typer.Typer) -> None:
    @app.command("contact-id")
    def contact_id(
        case: Path = typer.Argument(..., help="contact_specimen case file (TOML)"),
        frequencies: str = typer.Option(..., "--frequencies", "-f",
                                        help="measured natural frequencies in Hz, 'f1,f2,...'; one group per preload separated by ';'"),
        preloads: Optional[str] = typer.Option(None, "--preloads", "-p", help="preloads in N, 'P1,P2,...' (one per group)"),
        modes: Optional[str] = typer.Option(None, "--modes", help="1-based mode numbers of the frequencies in a group (default 1..n)"),
        mode: str = typer.Option("normal", "--mode", help="normal (1-D bar, seed 004 §4.1) or tangential (FE specimen, §4.3)"),
        json_out: Optional[str] = typer.Option(None, "--json", metavar="OUT", help=JSON_HELP),
        plot: Optional[Path] = typer.Option(None, "--plot", help="write a PNG of the relation and the identified points"),
    ) -> None:
        """Contact stiffness from measured natural frequencies (seed 004 §4)."""
        from femcheck.case import load_case
        from femcheck.contact_id.workflow import KINDS, run_identification
        from femcheck.report.atomic import refuse_input_overwrite, write_bytes_atomic

        if mode not in KINDS:
            raise ContactIdError(f"--mode {mode!r}; expected one of {list(KINDS)}")
        c = load_case(case)
        if getattr(c, "kind", None) != "contact_specimen":
            from femcheck.errors import CaseError
            raise CaseError(case, "meta.kind", f"is {getattr(c, 'kind', '?')!r}; contact-id needs a 'contact_specimen' case")
        P = _numbers(preloads, "--preloads") if preloads else None
        groups = parse_frequency_groups(frequencies, len(P) if P else 0)
        mode_numbers = None
        if modes:
            mode_numbers = []
            for tok in modes.split(","):
                if not tok.strip().isdigit() or int(tok) < 1:
                    raise ContactIdError(f"--modes {modes!r}: {tok!r}; expected mode numbers 1, 2, ...")
                mode_numbers.append(int(tok))
        report = run_identification(c, groups, P, mode_numbers, kind=mode)
        if plot is not None:
            refuse_input_overwrite(plot, [case])
            from femcheck.contact_id.plot import identification_png
            write_bytes_atomic(plot, identification_png(report, title=f"{case.name}: {mode} contact stiffness"))
        if json_out:
            emit_json(_clean({"case": str(case), **report.as_json(), "plot": str(plot) if plot else None}), json_out,
                      inputs=[case])
            return
        from rich.console import Console
        from rich.table import Table

        con = Console()
        sym = "k_n" if mode == "normal" else "k_t"
        for j, r in enumerate(report.identifications):
            head = f"{mode} contact stiffness" + ("" if P is None else f" at P = {P[j]:g} N")
            t = Table(title=head)
            for col in ("mode", "f (Hz)", f"{sym} (N/um)", "d ln f / d ln k", "df/dln k (Hz)", "sigma(ln k)", "used"):
                t.add_column(col, justify="right")
            ks = r.k_n_N_m if mode == "normal" else r.k_t_N_m
            for i in range(len(r.modes)):
                t.add_row(str(r.modes[i]), f"{r.frequencies_Hz[i]:.6g}", f"{ks[i] * 1e-6:.5g}", f"{r.sensitivity[i]:.4f}",
                          f"{r.df_dlnk_Hz[i]:.4g}", f"{r.sigma_ln_k[i]:.3g}", "*" if i == r.best else "")
            con.print(t)
            if not r.consistent:
                con.print(f"[yellow]warning: the modes disagree on {sym} by more than 3 sigma; "
                          "check the mode numbering (--modes) or the model data[/yellow]")
        if report.law is not None:
            law = report.law
            con.print(f"preload law {sym} = c P^m: c = {law.c:.4g} N/m/N^m, m = {law.m:.4f} "
                      f"(1 sigma: ln c {law.sigma_ln_c:.3g}, m {law.sigma_m:.3g}; dof {law.dof})")
        if plot is not None:
            con.print(f"wrote {plot}")
