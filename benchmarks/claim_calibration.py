"""How honest is the claim gate's covariance? Every claim it judges, against the truth.

Runs symloc's trials on bench worlds (realistic sensors, the bench's mapping trip) and records,
for every scan the claim gate judges (:meth:`symloc.localizer.claim.ClaimGate._judge`, wrapped
here, evaluation only), the claim's pose and covariance, the scan match's covariance and the
map's error terms, with the robot's true pose in the map frame. Then, over the judged claims
near the truth (within 0.5 m and 15 deg: the copy check, not the covariance, handles the rest)
that reached the gate's precision test, per world:

- the lidar's scale error fitted from the errors (``e_xy = s (p - c)``, ``c`` the gate's scale
  centre) and removed, and the position error along the match's widest axis (map terms and
  floors left out) in units of its std (``z``), and the heading's (``z_theta``): 1 is honest,
  below 1 the match's covariance is wider than its errors;
- for the match's information times ``k`` (the published covariance rebuilt as the gate
  builds it: match / k + map error, floored), the share of errors inside the 95 % ellipse, the
  share of claims that would pass the gate's precision test and how many of those are outside
  the tolerance.

Each judged claim also records the whole scan's fit along its widest covariance axis
(``axis_profile``), and a last table gives the claim gate's best-fit check
(:mod:`symloc.localizer.best_fit`) on the claims published within 5 cm of the truth: how many
it would withhold as they are (false alarms) and displaced 5-20 cm along that axis (its power).

Each judged claim also records the whole scan's fit with the scan turned about the robot
(``turn_fit``, -14 to +14 deg), and a third table gives the gate's turn check (the heading
part of the best-fit check) on the claims within 5 cm / 1.5 deg of the truth: false alarms as
they are, power turned 2-6 deg either way.

``--walls STD TILT_DEG``: the claim gate's matcher counts the walls' shared error
(:class:`symloc.mcl.scan_to_map.ScanMatchConfig` ``wall_std``, ``wall_tilt_std``; its module
docstring has the results), so that its calibration can be compared with
``information_scale``'s on the same trials.

``--profile D``: for every judged claim more than ``D`` metres from the truth with the heading
within 0.1 rad, log the whole scan's fit to the map (mean squared distance of every beam's end,
clipped at 0.3 m) at offsets along the error's direction from the truth, at the claim, and
where a prior-free alignment from the claim ends: whether the claim is the scan's best fit.

With it ``ScanMatchConfig.information_scale`` 0.3 was chosen on dev and undone on the test split
(see its module docstring): a calibration on these claims does not see every error the
gate's margin covers. Tune on dev only.

    python benchmarks/claim_calibration.py --out claims.jsonl \\
        corridor_short:0:0-9 corridor_short:1:0-9 regular:0:0-4 u_shape:1:0-4

(``FAMILY:WORLD_SEED:TRIALS``, trials ``a-b`` or ``a,b,c``; the dev split's world seeds are 0
and 1.) ``--analyse`` only reads an existing ``--out``. The JSON lines are written as the
trials run.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import logging
import math
import tempfile
import time
from collections import defaultdict
from pathlib import Path
from typing import Any

import numpy as np

from symloc.bench import grading
from symloc.bench.localization import bench_scenario
from symloc.bench.trial import TRIAL_KINDS, TrialConfig, TrialSpec, run_trial
from symloc.bench.world_sources import WorldRef, build_world
from symloc.geometry import wrap_angle
from symloc.localizer import claim as claim_module
from symloc.localizer.best_fit import (
    TURN_REACH,
    best_offset,
    fit_profile,
    turn_profile,
    widest_axis,
)
from symloc.localizer.claim import ClaimConfig, _floored
from symloc.mcl.scan_to_map import match_scan_to_map
from symloc.sim.generator import FAMILIES

log = logging.getLogger("claim_calibration")

#: chi-square 95 % quantile, 3 dof
CHI2_3_95 = 7.815
MULTIPLES = (1.0, 2.0, 3.0, 4.0)


def world_arg(text: str) -> tuple[str, int, list[int]]:
    """``FAMILY:WORLD_SEED:TRIALS`` (trials ``a-b`` or ``a,b,c``) as (family, seed, trials);
    a malformed one raises :class:`argparse.ArgumentTypeError` naming the part."""
    parts = text.split(":")
    if len(parts) != 3:
        raise argparse.ArgumentTypeError(
            f"world {text!r}: expected FAMILY:WORLD_SEED:TRIALS, e.g. corridor_short:0:0-9"
        )
    family, seed_text, trials_text = parts
    if family not in FAMILIES:
        raise argparse.ArgumentTypeError(
            f"world {text!r}: FAMILY {family!r} is not a generated family "
            f"(one of {', '.join(sorted(FAMILIES))})"
        )
    try:
        seed = int(seed_text)
        if "-" in trials_text:
            a, b = trials_text.split("-")
            trials = list(range(int(a), int(b) + 1))
        else:
            trials = [int(x) for x in trials_text.split(",")]
    except ValueError:
        trials = []
        seed = -1
    if seed < 0 or not trials or min(trials) < 0:
        raise argparse.ArgumentTypeError(
            f"world {text!r}: expected WORLD_SEED an integer >= 0 and TRIALS as a-b or "
            "a,b,c of integers >= 0 (a <= b)"
        )
    return family, seed, trials


def _fit(gate: Any, pose: np.ndarray, points: np.ndarray) -> float:
    """Mean squared distance [m^2] of ``points`` (N, 2, robot frame) placed at ``pose`` to the
    gate's map surfaces, each clipped at 0.3 m."""
    return float(fit_profile(gate.field, points, pose, np.zeros(2), np.zeros(1), 0.3)[0])


