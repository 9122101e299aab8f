"""``symloc places``: the SQLite visual map of symmetric places built from your own photos:
add a place (M photos taken at its centre, clockwise), list, decide a query's direction, remove."""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

from symloc.cli import options

__all__ = ["register"]


def register(subparsers: Any) -> None:
    """Add ``places`` with ``add``, ``list``, ``decide`` and ``remove``."""
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "places",
        help="visual map of symmetric places (SQLite): add, list, keyframes, align-keyframes, "
        "decide, remove",
    )
    sub = parser.add_subparsers(dest="places_command", metavar="ACTION")
    sub.required = True

    a = sub.add_parser(
        "add",
        help="store a place from M photos taken at its centre, in clockwise order",
        description="Photo j (j = 1..M) looks along heading - (j - 1) * 360/M degrees (clockwise"
        " order, as the paper stores them). Creates the database when it does not exist.",
    )
    a.add_argument(
        "--db", type=options.output_file, required=True, help="visual map database (SQLite)"
    )
    a.add_argument(
        "--images",
        type=Path,
        nargs="+",
        required=True,
        metavar="IMG",
        help="the M photos, direction 1 first, clockwise",
    )
    a.add_argument("--kind", default="polygon", help="room kind (square, polygon, circle, ...)")
    a.add_argument(
        "--order", type=options.symmetry_order, required=True, help="symmetry order of the room"
    )
    a.add_argument("--gv", type=options.nonnegative_float, required=True, help="G-V distance [m]")
    a.add_argument(
        "--pose",
        type=options.finite_float,
        nargs=3,
        default=(0.0, 0.0, 0.0),
        metavar=("X", "Y", "THETA_DEG"),
        help="map pose of the centre [m, m, deg]; THETA is the heading of direction 1",
    )
    a.add_argument("--label", default=None, help="a name for the place")
    a.add_argument("--vocabulary", type=Path, default=None, help="default: the shipped one")
    a.add_argument("--keep-images", action="store_true", help="also store the pixels (PNG)")
    a.set_defaults(func=_add)

    ls = sub.add_parser("list", help="list the stored places")
    ls.add_argument("--db", type=Path, required=True, help="visual map database (read only)")
    ls.set_defaults(func=_list)

    d = sub.add_parser(
        "decide",
        help="which stored direction does a photo taken at the place's centre face?",
        description="Scores the query against the place's M photos (BoW), requires the best to "
        "beat the second clearly, verifies it with a RANSAC homography and reads the residual "
        "heading offset from it. Exit code 0 when decided, 3 when undetermined or refused.",
    )
    d.add_argument("--db", type=Path, required=True, help="visual map database (read only)")
    d.add_argument(
        "--place", type=options.positive_int, required=True, help="place id (see 'places list')"
    )
    d.add_argument("--query", type=Path, required=True, help="query photo")
    _add_camera(d)
    d.add_argument(
        "--vocabulary",
        type=Path,
        default=None,
        help="the vocabulary the map was made with (default: the shipped one; another is refused)",
    )
    d.set_defaults(func=_decide)

    k = sub.add_parser(
        "keyframes",
        help="list the keyframes recorded along the mapping trip (map pose, features, size)",
    )
    k.add_argument("--db", type=Path, required=True, help="visual map database (read only)")
    k.set_defaults(func=_keyframes)

    al = sub.add_parser(
        "align-keyframes",
        help="make the keyframes' headings agree with their images (rotation averaging)",
        description="Measures the relative heading of overlapping keyframes from their images "
        "(homography / essential matrix) and solves for headings that agree with them, the "
        "stored (SLAM) headings a weak prior; rewrites the headings in one transaction "
        "(positions unchanged). Exit code 0.",
    )
    al.add_argument(
        "--db", type=Path, required=True, help="visual map database (its headings are rewritten)"
    )
    _add_camera(al)
    al.add_argument(
        "--distortion",
        type=options.finite_float,
        nargs="+",
        default=None,
        metavar="K",
        help="lens distortion k1 k2 p1 p2 [k3] (OpenCV; default: none)",
    )
    options.add_angle(
        al,
        "--measurement-sigma",
        default=0.5,
        help="standard deviation added to each measured relative heading (smaller: trust the "
        "images more)",
    )
    options.add_angle(
        al,
        "--chain-sigma",
        default=0.1,
        help="standard deviation of the stored relative heading of consecutive keyframes",
    )
    al.add_argument(
        "--dry-run", action="store_true", help="measure and report; the map is not written"
    )
    al.set_defaults(func=_align_keyframes)

    r = sub.add_parser("remove", help="remove a place and its images")
    r.add_argument("--db", type=Path, required=True, help="visual map database")
    r.add_argument("--place", type=options.positive_int, required=True, help="place id")
    r.set_defaults(func=_remove)


