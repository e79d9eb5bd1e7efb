"""tuflexperf/models/ is physics only (issue 9): no file access, no fitting, no io/reduction."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

MODELS = Path(__file__).resolve().parents[2] / "tuflexperf" / "models"
FORBIDDEN = {
    "file access": r"\bopen\(|read_text|read_bytes|write_text|loadmat|savemat|np\.load|"
                   r"np\.savetxt|np\.loadtxt|\bimport csv\b|\bimport gzip\b|pathlib",
    "fitting": r"least_squares|curve_fit|nlpsol|qpsol|lstsq|polyfit|\bminimize\(",
    "io or reduction": r"(?m)^\s*(?:from|import)\s+"
                       r"tuflexperf\.(io|reduction|analysis|report|export)\b",
}


@pytest.mark.parametrize("path", sorted(MODELS.glob("*.py")), ids=lambda p: p.name)
def test_model_module_is_physics_only(path: Path) -> None:
    code = "\n".join(
        line for line in path.read_text().splitlines() if not line.lstrip().startswith("#")
    )
    for what, pattern in FORBIDDEN.items():
        found = re.findall(pattern, code)
        assert not found, f"{path.name}: {what}: {found}"
