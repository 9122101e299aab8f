"""One vocabulary across every command: the whole ``symloc`` parser tree is walked and every
shared option is checked to have one name, one default and one validation
(:mod:`symloc.cli.options`)."""

from __future__ import annotations

import argparse
import math
from collections.abc import Iterator
from pathlib import Path

import pytest

from symloc.cli import options
from symloc.cli.commands import demo
from symloc.cli.main import build_parser, main


def _leaves(
    parser: argparse.ArgumentParser, path: tuple[str, ...] = ()
) -> Iterator[tuple[tuple[str, ...], argparse.ArgumentParser]]:
    subs = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    if not subs:
        yield path, parser
        return
    for action in subs:
        for name, sub in action.choices.items():
            yield from _leaves(sub, (*path, name))


LEAVES = dict(_leaves(build_parser()))


def _option(parser: argparse.ArgumentParser, flag: str) -> argparse.Action | None:
    return next((a for a in parser._actions if flag in a.option_strings), None)


#: Commands without randomness: no --seed.
NOT_STOCHASTIC = {
    ("places", "add"),
    ("places", "keyframes"),
    ("places", "align-keyframes"),
    ("places", "list"),
    ("places", "decide"),
    ("places", "remove"),
    ("ros", "node"),  # the seed is a node parameter (params.yaml)
    ("ros", "check-params"),
    ("ros", "setup"),  # builds interface packages: nothing random
    ("vocab", "convert"),
    ("vocab", "info"),
}
#: Old names of the lidar option, and of others, that must not come back.
RETIRED = ("--sensor", "--sensors", "--preset", "--presets", "--image-out", "--png-out")


def _ids(path: tuple[str, ...]) -> str:
    return " ".join(path)


def test_the_tree_is_walked() -> None:
    assert ("demo",) in LEAVES
    assert ("experiment", "table1") in LEAVES
    assert ("places", "decide") in LEAVES
    assert len(LEAVES) >= 25


@pytest.mark.parametrize("path", sorted(LEAVES), ids=_ids)
def test_shared_options_have_one_name_and_one_default(path: tuple[str, ...]) -> None:
    parser = LEAVES[path]
    flags = {s for a in parser._actions for s in a.option_strings}
    assert not flags & set(RETIRED), f"retired option names: {flags & set(RETIRED)}"
    seed = _option(parser, "--seed")
    if path[0] == "bench":  # seeds are per world there (--seeds / --split), printed per world
        assert seed is None or seed.default == options.DEFAULT_SEED
    elif path in NOT_STOCHASTIC:
        assert seed is None
    else:
        assert seed is not None, "every stochastic command takes --seed"
        assert seed.type is options.nonnegative_int
        # the demo's room and seed are its story's: plain AMCL confidently wrong (README)
        assert seed.default == (demo.DEFAULT_SEED if path == ("demo",) else options.DEFAULT_SEED)
    out = _option(parser, "--out")
    if out is not None:
        assert out.type is options.output_folder
        assert out.metavar == "DIR", "--out is always a folder"
        assert Path(out.default) == options.default_out(" ".join(path))
    js = _option(parser, "--json")
    if js is not None:
        assert js.type is options.output_file
        assert js.default is None
    lidar = _option(parser, "--lidar")
    if lidar is not None:
        assert lidar.default in (options.DEFAULT_LIDAR, [options.DEFAULT_LIDAR])
    room = _option(parser, "--room")
    if room is not None:
        assert room.default == (demo.DEFAULT_ROOM if path == ("demo",) else options.DEFAULT_ROOM)
        assert set(room.choices or ()) <= set(options.ROOMS)
    rooms = _option(parser, "--rooms")
    if rooms is not None:
        assert rooms.default == ["all"]
    trials = _option(parser, "--trials")
    if trials is not None:
        assert trials.type is options.count
    for action in parser._actions:
        text = (action.help or "").lower()
        assert "[rad" not in text, f"{action.option_strings}: angles are degrees for people"
        if action.dest != "help" and action.option_strings:
            assert action.help, f"{action.option_strings} has no help"


