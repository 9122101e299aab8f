"""Keyframes along the mapping trip: storage (SQLite, schema 2 and version-1 files), the
selection rule, the bytes per square metre, and pose hypotheses verified on rendered images."""

from __future__ import annotations

import itertools
import math
import sqlite3
from functools import lru_cache
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from symloc.errors import ConfigurationError, DatabaseError
from symloc.geometry import wrap_angle
from symloc.sim.camera import Camera
from symloc.sim.rooms import Room, build_room
from symloc.vision.bow import BowVector
from symloc.vision.default_vocabulary import default_vocabulary
from symloc.vision.keyframes import Keyframe, KeyframeSelector, KeyframeSettings
from symloc.vision.orb import OrbExtractor, OrbFeatures
from symloc.vision.verification import (
    VerificationSettings,
    expected_counts,
    expected_keyframes,
    verify_hypotheses,
    verify_hypothesis,
)
from symloc.vision.visual_map import _SCHEMA_V1, SCHEMA_VERSION, VisualMap

SIDE_GV = 3.0 / math.sqrt(2.0)  # a 3 m square, as in the paper
TRIP_RADIUS = 0.7


def _random_keyframe(seed: int, n: int = 40, with_image: bool = False) -> Keyframe:
    rng = np.random.default_rng(seed)
    kp = np.column_stack([rng.uniform(0, 640, (n, 2)), rng.uniform(5, 30, (n, 4))]).astype(
        np.float32
    )
    kp[:, 5] = np.floor(kp[:, 5] % 8)
    feats = OrbFeatures.from_arrays(kp, rng.integers(0, 256, (n, 32), dtype=np.uint8), (640, 480))
    words = np.unique(rng.integers(0, 1000, 20)).astype(np.int32)
    vals = rng.random(words.size)
    img = rng.integers(0, 256, (24, 32, 3), dtype=np.uint8) if with_image else None
    pose = np.array([rng.uniform(-3, 3), rng.uniform(-3, 3), rng.uniform(-math.pi, math.pi)])
    return Keyframe(pose, feats, BowVector(words, vals / vals.sum()), stamp=seed * 0.5, image=img)


def _same(a: Keyframe, b: Keyframe) -> None:
    np.testing.assert_array_equal(a.pose, b.pose)
    np.testing.assert_array_equal(a.features.descriptors, b.features.descriptors)
    np.testing.assert_array_equal(a.features.points, b.features.points)
    np.testing.assert_array_equal(a.bow.words, b.bow.words)
    np.testing.assert_array_equal(a.bow.values, b.bow.values)
    assert a.features.image_size == b.features.image_size
    assert a.stamp == b.stamp


# ---------------------------------------------------------------------------- storage


def test_keyframes_round_trip(tmp_path: Path) -> None:
    path = tmp_path / "vm.sqlite"
    kfs = [_random_keyframe(i, with_image=i == 2) for i in range(5)]
    with VisualMap(path) as vm:
        assert vm.schema_version == SCHEMA_VERSION == 2
        ids = vm.add_keyframes(kfs[:3])
        ids += [vm.add_keyframe(kfs[3]), vm.add_keyframe(kfs[4])]
        assert ids == sorted(ids)
        assert len(set(ids)) == 5
    with VisualMap(path, readonly=True) as vm:
        assert vm.keyframe_count() == 5
        got_ids, poses = vm.keyframe_poses()
        assert got_ids.tolist() == ids
        np.testing.assert_array_equal(poses, np.array([k.pose for k in kfs]))
        for kid, ref, got in zip(ids, kfs, vm.keyframes(), strict=True):
            _same(ref, got)
            assert got.keyframe_id == kid
            assert got.image is None
        with_img = vm.keyframe(ids[2], with_image=True)
        np.testing.assert_array_equal(with_img.image, kfs[2].image)
        best = vm.query_keyframes(kfs[1].bow)
        assert best[0] == (ids[1], pytest.approx(1.0))
        assert [k for k, _ in vm.query_keyframes(kfs[1].bow, ids=[ids[3], ids[4]])] in (
            [ids[3], ids[4]],
            [ids[4], ids[3]],
        )
        assert vm.keyframe_bytes() > 5 * 40 * (24 + 32)
        with pytest.raises(DatabaseError, match="no keyframe with id 999"):
            vm.keyframe(999)
        assert vm.integrity_check() == "ok"
    with VisualMap(path) as vm:
        vm.delete_keyframes([ids[0]])
        assert vm.keyframe_count() == 4
        vm.delete_keyframes()
        assert vm.keyframe_count() == 0
        assert vm.query_keyframes(kfs[0].bow) == []


