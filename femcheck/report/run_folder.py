"""Run folders: a command that writes many files (``verify``, ``coverage``) owns its ``--out`` folder.

So that no file of an earlier run can pass as current, a run starts by emptying the folder of what an
earlier femcheck run wrote, and marks the folder as femcheck's with :data:`MARKER` (a small JSON naming
the command and its start time). A folder that is not empty and carries no mark of femcheck (the marker or
a femcheck ``manifest.json``) may hold the user's own files: it is refused unless ``force`` is given.
The manifest is written last, so a folder without one holds an interrupted run.
"""
from __future__ import annotations

import datetime as _dt
import json
import shutil
from pathlib import Path

from femcheck.errors import FemcheckError
from femcheck.report.atomic import check_output_dir, write_text_atomic

#: marks a folder as a femcheck run folder
MARKER = ".femcheck-run"


def _is_femcheck_folder(path: Path) -> bool:
    if (path / MARKER).is_file():
        return True
    manifest = path / "manifest.json"
    if manifest.is_file():
        try:
            return str(json.loads(manifest.read_text()).get("command", "")).startswith("femcheck")
        except (ValueError, OSError, AttributeError):
            return False
    return False


def prepare_run_folder(path, command: str, force: bool = False, option: str = "--out", inputs=()) -> Path:
    """Check, empty and mark the run folder ``path`` before a run of ``command`` writes into it.

    Raises :class:`FemcheckError` (naming ``option``) when the folder cannot be written, or when it holds
    files that femcheck did not write and ``force`` is false, or when one of the ``inputs`` (case file,
    baselines, measured data) lies inside it: emptying the folder must never delete an input. Returns the folder.
    """
    path = check_output_dir(path, option)
    root = path.resolve()
    for inp in inputs:
        if inp and (root == Path(inp).resolve() or root in Path(inp).resolve().parents):
            raise FemcheckError(f"{option} {path}: holds the input {inp}; a run folder is emptied before a run, "
                                "choose another folder")
    if path.is_dir() and any(path.iterdir()):
        if not (force or _is_femcheck_folder(path)):
            n = sum(1 for _ in path.iterdir())
            raise FemcheckError(f"{option} {path}: holds {n} file(s) that femcheck did not write; choose an empty or "
                                "new folder, or pass --force to empty it")
        for entry in path.iterdir():
            if entry.is_dir() and not entry.is_symlink():
                shutil.rmtree(entry)
            else:
                entry.unlink()
    path.mkdir(parents=True, exist_ok=True)
    stamp = _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")
    write_text_atomic(path / MARKER, json.dumps({"command": command, "started_utc": stamp}) + "\n")
    return path
