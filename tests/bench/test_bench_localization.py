"""symloc bench localization: a small sweep, identical JSON whatever runs it, Ray local mode."""

from __future__ import annotations

import dataclasses
import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest

from symloc.bench.localization import WorldTask, run_world, summarize, trial_rows
from symloc.bench.results_file import load_results
from symloc.bench.scenario import build_scenario
from symloc.bench.sweep import run_sweep
from symloc.bench.trial import (
    DEFAULT_METHODS,
    MethodResult,
    TrialConfig,
    TrialSpec,
    needs_keyframes,
    run_trial,
    sample_free_pose,
)
from symloc.bench.world_sources import WorldRef, build_world, split_seeds
from symloc.cli.main import main
from symloc.errors import ConfigurationError

SMALL = [
    "bench",
    "localization",
    "--families",
    "square",
    "--seeds",
    "3",
    "4",
    "--trials",
    "2",
    "--map",
    "raster",
    "--claim-timeout",
    "4",
    "--track-time",
    "1",
]


def test_splits_never_overlap() -> None:
    dev = set(split_seeds("dev", 5000))
    test = set(split_seeds("test", 5000))
    assert not dev & test
    with pytest.raises(ConfigurationError, match="split"):
        split_seeds("train", 3)


def test_every_world_of_a_split_has_its_own_robot_and_noise() -> None:
    from symloc.bench.sensors import robot_hardware
    from symloc.lidar_spec import RPLIDAR_A2
    from symloc.sim.camera import Camera
    from symloc.sim.generator import FAMILIES

    refs = [WorldRef("generated", f, s) for f in FAMILIES for s in split_seeds("dev", 2)]
    robots = [r.robot_seed for r in refs]
    assert len(set(robots)) == len(refs)
    assert robots == [r.robot_seed for r in refs]  # the same on every call
    trials = {r.trial_seed(i) for r in refs for i in range(10)}
    assert len(trials) == 10 * len(refs)
    scales = {
        robot_hardware("realistic", RPLIDAR_A2, Camera(), r.robot_seed).lidar_scale for r in refs
    }
    assert len(scales) == len(refs)  # one lidar unit per world, not per seed
    with pytest.raises(ConfigurationError, match="index"):
        refs[0].trial_seed(-1)


def test_sweep_json_is_identical_for_one_and_two_workers(tmp_path: Path) -> None:
    assert main([*SMALL, "--workers", "1", "--out", str(tmp_path / "w1")]) == 0
    assert main([*SMALL, "--workers", "2", "--out", str(tmp_path / "w2")]) == 0
    a = (tmp_path / "w1" / "bench_localization.json").read_bytes()
    b = (tmp_path / "w2" / "bench_localization.json").read_bytes()
    assert a == b
    doc = json.loads(a)
    assert doc["settings"]["world_seeds"] == [3, 4]
    assert len(doc["trials"]) == 2 * 2 * len(DEFAULT_METHODS)  # worlds x trials x methods
    # every finished world was saved as it finished, with the same trial rows
    lines = (tmp_path / "w2" / "bench_localization.partial.jsonl").read_text().splitlines()
    saved = sorted(
        json.dumps(t, sort_keys=True) for line in lines for t in json.loads(line)["trials"]
    )
    assert saved == sorted(json.dumps(t, sort_keys=True) for t in doc["trials"])
    assert {t["kind"] for t in doc["trials"]} == {"global", "kidnap"}
    rows = {(r["family"], r["method"]): r for r in doc["summary"]}
    assert rows[("square", "symloc")]["trials"] == 4
    assert rows[("all", "amcl")]["trials"] == 4
    for r in doc["summary"]:
        assert r["correct"] + r["confident_wrong"] + r["undetermined"] == r["trials"]
        lo, hi = r["confident_wrong_ci95"]
        assert 0.0 <= lo <= r["confident_wrong_rate"] <= hi <= 1.0
    assert "NaN" not in a.decode()  # standard JSON: null
    assert (tmp_path / "w1" / "bench_localization.png").stat().st_size > 10_000
    # the compact results file beside it: the summary and the run's provenance
    results = load_results(tmp_path / "w2" / "bench_localization.results.json")
    assert results["command"].startswith("symloc bench localization --families square")
    assert results["settings"] == doc["settings"]
    assert results["workers"] == 2
    assert results["machine"]["cpus"] >= 1
    assert set(results["load"]) >= {"load_1min_start", "load_1min_end"}
    assert len(results["figures"]["summary"]) == len(doc["summary"])


