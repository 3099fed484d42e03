"""The exception hierarchy of footfall: one base class, subclasses that say what went wrong."""

from __future__ import annotations


class FootfallError(Exception):
    """Base class of every error footfall raises on purpose."""


class ConfigError(FootfallError, ValueError):
    """A configuration or robot description holds a value outside what is allowed."""


class UnreachableTargetError(FootfallError, ValueError):
    """A foot target lies outside a leg's workspace or joint limits.

    Attributes:
        leg: Name of the leg that cannot reach its target.
        excess_m: How far the target is out of reach [m]; for a joint-limit violation the
            distance the foot would have to move is not known and this is ``nan``.
    """

    def __init__(self, leg: str, message: str, excess_m: float) -> None:
        super().__init__(f"leg {leg}: {message}")
        self.leg = leg
        self.excess_m = excess_m


class SingularConfigurationError(FootfallError, ValueError):
    """A leg is at (or too near) a kinematic singularity to map foot velocity to joint rates."""


class DepthImageError(FootfallError, ValueError):
    """A depth image has the wrong shape or type, or no scale for integer depth."""


class InvalidPoseError(FootfallError, ValueError):
    """A pose is not a rigid transform: a non-unit quaternion, a non-finite value."""


class DatasetError(FootfallError, ValueError):
    """A recorded sequence is missing files or holds malformed entries."""


class PlanningError(FootfallError, ValueError):
    """A path cannot be planned: the start or goal lies in an obstacle, or no path exists."""


class MessageError(FootfallError, ValueError):
    """Bytes that do not decode to the message expected: truncated, corrupt, another version."""


class BackendError(FootfallError, RuntimeError):
    """The robot cannot go on: a servo stopped answering, overheated or is overloaded."""


class ClusterError(FootfallError, RuntimeError):
    """A cluster cannot run the walks: no cluster at its address, or a walk lost too often."""


class CameraError(FootfallError, RuntimeError):
    """The camera cannot go on: none connected, no depth stream, unplugged, a bad frame."""
