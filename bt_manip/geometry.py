"""Pose and rotation conversions: quaternions, rotation matrices, yaw, 4x4 transforms.

Quaternions are (x, y, z, w), as PyBullet uses them; a transform is a 4x4 homogeneous matrix;
a frame is a (position, rotation matrix) pair; a pose row is (x, y, z, qx, qy, qz, qw).
Conversions to and from Euler angles and rotation matrices are PyBullet's own, so a value
computed here and handed to the simulator is bit for bit what it computes itself.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pybullet as pb

Frame = tuple[np.ndarray, np.ndarray]
"""A frame as (position (3,), rotation matrix (3, 3))."""

IDENTITY_QUAT = (0.0, 0.0, 0.0, 1.0)


def quat_from_euler(rpy: Sequence[float]) -> tuple[float, float, float, float]:
    """Quaternion of fixed-axis roll, pitch, yaw (rad)."""
    return tuple(pb.getQuaternionFromEuler(list(rpy)))  # type: ignore[return-value]


def quat_from_yaw(yaw: float) -> tuple[float, float, float, float]:
    """Quaternion of a turn of ``yaw`` (rad) about z."""
    return quat_from_euler((0.0, 0.0, yaw))


def euler_from_quat(quat: Sequence[float]) -> tuple[float, float, float]:
    """Fixed-axis roll, pitch, yaw (rad) of a quaternion."""
    return tuple(pb.getEulerFromQuaternion(list(quat)))  # type: ignore[return-value]


def yaw_of(quat: Sequence[float]) -> float:
    """Heading (rad) of a quaternion: its yaw angle."""
    return float(pb.getEulerFromQuaternion(list(quat))[2])


def rotation_matrix(quat: Sequence[float] | np.ndarray) -> np.ndarray:
    """3x3 rotation matrix of a quaternion (normalised first)."""
    return np.array(pb.getMatrixFromQuaternion(list(quat))).reshape(3, 3)


def rpy_matrix(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """Rotation matrix of URDF fixed-axis roll, pitch, yaw (R = Rz(yaw) Ry(pitch) Rx(roll))."""
    cr, sr = np.cos(roll), np.sin(roll)
    cp, sp = np.cos(pitch), np.sin(pitch)
    cy, sy = np.cos(yaw), np.sin(yaw)
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


def quat_from_matrix(r: np.ndarray) -> np.ndarray:
    """Unit quaternion (x, y, z, w) of a rotation matrix, w >= 0."""
    m = r
    trace = m[0, 0] + m[1, 1] + m[2, 2]
    if trace > 0:
        s = 2.0 * np.sqrt(trace + 1.0)
        q = [(m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s, s / 4]
    elif m[0, 0] > m[1, 1] and m[0, 0] > m[2, 2]:
        s = 2.0 * np.sqrt(1.0 + m[0, 0] - m[1, 1] - m[2, 2])
        q = [s / 4, (m[0, 1] + m[1, 0]) / s, (m[0, 2] + m[2, 0]) / s, (m[2, 1] - m[1, 2]) / s]
    elif m[1, 1] > m[2, 2]:
        s = 2.0 * np.sqrt(1.0 + m[1, 1] - m[0, 0] - m[2, 2])
        q = [(m[0, 1] + m[1, 0]) / s, s / 4, (m[1, 2] + m[2, 1]) / s, (m[0, 2] - m[2, 0]) / s]
    else:
        s = 2.0 * np.sqrt(1.0 + m[2, 2] - m[0, 0] - m[1, 1])
        q = [(m[0, 2] + m[2, 0]) / s, (m[1, 2] + m[2, 1]) / s, s / 4, (m[1, 0] - m[0, 1]) / s]
    quat = np.array(q)
    quat /= np.linalg.norm(quat)
    return -quat if quat[3] < 0 else quat


def pose_matrix(
    position: Sequence[float] | np.ndarray, quat: Sequence[float] | np.ndarray
) -> np.ndarray:
    """4x4 transform of a position and a quaternion (x, y, z, w)."""
    out = np.eye(4)
    out[:3, :3] = rotation_matrix(quat)
    out[:3, 3] = position
    return out


def row_matrix(row: Sequence[float] | np.ndarray) -> np.ndarray:
    """4x4 transform of a pose row (x, y, z, qx, qy, qz, qw)."""
    return pose_matrix(row[:3], row[3:7])


def matrix_row(t: np.ndarray) -> np.ndarray:
    """Pose row (x, y, z, qx, qy, qz, qw) of a 4x4 transform (w >= 0)."""
    return np.concatenate([t[:3, 3], quat_from_matrix(t[:3, :3])])


def inverse_matrix(t: np.ndarray) -> np.ndarray:
    """Inverse of a rigid 4x4 transform."""
    out = np.eye(4)
    out[:3, :3] = t[:3, :3].T
    out[:3, 3] = -t[:3, :3].T @ t[:3, 3]
    return out


def frame_of(position: Sequence[float], quat: Sequence[float]) -> Frame:
    """Frame (position, rotation matrix) of a position and a quaternion."""
    return np.asarray(position, dtype=float), rotation_matrix(quat)


def compose(a: Frame, b: Frame) -> Frame:
    """Frame ``b`` (given in frame ``a``) expressed in ``a``'s parent."""
    return a[0] + a[1] @ b[0], a[1] @ b[1]


def inverse(a: Frame) -> Frame:
    """The frame that undoes ``a``."""
    rt = a[1].T
    return -rt @ a[0], rt


def compose_poses(
    a: tuple[Sequence[float], Sequence[float]], b: tuple[Sequence[float], Sequence[float]]
) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """Pose ``b`` (position, quaternion, given in pose ``a``) expressed in ``a``'s parent."""
    pos, quat = pb.multiplyTransforms(list(a[0]), list(a[1]), list(b[0]), list(b[1]))
    return tuple(pos), tuple(quat)


def invert_pose(
    pose: tuple[Sequence[float], Sequence[float]],
) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """The pose (position, quaternion) that undoes ``pose``."""
    pos, quat = pb.invertTransform(list(pose[0]), list(pose[1]))
    return tuple(pos), tuple(quat)
