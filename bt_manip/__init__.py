"""bt-manip: behaviour-tree task orchestration for mobile manipulators in PyBullet."""

__version__ = "0.1.0"
