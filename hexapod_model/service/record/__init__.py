"""The record a fixture's cycle publishes for each reading set, and its pose values."""

from .pose import POSE_KEYS, pose_record
from .pose_record import RECORD_KEYS, PoseRecord

__all__ = ["POSE_KEYS", "RECORD_KEYS", "PoseRecord", "pose_record"]
