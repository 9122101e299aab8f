"""What runs on a robot never imports what evaluates it (docs/architecture.md).

Every import statement of the robot-side packages is read from the source (top level and inside
functions alike), so a function-local import that dodges the rule fails here too.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "symloc"

ROBOT_SIDE = (
    "geometry.py",
    "scan.py",
    "odometry.py",
    "lidar_spec.py",
    "camera_model.py",
    "image_header.py",
    "errors.py",
    "_checks.py",
    "grid",
    "features",
    "symmetry",
    "mcl",
    "slam",
    "vision",
    "localizer",
    "msgs",
    "io",
    "ros",
)
EVALUATION = ("symloc.sim", "symloc.bench", "symloc.figures", "symloc.experiments", "symloc.cli")


def _modules() -> list[Path]:
    out: list[Path] = []
    for name in ROBOT_SIDE:
        path = PACKAGE / name
        out.extend(sorted(path.rglob("*.py")) if path.is_dir() else [path])
    return out


def _imports(path: Path) -> list[tuple[int, str]]:
    tree = ast.parse(path.read_text(), filename=str(path))
    found: list[tuple[int, str]] = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found.extend((node.lineno, alias.name) for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            found.append((node.lineno, node.module))
    return found


@pytest.mark.parametrize("path", _modules(), ids=lambda p: str(p.relative_to(PACKAGE)))
def test_robot_side_does_not_import_evaluation(path: Path) -> None:
    bad = [
        f"line {line}: {mod}"
        for line, mod in _imports(path)
        if any(mod == e or mod.startswith(e + ".") for e in EVALUATION)
    ]
    assert not bad, f"{path.relative_to(PACKAGE)} imports evaluation code: {bad}"
