"""The number tables in docs/ are what scripts/docs_numbers.py makes from the tool's runs.

Timing blocks (``bench:*``) are the bench scripts' verbatim output and are not compared
(timings vary from run to run); every other ``<!-- begin:NAME -->`` block must equal the
script's table, so a changed physics or data file that moves a documented number fails here
until ``python scripts/docs_numbers.py`` is run again.
"""

from __future__ import annotations

from pathlib import Path
from types import ModuleType

import pytest

from tests.conftest import load_script

ROOT = Path(__file__).resolve().parent.parent


def _script() -> ModuleType:
    return load_script("docs_numbers")


SCRIPT = _script()


def _all_blocks() -> dict[tuple[str, str], str]:
    return {(path.name, name): body for path in sorted((ROOT / "docs").glob("*.md"))
            for name, body in SCRIPT.blocks(path.read_text(encoding="utf-8")).items()}


def test_every_block_has_a_maker() -> None:
    found = _all_blocks()
    assert found, "no <!-- begin:NAME --> block in docs/"
    orphans = [f"{file}: {name}" for file, name in found
               if name not in SCRIPT.TABLES
               and not (name.startswith("bench:") and name[6:] in SCRIPT.BENCHES)]
    assert not orphans, f"blocks no script writes: {orphans}"
    for name in SCRIPT.TABLES:
        assert any(n == name for _, n in found), f"table {name} is in no docs file"


@pytest.mark.parametrize("name", sorted(SCRIPT.TABLES))
def test_docs_table_equals_the_script(name: str) -> None:
    made = SCRIPT.TABLES[name]()
    for (file, block), body in _all_blocks().items():
        if block == name:
            assert body == made, (f"docs/{file}: table '{name}' is stale; run "
                                  f"`python scripts/docs_numbers.py`\n--- docs\n{body}\n"
                                  f"--- script\n{made}")


def test_replace_rewrites_one_block_only() -> None:
    text = ("a\n<!-- begin:x -->\nold\n<!-- end:x -->\nb\n"
            "<!-- begin:y -->\nkeep\n<!-- end:y -->\n")
    out = SCRIPT.replace(text, "x", "new\nlines")
    assert SCRIPT.blocks(out) == {"x": "new\nlines", "y": "keep"}
    with pytest.raises(KeyError):
        SCRIPT.replace(text, "z", "anything")


def test_every_bench_script_has_its_block_in_speed_md() -> None:
    scripts = {p.stem for p in (ROOT / "bench").glob("bench_*.py")}
    assert scripts == set(SCRIPT.BENCHES), "scripts/docs_numbers.py's BENCHES lacks or names " \
        f"a bench: {sorted(scripts ^ set(SCRIPT.BENCHES))}"
    speed = SCRIPT.blocks((ROOT / "docs" / "speed.md").read_text(encoding="utf-8"))
    missing = [name for name in scripts if f"bench:{name}" not in speed]
    assert not missing, f"docs/speed.md has no block for {missing}"