@pytest.mark.parametrize(
    "path",
    sorted(p for p in LEAVES if p not in NOT_STOCHASTIC and _option(LEAVES[p], "--seed")),
    ids=_ids,
)
def test_a_negative_seed_is_a_usage_error(
    path: tuple[str, ...], capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as exc:
        main([*path, "--seed", "-1"])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "--seed: expected an integer >= 0, got -1" in err
    assert "Traceback" not in err


@pytest.mark.parametrize(
    "path", sorted(p for p in LEAVES if _option(LEAVES[p], "--trials")), ids=_ids
)
@pytest.mark.parametrize("value", ["0", "-5"])
def test_trials_below_one_are_a_usage_error(
    path: tuple[str, ...], value: str, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as exc:
        main([*path, "--trials", value])
    assert exc.value.code == 2
    assert "--trials: expected an integer >= 1" in capsys.readouterr().err


@pytest.mark.parametrize("path", sorted(LEAVES), ids=_ids)
def test_help_reads(path: tuple[str, ...], capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exc:
        main([*path, "--help"])
    assert exc.value.code == 0
    text = capsys.readouterr().out
    assert text.startswith("usage: symloc " + " ".join(path))
    if _option(LEAVES[path], "--out") is not None:
        assert "output folder" in text


def test_angles_are_degrees_at_the_command_line() -> None:
    angle_flags = {
        ("experiment", "photos"): ("--max-yaw", 5.0),
        ("experiment", "keyframes"): ("--step-deg", 5.0),
        ("experiment", "table3"): ("--heading-deg", 5.0),
    }
    for path, (flag, deg) in angle_flags.items():
        action = _option(LEAVES[path], flag)
        assert action is not None
        assert action.default == pytest.approx(math.radians(deg)), f"{path} {flag}"
        assert "degrees" in (action.help or "")


#: Destinations of options that name a path the command writes: a folder or one file.
OUTPUT_FOLDERS = {"out", "keep_build", "peer_build"}
OUTPUT_FILES = {"json", "png", "build_map", "output", "results"}


@pytest.mark.parametrize("path", sorted(LEAVES), ids=_ids)
def test_every_output_path_is_checked_by_the_shared_types(path: tuple[str, ...]) -> None:
    """Every option that names a written path is typed output_folder / output_file (checked
    while parsing, before any work), and no other option reads a bare Path under those names."""
    for action in LEAVES[path]._actions:
        if action.dest in OUTPUT_FOLDERS:
            assert action.type is options.output_folder, action.option_strings or action.dest
        elif action.dest in OUTPUT_FILES:
            assert action.type is options.output_file, action.option_strings or action.dest
        if action.type in (options.output_folder, options.output_file):
            assert action.dest in OUTPUT_FOLDERS | OUTPUT_FILES | {"db"}, action.dest


def _out_cases() -> list[tuple[tuple[str, ...], str, str]]:
    cases = []
    for path, parser in sorted(LEAVES.items()):
        for action in parser._actions:
            if action.type is options.output_folder and action.option_strings:
                cases.append((path, action.option_strings[-1], "folder"))
            elif action.type is options.output_file and action.option_strings:
                cases.append((path, action.option_strings[-1], "file"))
    return cases


@pytest.mark.parametrize(("path", "flag", "kind"), _out_cases(), ids=str)
@pytest.mark.parametrize("bad", ["wrong_kind", "under_a_file", "special"])
def test_a_bad_output_path_is_a_usage_error_naming_option_and_path(
    path: tuple[str, ...],
    flag: str,
    kind: str,
    bad: str,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    a_file = tmp_path / "a_file"
    a_file.write_text("x")
    a_folder = tmp_path / "a_folder"
    a_folder.mkdir()
    value = {
        "wrong_kind": str(a_file if kind == "folder" else a_folder),
        "under_a_file": str(a_file / "below"),
        "special": "/dev/null",
    }[bad]
    with pytest.raises(SystemExit) as exc:
        main([*path, flag, value])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert f"argument {flag}: {value} " in err, err
    assert "Traceback" not in err
    assert a_file.read_text() == "x"
    assert a_folder.is_dir()


@pytest.mark.parametrize("path", sorted(p for p in LEAVES if _option(LEAVES[p], "--out")), ids=_ids)
def test_the_default_out_folder_is_checked_too(
    path: tuple[str, ...],
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    monkeypatch.chdir(tmp_path)
    options.default_out(" ".join(path)).write_text("a file where the default folder goes")
    with pytest.raises(SystemExit) as exc:
        main(list(path))
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert f"argument --out: {options.default_out(' '.join(path))} is an existing file" in err


#: Numeric options without an upper bound, and why none is needed: nothing is allocated or run
#: in proportion to them (or the library checks them against what they index).
UNBOUNDED_NUMBERS = {
    "seed": "any integer >= 0 seeds numpy's SeedSequence",
    "seeds": "world seeds: any integer >= 0",
    "max_scans": "only truncates a log",
    "timeout": "wall seconds a peer may run; nothing is allocated for it",
    "odom_alpha": "a noise level",
    "amcl_alpha": "a noise level",
    "global_exponent": "AmclParams checks it in (0, 1]",
    "step": "an angle",
    "max_yaw": "an angle",
    "max_heading": "an angle",
    "measurement_sigma": "an angle",
    "chain_sigma": "an angle",
    "hfov": "an angle (the camera's resolution is fixed)",
    "loop_every": "larger means fewer loop searches",
    "loop_resample": "larger means fewer loop searches",
    "loop_constrained": "larger means fewer loop searches",
    "stride": "larger means fewer scans judged",
    "range_sigma": "a tolerance",
    "range_sigma_relative": "a tolerance",
    "radius_mm": "a tolerance",
    "gv": "places add: stored with the place, nothing built from it",
    "pose": "a pose",
    "intrinsics": "camera intrinsics (checked by the camera model)",
    "distortion": "distortion coefficients (checked by the camera model)",
    "place": "an id looked up in the database",
    "index": "a scan index looked up in the log",
    "time": "a simulated time of day",
    "gain": "an image gain",
}
_NUMERIC = {
    options.positive_int,
    options.nonnegative_int,
    options.positive_float,
    options.nonnegative_float,
    options.finite_float,
    options.integer,
    options._radians,
    int,
    float,
}


@pytest.mark.parametrize("path", sorted(LEAVES), ids=_ids)
def test_numeric_options_are_bounded_or_say_why_not(path: tuple[str, ...]) -> None:
    for action in LEAVES[path]._actions:
        if isinstance(action.type, options.Bounded):
            assert action.type.high is not None or action.type.low is not None
            assert action.type.why
        elif action.type in _NUMERIC:
            assert action.dest in UNBOUNDED_NUMBERS, (
                f"{action.option_strings}: a numeric option needs an upper bound"
                " (options.bounded) or a reason in UNBOUNDED_NUMBERS"
            )
