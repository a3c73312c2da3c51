"""The user documentation holds to what the product does.

* docs/validation.md is the page generated from reports/bench/*.json, and every figure on it is the JSON's;
* every command line shown in docs/ and README.md parses through the real command-line parser (unknown options,
  bad choices and missing case files fail), and the quick ones are run for real;
* the README and the docs stay within their line budgets;
* nothing in the product speaks of the way it was developed (issue numbers, sessions, agents).

``python tests/test_docs.py`` prints the process words still left in the product, file by file.
"""
from __future__ import annotations

import json
import os
import re
import shlex
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOC_FILES = sorted((ROOT / "docs").rglob("*.md")) + [ROOT / "README.md"]


# ---------------------------------------------------------------------------------------------- validation page
def test_validation_page_is_generated_from_the_bench_json():
    from femcheck.bench import validation_page as vp
    figures = vp.load_figures()
    assert figures, "reports/bench/*.json must be committed: docs/validation.md is built from them"
    page = (ROOT / "docs" / "validation.md").read_text(encoding="utf-8")
    assert page == vp.render(figures), "docs/validation.md is stale: run python -m femcheck.bench.validation_page"


def test_validation_page_figures_are_the_json_figures():
    """Read back independently of the generator: each area's section names its command and machine, and each
    table row's value is the JSON value (floats printed to 6 significant digits: relative 1e-5 covers the rounding,
    any other change of a figure is far larger)."""
    page = (ROOT / "docs" / "validation.md").read_text(encoding="utf-8")
    sections = dict(re.findall(r"^## (\w+)\n(.*?)(?=^## |\Z)", page, re.S | re.M))
    for path in sorted((ROOT / "reports" / "bench").glob("*.json")):
        fig = json.loads(path.read_text(encoding="utf-8"))
        text = sections[path.stem]
        assert f"`python -m femcheck.bench {path.stem}`" in text
        assert f"Machine: {fig['machine']}" in text
        rows = dict(re.findall(r"`([^`]+)` \| ([^|]*?) \|", text))
        shown = {k: v for k, v in fig.items() if k not in ("machine", "machine_cpus", "machine_python",
                                                             "machine_blas_threads", "load_average", "bench_wall_s")
                 and not isinstance(v, (dict, list))}   # per-case detail stays in the JSON, named on the page
        assert set(rows) == set(shown), path.name
        for key, value in shown.items():
            cell = rows[key].split(" (`")[0]
            if isinstance(value, float) or (isinstance(value, int) and not isinstance(value, bool)):
                assert float(cell) == pytest.approx(value, rel=1e-5), (path.name, key)
            elif isinstance(value, str):
                assert cell == value.replace("|", "/"), (path.name, key)


def test_bench_keeps_committed_figures_when_an_area_cannot_compare(tmp_path, monkeypatch):
    """``make bench`` rewrites reports/bench/<area>.json, except for an area that could not run its comparison here
    (calculix without ccx): the committed figures stay, so the page never loses a measurement to a machine
    without the optional tool."""
    import types
    from femcheck.bench import __main__ as bench
    (tmp_path / "reports" / "bench").mkdir(parents=True)
    kept = tmp_path / "reports" / "bench" / "calculix.json"
    kept.write_text('{"ccx_status": "ran"}\n')
    areas = [types.SimpleNamespace(AREA="calculix", run=lambda: {"ccx_status": "skipped: ccx not found"}),
             types.SimpleNamespace(AREA="vjm", run=lambda: {"batch_poses_per_s": 1.0})]
    monkeypatch.setattr(bench, "_areas", lambda: areas)
    monkeypatch.chdir(tmp_path)
    assert bench.main([]) == 0
    assert json.loads(kept.read_text()) == {"ccx_status": "ran"}
    written = json.loads((tmp_path / "reports" / "bench" / "vjm.json").read_text())
    assert written["batch_poses_per_s"] == 1.0 and "machine" in written and "load_average" in written


# ---------------------------------------------------------------------------------------------- line budgets
def test_readme_and_docs_within_their_line_budgets():
    readme = len((ROOT / "README.md").read_text(encoding="utf-8").splitlines())
    total = sum(len(p.read_text(encoding="utf-8").splitlines()) for p in DOC_FILES)
    assert readme <= 150, readme     # the README is an entry page: what, quickstart, commands, where next
    assert total <= 2000, total      # docs that teach: one page per task, no measurement history


