"""``femcheck coverage CASE [--mutation PCT] [--points P0,P5] [--mesh coarse|default|fine] [--parts beam|solid]
[--json OUT]``: how much of the detailed analytical model the FE verification checks (mutation of each element's
law), for the 6-PSU and for ``parallel_device`` cases."""
from __future__ import annotations

from typing import Optional

import typer

from femcheck.cli._common import JSON_HELP, emit_json, load_case_for


def register(app: typer.Typer) -> None:
    @app.command("coverage")
    def coverage_cmd(
        case_path: str = typer.Argument(..., metavar="CASE", help="case file (TOML)"),
        mutation: float = typer.Option(50.0, "--mutation", metavar="PCT", help="scale each element's compliance law by 1 + PCT/100"),
        points: str = typer.Option("P0,P5", "--points", help="comma-separated test points"),
        mesh: str = typer.Option("coarse", "--mesh", help="FE mesh: coarse | default | fine"),
        json_out: Optional[str] = typer.Option(None, "--json", metavar="OUT", help=JSON_HELP),
        jobs: int = typer.Option(1, "--jobs", min=1, help="worker processes for the FE super-elements"),
        joint_fe: bool = typer.Option(True, "--joint-fe/--no-joint-fe", help="the FE's passive joints as their contact "
                                      "FE measures them (cached; first run 1-3 min); off: the closed-form joint laws"),
        joint_mesh: str = typer.Option("coarse", "--joint-mesh", help="mesh of the joint contact FE: coarse | default | fine"),
        parts: str = typer.Option("beam", "--parts", help="parallel devices: the FE's links as beam elements (beam) "
                                  "or meshed solids (solid, at --mesh)"),
        set_: Optional[list[str]] = typer.Option(None, "--set", metavar="KEY=VALUE",
                                                 help="override a case key (TOML value), e.g. actuation.fe.model=elements; repeatable"),
    ):
        """Mutate each element's compliance law where it is defined, rerun the analytical model and the FE,
        and report which mutations the verify check catches (docs/verify.md, "Coverage")."""
        from femcheck.cli import console, progress
        from femcheck.coverage import element_coverage
        from femcheck.fe_device.mesh_levels import MESH_LEVELS
        from femcheck.kinematics.psu6 import POINT_LABELS

        if not (mutation == mutation and 0 < mutation <= 1000):
            raise typer.BadParameter(f"--mutation: {mutation}; expected a percentage in (0, 1000]")
        if mesh not in MESH_LEVELS:
            raise typer.BadParameter(f"--mesh: {mesh!r}; expected one of {', '.join(MESH_LEVELS)}")
        if joint_mesh not in MESH_LEVELS:
            raise typer.BadParameter(f"--joint-mesh: {joint_mesh!r}; expected one of {', '.join(MESH_LEVELS)}")
        if parts not in ("beam", "solid"):
            raise typer.BadParameter(f"--parts: {parts!r}; expected beam or solid")
        pts = tuple(p.strip().upper() for p in points.split(",") if p.strip())
        bad = [p for p in pts if p not in POINT_LABELS]
        if bad or not pts:
            raise typer.BadParameter(f"--points: {bad[0] if bad else points!r}; expected labels P0..P8")
        if json_out and json_out != "-":
            from femcheck.report.atomic import check_output_file
            check_output_file(json_out, "--json")
        case = load_case_for(case_path, "coverage", kinds=("haptic_6psu", "parallel_device"))
        if set_:
            case = case.with_params(**parse_overrides(set_))
        con = console()
        if case.meta.kind == "parallel_device":
            res = _device_coverage(case, pts, mutation, mesh, parts, joint_fe, joint_mesh, json_out)
            return _print(con, res, mutation, pts, mesh, json_out, case_path)
        from femcheck.coverage.element_coverage import progress_weights
        from femcheck.fe_device.joint_laws import cached
        weights = progress_weights(len(pts), mesh, cached(case, joint_mesh) if joint_fe else None)
        with progress("coverage", None, weights=weights, stderr=json_out == "-") as bar:
            laws = None
            if joint_fe:
                from femcheck.fe_device.joint_laws import measure_joint_laws
                laws = measure_joint_laws(case, joint_mesh, progress=lambda d: bar.advance(1, d))
            res = element_coverage(case, pts, mutation, mesh, jobs=jobs, progress=lambda d: bar.advance(1, d),
                                   joint_laws=laws)
        _print(con, res, mutation, pts, mesh, json_out, case_path)