def _open(db: Path, *, create: bool = False, readonly: bool = False) -> Any:
    from symloc.vision.visual_map import VisualMap

    return VisualMap(db, create=create, readonly=readonly)


def _vocabulary(path: Path | None, vmap: Any, *, option: str = "--vocabulary") -> tuple[Any, str]:
    """The vocabulary to use with ``vmap`` and its identity to store (``"default"`` or its
    fingerprint). The map's record says which vocabulary made its BoW vectors; another one is
    refused. A path is never read from the database (a crafted one could point anywhere)."""
    from symloc.errors import ConfigurationError
    from symloc.vision.default_vocabulary import default_vocabulary
    from symloc.vision.vocabulary import Vocabulary

    stored = vmap.get_meta("vocabulary")
    voc = default_vocabulary() if path is None else Vocabulary.load(path)
    name = "the shipped vocabulary" if path is None else str(path)
    ident = voc.fingerprint()
    if stored is None:
        return voc, "default" if path is None else ident
    if stored == "default":
        want = default_vocabulary().fingerprint()
    elif stored.startswith("sha256:"):
        want = stored
    else:  # maps written before fingerprints: the vocabulary file's path
        if path is None:
            raise ConfigurationError(
                f"{option}: this map's BoW vectors were made with {stored}; give that file"
                f" (symloc never opens a path stored in the database)"
            )
        if Path(stored).resolve() != path.resolve():
            raise ConfigurationError(
                f"{option}: this map's BoW vectors were made with {stored}, not {path}"
            )
        return voc, stored
    if ident != want:
        made = "the shipped vocabulary" if stored == "default" else f"vocabulary {want[:19]}..."
        hint = "" if path is not None else " (give it with --vocabulary)"
        raise ConfigurationError(
            f"{option}: this map's BoW vectors were made with {made}, not {name}"
            f" ({ident[:19]}...){hint}; scores against another vocabulary mean nothing"
        )
    return voc, "default" if stored == "default" else ident


def _add(args: argparse.Namespace) -> int:
    from symloc.errors import ConfigurationError
    from symloc.vision.image_files import place_images_from_files

    if args.order >= 1 and len(args.images) % args.order:
        raise ConfigurationError(
            f"--images: {len(args.images)} photos for a room of symmetry order {args.order}; "
            "expected a multiple of the order"
        )
    with _open(args.db, create=True) as vmap:
        voc, voc_id = _vocabulary(args.vocabulary, vmap)
        stored = vmap.get_meta("vocabulary")
        images = place_images_from_files(
            args.images,
            voc,
            heading0=math.radians(args.pose[2]),
            keep_images=args.keep_images,
        )
        x, y, th = args.pose
        pid = vmap.add_place(
            kind=args.kind,
            order=args.order,
            gv_distance=args.gv,
            pose=(x, y, math.radians(th)),
            images=images,
            label=args.label,
        )
        if stored is None:
            vmap.set_meta("vocabulary", voc_id)
            vmap.set_meta(
                "vocabulary_file", "shipped" if args.vocabulary is None else str(args.vocabulary)
            )
    counts = ", ".join(str(len(im.features)) for im in images)
    print(f"added place {pid} to {args.db}: {args.kind}, order {args.order}, G-V {args.gv} m")
    print(f"  {len(images)} directions (ORB keypoints: {counts})")
    return 0


def _list(args: argparse.Namespace) -> int:
    with _open(args.db, readonly=True) as vmap:
        ids = vmap.place_ids()
        voc = vmap.get_meta("vocabulary")
        made = vmap.get_meta("vocabulary_file") or voc
        print(f"{args.db}: {len(ids)} place(s), vocabulary {made} ({voc})")
        if ids:
            print(f"{'id':>4}  {'kind':<10}{'order':>6}{'G-V [m]':>9}{'M':>3}  pose (x, y, deg)")
        for pid in ids:
            p = vmap.place(pid, with_images=False)
            print(
                f"{p.place_id:>4}  {p.kind:<10}{p.order!s:>6}{p.gv_distance:>9.3f}{p.m:>3}  "
                f"({p.center[0]:.2f}, {p.center[1]:.2f}, {math.degrees(p.heading0):.1f})"
                + (f"  {p.label}" if p.label else "")
            )
    return 0