def test_links_and_images_of_the_docs_resolve():
    """Every relative Markdown link or image of docs/ and the README names a file of the repository."""
    broken = []
    for path in DOC_FILES:
        for target in re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", path.read_text(encoding="utf-8")):
            if "://" not in target and not (path.parent / target).exists():
                broken.append(f"{path.relative_to(ROOT)}: {target}")
    assert not broken, broken


# ---------------------------------------------------------------------------------------------- command lines
def command_lines(path: Path) -> list[tuple[str, str | None]]:
    """(command line, the error line the docs show after it or None) of the fenced sh/console blocks of a
    Markdown file: in ``sh`` blocks every non-comment line (backslash continuations joined), in ``console``
    blocks the lines after a ``$`` prompt."""
    out = []
    for lang, body in re.findall(r"^```(sh|console|bash|shell)\n(.*?)^```", path.read_text(encoding="utf-8"), re.S | re.M):
        lines = [ln.strip() for ln in body.replace("\\\n", " ").splitlines()]
        for k, line in enumerate(lines):
            if lang == "console":
                if not line.startswith("$ "):
                    continue
                line = line[2:]
            if line and not line.startswith("#"):
                shown = lines[k + 1] if k + 1 < len(lines) and lines[k + 1].startswith("error: ") else None
                out.append((line, shown))
    return out


#: subcommands that finish in seconds at the settings the docs show: run for real, in a scratch folder
RUN_FOR_REAL = {"stiffness", "deflect", "import-urdf"}


def _all_commands():
    for path in DOC_FILES:
        for line, error in command_lines(path):
            yield pytest.param(line, error, id=f"{path.relative_to(ROOT)}: {line[:60]}")


def _parse(args: list[str]):
    """Parse ``femcheck ARGS`` with the real click command tree, without running it; returns the leaf command."""
    import typer
    from femcheck.cli import get_app
    cmd = typer.main.get_command(get_app())
    ctx = cmd.make_context("femcheck", list(args), resilient_parsing=False)
    while hasattr(cmd, "resolve_command"):   # a group (typer may vendor its own click): descend to the leaf
        protected = ctx._protected_args if hasattr(ctx, "_protected_args") else ctx.protected_args
        name, cmd, rest = cmd.resolve_command(ctx, [*protected, *ctx.args])
        ctx = cmd.make_context(name, rest, parent=ctx)
    return cmd


@pytest.mark.parametrize("line, error", list(_all_commands()))
def test_documented_command_line_runs(line, error, tmp_path, monkeypatch, capsys):
    """Each documented command parses with the real parser; the quick ones run, and an error the docs show is
    the one the command prints (exit 2, one line)."""
    words = shlex.split(line, comments=True)
    if words[0] == "make":
        makefile = (ROOT / "Makefile").read_text()
        for target in (w for w in words[1:] if "=" not in w):
            assert re.search(rf"^{re.escape(target)}:", makefile, re.M), f"make target {target} not in the Makefile"
        return
    if words[:2] == ["python", "-m"] and words[2].startswith("femcheck.bench"):
        from femcheck.bench.__main__ import _areas
        if words[2] == "femcheck.bench":
            areas = {m.AREA for m in _areas()}
            assert set(w for w in words[3:] if not w.startswith("-")) <= areas, line
        else:   # python -m femcheck.bench.validation_page: the committed page is the generated one
            from femcheck.bench import validation_page
            assert validation_page.main(["--check"]) == 0
        return
    if words[0] == "python" and words[1].endswith(".py"):
        assert (ROOT / words[1]).is_file(), line   # tests/test_examples.py runs the example scripts
        return
    if words[:3] == ["python", "-m", "femcheck"]:
        words = words[2:]
    assert words[0] == "femcheck", f"a documented command must start with femcheck, python -m femcheck or make: {line}"
    args = words[1:]
    # every documented command is scratch-safe: it reads the repository's cases and writes into a scratch folder
    for name in ("cases", "examples", "geometry"):
        (tmp_path / name).symlink_to(ROOT / name)
    monkeypatch.chdir(tmp_path)
    if args[-1] == "--help" or args == []:
        from typer.testing import CliRunner
        from femcheck.cli import get_app
        res = CliRunner().invoke(get_app(), args or ["--help"])
        assert res.exit_code == 0, res.output
        return
    for word in args:   # a case or example the docs name is one the repository has
        if word.startswith(("cases/", "examples/")):
            assert (ROOT / word.split("=")[-1]).exists(), f"{word} not in the repository"
    if error is None:
        _parse(args)     # the options exist and their values parse (choices, numbers)
    sub = next(a for a in args if not a.startswith("-"))
    if sub in RUN_FOR_REAL or error is not None:
        from femcheck.cli import main
        code = main(args)
        if error is None:
            assert code == 0, line
        else:   # bad input: exit 2 and exactly the line the docs show
            assert code == 2, line
            printed = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
            assert " ".join(printed[-1].split()) == " ".join(error.split())


