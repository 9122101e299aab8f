"""The README's library example runs as written and prints what the README says it prints."""

from __future__ import annotations

import contextlib
import io
import os
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _library_example() -> tuple[str, str]:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    section = text[text.index("## Library\n") :]
    code = re.search(r"```python\n(.*?)```", section, re.S)
    assert code is not None, "README.md: no python block under '## Library'"
    promised = re.search(r"print\(.*\)\s+# (.*)\n", code.group(1))
    assert promised is not None, "README.md: the example's print has no '# expected output'"
    return code.group(1), promised.group(1)


def test_readme_library_example_runs_and_prints_what_it_promises(tmp_path: Path) -> None:
    code, promised = _library_example()
    out = io.StringIO()
    cwd = Path.cwd()
    os.chdir(tmp_path)  # the example writes map.yaml / map.<write id>.pgm where it runs
    try:
        with contextlib.redirect_stdout(out):
            exec(compile(code, "README.md (Library)", "exec"), {"__name__": "readme"})
    finally:
        os.chdir(cwd)
    # NumPy pads array columns with spaces: compare without whitespace
    assert re.sub(r"\s+", "", out.getvalue()) == re.sub(r"\s+", "", promised)
    assert (tmp_path / "map.yaml").is_file()