def test_keyframes_written_all_or_none(tmp_path: Path) -> None:
    with VisualMap(tmp_path / "vm.sqlite") as vm:
        with pytest.raises(ConfigurationError, match=r"keyframes\[1\]: expected a Keyframe"):
            vm.add_keyframes([_random_keyframe(0), "not a keyframe"])  # type: ignore[list-item]
        assert vm.keyframe_count() == 0
        # a failure inside the transaction (a duplicate id forced by a trigger) rolls back
        vm._con.execute(
            "CREATE TRIGGER boom BEFORE INSERT ON keyframes WHEN NEW.stamp > 1 "
            "BEGIN SELECT RAISE(ABORT, 'boom'); END"
        )
        with pytest.raises(DatabaseError, match="boom"):
            vm.add_keyframes([_random_keyframe(0), _random_keyframe(1), _random_keyframe(3)])
        assert vm.keyframe_count() == 0


def _version1_file(path: Path) -> None:
    """A visual map as symloc wrote it before keyframes (schema version 1), with one place."""
    con = sqlite3.connect(path)
    con.executescript(_SCHEMA_V1)
    con.execute("PRAGMA application_id = 1398361420")
    con.execute("PRAGMA user_version = 1")
    con.execute("INSERT INTO meta VALUES ('created_by', 'symloc')")
    con.execute("INSERT INTO places VALUES (1, 'square', 4, 2.12, 0.5, -0.5, 0.25, 1, NULL, 0.0)")
    kf = _random_keyframe(7)
    con.execute(
        "INSERT INTO images VALUES (1, 0, 0.25, 640, 480, ?, ?, ?, ?, ?, NULL)",
        (
            len(kf.features),
            kf.bow.words.astype("<i4").tobytes(),
            kf.bow.values.astype("<f8").tobytes(),
            kf.features.keypoint_array().astype("<f4").tobytes(),
            kf.features.descriptors.tobytes(),
        ),
    )
    con.commit()
    con.close()


def test_version_1_file_is_read_and_migrated(tmp_path: Path) -> None:
    path = tmp_path / "v1.sqlite"
    _version1_file(path)
    # opened for reading: nothing is written, no keyframes, writes refused
    for kw in ({"readonly": True}, {"create": False}):
        with VisualMap(path, **kw) as vm:  # type: ignore[arg-type]
            assert vm.schema_version == 1
            assert vm.keyframe_count() == 0
            assert vm.keyframes() == []
            assert vm.keyframe_poses()[1].shape == (0, 3)
            assert vm.place(1).center.tolist() == [0.5, -0.5]
            with pytest.raises(DatabaseError, match="has no keyframes table; open the map"):
                vm.add_keyframe(_random_keyframe(1))
    assert sqlite3.connect(path).execute("PRAGMA user_version").fetchone()[0] == 1
    # opened to write: migrated in place, the place kept, keyframes stored
    with VisualMap(path) as vm:
        assert vm.schema_version == 2
        assert vm.get_meta("migrated_from") == "1"
        assert len(vm) == 1
        assert vm.place(1).m == 1
        vm.add_keyframe(_random_keyframe(1))
    with VisualMap(path, readonly=True) as vm:
        assert vm.schema_version == 2
        assert vm.keyframe_count() == 1
        assert vm.integrity_check() == "ok"