def _device_coverage(case, pts, mutation, mesh, parts, joint_fe, joint_mesh, json_out):
    """Coverage of a ``parallel_device`` case (:mod:`femcheck.coverage.device_coverage`)."""
    from femcheck.cli import progress
    from femcheck.coverage.device_coverage import device_coverage
    from femcheck.parallel.beam_fe import fe_laws_of
    from femcheck.parallel.joint_specimen import DeviceJointLaws, cached

    missing = sum(not hit for hit in cached(case, joint_mesh).values()) if joint_fe else 0
    # expected seconds (shared 2-core machine, measured): a joint's contact FE 100-150 s when not cached; the FE
    # models at two points 2 s with beam links, about 60 s with solid links (their meshes; later steps reuse them)
    weights = [0.01 + 120.0 * missing, 60.0 if parts == "solid" else 2.0] + [2.0] * len(case.device.element_names)
    with progress("coverage", None, weights=weights, stderr=json_out == "-") as bar:
        laws = fe_laws_of(case, joint_fe, joint_mesh)
        bar.advance(1, "joint laws")
        return device_coverage(case, pts, mutation, fe_laws=laws, parts=parts, mesh=mesh,
                               joint_law_details=DeviceJointLaws(laws.joints).details(),
                               progress=lambda d: bar.advance(1, d))


def _print(con, res, mutation, pts, mesh, json_out, case_path) -> None:
    """The coverage table (or its JSON)."""
    from rich.table import Table

    if json_out:
        emit_json(res.as_json(), json_out, inputs=[case_path])
        if json_out == "-":
            return
    t = Table(title=f"verification coverage: each law's compliance x {1 + mutation / 100:g} at {', '.join(pts)} "
                    f"(FE {res.fe_joints} joints vs analytical {res.analytical_joints}, "
                    f"{'beam-element links' if res.fe_links == 'beam' else f'mesh {res.mesh}'}, "
                    f"threshold {res.threshold_pct:g} %)")
    for h in ("element", "share %", "FE source", "error change (points)", "detected", "min detectable %"):
        t.add_column(h, justify="left" if h in ("element", "FE source") else "right")
    for e in res.elements:
        t.add_row(e.element, f"{e.share_pct:.1f}", e.fe_source, f"{e.error_change_pct:+.2f}", "yes" if e.detected else "no",
                  "-" if e.min_detectable_pct is None else f"{e.min_detectable_pct:.0f}")
    con.print(t)
    laws = ", ".join(f"{j} {s}" if isinstance(s, str) else f"{j} ({s['kind']}) {s['source']}"
                     for j, s in res.joint_laws.items()) or "none"
    con.print(f"covered share: {res.covered_share_pct:.1f} % of the detailed compliance is caught by the FE at a "
              f"{mutation:g} % mutation; independent share: {res.independent_share_pct:.1f} % is modelled by the FE "
              f"on its own (base error {res.base_error_pct:.2f} %; {res.seconds:.1f} s; joint laws on the FE side: "
              f"{laws})")
    if not res.base_passes:
        con.print(f"[yellow]the unmutated model already fails the check ({res.base_error_pct:.2f} % > "
                  f"{res.threshold_pct:g} %): every mutation is caught trivially[/yellow]")


def parse_overrides(items) -> dict:
    """["a.b=1.5", "x.y=elements"] -> {"a.b": 1.5, "x.y": "elements"}: each VALUE read as a TOML value, else
    taken as a bare string."""
    import tomllib
    out = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            raise typer.BadParameter(f"--set: {item!r}; expected KEY=VALUE, e.g. actuation.fe.model=elements")
        try:
            out[key.strip()] = tomllib.loads(f"v = {value.strip()}")["v"]
        except tomllib.TOMLDecodeError:
            out[key.strip()] = value.strip()
    return out
