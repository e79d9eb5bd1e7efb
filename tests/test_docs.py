"""README.md is for users; docs/ holds the rest. Rules a reviewer would otherwise check by eye."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
README = ROOT / "README.md"
DOCS = sorted((ROOT / "docs").glob("*.md"))
SETUP = ("python3 -m venv .venv && .venv/bin/pip install -e '.[test]' && "
         ".venv/bin/tuflexperf check requirements/tuflex.yaml")
TESTS = "python3 -m venv .venv && .venv/bin/pip install -e '.[test]' && .venv/bin/python -m pytest"
# fix history and citations of a contract that is not in the repository
FORBIDDEN = [r"\bSPEC\b", r"outside audit", r"\baudit\b", r"\bsession\b",
             r"earlier (version|code|RK4|one)", r"\bused to\b", r"PASSed"]


def test_readme_is_short_and_keeps_the_two_commands() -> None:
    text = README.read_text(encoding="utf-8")
    assert len(text.splitlines()) <= 300
    assert SETUP in text
    assert TESTS in text
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    # CI runs the README's test command (its two halves may stand on two lines)
    head, _, tail = TESTS.rpartition(" && ")
    assert head in ci and tail in ci


@pytest.mark.parametrize("path", [README, *DOCS], ids=lambda p: p.name)
def test_no_fix_history_and_no_spec_citations(path: Path) -> None:
    # a bench block is the bench script's own output, pasted verbatim
    text = re.sub(r"<!-- begin:bench:.*?<!-- end:bench:[\w-]+ -->", "",
                  path.read_text(encoding="utf-8"), flags=re.S)
    found = [(pattern, match.group(0)) for pattern in FORBIDDEN
             for match in re.finditer(pattern, text)]
    assert not found, f"{path.name}: {found}"


@pytest.mark.parametrize("path", [README, *DOCS], ids=lambda p: p.name)
def test_relative_links_resolve(path: Path) -> None:
    text = path.read_text(encoding="utf-8")
    broken = []
    for target in re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", text):
        if "://" in target:
            continue
        if not (path.parent / target).exists():
            broken.append(target)
    design = ROOT / "docs" / "design.md"
    broken = [b for b in broken if not (b.endswith("design.md") and not design.exists())]
    assert not broken, f"{path.name}: broken links {broken}"


def test_readme_lists_every_command() -> None:
    from tuflexperf.cli import app

    text = README.read_text(encoding="utf-8")
    names = [c.name or c.callback.__name__ for c in app.registered_commands]
    missing = [n for n in names if f"`tuflexperf {n}" not in text]
    assert not missing, f"README's command table lacks {missing}"


@pytest.mark.parametrize("path", [README, *DOCS], ids=lambda p: p.name)
def test_named_files_exist(path: Path) -> None:
    # a test, script or bench the docs point to must be there (files are split and renamed)
    text = path.read_text(encoding="utf-8")
    missing = []
    for name in set(re.findall(r"`((?:tests|scripts|bench)/[\w/*.-]+\.py)`", text)):
        if not list(ROOT.glob(name)):
            missing.append(name)
    for name in set(re.findall(r"`(test_[\w*]+\.py)`", text)):
        if not list(ROOT.glob(f"tests/**/{name}")):
            missing.append(name)
    assert not missing, f"{path.name} names files that do not exist: {sorted(missing)}"
