"""The fault spec of ``footfall walk --faults``: comma-separated ``name=value`` items.

See :mod:`footfall.runtime.faults` for what each fault does and the link that injects them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace

from footfall.errors import ConfigError
from footfall.sensing.pose import SlamNoiseConfig

FAULT_NAMES = ("drop", "delay", "repeat", "nan", "drift", "jump", "pose_loss", "overrun")


@dataclass(frozen=True)
class PoseJump:
    """A step change of the pose estimate.

    Attributes:
        distance_m: Horizontal translation [m].
        angle_deg: Rotation [degrees].
        at_s: When [s].
    """

    distance_m: float
    angle_deg: float
    at_s: float


@dataclass(frozen=True)
class FaultSpec:
    """Which faults to inject (all off by default).

    Attributes:
        drop: Fraction of depth frames lost.
        delay_s: How late every depth frame arrives [s].
        repeat: Fraction of depth frames that repeat the previous image.
        nan: Fraction of each image covered by NaN and zero-depth patches.
        drift: SLAM-like drift and jitter on the pose estimate, or None.
        jumps: Pose jumps.
        pose_loss: ``(duration, start)`` of a pose outage [s], or None.
        overrun: Fraction of control ticks that run late.
    """

    drop: float = 0.0
    delay_s: float = 0.0
    repeat: float = 0.0
    nan: float = 0.0
    drift: SlamNoiseConfig | None = None
    jumps: tuple[PoseJump, ...] = ()
    pose_loss: tuple[float, float] | None = None
    overrun: float = 0.0

    def __post_init__(self) -> None:
        for name in ("drop", "repeat", "nan", "overrun"):
            value = getattr(self, name)
            if not 0.0 <= value < 1.0:
                raise ConfigError(f"fault {name}={value}: a fraction in [0, 1) is needed")
        if not (math.isfinite(self.delay_s) and 0.0 <= self.delay_s <= 10.0):
            raise ConfigError(f"fault delay={self.delay_s}: seconds in [0, 10] are needed")
        for jump in self.jumps:
            if not (
                math.isfinite(jump.distance_m)
                and math.isfinite(jump.angle_deg)
                and math.isfinite(jump.at_s)
                and 0.0 <= jump.distance_m <= 10.0
                and 0.0 <= jump.angle_deg <= 180.0
                and jump.at_s >= 0.0
            ):
                raise ConfigError(
                    f"fault jump={jump.distance_m}:{jump.angle_deg}@{jump.at_s}: needs a "
                    "distance in [0, 10] m, an angle in [0, 180] degrees and a time >= 0 s"
                )
        if self.pose_loss is not None:
            duration, start = self.pose_loss
            if not (math.isfinite(duration) and math.isfinite(start)) or duration <= 0 or start < 0:
                raise ConfigError(
                    f"fault pose_loss={duration}@{start}: needs a duration > 0 s and a start >= 0 s"
                )

    @property
    def active(self) -> bool:
        """Whether any fault is on."""
        return self != FaultSpec()

    @property
    def sensor_faults(self) -> bool:
        """Whether any fault acts on the depth frames or the pose estimates."""
        return replace(self, overrun=0.0).active

    @classmethod
    def parse(cls, text: str) -> FaultSpec:
        """A spec from comma-separated ``name=value`` items (see the module docstring).

        Raises:
            ConfigError: An unknown name, a repeated one (other than ``jump``), or a value
                that does not parse or lies out of range.
        """
        values: dict[str, object] = {}
        jumps: list[PoseJump] = []
        for item in (part.strip() for part in text.split(",")):
            if not item:
                continue
            name, sep, value = item.partition("=")
            name, value = name.strip(), value.strip()
            if not sep or not value:
                raise ConfigError(f"fault {item!r}: write name=value")
            if name not in FAULT_NAMES:
                raise ConfigError(f"unknown fault {name!r}; choose from {', '.join(FAULT_NAMES)}")
            if name == "jump":
                jumps.append(_parse_jump(value))
                continue
            if name in values:
                raise ConfigError(f"fault {name!r} is given twice")
            if name == "drift":
                model, _, times = value.partition(":")
                if model != "slam":
                    raise ConfigError(
                        f"fault drift={value!r}: the drift model is 'slam' (or 'slam:K', K "
                        "times its magnitudes)"
                    )
                k = _number(times, "drift") if times else 1.0
                if not 0.0 < k <= 100.0:
                    raise ConfigError(f"fault drift={value!r}: a scale in (0, 100] is needed")
                base = SlamNoiseConfig()
                values["drift"] = SlamNoiseConfig(
                    **{f.name: k * getattr(base, f.name) for f in fields(base)}
                )
            elif name == "pose_loss":
                duration, at = _parse_at(value, "pose_loss", "SECONDS@START")
                values["pose_loss"] = (_number(duration, "pose_loss"), at)
            else:
                values["delay_s" if name == "delay" else name] = _number(value, name)
        return cls(jumps=tuple(jumps), **values)  # type: ignore[arg-type]


def _number(text: str, name: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise ConfigError(f"fault {name}={text!r}: not a number") from None
    if not math.isfinite(value):
        raise ConfigError(f"fault {name}={text!r}: not a finite number")
    return value


def _parse_at(text: str, name: str, form: str) -> tuple[str, float]:
    head, sep, at = text.partition("@")
    if not sep:
        raise ConfigError(f"fault {name}={text!r}: write {name}={form}")
    return head, _number(at, name)


def _parse_jump(text: str) -> PoseJump:
    head, at = _parse_at(text, "jump", "METRES:DEGREES@SECONDS")
    distance, sep, angle = head.partition(":")
    if not sep:
        raise ConfigError(f"fault jump={text!r}: write jump=METRES:DEGREES@SECONDS")
    return PoseJump(_number(distance, "jump"), _number(angle, "jump"), at)
