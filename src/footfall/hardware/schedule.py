"""What a Dynamixel bus can carry each control tick: the read schedule and its budget."""

from __future__ import annotations

from dataclasses import dataclass

from footfall.hardware.config import HardwareConfig

# The share of a control period the read schedule fills (headroom under 70 %).
BUS_BUDGET = 0.65


@dataclass(frozen=True)
class ReadSchedule:
    """What the backend reads back each control tick, and what the bus then carries.

    Protocol 1.0 servos have no sync read: each read is its own instruction and status,
    so a tick reads the state block (position, speed, load, voltage, temperature) of
    ``reads`` servos in turn. Protocol 2.0 reads every servo's position, speed and load in
    one sync read and the voltage and temperature of ``reads`` servos in turn.

    Attributes:
        reads: Servos read one by one per tick.
        write_bytes: Bytes of the tick's sync write.
        read_bytes: Bytes of the tick's reads and their status packets.
        seconds: Wire time of a tick's traffic at the bus's baud and return delay [s].
    """

    reads: int
    write_bytes: int
    read_bytes: int
    seconds: float

    @classmethod
    def fitting(cls, config: HardwareConfig, period: float) -> ReadSchedule:
        """The most reads per tick whose traffic fits in ``BUS_BUDGET`` of ``period`` [s]."""
        n = len(config.servos)
        if config.protocol == 1:
            write = 8 + n * 5  # sync write of goal and speed, 2 + 2 bytes each
            read_one = 8 + 6 + 8  # read of addresses 36-43 and its status
            block = 0
        else:
            write = 14 + n * 9  # sync write of profile velocity and goal, 4 + 4 bytes each
            read_one = 14 + 11 + 3  # read of addresses 144-146 and its status
            block = 14 + n + n * (11 + 10)  # sync read of addresses 126-135
        t, delay = config.byte_time, config.return_delay
        fixed = (write + block) * t + (0 if config.protocol == 1 else n * delay)
        per_read = read_one * t + delay
        reads = int((BUS_BUDGET * period - fixed) // per_read)
        reads = max(1, min(n, reads))
        return cls(reads, write, block + reads * read_one, fixed + reads * per_read)
