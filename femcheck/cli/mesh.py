"""``femcheck mesh CASE --part NAME [--size H] [--point P0..P8] --out FILE.vtu [--png FILE.png]``.

Meshes one part of the device (or one whole leg at a test point) from the case parameters, writes it
with its region tags (VTU/XDMF + FILE.json sidecar with region names, reference points and quality) and
optionally a picture with the regions coloured. See docs/fe_solver.md.
"""
from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from femcheck.cli._common import load_case_for

#: finest --size accepted, as a fraction of the part's default edge length
MAX_REFINEMENT = 20.0


def register(app: typer.Typer) -> None:
    @app.command("mesh")
    def mesh_cmd(
        case: Path = typer.Argument(..., help="case file (TOML)"),
        part: str = typer.Option(..., "--part", help="guideway | proximal_link | spherical_joint | universal_joint | platform | leg"),
        out: Path = typer.Option(..., "--out", help="mesh file to write (.vtu or .xdmf)"),
        size: Optional[float] = typer.Option(None, "--size", help="target edge length away from contacts, m (default: [solid.mesh])"),
        point: str = typer.Option("P0", "--point", help="test point P0..P8 (guideway length, leg pose)"),
        chain: int = typer.Option(0, "--chain", help="chain (leg) 0..5 for --part leg / guideway"),
        png: Optional[Path] = typer.Option(None, "--png", help="also write a picture of the part with its regions coloured"),
        no_cache: bool = typer.Option(False, "--no-cache", help="re-mesh even if the mesh cache has this part"),
    ) -> None:
        """Mesh a part of the device from the case parameters (linear tets + named regions)."""
        from rich.console import Console
        from rich.table import Table

        from femcheck.errors import FemcheckError
        from femcheck.report.atomic import check_output_file, refuse_input_overwrite
        from geometry import PARTS, MeshingError, build_part
        from geometry.io import write_mesh

        if part not in PARTS:
            raise MeshingError(part, {}, f"unknown part; expected one of {', '.join(PARTS)}")
        if out.suffix.lower() not in (".vtu", ".xdmf"):
            raise FemcheckError(f"--out {out}: expected a .vtu or .xdmf file name")
        if png is not None and png.suffix.lower() != ".png":
            raise FemcheckError(f"--png {png}: expected a .png file name")
        if size is not None and not (size == size and 0 < size < float("inf")):
            raise FemcheckError(f"--size {size}: expected a positive edge length in m (omit it for the case's [solid.mesh] size)")
        check_output_file(out)
        if png is not None:
            check_output_file(png, "--png")
        refuse_input_overwrite(out, [case])
        import time

        c = load_case_for(case, "mesh")
        if size is not None:
            sizes = c.solid.mesh
            default = getattr(sizes, f"{part}_size_m", None) or min(
                sizes.guideway_size_m, sizes.proximal_link_size_m, sizes.spherical_joint_size_m,
                sizes.universal_joint_size_m, sizes.platform_size_m)
            # tets grow as (default/size)^3: 20x finer is ~8000x the default mesh, about the memory of this machine
            if size < default / MAX_REFINEMENT:
                raise FemcheckError(f"--size {size:g} m: more than {MAX_REFINEMENT:g}x finer than the {part} default "
                                    f"{default:g} m (about {(default / size) ** 3:.3g}x the tets); expected >= {default / MAX_REFINEMENT:g} m")
        t0 = time.perf_counter()
        try:
            m = build_part(c, part, size, point=point, chain=chain, use_cache=not no_cache)
        except ValueError as exc:
            if isinstance(exc, FemcheckError):
                raise
            raise MeshingError(part, {"point": point, "chain": chain, "size_m": size}, str(exc)) from None
        wall = time.perf_counter() - t0
        write_mesh(m, out)
        console = Console()
        q = m.quality
        console.print(f"[bold]{part}[/bold]: {q['n_nodes']} nodes, {q['n_tets']} tets (P1), "
                      f"watertight={q['watertight']}, min dihedral {q['min_dihedral_deg']:.1f} deg, "
                      f"max aspect {q['max_aspect_ratio']:.2f}, meshing took {q.get('mesh_time_s', 0.0):.2f} s, this run {wall:.2f} s "
                      f"(cache key {m.cache_key})")
        tb = Table(title="bodies")
        for col in ("body", "material", "tets", "volume mm^3", "analytic mm^3", "error %"):
            tb.add_column(col, justify="right" if col not in ("body", "material") else "left")
        for b in m.bodies:
            bq = q["bodies"].get(b.name) or q["bodies"].get(b.name.split(":")[-1], {})
            tb.add_row(b.name, b.material, str(bq.get("n_tets", "")), f"{bq.get('volume_m3', float('nan')) * 1e9:.3f}",
                       f"{b.analytic_volume_m3 * 1e9:.3f}", f"{100 * bq.get('volume_rel_error', float('nan')):+.3f}")
        console.print(tb)
        tr = Table(title="regions")
        for col in ("region", "kind", "pair/side", "facets", "nodes", "reference point (mm)"):
            tr.add_column(col)
        for name, r in m.regions.items():
            ref = "" if r.reference_point is None else ", ".join(f"{1e3 * v:.2f}" for v in r.reference_point)
            tr.add_row(name, r.kind, f"{r.pair} {r.side}".strip(), str(len(r.facets)), str(len(r.nodes)), ref)
        console.print(tr)
        console.print(f"wrote {out} (+ {out.name}.json)")
        if png is not None:
            from geometry.picture import render
            render(m, png)
            console.print(f"wrote {png}")
