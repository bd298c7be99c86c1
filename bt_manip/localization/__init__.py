"""Localisation: Monte Carlo localisation of a base on a map of the world's static geometry.

- :mod:`.inputs`: the odometry pose and laser scan records the filter reads.
- :mod:`.options`: :class:`LocalizationOptions`, named after Nav2's AMCL parameters.
- :mod:`.map_from_world`: the map, an occupancy grid of the walls and furniture.
- :mod:`.likelihood_field`: distance to the nearest obstacle per cell; the sensor model.
- :mod:`.motion_model`: the odometry motion model of a differential-drive base.
- :mod:`.particles`, :mod:`.resampling`, :mod:`.kld`: particle sets, low-variance resampling,
  the KLD bound on their size.
- :mod:`.estimate`: the best cluster's mean and covariance.
- :mod:`.filter`: :class:`ParticleFilter`, all of it, one update at a time.
"""

from bt_manip.localization.estimate import PoseEstimate
from bt_manip.localization.filter import NotInitialised, ParticleFilter
from bt_manip.localization.inputs import OdomPose, Scan
from bt_manip.localization.likelihood_field import LikelihoodField
from bt_manip.localization.map_from_world import map_from_world, static_outlines
from bt_manip.localization.options import LocalizationOptions, OptionsError

__all__ = [
    "LikelihoodField",
    "LocalizationOptions",
    "NotInitialised",
    "OdomPose",
    "OptionsError",
    "ParticleFilter",
    "PoseEstimate",
    "Scan",
    "map_from_world",
    "static_outlines",
]
