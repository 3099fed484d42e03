"""Messages of the radio link between the robot and its station (``runtime/wire.py``).

On the robot, nodes exchange full-precision messages. Over a radio link the station gets
what it draws, packed: the map quantised and sent as the cells that changed since a whole
map, depth as compressed millimetres, colour as JPEG. A receiving bus turns each back
into the message it stands for before any subscriber sees it, and acknowledges it, so the
sender can keep what is in flight on the link to what the link carries.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from footfall.errors import MessageError
from footfall.messages.codec import Message
from footfall.sensing.camera import PinholeCamera
from footfall.sensing.pose import Pose


@dataclass(frozen=True)
class PackedMap(Message):
    """A map update quantised for the station, whole or as the cells changed since one.

    Attributes:
        stamp: The update's stamp [s].
        sequence: The update's number.
        base: Sequence of the whole map the changed cells apply to; 0 for a whole map.
        origin: World ``(x, y)`` of the corner of cell ``[0, 0]`` [m].
        resolution: Cell side [m].
        rows: Cells along x.
        cols: Cells along y.
        height_offset_mm: Added to every height [mm] (heights travel as 16-bit offsets).
        has_spread: Whether the map keeps each cell's spread (the layer travels).
        cells: The zstd-compressed layers (see :mod:`footfall.runtime.wire`).
        link_sequence: Number of this message among everything the sender sent packed.
        offered_at: When the robot offered it to the link, before it waited its turn
            (``time.time()``): its age at a receiver counts from here [s].
    """

    TOPIC = "map"

    stamp: float
    sequence: int
    base: int
    origin: tuple[float, float]
    resolution: float
    rows: int
    cols: int
    height_offset_mm: int
    has_spread: bool
    cells: npt.NDArray[np.uint8]
    link_sequence: int = 0
    offered_at: float = 0.0

    def __post_init__(self) -> None:
        if self.rows <= 0 or self.cols <= 0:
            raise MessageError(f"a packed map needs cells, got {self.rows} x {self.cols}")
        if not self.resolution > 0:
            raise MessageError(f"map resolution must be positive, got {self.resolution}")


@dataclass(frozen=True)
class PackedDepth(Message):
    """A depth image as zstd-compressed 16-bit millimetres (0: no reading).

    Attributes:
        stamp: Capture time [s].
        sequence: Frame number.
        intrinsics: The packed image's camera (after any decimation).
        camera_in_body: The optical frame in the body frame.
        depth_mm: The zstd-compressed little-endian ``uint16`` image, row-major.
        link_sequence: Number of this message among everything the sender sent packed.
        offered_at: When the robot offered it to the link, before it waited its turn
            (``time.time()``): its age at a receiver counts from here [s].
    """

    TOPIC = "depth"

    stamp: float
    sequence: int
    intrinsics: PinholeCamera
    camera_in_body: Pose
    depth_mm: npt.NDArray[np.uint8]
    link_sequence: int = 0
    offered_at: float = 0.0


@dataclass(frozen=True)
class PackedColor(Message):
    """A colour image as JPEG.

    Attributes:
        stamp: Capture time [s].
        sequence: Frame number.
        jpeg: The JPEG file's bytes.
        link_sequence: Number of this message among everything the sender sent packed.
        offered_at: When the robot offered it to the link, before it waited its turn
            (``time.time()``): its age at a receiver counts from here [s].
    """

    TOPIC = "color"

    stamp: float
    sequence: int
    jpeg: npt.NDArray[np.uint8]
    link_sequence: int = 0
    offered_at: float = 0.0


@dataclass(frozen=True)
class LinkAck(Message):
    """A receiver's word that packed messages arrived (sent a few times a second).

    Attributes:
        link_sequences: The messages' ``link_sequence`` numbers.
        received_at: When the last of them arrived (``time.time()``) [s].
        receiver: Who received them (the receiving session's id).
    """

    TOPIC = "link/ack"

    link_sequences: npt.NDArray[np.int64]
    received_at: float
    receiver: str = ""


@dataclass(frozen=True)
class WholeMapRequest(Message):
    """A receiver asks for a whole map: it has just joined, or missed the one changes apply to.

    Attributes:
        stamp: When it asked (``time.time()``) [s].
        receiver: Who asks.
    """

    TOPIC = "link/whole"

    stamp: float
    receiver: str = ""
