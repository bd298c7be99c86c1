"""Simulated sensors of a robot: a planar laser scanner and wheel odometry.

- :mod:`bt_manip.sensing.sensors`: the ``sensors:`` records of a robot descriptor
  (:class:`~bt_manip.sensing.sensors.LidarSpec`) and how they are read.
- :mod:`bt_manip.sensing.sections`: cross-sections of collision shapes by a horizontal plane.
- :mod:`bt_manip.sensing.scan_scene`: the world cut at a laser's scan plane, kept up to date as
  bodies move, come and go.
- :mod:`bt_manip.sensing.raycast`: the compiled 2D ray caster.
- :mod:`bt_manip.sensing.lidar`: the :class:`~bt_manip.sensing.lidar.Scan` record and
  :class:`~bt_manip.sensing.lidar.Lidar`, which scans a robot's surroundings at its true pose.
- :mod:`bt_manip.sensing.odometry`: wheel odometry integrated from what the wheels did.

Nothing here changes the simulation: a sensor only reads it.
"""