@pytest.mark.skipif(importlib.util.find_spec("ray") is None, reason="needs the [ray] extra")
def test_sweep_through_ray_local_gives_the_same_json(tmp_path: Path) -> None:
    assert main([*SMALL, "--workers", "1", "--out", str(tmp_path / "w1")]) == 0
    assert main([*SMALL, "--workers", "2", "--ray", "local", "--out", str(tmp_path / "ray")]) == 0
    a = (tmp_path / "w1" / "bench_localization.json").read_bytes()
    assert (tmp_path / "ray" / "bench_localization.json").read_bytes() == a


def test_sweep_keeps_task_order_and_rejects_bad_worker_counts() -> None:
    got: list[int] = []
    assert run_sweep(abs, [-3, 2, -1], workers=2, on_result=lambda i, _r: got.append(i)) == [
        3,
        2,
        1,
    ]
    assert sorted(got) == [0, 1, 2]
    with pytest.raises(ConfigurationError, match="workers"):
        run_sweep(abs, [1], workers=0)


def test_trial_grades_every_scan_and_both_methods_share_the_start(tmp_path: Path) -> None:
    room = build_world(WorldRef("builtin", "square", 0))
    scen = build_scenario(room, rng=0, workdir=tmp_path, map_source="raster")
    try:
        cfg = TrialConfig(claim_timeout=3.0, track_time=1.0, kidnap_after=1.0)
        res = run_trial(scen, TrialSpec("square#0", "square", 0, "kidnap", 7), cfg)
        again = run_trial(scen, TrialSpec("square#0", "square", 0, "kidnap", 7), cfg)
    finally:
        scen.close()
    assert res.start == again.start
    assert res.kidnap_to == again.kidnap_to
    assert set(res.results) == set(DEFAULT_METHODS)
    for m, r in res.results.items():
        assert r.grade == again.results[m].grade  # same seed, same trial
        # kidnapped after 1 s; then a claim (right or wrong) and 1 s of tracking, or 3 s
        assert r.grade.scans >= int(2.0 / 0.1)
        assert r.collisions == 0
    start = np.array(res.start)
    assert float(room.world.distance(start[None, :2])[0]) >= cfg.clearance


def _outcome(r: MethodResult) -> str:
    """Everything a method's run of a trial reports but its wall time, as text (NaN == NaN)."""
    d = dataclasses.asdict(r)
    d.pop("wall_time")
    return json.dumps(d, sort_keys=True)


def test_a_trial_is_the_same_whatever_ran_before_it_in_the_process(tmp_path: Path) -> None:
    """Each method's run of a trial follows its world and seed alone: plain AMCL alone, after
    another trial of every method, and beside symloc's methods gives the same run (the plain
    AMCL trials of a sweep depend neither on the trials a worker ran before nor on the other
    methods; the state shared across trials -- the scenario's map and its cached fields, the
    room's free-space cache, the kernels -- is read only)."""
    room = build_world(WorldRef("builtin", "square", 0))
    scen = build_scenario(room, rng=0, workdir=tmp_path, map_source="raster")
    cfg = TrialConfig(claim_timeout=3.0, track_time=1.0, kidnap_after=1.0)
    spec = TrialSpec("square#0", "square", 0, "kidnap", 11)
    other = TrialSpec("square#0", "square", 1, "global", 12)
    try:
        alone = run_trial(scen, spec, cfg, methods=("amcl",))
        run_trial(scen, other, cfg)  # every default method, another seed
        first = run_trial(scen, spec, cfg)
        run_trial(scen, other, cfg, methods=("amcl",))
        again = run_trial(scen, spec, cfg)
    finally:
        scen.close()
    assert _outcome(alone.results["amcl"]) == _outcome(first.results["amcl"])
    for method in DEFAULT_METHODS:
        assert _outcome(first.results[method]) == _outcome(again.results[method]), method


