"""The base station: a browser page (viser) over the robot's messages."""

from footfall.station.page import HEARTBEAT_HZ as HEARTBEAT_HZ
from footfall.station.page import Station as Station
from footfall.station.views import ground_point as ground_point

__all__ = ["HEARTBEAT_HZ", "Station", "ground_point"]
