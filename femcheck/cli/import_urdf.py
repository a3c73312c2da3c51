"""``femcheck import-urdf ROBOT.urdf --marker NAME=LINK[@x,y,z] --out CASE.toml``: a URDF as a serial_tree case
(femcheck.robot.urdf), ready for ``femcheck diagnose`` on measured marker positions."""
from __future__ import annotations

import typer



def register(app: typer.Typer) -> None:
    @app.command("import-urdf")
    def import_urdf_cmd(
        urdf: str = typer.Argument(..., metavar="ROBOT.urdf", help="URDF robot description (revolute, continuous, prismatic, fixed joints)"),
        marker: list[str] = typer.Option(..., "--marker", help="NAME=LINK[@x,y,z]: a marker on LINK at x, y, z m in the "
                                         "link's frame (repeatable; the CSV's marker names)"),
        out: str = typer.Option(..., "--out", help="case file (TOML) to write"),
        root: str = typer.Option(None, "--root", help="link the tree starts from (default: the URDF's only root link)"),
        guide: list[str] = typer.Option(None, "--guide-overlap", help="JOINT=METRES: engaged length of a prismatic "
                                        "joint's guide at q = 0 (it shrinks as q grows); enables its guide_clearance cause"),
        sigma_mm: float = typer.Option(None, "--sigma-mm", help="marker noise (1 sigma per coordinate, mm) to state in the case"),
        force: bool = typer.Option(False, "--force", help="overwrite an existing --out"),
    ):
        """Write the URDF's kinematic tree (joint origins and axes as static frames, link masses and centres of
        mass, mimic joints as couplings) as a serial_tree case with the given markers."""
        import math
        from pathlib import Path

        from femcheck.case.registry import build_case
        from femcheck.errors import CaseError, FemcheckError
        from femcheck.report.atomic import check_output_file, refuse_input_overwrite, write_text_atomic
        from femcheck.robot.simulate import to_toml
        from femcheck.robot.urdf import urdf_document

        check_output_file(out, "--out")
        refuse_input_overwrite(out, [urdf])
        if Path(out).exists() and not force:
            raise FemcheckError(f"refusing to overwrite existing {out} (use --force)")
        markers = {}
        for spec in marker:
            name, eq, rest = spec.partition("=")
            link, _, xyz = rest.partition("@")
            try:
                off = tuple(float(v) for v in xyz.split(",")) if xyz else (0.0, 0.0, 0.0)
            except ValueError:
                off = ()
            if not (eq and name and link) or len(off) != 3 or not all(map(math.isfinite, off)):
                raise CaseError(urdf, "--marker", f"{spec!r}; expected NAME=LINK or NAME=LINK@x,y,z (m)")
            markers[name] = (link, off)
        overlaps = {}
        for spec in guide or []:
            jn, eq, val = spec.partition("=")
            try:
                overlaps[jn] = float(val)
            except ValueError:
                eq = ""
            if not (eq and jn):
                raise CaseError(urdf, "--guide-overlap", f"{spec!r}; expected JOINT=METRES")
        doc = urdf_document(urdf, markers, root, guide_overlap=overlaps)
        if sigma_mm is not None:
            if not (math.isfinite(sigma_mm) and sigma_mm > 0):
                raise CaseError(urdf, "--sigma-mm", f"{sigma_mm}; expected a positive number of mm")
            doc["measurement"] = {"sigma_m": sigma_mm * 1e-3}
        build_case(doc, out)         # validate before writing: a file we write always loads
        from femcheck.robot.positions import q_column
        independent = [r for r in doc["joints"] if "coupling" not in r]
        header = (f"# {doc['meta']['reference']}\n# CSV joint columns, in order: "
                  + ", ".join(f"{q_column(k, r.get('type') == 'prismatic')} = {r['name']}" for k, r in enumerate(independent))
                  + "\n# Add stiffness_Nm_per_rad (axial_stiffness_N_per_m on prismatic rows) to rows with a known drive "
                  "stiffness; state [measurement] sigma_m for a verdict that can say 'unexplained'.\n\n")
        write_text_atomic(out, header + to_toml(doc))
        typer.echo(f"wrote {out}: {len(doc['joints'])} rows ({len(independent)} independent), "
                   f"{len(doc['markers'])} markers, {sum(r['mass_kg'] for r in doc['joints']):.2f} kg carried")