# ---------------------------------------------------------------------------------------------- process words
PRODUCT = ["docs", "README.md", "femcheck", "geometry", "cases", "examples", "Makefile", "reports/README.md", "pyproject.toml",
           ".ci"]

#: words about how the product was developed; domain words (a Dask worker, a helper function) are not matched
PROCESS_WORDS = re.compile(
    r"\bissues?\s*#?\d+"          # issue 7, issues 14, issue #3
    r"|\bsessions?\b"             # this session, earlier sessions
    r"|\bagents?\b"               # other agents' jobs
    r"|\bfiled by\b",
    re.I)

#: code that legitimately says "session": pytest fixture scopes
ALLOWED = re.compile(r"""scope\s*=\s*["']session["']""")


def _product_files(top: str) -> list[Path]:
    base = ROOT / top
    if base.is_file():
        return [base]
    return sorted(p for p in base.rglob("*") if p.is_file() and "__pycache__" not in p.parts
                  and p.suffix in {".py", ".md", ".toml", ".txt", ".json", ".cfg", ".html"})


def _grep(top: str, pattern: re.Pattern, allowed: re.Pattern | None = None) -> list[str]:
    """``path:line: text`` for every line of the product file or folder ``top`` that ``pattern`` matches."""
    hits = []
    for path in _product_files(top):
        for n, text in enumerate(path.read_text(encoding="utf-8", errors="replace").splitlines(), 1):
            if pattern.search(allowed.sub("", text) if allowed else text):
                hits.append(f"{path.relative_to(ROOT)}:{n}: {text.strip()}")
    return hits


def process_word_hits(top: str) -> list[str]:
    """Every process word in the product file or folder ``top``."""
    return _grep(top, PROCESS_WORDS, ALLOWED)


def test_the_word_list_catches_what_it_is_for():
    """The patterns match the phrasings they exist for and leave domain words alone."""
    for bad in ("(issue 14 part 3)", "Issues #7", "in the first session", "other agents' jobs", "filed by a helper"):
        assert PROCESS_WORDS.search(bad), bad
    for good in ('@pytest.fixture(scope="session")', "Dask workers", "the one plugin-discovery helper", "an issue of units"):
        assert not PROCESS_WORDS.search(ALLOWED.sub("", good)), good


@pytest.mark.parametrize("top", PRODUCT)
def test_product_says_nothing_of_issues_sessions_or_agents(top):
    hits = process_word_hits(top)
    assert not hits, f"{len(hits)} process words in {top}:\n" + "\n".join(hits[:40])


#: a path outside a user's clone, or the conventions file by its former outside name (the repository has
#: docs/conventions.md with the same section numbers)
OUTSIDE = re.compile(r"\.\./shared|shared/reference|/work/|(?<!docs/)\bCONVENTIONS\.md")


#: a documentation page named in the product
PAGE_REFERENCE = re.compile(r"\bdocs/[\w./-]+\.md")


def _missing_pages(top: str) -> list[str]:
    """Product lines naming a docs/*.md page that the repository does not have."""
    return [hit for hit in _grep(top, PAGE_REFERENCE)
            if any(not (ROOT / ref).is_file() for ref in PAGE_REFERENCE.findall(hit.split(": ", 1)[1]))]


@pytest.mark.parametrize("top", PRODUCT)
def test_product_points_nowhere_outside_the_repository(top):
    """A user's clone has no ../shared folder: docs, messages and cases name only files of the repository, and
    every docs page they name exists."""
    bad = _grep(top, OUTSIDE) + _missing_pages(top)
    assert not bad, f"{len(bad)} references outside the repository in {top}:\n" + "\n".join(bad[:40])


if __name__ == "__main__":
    os.chdir(ROOT)
    total = 0
    for top in PRODUCT:
        for hit in process_word_hits(top) + _grep(top, OUTSIDE) + _missing_pages(top):
            print(hit)
            total += 1
    print(f"{total} process words or outside references in the product", file=sys.stderr)