def test_damaged_keyframe_record_is_reported(tmp_path: Path) -> None:
    path = tmp_path / "vm.sqlite"
    with VisualMap(path) as vm:
        kid = vm.add_keyframe(_random_keyframe(0))
        vm._con.execute("UPDATE keyframes SET descriptors = x'00' WHERE id = ?", (kid,))
        with pytest.raises(DatabaseError, match=r"keyframe 1: keyframes.descriptors: 1 bytes"):
            vm.keyframes()
    con = sqlite3.connect(path)
    con.execute("ALTER TABLE keyframes RENAME COLUMN stamp TO when_")
    con.commit()
    con.close()
    with pytest.raises(DatabaseError, match=r"column keyframes.stamp is missing"):
        VisualMap(path)


# ---------------------------------------------------------------------------- selection rule


def test_selection_rule() -> None:
    sel = KeyframeSelector(KeyframeSettings(min_translation=0.5, min_rotation=math.radians(20)))
    assert sel.consider([0, 0, 0]).reason == "first keyframe"
    sel.accept([0, 0, 0])
    assert not sel.pose_due([0.4, 0.0, math.radians(15)])
    assert not sel.consider([0.4, 0.0, math.radians(15)]).keep
    d = sel.consider([0.51, 0.0, 0.0])
    assert d.keep
    assert d.reason.startswith("moved 0.51 m")
    d = sel.consider([0.0, 0.0, math.radians(-25)])
    assert d.keep
    assert d.reason.startswith("turned 25.0 deg")
    # a turn across +-pi is a small turn
    sel.accept([0, 0, math.pi - 0.05])
    assert not sel.pose_due([0, 0, -math.pi + 0.05])
    # too little texture is never kept
    d = KeyframeSelector().consider([0, 0, 0], OrbFeatures.empty((640, 480)))
    assert not d.keep
    assert "too little texture" in d.reason


def test_selection_rule_covisibility() -> None:
    room = build_room("square", SIDE_GV, lab=False, textured=True)
    cam, ex = Camera(), OrbExtractor()
    sel = KeyframeSelector(KeyframeSettings(min_rotation=math.radians(60), min_covisibility=0.25))
    first = ex.extract(cam.render(room.world, [0, 0, 0], 0))
    sel.accept([0, 0, 0], first)
    same = sel.consider([0, 0, 0.02], ex.extract(cam.render(room.world, [0, 0, 0.02], 1)))
    assert not same.keep
    assert same.covisibility > 0.25
    # a turn of 50 deg (below min_rotation) leaves less than a quarter of the view in common
    far = sel.consider([0, 0, 0.87], ex.extract(cam.render(room.world, [0, 0, 0.87], 2)))
    assert far.keep, far
    assert far.reason.startswith("covisibility"), far


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("min_translation", 0.0),
        ("min_rotation", 4.0),
        ("min_covisibility", 1.0),
        ("min_features", -1),
        ("lowe_ratio", 1.0),
    ],
)
def test_selection_settings_are_validated(field: str, value: float) -> None:
    with pytest.raises(ConfigurationError, match=rf"KeyframeSettings\.{field}"):
        KeyframeSettings(**{field: value})  # type: ignore[arg-type]


@settings(max_examples=50, deadline=None)
@given(
    st.lists(
        st.tuples(st.floats(-0.3, 0.3), st.floats(-0.3, 0.3), st.floats(-0.4, 0.4)),
        min_size=1,
        max_size=40,
    )
)
def test_selection_rule_property(steps: list[tuple[float, float, float]]) -> None:
    """Every frame not kept lies within the thresholds of the last keyframe; every kept one
    (after the first) beyond one of them."""
    s = KeyframeSettings()
    sel = KeyframeSelector(s)
    pose = np.zeros(3)
    for dx, dy, dth in steps:
        pose = np.array([pose[0] + dx, pose[1] + dy, float(wrap_angle(pose[2] + dth))])
        last = sel.last_pose
        d = sel.consider(pose)
        assert d.keep == sel.pose_due(pose)
        if last is None:
            assert d.keep
        else:
            moved = math.hypot(*(pose[:2] - last[:2]))
            turned = abs(float(wrap_angle(pose[2] - last[2])))
            assert d.keep == (moved > s.min_translation or turned > s.min_rotation)
        if d.keep:
            sel.accept(pose)


