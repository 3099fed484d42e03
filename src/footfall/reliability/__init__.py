"""Reliability: walking through injected faults, and long runs that keep bounded memory.

:mod:`footfall.reliability.faults_bench` walks every fault class over the terrains and
measures what map drift compensation does to the map's error; :mod:`footfall.reliability.soak`
walks laps for a long time and samples memory and per-frame times.
"""
