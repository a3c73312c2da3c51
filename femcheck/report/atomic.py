"""Atomic file output: write to a temporary file in the same folder, then rename.

A crash or Ctrl-C never leaves a half-written report, and an existing file is replaced in one step.
"""
from __future__ import annotations

import os
import tempfile
from pathlib import Path


def write_bytes_atomic(path, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically (parents created). Returns the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        # mkstemp creates 0600; a report should get the usual permissions (0666 less the umask)
        umask = os.umask(0)
        os.umask(umask)
        os.fchmod(fd, 0o666 & ~umask)
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    return path


def write_text_atomic(path, text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically."""
    return write_bytes_atomic(path, text.encode("utf-8"))


def refuse_input_overwrite(path, inputs) -> None:
    """Raise if ``path`` would overwrite one of the user's input files (case, measured data)."""
    p = Path(path).resolve()
    for inp in inputs:
        if inp and Path(inp).resolve() == p:
            from femcheck.errors import FemcheckError
            raise FemcheckError(f"refusing to write {path}: it is an input file")


def _nearest_existing(path: Path) -> Path:
    p = path
    while not p.exists() and p != p.parent:
        p = p.parent
    return p


def check_output_file(path, option: str = "--out") -> Path:
    """Fail before any work if the file ``path`` could not be written: its folder is a file, it is a folder,
    or the nearest existing folder is not writable. Names the option and the path."""
    from femcheck.errors import FemcheckError
    path = Path(path)
    if path.is_dir():
        raise FemcheckError(f"{option} {path}: is a folder; expected a file name")
    base = _nearest_existing(path.parent if str(path.parent) else Path("."))
    if not base.is_dir():
        raise FemcheckError(f"{option} {path}: cannot be written, {base} is a file, not a folder")
    if not os.access(base, os.W_OK | os.X_OK):
        raise FemcheckError(f"{option} {path}: cannot be written, no write permission in {base}")
    if path.exists() and not os.access(path, os.W_OK):
        raise FemcheckError(f"{option} {path}: cannot be written, the file is read-only")
    return path


def check_output_dir(path, option: str = "--out") -> Path:
    """Fail before any work if the folder ``path`` could not be created or written into."""
    from femcheck.errors import FemcheckError
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise FemcheckError(f"{option} {path}: is a file; expected a folder")
    base = _nearest_existing(path)
    if not base.is_dir():
        raise FemcheckError(f"{option} {path}: cannot be created, {base} is a file, not a folder")
    if not os.access(base, os.W_OK | os.X_OK):
        raise FemcheckError(f"{option} {path}: cannot be written, no write permission in {base}")
    return path