#: Offsets [m] along a claim's widest axis at which ``axis_profile`` records the scan's fit.
AXIS_OFFSETS = np.round(np.arange(-0.3, 0.3001, 0.025), 3)
#: the turns [rad] at which each judged claim's whole-scan fit is recorded: the gate's turn
#: check profiles +-8 deg; the rest lets a claim displaced by up to 6 deg be checked too
TURN_OFFSETS = np.radians(np.round(np.arange(-14.0, 14.001, 0.5), 1))
#: heading displacements [rad] of the turn check's power table
TURN_DISPLACEMENTS = np.radians([0.0, 2.0, 3.0, 4.0, 6.0])


def _axis_profile(gate: Any, pose: np.ndarray, cov: Any, points: np.ndarray) -> dict[str, Any]:
    """The whole scan's fit [m^2] (:func:`_fit`) at :data:`AXIS_OFFSETS` along the widest axis
    of the claim's covariance ``cov`` (3, 3) (the gate's best-fit check,
    :mod:`symloc.localizer.best_fit`, on a fixed grid), the axis (2,) and the std along it [m]."""
    axis, std = widest_axis(np.asarray(cov))
    fits = fit_profile(gate.field, np.asarray(points), pose, axis, AXIS_OFFSETS, 0.3)
    return {"axis": axis.tolist(), "std": std, "fit": fits.tolist()}


def _profile(gate: Any, pose: np.ndarray, truth: np.ndarray, points: np.ndarray) -> str:
    """The fit along the claim's error direction from the truth, at the claim, and where a
    prior-free alignment from the claim ends (cm^2)."""
    e = pose[:2] - truth[:2]
    u = e / math.hypot(e[0], e[1])
    steps = np.linspace(-0.6, 0.6, 13)
    at = [np.array([truth[0] + o * u[0], truth[1] + o * u[1], pose[2]]) for o in steps]
    free = match_scan_to_map(gate.field, points, pose, gate.match_config)
    profile = " ".join(
        f"{o:+.1f}:{1e4 * _fit(gate, p, points):.1f}" for o, p in zip(steps, at, strict=True)
    )
    return (
        f"error {100 * math.hypot(e[0], e[1]):.0f} cm; fit at the truth "
        f"{1e4 * _fit(gate, np.array([*truth[:2], pose[2]]), points):.1f}, at the claim "
        f"{1e4 * _fit(gate, pose, points):.1f} cm^2; a prior-free alignment from the claim ends "
        f"{100 * math.hypot(*(free.pose[:2] - truth[:2])):.0f} cm from the truth; along the "
        f"error from the truth [m:cm^2] {profile}"
    )