# ---------------------------------------------------------------------------- rendered trip


@lru_cache(maxsize=2)
def _trip(textured: bool) -> tuple[Room, tuple[Keyframe, ...]]:
    """Keyframes of a drive around the centre of a 3 m square (radius 0.7 m, facing along the
    path), chosen by the default selection rule."""
    room = build_room("square", SIDE_GV, lab=False, textured=textured)
    cam, ex, voc = Camera(), OrbExtractor(), default_vocabulary()
    sel = KeyframeSelector()
    kfs: list[Keyframe] = []
    for i, a in enumerate(np.linspace(0.0, 2.0 * math.pi, 181)[:-1]):
        pose = np.array(
            [TRIP_RADIUS * math.cos(a), TRIP_RADIUS * math.sin(a), wrap_angle(a + math.pi / 2)]
        )
        if not sel.pose_due(pose):
            continue
        feats = ex.extract(cam.render(room.world, pose, i))
        if sel.consider(pose, feats).keep:
            sel.accept(pose, feats)
            kfs.append(Keyframe(pose, feats, voc.bow(feats.descriptors), stamp=float(i)))
    return room, tuple(kfs)


def test_bytes_per_square_metre(tmp_path: Path) -> None:
    room, kfs = _trip(True)
    assert 12 <= len(kfs) <= 24
    path = tmp_path / "vm.sqlite"
    with VisualMap(path) as vm:
        vm.add_keyframes(kfs)
        vm.checkpoint()
        records = vm.keyframe_bytes()
    empty = tmp_path / "empty.sqlite"
    with VisualMap(empty) as vm:
        vm.checkpoint()
    file_bytes = path.stat().st_size - empty.stat().st_size
    per_m2 = file_bytes / room.area
    print(
        f"{len(kfs)} keyframes, {records / len(kfs) / 1024:.1f} KiB each, "
        f"{file_bytes / 1024:.0f} KiB on disk for {room.area:.1f} m2: {per_m2 / 1024:.1f} KiB/m2"
    )
    assert records <= file_bytes
    assert per_m2 < 100 * 1024  # under 100 KiB per square metre of floor


def _copies(truth: np.ndarray, k: int = 4) -> np.ndarray:
    out = []
    for j in range(k):
        c, s = math.cos(2 * math.pi * j / k), math.sin(2 * math.pi * j / k)
        out.append(
            [
                c * truth[0] - s * truth[1],
                s * truth[0] + c * truth[1],
                wrap_angle(truth[2] + 2 * math.pi * j / k),
            ]
        )
    return np.array(out)


def _truths(n: int, seed: int) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        a = rng.uniform(-math.pi, math.pi)
        r = TRIP_RADIUS + rng.uniform(-0.15, 0.15)
        th = a + math.pi / 2 + rng.uniform(-0.2, 0.2)
        out.append(np.array([r * math.cos(a), r * math.sin(a), float(wrap_angle(th))]))
    return out


def test_symmetric_copies_only_the_true_one_verified(tmp_path: Path) -> None:
    room, kfs = _trip(True)
    cam, voc = Camera(), default_vocabulary()
    with VisualMap(tmp_path / "vm.sqlite") as vm:
        vm.add_keyframes(kfs)
        tally = {"correct": 0, "none": 0, "wrong": 0}
        for t, truth in enumerate(_truths(6, 3)):
            image = cam.render(room.world, truth, 1000 + t)
            # the true pose is not always hypothesis 1
            order = np.roll(np.arange(4), t)
            hyps = _copies(truth)[order]
            dec = verify_hypotheses(hyps, image, vm, voc, cam.calibration)
            true_index = int(np.flatnonzero(order == 0)[0])
            tally[
                "correct" if dec.index == true_index else "none" if dec.index is None else "wrong"
            ] += 1
            assert dec.counts["verified"] == 1, [c.reason for c in dec.checks]
            check = dec.checks[true_index]
            assert check.verified
            assert check.inliers >= 25
            assert check.keyframe_id is not None
            assert abs(check.heading_offset) < math.radians(4.0), check.reason
            assert all(
                c.status == "contradicted" for i, c in enumerate(dec.checks) if i != true_index
            )
            assert dec.pose is not None
            assert abs(float(wrap_angle(dec.pose[2] - truth[2]))) < math.radians(4.0)
        print(tally)
        assert tally == {"correct": 6, "none": 0, "wrong": 0}


