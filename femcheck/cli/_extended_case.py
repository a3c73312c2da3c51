"""The outputs of ``diagnose --extended-case / --compensation``: checked before the diagnosis runs, written after."""
from __future__ import annotations

from pathlib import Path

from femcheck.errors import FemcheckError


def check_extended_outputs(case, case_path, measured, extended_case, compensation, poses) -> None:
    """Refuse, before any work, an output that would overwrite an input (OUT == CASE), an unwritable folder, a
    compensation table without poses (or on a case kind without markers), and a case kind with no writer."""
    from femcheck.report.atomic import check_output_file, refuse_input_overwrite
    inputs = [case_path, measured, poses]
    for out, opt in ((extended_case, "--extended-case"), (compensation, "--compensation")):
        if out:
            refuse_input_overwrite(out, inputs)
            check_output_file(out, opt)
    serial = case.meta.kind in ("serial_tree", "serial_robot")
    if (compensation is None) != (poses is None):
        raise FemcheckError("--compensation and --poses go together: the table lists the deflection at the poses given")
    if compensation and not serial:
        raise FemcheckError(f"--compensation: a {case.meta.kind} case; the table is written for serial trees (markers "
                            "at joint angles)")
    if extended_case and case.meta.kind not in ("haptic_6psu", "serial_tree", "parallel_device"):
        raise FemcheckError(f"--extended-case: a {case.meta.kind} case; the corrected case is written for haptic_6psu, "
                            "parallel_device and serial_tree cases")
    if extended_case and Path(extended_case).suffix.lower() != ".toml":
        raise FemcheckError(f"--extended-case: {extended_case}; expected a .toml file name")


def write_serial_outputs(case, case_path, diagnosis, extended_case, compensation, poses) -> None:
    """Write the corrected serial-tree case and/or the compensation table of its elastic deflection."""
    from femcheck.report.atomic import write_text_atomic
    from femcheck.robot.corrected_case import compensation_csv, corrected_case, read_poses_csv
    text, corrected = corrected_case(case, Path(case_path).read_text(), diagnosis)
    table = None
    if compensation:
        labels, q, pay = read_poses_csv(poses, corrected.tree.n_joints)
        table = compensation_csv(corrected, labels, q, pay)
    if extended_case:
        write_text_atomic(extended_case, text)
    if table is not None:
        write_text_atomic(compensation, table)
