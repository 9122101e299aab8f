"""Adaptive Monte Carlo localization: the filter that ties the models together.

``Amcl`` follows nav2_amcl's update cycle (the paper's Algorithm 4 with the KLD-sampling and
augmented-MCL extensions of Section 4.4):

1. the first scan after an initialisation is integrated at once, without motion;
2. afterwards a scan is integrated only once the odometry moved by ``update_min_d`` [m] or
   turned by ``update_min_a`` [rad] since the last integrated scan; the particles are then
   moved by the odometry-based motion model (eq. 6),
3. re-weighted by the laser model (eq. 7-8: weights multiply until resampled),
4. resampled every ``resample_interval`` integrated scans: low-variance resampling, the set
   size chosen by KLD-sampling, random free-space particles injected by augmented-MCL
   recovery;
5. clustered into hypotheses; the estimate is the heaviest cluster, reported with its own
   covariance, and ``n_hypotheses`` counts the clusters holding at least
   ``hypothesis_min_weight`` of the weight, which is what tells a caller that the robot may
   stand in a symmetric place.

That is all :meth:`Amcl.update` does, so its cost is bounded by the particle count and the
beams. Whether the estimate is *confident* (one dominant, tight hypothesis whose scan agrees
with the map, sustained, and no rival place on the whole map) is judged after the update, as
beluga's ``amcl_core`` estimates after the filter update: by
:class:`symloc.mcl.confidence.ConfidenceJudge`, whose rival search may take a second.

The map's fields (the likelihood field, ...) come from the map's one shared cache,
:class:`symloc.grid.fields.MapFields`: pass the grid or its ``MapFields``.

Differences from nav2_amcl, on purpose: ``update_min_d`` is tested on the Euclidean distance
(nav2 tests |dx| and |dy| in the odom frame separately, so its threshold depends on the
heading; set ``update_min_d_euclidean=False`` for nav2's test); ``pf_z`` enters KLD-sampling
through its normal quantile; resampling is O(N); heading bins wrap when clustering; each
cluster has its own covariance; bad parameters raise instead of being reset.

Bad input: a scan with no usable beam is a *counted skip* (the motion is applied, the sensor
update and resampling are not; ``AmclResult.sensor_skipped`` says so and
``Amcl.n_scans_skipped`` counts); a map with no free cell raises at construction; non-finite
odometry raises :class:`~symloc.errors.DataFormatError`. The pose estimate is never NaN.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc._checks import as_rng
from symloc.errors import ConfigurationError, DataFormatError, SymlocError
from symloc.geometry import wrap_angle
from symloc.grid.distance_field import DistanceField
from symloc.grid.fields import MapFields
from symloc.grid.occupancy_grid import OccupancyGrid
from symloc.mcl import kernels
from symloc.mcl.beam_model import beam_model_weights
from symloc.mcl.beams import BeamSet, select_beams
from symloc.mcl.clustering import (
    BIN_ANGLE,
    BIN_XY,
    N_ANGLE_BINS,
    ClusterStats,
    Hypothesis,
    bin_keys,
    cluster_particles,
)
from symloc.mcl.kld_sampling import kld_stop_index, pf_z_quantile
from symloc.mcl.likelihood_field import likelihood_field_weights
from symloc.mcl.likelihood_field_prob import BeamSkipReport, likelihood_field_prob_log_weights
from symloc.mcl.motion_model import sample_motion_model_odometry
from symloc.mcl.params import AmclParams
from symloc.mcl.recovery import FreeSpaceSampler, RecoveryState
from symloc.mcl.resampling import low_variance_resample
from symloc.odometry import OdometryReading
from symloc.scan import LaserScan

__all__ = ["Amcl", "AmclResult", "NotInitializedError"]

FloatArray = NDArray[np.float64]

#: nav2_amcl's default initial covariance (0.5 m, 0.5 m, pi/12 rad standard deviations).
DEFAULT_INITIAL_COVARIANCE = np.diag([0.25, 0.25, (np.pi / 12.0) ** 2])


class NotInitializedError(SymlocError, RuntimeError):
    """``Amcl.update`` was called before ``initialize_global`` or ``initialize_pose``."""


@dataclass(frozen=True, slots=True, eq=False)
class AmclResult:
    """The filter's belief after one call to :meth:`Amcl.update`.

    Attributes
    ----------
    estimate : ndarray of shape (3,)
        Mean pose x [m], y [m], theta [rad] of the heaviest cluster (map frame).
    covariance : ndarray of shape (3, 3)
        That cluster's own covariance.
    hypotheses : list of Hypothesis
        Every cluster, heaviest first, each with weight, mean and own covariance.
    n_hypotheses : int
        Clusters holding at least ``hypothesis_min_weight`` of the total weight (>= 1).
    particles : ndarray of shape (N, 3)
        The particle poses (read-only).
    weights : ndarray of shape (N,)
        Their normalised weights (read-only, sum 1).
    updated : bool
        True if this call integrated the scan (moved enough, or first scan).
    resampled : bool
        True if the particles were resampled.
    sensor_skipped : bool
        True if the scan had no usable beam, so only the motion was applied (counted).
    n_beams : int
        Beams the sensor model scored.
    injected : int
        Random particles injected by recovery in this call.
    beam_skip : BeamSkipReport or None
        Beam-skipping report (likelihood_field_prob with ``do_beamskip``).

    Whether the estimate is confident is judged afterwards, by
    :class:`symloc.mcl.confidence.ConfidenceJudge`.
    """

    estimate: FloatArray
    covariance: FloatArray
    hypotheses: list[Hypothesis]
    n_hypotheses: int
    particles: FloatArray
    weights: FloatArray
    updated: bool
    resampled: bool
    sensor_skipped: bool = False
    n_beams: int = 0
    injected: int = 0
    beam_skip: BeamSkipReport | None = None

    @property
    def weight(self) -> float:
        """Weight of the heaviest cluster (0..1)."""
        return self.hypotheses[0].weight if self.hypotheses else 1.0


@dataclass
class _Counters:
    n_updates: int = 0
    n_scans_skipped: int = 0
    n_resamples: int = 0
    n_injected: int = 0
    #: calls of initialize_global / initialize_pose (a judge of the estimate resets on a new one)
    n_initializations: int = 0
    skip_reasons: list[str] = field(default_factory=list)


class Amcl:
    """Adaptive Monte Carlo localization on an occupancy grid (nav2_amcl's filter).

    Parameters
    ----------
    grid : OccupancyGrid or MapFields
        The map, or its shared fields (:meth:`MapFields.of(grid) <MapFields.of>`, what a grid
        stands for). Must contain at least one free cell.
    params : AmclParams, optional
        nav2-named parameters (defaults as nav2).
    rng : numpy.random.Generator or int or None
        Source of all randomness.
    """

    def __init__(
        self,
        grid: OccupancyGrid | MapFields,
        params: AmclParams | None = None,
        rng: np.random.Generator | int | None = None,
    ) -> None:
        if not isinstance(grid, (OccupancyGrid, MapFields)):
            raise ConfigurationError(
                f"grid: expected an OccupancyGrid or MapFields, got {type(grid).__name__}"
            )
        self.params = AmclParams() if params is None else params
        if not isinstance(self.params, AmclParams):
            raise ConfigurationError("params: expected an AmclParams")
        #: the map's shared fields (one cache per map, :class:`symloc.grid.fields.MapFields`)
        self.fields = MapFields.of(grid)
        self.grid = self.fields.grid
        self.rng = as_rng(rng)
        self.free_space = FreeSpaceSampler(self.grid)
        self.field: DistanceField = self.fields.distance(self.params.laser_likelihood_max_dist)
        p = self.params
        self._z = pf_z_quantile(p.pf_z)
        self._alphas = (p.alpha1, p.alpha2, p.alpha3, p.alpha4, p.alpha5)
        self.recovery = RecoveryState(p.recovery_alpha_slow, p.recovery_alpha_fast)
        self.counters = _Counters()
        self._particles: FloatArray | None = None
        self._weights: FloatArray | None = None
        self._odom_last: FloatArray | None = None
        self._force_update = False
        self._resample_count = 0
        self._stats: ClusterStats | None = None

    # ------------------------------------------------------------------ state
    @property
    def initialized(self) -> bool:
        """True once a particle set exists."""
        return self._particles is not None

    @property
    def particles(self) -> FloatArray:
        """Current particles ``(N, 3)`` (read-only)."""
        if self._particles is None:
            raise NotInitializedError("Amcl: call initialize_global() or initialize_pose() first")
        return self._particles

    @property
    def weights(self) -> FloatArray:
        """Current normalised weights ``(N,)`` (read-only)."""
        if self._weights is None:
            raise NotInitializedError("Amcl: call initialize_global() or initialize_pose() first")
        return self._weights

    @property
    def n_scans_skipped(self) -> int:
        """Scans whose sensor update was skipped because no beam was usable."""
        return self.counters.n_scans_skipped

    def _set(self, particles: FloatArray, weights: FloatArray | None = None) -> None:
        n = particles.shape[0]
        w = np.full(n, 1.0 / n) if weights is None else weights
        particles.setflags(write=False)
        w.setflags(write=False)
        self._particles = particles
        self._weights = w
        self._stats = None

    def _reset_after_init(self) -> None:
        self._odom_last = None
        self._force_update = True
        self._resample_count = 0
        self.recovery.reset()
        self.counters.n_initializations += 1

    # ----------------------------------------------------------- initialise
    def initialize_global(self) -> None:
        """Spread ``max_particles`` particles uniformly over the free cells, headings uniform."""
        self._set(self.free_space.sample(self.params.max_particles, self.rng))
        self._reset_after_init()

    def initialize_pose(self, pose: ArrayLike, covariance: ArrayLike | None = None) -> None:
        """Draw ``max_particles`` particles from a Gaussian around ``pose``.

        Parameters
        ----------
        pose : array of shape (3,)
            Mean x [m], y [m], theta [rad] in the map frame.
        covariance : array of shape (3, 3), optional
            Symmetric positive semi-definite; default nav2's diag(0.25, 0.25, (pi/12)^2).
        """
        try:
            mean = np.asarray(pose, dtype=np.float64)
        except (TypeError, ValueError) as err:
            raise ConfigurationError("pose: expected three numbers x, y, theta") from err
        if mean.shape != (3,) or not np.all(np.isfinite(mean)):
            raise ConfigurationError(f"pose: expected finite shape (3,) x, y, theta, got {mean}")
        cov = DEFAULT_INITIAL_COVARIANCE if covariance is None else covariance
        try:
            c = np.asarray(cov, dtype=np.float64)
        except (TypeError, ValueError) as err:
            raise ConfigurationError("covariance: expected a 3 x 3 array") from err
        if c.shape != (3, 3) or not np.all(np.isfinite(c)):
            raise ConfigurationError(f"covariance: expected a finite (3, 3) array, got {c.shape}")
        if not np.allclose(c, c.T, atol=1e-12):
            raise ConfigurationError("covariance: expected a symmetric matrix")
        evals, evecs = np.linalg.eigh(c)
        if evals.min() < -1e-12 * max(1.0, float(np.abs(evals).max())):
            raise ConfigurationError(
                f"covariance: expected positive semi-definite, eigenvalues {evals}"
            )
        n = self.params.max_particles
        z = self.rng.standard_normal((n, 3)) * np.sqrt(np.clip(evals, 0.0, None))
        parts = mean + z @ evecs.T
        parts[:, 2] = wrap_angle(parts[:, 2])
        self._set(parts)
        self._reset_after_init()

    def request_nomotion_update(self) -> None:
        """Integrate the next scan even if the robot has not moved (nav2's service of the same
        name): the next :meth:`update` runs the sensor update whatever the odometry says."""
        self._force_update = True

    # ---------------------------------------------------------------- update
    def update(
        self,
        odom: OdometryReading,
        scan: LaserScan,
        *,
        laser_pose: ArrayLike = (0.0, 0.0, 0.0),
    ) -> AmclResult:
        """Integrate one odometry reading and laser scan (nav2's ``laserReceived``).

        Parameters
        ----------
        odom : OdometryReading
            The robot's odometry pose when the scan was taken.
        scan : LaserScan
        laser_pose : array of shape (3,)
            The laser's pose in the robot frame (``base_from_laser``).

        Returns
        -------
        AmclResult
            The belief after motion, sensor update, resampling and clustering; judge its
            confidence afterwards with :class:`symloc.mcl.confidence.ConfidenceJudge`.
        """
        return self._update(odom, scan, laser_pose)

    def _update(self, odom: OdometryReading, scan: LaserScan, laser_pose: ArrayLike) -> AmclResult:
        if self._particles is None:
            raise NotInitializedError("Amcl: call initialize_global() or initialize_pose() first")
        if not isinstance(odom, OdometryReading):
            raise DataFormatError(f"odom: expected an OdometryReading, got {type(odom).__name__}")
        if not isinstance(scan, LaserScan):
            raise DataFormatError(f"scan: expected a LaserScan, got {type(scan).__name__}")
        pose = np.asarray(odom.pose, dtype=np.float64)
        if not np.all(np.isfinite(pose)):
            raise DataFormatError(f"odom.pose: expected finite values, got {pose}")
        lp = np.asarray(laser_pose, dtype=np.float64)
        if lp.shape != (3,) or not np.all(np.isfinite(lp)):
            raise ConfigurationError(f"laser_pose: expected finite (x, y, theta), got {lp}")
        p = self.params

        if self._odom_last is None:
            self._odom_last = pose.copy()
            integrate = True
        else:
            dx, dy = pose[0] - self._odom_last[0], pose[1] - self._odom_last[1]
            da = abs(float(wrap_angle(pose[2] - self._odom_last[2])))
            if p.update_min_d_euclidean:
                moved = float(np.hypot(dx, dy)) > p.update_min_d
            else:
                moved = abs(dx) > p.update_min_d or abs(dy) > p.update_min_d
            integrate = moved or da > p.update_min_a or self._force_update
            if integrate:
                moved_parts = sample_motion_model_odometry(
                    self._particles,
                    self._odom_last,
                    pose,
                    self._alphas,
                    self.rng,
                    model=p.motion_model,
                )
                self._set(moved_parts, self._weights.copy())  # type: ignore[union-attr]
                self._odom_last = pose.copy()
        if not integrate:
            return self._result(updated=False, resampled=False)
        self._force_update = False
        self.counters.n_updates += 1

        beams = select_beams(
            scan, p.max_beams, laser_max_range=p.laser_max_range, laser_min_range=p.laser_min_range
        )
        usable = beams.ranges.size if p.laser_model_type == "beam" else beams.n_hits
        if usable == 0:
            self.counters.n_scans_skipped += 1
            return self._result(updated=True, resampled=False, sensor_skipped=True)
        skip_report = self._sensor_update(beams, lp)
        resampled = False
        injected = 0
        self._resample_count += 1
        if self._resample_count % p.resample_interval == 0:
            injected = self._resample()
            resampled = True
        return self._result(
            updated=True,
            resampled=resampled,
            n_beams=int(usable),
            injected=injected,
            beam_skip=skip_report,
        )

    def _sensor_update(self, beams: BeamSet, laser_pose: FloatArray) -> BeamSkipReport | None:
        p = self.params
        parts = self.particles
        w_prev = self.weights
        report = None
        if p.laser_model_type == "likelihood_field_prob":
            logf, report = likelihood_field_prob_log_weights(
                self.field,
                parts,
                beams,
                z_hit=p.z_hit,
                z_rand=p.z_rand,
                sigma_hit=p.sigma_hit,
                laser_pose=laser_pose,
                do_beamskip=p.do_beamskip,
                beam_skip_distance=p.beam_skip_distance,
                beam_skip_threshold=p.beam_skip_threshold,
                beam_skip_error_threshold=p.beam_skip_error_threshold,
            )
            logf *= p.laser_likelihood_exponent
            shift = float(logf.max())
            w = w_prev * np.exp(logf - shift)
            total = float(w.sum())
            w_avg = total * float(np.exp(shift)) / w.size  # may underflow to 0: then ignored
        else:
            if p.laser_model_type == "likelihood_field":
                factor = likelihood_field_weights(
                    self.field,
                    parts,
                    beams,
                    z_hit=p.z_hit,
                    z_rand=p.z_rand,
                    sigma_hit=p.sigma_hit,
                    laser_pose=laser_pose,
                )
            else:
                factor = beam_model_weights(
                    self.grid,
                    parts,
                    beams,
                    z_hit=p.z_hit,
                    z_short=p.z_short,
                    z_max=p.z_max,
                    z_rand=p.z_rand,
                    sigma_hit=p.sigma_hit,
                    lambda_short=p.lambda_short,
                    laser_pose=laser_pose,
                )
            if p.laser_likelihood_exponent != 1.0:
                factor **= p.laser_likelihood_exponent
            w = w_prev * factor
            total = float(w.sum())
            w_avg = total / w.size
        if total > 0.0 and np.isfinite(total):
            w /= total
            if w_avg > 0.0 and np.isfinite(w_avg):
                self.recovery.observe(w_avg)
        else:
            w = np.full(w.size, 1.0 / w.size)
        self._set(parts, w)  # the poses are unchanged (and read-only): no copy
        return report

    def _resample(self) -> int:
        p = self.params
        parts, w = self.particles, self.weights
        m_max = p.max_particles
        idx = low_variance_resample(w, m_max, self.rng)
        if p.min_particles < p.max_particles:
            idx = idx[self.rng.permutation(idx.size)]
            new = parts[idx]
            n = kernels.kld_stop(
                new,
                BIN_XY,
                BIN_ANGLE,
                N_ANGLE_BINS,
                p.pf_err,
                self._z,
                p.min_particles,
                p.max_particles,
            )
            if n < 0:  # a pose that is not finite: the NumPy definition decides
                n = kld_stop_index(
                    bin_keys(new), p.pf_err, self._z, p.min_particles, p.max_particles
                )
            new = new[:n]
        else:
            new = parts[idx]
        w_diff = self.recovery.injection_probability()
        injected = 0
        if w_diff > 0.0:
            mask = self.rng.random(new.shape[0]) < w_diff
            injected = int(np.count_nonzero(mask))
            if injected:
                new[mask] = self.free_space.sample(injected, self.rng)
            self.recovery.reset()
        self.counters.n_resamples += 1
        self.counters.n_injected += injected
        self._set(new)
        return injected

    # ---------------------------------------------------------------- output
    def cluster_stats(self) -> ClusterStats:
        """Clusters of the current particle set (cached until the set changes)."""
        if self._stats is None:
            self._stats = cluster_particles(self.particles, self.weights)
        return self._stats

    def _result(self, *, updated: bool, resampled: bool, **kw: object) -> AmclResult:
        stats = self.cluster_stats()
        hyps = stats.hypotheses()
        n_well = int(np.count_nonzero(stats.weights >= self.params.hypothesis_min_weight))
        return AmclResult(
            estimate=stats.means[0].copy(),
            covariance=stats.covariances[0].copy(),
            hypotheses=hyps,
            n_hypotheses=max(n_well, 1),
            particles=self.particles,
            weights=self.weights,
            updated=updated,
            resampled=resampled,
            **kw,  # type: ignore[arg-type]
        )