def record(
    out: Path,
    worlds: list[tuple[str, int, list[int]]],
    regime: str,
    profile: float | None = None,
    walls: tuple[float, float] | None = None,
) -> None:
    """Run the trials of ``worlds`` and append every judged claim to ``out`` (JSON lines);
    with ``profile`` [m], log the fit profile of claims that far from the truth; with
    ``walls`` (m, deg), the claim gate's matcher counts the walls' shared error
    (:class:`~symloc.mcl.scan_to_map.ScanMatchConfig` ``wall_std``, ``wall_tilt_std``)."""
    pending: list[dict[str, Any]] = []
    scans: list[tuple[Any, np.ndarray, np.ndarray]] = []
    context: dict[str, Any] = {}
    judge = claim_module.ClaimGate._judge
    append = grading.ScanLog.append
    init = claim_module.ClaimGate.__init__

    def with_walls(self: Any, *args: Any, **kwargs: Any) -> None:
        init(self, *args, **kwargs)
        if walls is not None:
            self.match_config = dataclasses.replace(
                self.match_config, wall_std=walls[0], wall_tilt_std=math.radians(walls[1])
            )

    def judged(self: Any, prior: Any, prior_cov: Any, match: Any, points: Any) -> Any:
        c = judge(self, prior, prior_cov, match, points)
        if c.pose is None or c.covariance is None:
            return c
        if profile is not None:
            scans.append((self, np.asarray(c.pose, dtype=np.float64), np.asarray(points)))
        pending.append(
            {
                "verdict": c.verdict.name,
                "reason": (c.reason or "")[:60],
                "pose": [float(x) for x in c.pose],
                "cov": np.asarray(c.covariance).tolist(),
                "map_error": np.asarray(self.map_error(c.pose)).tolist(),
                "map_error_no_scale": np.asarray(self.map_error(c.pose, scale=False)).tolist(),
                "match_cov": np.asarray(match.covariance).tolist(),
                "scale_centre": [float(x) for x in self.scale_centre],
                "axis_profile": _axis_profile(self, np.asarray(c.pose), c.covariance, points),
                "turn_fit": turn_profile(
                    self.field, np.asarray(points), np.asarray(c.pose), TURN_OFFSETS, 0.3
                ).tolist(),
            }
        )
        return c

    with out.open("a", encoding="utf-8") as sink:

        def logged(self: Any, t: float, truth: Any, *args: Any, **kwargs: Any) -> Any:
            for row in pending:
                row.update(t=t, truth=[float(x) for x in truth], **context)
                sink.write(json.dumps(row) + "\n")
            pending.clear()
            for gate, pose, points in scans:
                e = pose - np.asarray(truth, dtype=np.float64)
                turned = abs(float(wrap_angle(e[2])))
                if math.hypot(e[0], e[1]) > (profile or math.inf) and turned < 0.1:
                    log.info("t %.1f s: %s", t, _profile(gate, pose, np.asarray(truth), points))
            scans.clear()
            sink.flush()
            return append(self, t, truth, *args, **kwargs)

        claim_module.ClaimGate._judge = judged  # type: ignore[method-assign]
        claim_module.ClaimGate.__init__ = with_walls  # type: ignore[method-assign]
        grading.ScanLog.append = logged  # type: ignore[method-assign]
        try:
            for family, seed, trials in worlds:
                ref = WorldRef("generated", family, seed)
                room = build_world(ref)
                t0 = time.perf_counter()
                with tempfile.TemporaryDirectory() as tmp:
                    scen = bench_scenario(ref, room, Path(tmp), regime=regime)
                    for i in trials:
                        kind = TRIAL_KINDS[i % len(TRIAL_KINDS)]
                        spec = TrialSpec(ref.world_id, family, i, kind, ref.trial_seed(i))
                        context.update(family=family, world=ref.world_id, trial=i)
                        res = run_trial(scen, spec, TrialConfig(), methods=("symloc",))
                        grade = res.results["symloc"].grade
                        log.info(
                            "%s trial %d: %s, first claim %.1f s (%.0f s)",
                            ref.world_id,
                            i,
                            grade.grade,
                            grade.time_to_claim,
                            time.perf_counter() - t0,
                        )
                    scen.close()
        finally:
            claim_module.ClaimGate._judge = judge  # type: ignore[method-assign]
            claim_module.ClaimGate.__init__ = init  # type: ignore[method-assign]
            grading.ScanLog.append = append  # type: ignore[method-assign]