def test_start_poses_cover_the_room_near_walls_too(tmp_path: Path) -> None:
    room = build_world(WorldRef("builtin", "square", 0))
    scen = build_scenario(room, rng=0, workdir=tmp_path, map_source="raster")
    try:
        rng = np.random.default_rng(0)
        poses = np.array([sample_free_pose(scen, rng, 0.2) for _ in range(300)])
    finally:
        scen.close()
    d = room.world.distance(poses[:, :2])
    assert d.min() >= 0.2
    assert np.mean(d < 0.4) > 0.15  # a good share within 0.4 m of a wall
    assert room.contains(poses[:, :2]).all()


def test_summary_counts_per_family_and_all(tmp_path: Path) -> None:
    task = WorldTask(
        WorldRef("builtin", "square", 5),
        trials=1,
        kinds=("global",),
        map_source="raster",
        config=TrialConfig(claim_timeout=2.0, track_time=1.0),
        methods=("amcl",),
    )
    rows = trial_rows([run_world(task)])
    assert [r["method"] for r in rows] == ["amcl"]
    summary = summarize(rows)
    assert [(r["family"], r["method"], r["trials"]) for r in summary] == [
        ("square", "amcl", 1),
        ("all", "amcl", 1),
    ]


def test_world_files_run_and_bad_ones_name_the_key(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from importlib.resources import files

    example = str(files("symloc") / "data" / "worlds" / "square_with_box.yaml")
    args = ["bench", "localization", "--world", example, "--seeds", "2", "--trials", "1"]
    args += ["--kinds", "global", "--map", "raster", "--claim-timeout", "3", "--track-time", "1"]
    assert main([*args, "--workers", "1", "--out", str(tmp_path / "ok")]) == 0
    doc = json.loads((tmp_path / "ok" / "bench_localization.json").read_text())
    assert doc["summary"][0]["family"] == "file:square_with_box.yaml"
    assert doc["worlds"][0]["order"] == 1  # the box breaks the square's symmetry
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: x\nroom:\n  polygon: [[0, 0], [2, 2], [2, 0], [0, 2]]\n")
    assert main(["bench", "localization", "--world", str(bad), "--out", str(tmp_path)]) == 2
    assert "room.polygon" in capsys.readouterr().err
    bad.write_text("name: x\nroom:\n  circle: {radius: 2}\nfurnitures: []\n")
    assert main(["bench", "localization", "--world", str(bad), "--out", str(tmp_path)]) == 2
    assert "furnitures" in capsys.readouterr().err


def test_a_furnished_world_runs_a_trial_and_records_its_near_symmetry() -> None:
    from symloc.bench.localization import world_summary
    from symloc.sim.generator import generate_world

    task = WorldTask(
        WorldRef("generated", "furnished", 0),
        trials=1,
        kinds=("global",),
        map_source="raster",
        config=TrialConfig(claim_timeout=2.0, track_time=1.0),
    )
    w = run_world(task)
    assert w.family == "furnished"
    assert len(w.trials) == 1
    assert set(w.trials[0].results) == set(DEFAULT_METHODS)
    for r in w.trials[0].results.values():
        assert r.collisions == 0
    meta = generate_world("furnished", 0).meta
    assert w.metadata == meta
    assert w.order in (1, meta["base_order"])
    summary = json.loads(json.dumps(world_summary(w)))
    assert summary["metadata"]["overlap"] == meta["overlap"]


def test_keyframes_are_recorded_for_the_methods_that_decide_where_the_robot_stands() -> None:
    # symloc as shipped decides where it stands when its settings say so; centre never does
    assert needs_keyframes(("symloc", "amcl"), default_decide_here=True)
    assert not needs_keyframes(("symloc", "amcl"), default_decide_here=False)
    assert not needs_keyframes(("centre", "amcl"), default_decide_here=True)
    assert needs_keyframes(("decide",), default_decide_here=False)


def test_mapping_reach_is_zero_or_a_quarter_metre_at_least(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A reach below 0.25 m would leave a stop every few cells: refused by name, before any
    world is mapped; a negative one by argparse."""
    args = ["bench", "localization", "--families", "square", "--out", str(tmp_path)]
    assert main([*args, "--mapping-reach", "0.1"]) == 2
    assert "--mapping-reach" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main([*args, "--mapping-reach", "-1"])
    assert "--mapping-reach" in capsys.readouterr().err
