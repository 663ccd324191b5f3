"""The README and the pages of docs/ stay true: their code runs and what they name exists.

- every ```python block of README.md and docs/*.md runs (in an empty folder, writing nothing);
- every repository path they quote in backticks (``streams/timing.py``) exists;
- every dotted name of ours they quote (``streams.stream_map.make_stream_map``) names a module,
  or a top-level definition of the longest module it starts with (read with ``ast``, nothing
  imported);
- every relative link (``[text](docs/sdar.md)``) points at a file of the repository;
- the README stays a guide: at most 250 lines.
"""

from __future__ import annotations

import ast
import re
from functools import cache
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
PACKAGES = ("sdar_tamp", "solvers", "streams", "domains")
#: Folders of the repository a quoted path may start with.
TOP_FOLDERS = (*PACKAGES, "tests", "benchmarks", "examples", "docs")
README_MAX_LINES = 250


def _blocks() -> list[tuple[str, int, str]]:
    found = []
    for page in PAGES:
        text = page.read_text(encoding="utf-8")
        for k, block in enumerate(re.findall(r"```python\n(.*?)```", text, re.S)):
            found.append((page.relative_to(ROOT).as_posix(), k, block))
    return found


BLOCKS = _blocks()


def _quoted(page: Path) -> list[tuple[int, str]]:
    """``(line, text)`` of every inline code span of ``page`` outside fenced blocks."""
    spans: list[tuple[int, str]] = []
    fenced = False
    for number, line in enumerate(page.read_text(encoding="utf-8").splitlines(), start=1):
        if line.lstrip().startswith("```"):
            fenced = not fenced
            continue
        if not fenced:
            spans.extend((number, span) for span in re.findall(r"`([^`\n]+)`", line))
    return spans


@cache
def _top_level_names(path: Path) -> frozenset[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    names: set[str] = set()
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, ast.Assign):
            names.update(t.id for t in node.targets if isinstance(t, ast.Name))
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            names.add(node.target.id)
        elif isinstance(node, (ast.Import, ast.ImportFrom)):
            names.update((a.asname or a.name).split(".")[0] for a in node.names)
    return frozenset(names)


def _module_file(parts: list[str]) -> Path | None:
    base = ROOT.joinpath(*parts)
    if (base / "__init__.py").is_file():
        return base / "__init__.py"
    if base.with_suffix(".py").is_file():
        return base.with_suffix(".py")
    return None


def dotted_name_exists(name: str) -> bool:
    """Whether ``pkg.module[.attribute...]`` names a module or a top-level definition of one."""
    parts = name.split(".")
    for n in range(len(parts), 0, -1):
        module = _module_file(parts[:n])
        if module is None:
            continue
        rest = parts[n:]
        return not rest or rest[0] in _top_level_names(module)
    return False


def _references(page: Path) -> list[tuple[int, str]]:
    refs = []
    for line, span in _quoted(page):
        token = span.split()[0] if span.split() else ""
        token = token.rstrip(".,:;)").split("(")[0]
        if not token or any(c in token for c in "<>*{}[]$~"):
            continue
        if "/" in token and token.split("/")[0] in TOP_FOLDERS:
            refs.append((line, token.split(":")[0].split("#")[0]))
        elif (
            re.fullmatch(r"[A-Za-z_][\w]*(\.[A-Za-z_]\w*)+", token)
            and token.split(".")[0] in PACKAGES
            and not token.endswith(".py")  # a file name (`streams.py`), not a dotted name
        ):
            refs.append((line, token))
    return refs


def test_pages_have_examples() -> None:
    assert any(page == "README.md" for page, _, _ in BLOCKS)


@pytest.mark.parametrize(("page", "index", "code"), BLOCKS, ids=[f"{p}[{k}]" for p, k, _ in BLOCKS])
def test_python_block_runs(
    page: str, index: int, code: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    if "ompl" in code:
        pytest.importorskip("ompl")
    monkeypatch.chdir(tmp_path)
    exec(compile(code, f"{page}[block {index}]", "exec"), {"__name__": "docs"})
    assert list(tmp_path.iterdir()) == []  # nothing written to the working directory


@pytest.mark.parametrize("page", PAGES, ids=[p.relative_to(ROOT).as_posix() for p in PAGES])
def test_named_paths_and_modules_exist(page: Path) -> None:
    missing = []
    for line, ref in _references(page):
        exists = (ROOT / ref).exists() if "/" in ref else dotted_name_exists(ref)
        if not exists:
            missing.append(f"{page.name}:{line}: {ref}")
    assert not missing, "\n".join(missing)


@pytest.mark.parametrize("page", PAGES, ids=[p.relative_to(ROOT).as_posix() for p in PAGES])
def test_relative_links_exist(page: Path) -> None:
    text = page.read_text(encoding="utf-8")
    broken = []
    for target in re.findall(r"\]\(([^)\s]+)\)", text):
        if re.match(r"[a-z]+:", target):  # https:, mailto:
            continue
        path = target.split("#")[0]
        if path and not (page.parent / path).exists():
            broken.append(target)
    assert not broken, f"{page.name}: broken links {broken}"


def test_readme_is_a_guide() -> None:
    lines = (ROOT / "README.md").read_text(encoding="utf-8").splitlines()
    assert len(lines) <= README_MAX_LINES


def test_the_checks_catch_a_stale_name() -> None:
    assert dotted_name_exists("solvers.solve")
    assert dotted_name_exists("solvers.solution.Solution")
    assert not dotted_name_exists("solvers.solution.NoSuchThing")
    assert not dotted_name_exists("streams.no_such_module")
