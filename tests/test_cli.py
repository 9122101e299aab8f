from __future__ import annotations

import pytest

from symloc.cli.main import build_parser, main


def test_version(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    assert "symloc" in capsys.readouterr().out


def test_parser_has_experiment_command() -> None:
    parser = build_parser()
    with pytest.raises(SystemExit):
        parser.parse_args(["experiment", "--help"])