def test_pose_30cm_10deg_off_is_still_verified() -> None:
    room, kfs = _trip(True)
    cam, voc = Camera(), default_vocabulary()
    rng = np.random.default_rng(5)
    for t, truth in enumerate(_truths(5, 11)):
        image = cam.render(room.world, truth, 2000 + t)
        a = rng.uniform(-math.pi, math.pi)
        sign = 1.0 if t % 2 else -1.0
        hyp = truth + np.array([0.3 * math.cos(a), 0.3 * math.sin(a), sign * math.radians(10.0)])
        check = verify_hypothesis(hyp, image, kfs, voc, cam.calibration)
        assert check.verified, check.reason
        # the camera measures the 10 degrees the hypothesis is off
        assert abs(check.heading_offset + sign * math.radians(10.0)) < math.radians(4.0), (
            check.reason
        )


def test_wrong_heading_is_contradicted() -> None:
    """Same place, heading 45 degrees off: the keyframes facing that way are seen, but not
    where the hypothesis says."""
    room, kfs = _trip(True)
    cam, voc = Camera(), default_vocabulary()
    truth = _truths(1, 17)[0]
    image = cam.render(room.world, truth, 7)
    wrong = truth + np.array([0.0, 0.0, math.radians(30.0)])
    check = verify_hypothesis(
        wrong, image, kfs, voc, cam.calibration, VerificationSettings(max_heading_difference=1.0)
    )
    assert check.status == "contradicted", check.reason


def test_untextured_room_verifies_nothing() -> None:
    room, kfs = _trip(False)
    assert kfs == ()  # the selection rule keeps no untextured view
    _textured_room, textured_kfs = _trip(True)
    cam, voc = Camera(), default_vocabulary()
    for t, truth in enumerate(_truths(3, 23)):
        image = cam.render(room.world, truth, 3000 + t)
        for keyframes in (kfs, textured_kfs):
            dec = verify_hypotheses(_copies(truth), image, keyframes, voc, cam.calibration)
            assert dec.index is None
            assert all(c.status == "unknown" for c in dec.checks), [c.reason for c in dec.checks]
    # untextured keyframes forced into the map: still unknown, never a wrong pose
    plain = build_room("square", SIDE_GV, lab=False, textured=False)
    ex = OrbExtractor()
    forced = []
    for i, truth in enumerate(_truths(4, 29)):
        f = ex.extract(cam.render(plain.world, truth, i))
        forced.append(Keyframe(truth, f, voc.bow(f.descriptors), keyframe_id=i))
    query = cam.render(plain.world, forced[0].pose, 99)
    loose = VerificationSettings(min_keypoints=1)
    dec = verify_hypotheses(_copies(forced[0].pose), query, forced, voc, cam.calibration, loose)
    assert dec.index is None
    assert dec.counts["verified"] == 0


def test_no_keyframe_nearby_is_unknown() -> None:
    room, kfs = _trip(True)
    cam, voc = Camera(), default_vocabulary()
    truth = np.array([0.0, 0.0, 0.3])  # the centre: 0.7 m from the trip, facing across it
    image = cam.render(room.world, truth, 1)
    check = verify_hypothesis(
        truth, image, kfs, voc, cam.calibration, VerificationSettings(max_distance=0.3)
    )
    assert check.status == "unknown"
    assert "no keyframe within 0.3 m" in check.reason