def _keyframes(args: argparse.Namespace) -> int:
    with _open(args.db, readonly=True) as vmap:
        kfs = vmap.keyframes()
        size = vmap.keyframe_bytes()
        print(
            f"{args.db}: schema version {vmap.schema_version}, {len(kfs)} keyframe(s), "
            f"{size / 1024:.0f} KiB"
        )
        if kfs:
            print(f"{'id':>5}  {'time [s]':>9}  {'features':>8}  {'words':>6}  pose (x, y, deg)")
        for kf in kfs:
            x, y, th = kf.pose
            print(
                f"{kf.keyframe_id:>5}  {kf.stamp:>9.2f}  {len(kf.features):>8}  "
                f"{len(kf.bow):>6}  ({x:.2f}, {y:.2f}, {math.degrees(th):.1f})"
            )
    return 0


def _add_camera(parser: argparse.ArgumentParser) -> None:
    """The camera of a command: ``--hfov`` or ``--intrinsics``, one of them."""
    cam = parser.add_mutually_exclusive_group(required=True)
    cam.add_argument(
        "--hfov", type=options.field_of_view, help="horizontal field of view [degrees]"
    )
    cam.add_argument(
        "--intrinsics",
        type=options.finite_float,
        nargs=4,
        metavar=("FX", "FY", "CX", "CY"),
        help="camera intrinsics [px]",
    )


def _camera_matrix(args: argparse.Namespace, image_size: Callable[[], tuple[int, int]]) -> Any:
    """K (3, 3) from ``--intrinsics``, or from ``--hfov`` and ``image_size()`` (width, height
    [px]; asked only then)."""
    from symloc.vision.image_files import intrinsics_from_fov, intrinsics_from_values

    if args.hfov is not None:
        w, h = image_size()
        return intrinsics_from_fov(args.hfov, w, h)
    return intrinsics_from_values(*args.intrinsics)


def _align_keyframes(args: argparse.Namespace) -> int:
    import numpy as np

    from symloc.vision.rotation_averaging import HeadingAlignmentSettings, align_map_keyframes

    with _open(args.db, readonly=args.dry_run) as vmap:
        n = vmap.keyframe_count()
        if n == 0:
            print(f"{args.db}: no keyframes; nothing to align")
            return 0
        K = _camera_matrix(
            args, lambda: vmap.keyframe(int(vmap.keyframe_poses()[0][0])).features.image_size
        )
        settings = HeadingAlignmentSettings(
            measurement_sigma=args.measurement_sigma, chain_sigma=args.chain_sigma
        )
        res = align_map_keyframes(
            vmap, K, settings, dist_coeffs=args.distortion, write=not args.dry_run
        )
    corr = np.degrees(res.corrections)
    print(f"{args.db}: {n} keyframe(s)")
    print(res.summary())
    if corr.size:
        print(f"heading change [deg]: min {corr.min():+.2f}, max {corr.max():+.2f}")
    print("dry run: nothing written" if args.dry_run else "headings rewritten (one transaction)")
    return 0


def _decide(args: argparse.Namespace) -> int:
    from symloc.vision.image_files import check_photo_size, read_image
    from symloc.vision.orb import OrbExtractor
    from symloc.vision.orientation import decide_orientation

    with _open(args.db, readonly=True) as vmap:
        place = vmap.place(args.place, with_images=False)
        voc, _ = _vocabulary(args.vocabulary, vmap)
    query = read_image(args.query)
    check_photo_size(query, args.query, OrbExtractor())
    h, w = query.shape[:2]
    K = _camera_matrix(args, lambda: (w, h))
    d = decide_orientation(query, place, voc, K)
    scores = ", ".join(f"{s:.3f}" for s in d.scores)
    print(f"place {place.place_id} ({place.kind}, M={place.m}), query {args.query}")
    print(f"status:         {d.status}")
    if d.decided:
        print(f"direction:      {options.direction_text(d.direction or 0, place.m)}")
        print(f"heading offset: {math.degrees(d.heading_offset):+.2f} deg (CCW positive)")
        print(f"heading:        {math.degrees(d.heading):.2f} deg (map)")
    print(f"scores:         [{scores}]")
    print(f"inliers:        {d.inliers} (second direction {d.second_inliers})")
    print(f"keypoints:      {d.n_keypoints}")
    print(f"reason:         {d.reason}")
    if not d.decided:
        print(f"advice:         turn clockwise by {360.0 / place.m:g} deg and try again")
    return 0 if d.decided else 3


def _remove(args: argparse.Namespace) -> int:
    with _open(args.db) as vmap:
        vmap.place(args.place, with_images=False)  # raises DatabaseError for a bad id
        vmap.delete_place(args.place)
        print(f"removed place {args.place} from {args.db} ({len(vmap)} left)")
    return 0
