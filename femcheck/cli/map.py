"""``femcheck map``: stiffness map over a workspace slice (seed 000 Figs. 20-22)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import typer

from femcheck.cli._common import load_case_for

from femcheck.cli._common import Joints, ModelLevel
from femcheck.errors import FemcheckError
from femcheck.report.atomic import check_output_file, refuse_input_overwrite, write_bytes_atomic
from femcheck.report.stiffness_map import plot_stiffness_map, stiffness_map

#: grid points per side: 1001^2 poses is already ~1 M chain evaluations
MAX_RESOLUTION = 1001


def register(app: typer.Typer) -> None:
    @app.command("map")
    def map_cmd(
        case_path: str = typer.Argument(..., metavar="CASE", help="case file (TOML)"),
        model: ModelLevel = typer.Option(ModelLevel.detailed, "--model"),
        joints: Joints = typer.Option(None, "--joints", help="default: the case's idealization"),
        z: float = typer.Option(0.025, "--z", help="slice height above the cube centre (m)"),
        direction: str = typer.Option("x", "--direction", help="x, y or z"),
        out: Path = typer.Option(..., "--out", help="output PNG file"),
        half_width: float = typer.Option(0.1, "--half-width", help="half width of the mapped square (m)"),
        resolution: int = typer.Option(81, "--resolution", help="grid points per side"),
    ):
        """Directional stiffness over a horizontal workspace slice, with the test cube drawn."""
        if direction not in ("x", "y", "z"):
            raise typer.BadParameter(f"--direction {direction!r}; expected x, y or z")
        if not np.isfinite(z):
            raise typer.BadParameter(f"--z: {z}; expected a finite height in m")
        if not (np.isfinite(half_width) and 0 < half_width <= 1.0):
            raise typer.BadParameter(f"--half-width: {half_width}; expected 0 < half width <= 1 m")
        if not 2 <= resolution <= MAX_RESOLUTION:
            raise typer.BadParameter(f"--resolution: {resolution}; expected 2..{MAX_RESOLUTION} grid points per side")
        if out.suffix.lower() != ".png":
            raise typer.BadParameter(f"--out: {str(out)!r}; expected a .png file name (the map is a PNG picture)")
        check_output_file(out)
        case = load_case_for(case_path, "map", kinds=("haptic_6psu", "parallel_device"))
        refuse_input_overwrite(out, [case_path])
        if case.kind == "parallel_device":
            from femcheck.parallel.stiffness_map import stiffness_map as parallel_stiffness_map
            smap = parallel_stiffness_map(case, direction, z, model.value, joints.value if joints else None, half_width,
                                          resolution)
        else:
            smap = stiffness_map(case, direction, z, model.value, joints.value if joints else None, half_width, resolution)
        if not np.isfinite(smap.k).any():
            raise FemcheckError(f"--z {z}: no grid point of the {2 * half_width:g} m square at z = {smap.z * 1e3:.0f} mm "
                                f"is reachable; nothing written to {out} (--z is measured from the test-cube centre)")
        write_bytes_atomic(out, plot_stiffness_map(case, smap))
        k = smap.k[~np.isnan(smap.k)]
        typer.echo(f"wrote {out}: k_{direction} {k.min()/1e3:.2f}..{k.max()/1e3:.2f} N/mm over "
                   f"{k.size}/{smap.k.size} reachable grid points at z = {smap.z*1e3:.0f} mm")
