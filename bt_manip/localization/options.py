"""The particle filter's options, named as Nav2's AMCL names its parameters where one exists.

:class:`LocalizationOptions` is frozen: change one with :func:`dataclasses.replace`. Every value
is checked when the options are made; a bad one raises :class:`OptionsError` (a ``ValueError``)
whose message names each offending option, its value and what would be right.

Departures from Nav2's defaults, on purpose:

- ``recovery_alpha_slow`` / ``recovery_alpha_fast`` (Nav2: ``recovery_alpha_slow``,
  ``recovery_alpha_fast``, both 0, which turns random-particle injection off) are 0.001 and 0.1
  here, so that a filter whose robot was carried elsewhere (a kidnap) finds it again. The
  averages follow the scan's likelihood as the newly weighted particles see it (see
  :mod:`bt_manip.localization.filter`), which depends neither on how many particles there are
  nor on the random ones just injected: injection stops once the filter has found the robot.
- ``beam_weight`` (not in Nav2) tempers the product of the beam likelihoods; AMCL's
  ``1 + sum(pz^3)`` weighs poses more flatly (see :mod:`bt_manip.localization.likelihood_field`).
- ``sigma_hit`` is 0.05 m (Nav2: 0.2 m): a simulated LiDAR's ranges are good to about a
  centimetre; ``z_hit`` / ``z_rand`` are 0.95 / 0.05 (Nav2: 0.5 / 0.5) for the same reason.
  ``max_beams`` is 120 (Nav2: 60), spread over the usable returns only (the robot's own body
  hides a third of the Husky's 270 deg, a carried panel half of the rest).
- ``motion_model`` is ``"planar"`` (Nav2: ``DifferentialMotionModel``): AMCL's diff model
  reads a skid-steer's sideways slide while turning on the spot (a few centimetres) as a
  large turn towards it and back, and its noise then scatters the particles over a metre;
  the planar model (:mod:`bt_manip.localization.motion_model`) adds noise to the forward,
  sideways and turning parts of the move in the base's frame. ``"diff"`` is AMCL's model.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

MAX_PARTICLES_BOUND = 200_000
"""Largest ``max_particles`` accepted (memory and time per update grow with it)."""

MAX_BEAMS_BOUND = 4096
"""Largest ``max_beams`` accepted."""


class OptionsError(ValueError):
    """Localisation options that cannot be used; the message names each problem."""


@dataclass(frozen=True)
class LocalizationOptions:
    """What the Monte Carlo localisation filter does and how much it may spend."""

    # -- particle count (KLD sampling) ---------------------------------------------------------
    min_particles: int = 500
    """Fewest particles kept after a resampling."""
    max_particles: int = 2000
    """Most particles; also how many a global localisation starts with."""
    pf_err: float = 0.05
    """KLD sampling: largest tolerated divergence between the particles and the true
    posterior."""
    pf_z: float = 0.99
    """KLD sampling: upper standard normal quantile of the confidence (0.99 is Nav2's)."""
    kld_bin_xy: float = 0.5
    """Histogram bin side (m) in x and y used to count the occupied bins."""
    kld_bin_yaw: float = math.radians(10.0)
    """Histogram bin width (rad) in yaw."""

    # -- motion model (differential drive, AMCL's sample_motion_model_odometry) -----------------
    motion_model: str = "planar"
    """``"diff"`` (AMCL's differential-drive model) or ``"planar"`` (the move taken apart in
    the base's frame: see :mod:`bt_manip.localization.motion_model`)."""
    alpha1: float = 0.2
    """Rotation noise from rotation."""
    alpha2: float = 0.2
    """Rotation noise from translation."""
    alpha3: float = 0.2
    """Translation noise from translation."""
    alpha4: float = 0.2
    """Translation noise from rotation."""
    alpha5: float = 0.05
    """Sideways slip from rotation, of the planar model only: the variance of a move across
    the heading per squared radian turned (see :mod:`bt_manip.localization.motion_model`)."""

    # -- likelihood-field sensor model ---------------------------------------------------------
    z_hit: float = 0.95
    """Weight of the Gaussian around the nearest obstacle."""
    z_rand: float = 0.05
    """Weight of the uniform (random reading) part."""
    sigma_hit: float = 0.05
    """Standard deviation (m) of a reading's distance to the nearest obstacle."""
    sigma_hit_wide: float = 0.1
    """``sigma_hit`` (m) while the particles are spread over several places (after a global
    localisation; see :mod:`bt_manip.localization.filter`)."""
    beam_weight_wide: float = 0.1
    """``beam_weight`` while the particles are spread over several places."""
    laser_likelihood_max_dist: float = 2.0
    """Distances to the nearest obstacle are capped here (m)."""
    max_beams: int = 120
    """Beams used per update, evenly spaced over the usable returns."""
    beam_weight: float = 0.2
    """Each beam's log-likelihood counts this much (neighbouring beams are not independent
    evidence: under 1, one scan cannot make the filter sure of a wrong place at once)."""

    # -- when to update -------------------------------------------------------------------------
    update_min_d: float = 0.25
    """Travel (m) since the last update before the next scan is used."""
    update_min_a: float = 0.2
    """Turn (rad) since the last update before the next scan is used."""
    resample_interval: int = 1
    """Updates between two resamplings."""

    # -- recovery (random particles) ------------------------------------------------------------
    recovery_alpha_slow: float = 0.001
    """Rate of the slow average of the likelihood (0 with ``recovery_alpha_fast`` 0: off)."""
    recovery_alpha_fast: float = 0.1
    """Rate of the fast average of the likelihood; random particles are injected in proportion
    to how far the fast average falls under the slow one."""

    # -- initial pose ---------------------------------------------------------------------------
    initial_sigma_xy: float = 0.5
    """Standard deviation (m) in x and y of an initial pose given without one."""
    initial_sigma_yaw: float = math.radians(15.0)
    """Standard deviation (rad) in yaw of an initial pose given without one."""

    # -- estimate and "lost" --------------------------------------------------------------------
    cluster_radius: float = 0.5
    """Radius (m) of the window the estimate's cluster is gathered in."""
    cluster_yaw: float = 0.6
    """Half width (rad) in yaw of that window."""
    lost_std_xy: float = 0.5
    """The filter says it is lost when the estimate's x or y standard deviation exceeds this."""
    lost_std_yaw: float = 0.5
    """... or its yaw standard deviation (rad) exceeds this ..."""
    lost_likelihood_ratio: float = 0.8
    """... or the fast average of the likelihood falls under this share of the slow one ..."""
    lost_cluster_weight: float = 0.5
    """... or the estimate's cluster holds less than this share of the weight (the particles
    back several places)."""

    def __post_init__(self) -> None:
        problems = _problems(self)
        if problems:
            raise OptionsError("bad localisation options: " + "; ".join(problems))


_COUNTS = ("min_particles", "max_particles", "max_beams", "resample_interval")
_POSITIVE = ("pf_err", "beam_weight", "beam_weight_wide", "kld_bin_xy", "kld_bin_yaw",
             "sigma_hit", "sigma_hit_wide",
             "laser_likelihood_max_dist", "cluster_radius", "cluster_yaw", "lost_std_xy",
             "lost_std_yaw")
_NON_NEGATIVE = ("alpha1", "alpha2", "alpha3", "alpha4", "alpha5", "z_hit", "z_rand",
                 "update_min_d", "update_min_a", "initial_sigma_xy", "initial_sigma_yaw")
MOTION_MODELS = ("diff", "planar")
"""The motion models :attr:`LocalizationOptions.motion_model` names."""
_UNIT = ("recovery_alpha_slow", "recovery_alpha_fast", "lost_likelihood_ratio",
         "lost_cluster_weight")


def _problems(o: LocalizationOptions) -> list[str]:
    """One line per bad value of ``o``."""
    out: list[str] = []
    for f in fields(o):
        v = getattr(o, f.name)
        if f.name == "motion_model":
            if v not in MOTION_MODELS:
                out.append(f"motion_model must be one of {', '.join(MOTION_MODELS)}, not {v!r}")
        elif f.name in _COUNTS:
            if isinstance(v, bool) or not isinstance(v, int):
                out.append(f"{f.name} must be a whole number, not {v!r}")
            elif v < 1:
                out.append(f"{f.name} must be at least 1, not {v}")
        elif isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            out.append(f"{f.name} must be a finite number, not {v!r}")
        elif f.name in _POSITIVE and v <= 0:
            out.append(f"{f.name} must be > 0, not {v}")
        elif f.name in _NON_NEGATIVE and v < 0:
            out.append(f"{f.name} must be >= 0, not {v}")
        elif f.name in _UNIT and not 0 <= v <= 1:
            out.append(f"{f.name} must be between 0 and 1, not {v}")
    if out:
        return out
    if o.min_particles > o.max_particles:
        out.append(f"min_particles ({o.min_particles}) must not exceed max_particles "
                   f"({o.max_particles})")
    if o.max_particles > MAX_PARTICLES_BOUND:
        out.append(f"max_particles must be at most {MAX_PARTICLES_BOUND:,}, not "
                   f"{o.max_particles:,}")
    if o.max_beams > MAX_BEAMS_BOUND:
        out.append(f"max_beams must be at most {MAX_BEAMS_BOUND}, not {o.max_beams}")
    if not 0 < o.pf_z < 1:
        out.append(f"pf_z must be between 0 and 1 (a probability), not {o.pf_z}")
    if o.z_hit + o.z_rand <= 0:
        out.append("z_hit and z_rand must not both be 0")
    if o.recovery_alpha_slow > 0 and o.recovery_alpha_fast <= o.recovery_alpha_slow:
        out.append(f"recovery_alpha_fast ({o.recovery_alpha_fast}) must exceed "
                   f"recovery_alpha_slow ({o.recovery_alpha_slow})")
    return out