@settings(max_examples=60, deadline=None)
@given(
    st.floats(-3, 3),
    st.floats(-3, 3),
    st.floats(-math.pi, math.pi),
    st.floats(0.1, 2.0),
    st.floats(0.1, math.pi),
)
def test_expected_keyframes_property(
    x: float, y: float, th: float, max_d: float, max_dth: float
) -> None:
    rng = np.random.default_rng(0)
    poses = np.column_stack(
        [rng.uniform(-3, 3, 200), rng.uniform(-3, 3, 200), rng.uniform(-math.pi, math.pi, 200)]
    )
    ids = np.arange(200) * 3 + 1
    s = VerificationSettings(max_distance=max_d, max_heading_difference=max_dth)
    got = expected_keyframes([x, y, th], ids, poses, s)
    d = np.hypot(poses[:, 0] - x, poses[:, 1] - y)
    dth = np.abs(np.asarray(wrap_angle(poses[:, 2] - th)))
    want = set(ids[(d <= max_d) & (dth <= max_dth)].tolist())
    assert set(got.tolist()) == want
    assert len(got) == len(want)
    cost = {int(i): d[k] / max_d + dth[k] / max_dth for k, i in enumerate(ids)}
    assert all(cost[int(a)] <= cost[int(b)] for a, b in itertools.pairwise(got))


def test_verification_settings_and_inputs_are_validated() -> None:
    with pytest.raises(ConfigurationError, match=r"VerificationSettings\.min_inliers"):
        VerificationSettings(min_inliers=3)
    with pytest.raises(ConfigurationError, match=r"VerificationSettings\.heading_tolerance"):
        VerificationSettings(heading_tolerance=0.0)
    with pytest.raises(ConfigurationError, match=r"VerificationSettings\.margin"):
        VerificationSettings(margin=0.5)
    voc = default_vocabulary()
    with pytest.raises(ConfigurationError, match=r"poses: expected an \(N, 3\) array"):
        verify_hypotheses(np.zeros((2, 2)), OrbFeatures.empty(), [], voc, Camera().calibration)


def test_cli_lists_keyframes(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from symloc.cli.main import main

    path = tmp_path / "vm.sqlite"
    with VisualMap(path) as vm:
        vm.add_keyframes([_random_keyframe(i) for i in range(3)])
    assert main(["places", "keyframes", "--db", str(path)]) == 0
    out = capsys.readouterr().out
    assert "schema version 2, 3 keyframe(s)" in out
    assert len([ln for ln in out.splitlines() if ln.strip().startswith(("1 ", "2 ", "3 "))]) == 3


def test_expected_counts_are_the_lengths_of_the_expected_keyframes() -> None:
    rng = np.random.default_rng(3)
    kf = np.column_stack([rng.uniform(-3, 3, (60, 2)), rng.uniform(-math.pi, math.pi, 60)])
    poses = np.column_stack([rng.uniform(-3, 3, (40, 2)), rng.uniform(-math.pi, math.pi, 40)])
    s = VerificationSettings(max_distance=1.5)
    counts = expected_counts(poses, kf, s)
    lengths = [len(expected_keyframes(p, np.arange(60), kf, s)) for p in poses]
    assert counts.tolist() == lengths
    assert max(lengths) > 0
    assert expected_counts(poses, np.zeros((0, 3)), s).tolist() == [0] * 40


def test_a_store_reaches_further_for_hypotheses_sampled_along_a_line(tmp_path: Path) -> None:
    from dataclasses import replace

    from symloc.localizer.vision_store import VisionPlaceStore

    kf = replace(_random_keyframe(0), pose=np.array([1.3, 0.0, 0.0]))
    with VisualMap(tmp_path / "vm.sqlite") as vm:
        vm.add_keyframes([kf])
        store = VisionPlaceStore(vm, vocabulary=None, intrinsics=np.eye(3))
        here = np.zeros((1, 3))
        assert store.verification.max_distance == 1.0
        assert store.expected_counts(here).tolist() == [0]  # 1.3 m away: beyond 1 m
        assert store.expected_counts(here, reach=0.5).tolist() == [1]
        assert store.verification.max_distance == 1.0  # the store's own settings unchanged
        with pytest.raises(ConfigurationError, match="reach"):
            store.expected_counts(here, reach=-0.1)