def analyse(path: Path, config: ClaimConfig | None = None) -> None:
    """Print the per-world table of the module docstring from the JSON lines at ``path``."""
    cfg = config if config is not None else ClaimConfig()
    by_world: dict[str, list[dict[str, Any]]] = defaultdict(list)
    for line in path.read_text(encoding="utf-8").splitlines():
        row = json.loads(line)
        if "truth" not in row:
            continue
        e = np.array(row["pose"]) - np.array(row["truth"])
        e[2] = float(wrap_angle(e[2]))
        if math.hypot(e[0], e[1]) > 0.5 or abs(e[2]) > math.radians(15.0):
            continue
        if row["verdict"] != "CLAIM" and not row["reason"].startswith("claim withheld: std"):
            continue
        row["e"] = e
        by_world[row["world"]].append(row)
    head = "  ".join(f"k={k:g}: cov95 pass wrong" for k in MULTIPLES)
    print(f"{'world':22s} {'n':>5s} {'scale':>7s} {'z':>5s} {'z_th':>5s}  {head}")
    for world, rows in sorted(by_world.items()):
        err = np.array([r["e"] for r in rows])
        r_vec = np.array([np.array(r["pose"][:2]) - r["scale_centre"] for r in rows])
        scale = float(np.sum(err[:, :2] * r_vec) / max(float(np.sum(r_vec * r_vec)), 1e-12))
        rest = err[:, :2] - scale * r_vec
        z, z_th = [], []
        for r, d in zip(rows, rest, strict=True):
            m = np.array(r["match_cov"])
            w, v = np.linalg.eigh(m[:2, :2])
            z.append(float(d @ v[:, 1]) / math.sqrt(w[1]))
            z_th.append(r["e"][2] / math.sqrt(m[2, 2]))
        cells = []
        for k in MULTIPLES:
            cov95 = passed = wrong = 0
            for r in rows:
                c = _floored(
                    np.array(r["match_cov"]) / k + np.array(r["map_error"]),
                    cfg.floor_xy,
                    cfg.floor_theta,
                )
                e = r["e"]
                cov95 += float(e @ np.linalg.solve(c, e)) <= CHI2_3_95
                ok = cfg.precise(c)
                passed += ok
                wrong += ok and (
                    math.hypot(e[0], e[1]) > cfg.tolerance_position
                    or abs(e[2]) > cfg.tolerance_heading
                )
            n = len(rows)
            cells.append(f"      {cov95 / n:.3f} {passed / n:.2f} {wrong:4d}")
        print(
            f"{world:22s} {len(rows):5d} {100 * scale:+6.2f}% {np.std(z):5.2f} "
            f"{np.std(z_th):5.2f}" + "".join(cells)
        )


#: Displacements [m] along a claim's widest axis at which :func:`analyse_best_fit` tests the
#: gate's best-fit check.
DISPLACEMENTS = (0.0, 0.05, 0.075, 0.1, 0.15, 0.2)


def analyse_best_fit(path: Path, config: ClaimConfig | None = None) -> None:
    """How often the gate's best-fit check (:mod:`symloc.localizer.best_fit`) would withhold
    the claims published within 5 cm of the truth as they were (displacement 0: false alarms)
    and displaced by each of :data:`DISPLACEMENTS` along their widest axis, either way (its
    power). A displaced claim's profile is the recorded one shifted (``axis_profile``, so the
    side towards the displacement is cut short)."""
    cfg = (config if config is not None else ClaimConfig()).best_fit
    step = float(AXIS_OFFSETS[1] - AXIS_OFFSETS[0])
    rows = []
    for line in path.read_text(encoding="utf-8").splitlines():
        row = json.loads(line)
        if "truth" not in row or "axis_profile" not in row or row["verdict"] != "CLAIM":
            continue
        e = np.array(row["pose"]) - np.array(row["truth"])
        if math.hypot(e[0], e[1]) <= 0.05:
            rows.append(row)
    print(f"# best-fit check ({cfg}) on {len(rows)} claims published within 5 cm of the truth")
    families = sorted({r["family"] for r in rows})
    print(f"{'displaced':>9s} {'all':>13s} " + " ".join(f"{f:>17s}" for f in families))
    for d in DISPLACEMENTS:
        k = round(d / step)
        fired: dict[str, list[bool]] = defaultdict(list)
        for r in rows:
            fits = np.array(r["axis_profile"]["fit"])
            std = float(r["axis_profile"]["std"])
            for profile in (fits, fits[::-1])[: 1 if k == 0 else 2]:
                shifted = profile[k:]
                at, gain = best_offset(AXIS_OFFSETS[: len(shifted)], shifted)
                hit = cfg.contradicts(at, gain, std)
                fired[r["family"]].append(hit)
                fired["all"].append(hit)
        cells = [f"{sum(fired[f])}/{len(fired[f])}" for f in ["all", *families]]
        print(f"{100 * d:7.1f}cm {cells[0]:>13s} " + " ".join(f"{c:>17s}" for c in cells[1:]))


def analyse_best_turn(path: Path, config: ClaimConfig | None = None) -> None:
    """The same for the turn check: the claims published (or withheld by the turn check alone)
    within 5 cm and 1.5 deg of the truth, as they were and turned by each of
    :data:`TURN_DISPLACEMENTS` either way (the recorded ``turn_fit`` read at shifted turns)."""
    cfg = (config if config is not None else ClaimConfig()).best_fit
    if cfg.turn_reach <= 0.0:  # off in the gate: the calibrated reach
        cfg = dataclasses.replace(cfg, turn_reach=TURN_REACH)
    centre = len(TURN_OFFSETS) // 2
    half = len(cfg.turns) // 2
    step = float(TURN_OFFSETS[1] - TURN_OFFSETS[0])
    rows = []
    for line in path.read_text(encoding="utf-8").splitlines():
        row = json.loads(line)
        if "truth" not in row or "turn_fit" not in row:
            continue
        if row["verdict"] != "CLAIM" and "better turn" not in row["reason"]:
            continue
        e = np.array(row["pose"]) - np.array(row["truth"])
        if math.hypot(e[0], e[1]) <= 0.05 and abs(float(wrap_angle(e[2]))) <= math.radians(1.5):
            rows.append(row)
    print(f"# turn check on {len(rows)} claims within 5 cm / 1.5 deg of the truth")
    families = sorted({r["family"] for r in rows})
    print(f"{'turned':>9s} {'all':>13s} " + " ".join(f"{f:>17s}" for f in families))
    for d in TURN_DISPLACEMENTS:
        k = round(float(d) / step)
        fired: dict[str, list[bool]] = defaultdict(list)
        for r in rows:
            fits = np.array(r["turn_fit"])
            std = math.sqrt(float(np.array(r["cov"])[2][2]))
            for sign in (1, -1)[: 1 if k == 0 else 2]:
                lo = centre + sign * k - half
                window = fits[lo : lo + 2 * half + 1]
                at, gain = best_offset(cfg.turns, window)
                hit = cfg.turn_contradicts(at, gain, std)
                fired[r["family"]].append(hit)
                fired["all"].append(hit)
        cells = [f"{sum(fired[f])}/{len(fired[f])}" for f in ["all", *families]]
        line = f"{math.degrees(d):6.1f}deg {cells[0]:>13s} "
        print(line + " ".join(f"{c:>17s}" for c in cells[1:]))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("worlds", nargs="*", type=world_arg, help="FAMILY:WORLD_SEED:TRIALS")
    parser.add_argument("--out", type=Path, required=True, help="JSON lines, appended to")
    parser.add_argument("--regime", default="realistic")
    parser.add_argument("--analyse", action="store_true", help="only analyse --out")
    parser.add_argument(
        "--profile", type=float, metavar="D", help="log the fit profile of claims D m off"
    )
    parser.add_argument(
        "--walls",
        type=float,
        nargs=2,
        metavar=("STD", "TILT_DEG"),
        help="give the claim gate's matcher the walls' shared error (ScanMatchConfig.wall_std "
        "[m], wall_tilt_std [deg]); default: its information_scale alone",
    )
    args = parser.parse_args()
    if args.analyse and not args.out.is_file():
        parser.error(f"--out {args.out}: --analyse reads an existing JSON-lines file; none there")
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    print(
        f"# claim_calibration: worlds {args.worlds}, regime {args.regime}, out {args.out}, "
        f"profile {args.profile}, walls {args.walls}"
    )
    print("# robot and trial seeds: WorldRef.robot_seed and .trial_seed (the bench's)")
    if not args.analyse:
        record(args.out, args.worlds, args.regime, args.profile, args.walls)
    analyse(args.out)
    analyse_best_fit(args.out)
    analyse_best_turn(args.out)


if __name__ == "__main__":
    main()
