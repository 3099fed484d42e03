"""Reliability: the terrain sweep, walking through injected faults, and long runs.

:mod:`footfall.reliability.terrain_bench` walks every terrain over its difficulty range;
both it and the fault benchmark walk every robot and gait asked for
(:mod:`footfall.reliability.variants`);
:mod:`footfall.reliability.faults_bench` walks every fault class over the terrains and
measures what map drift compensation does to the map's error; :mod:`footfall.reliability.soak`
walks laps for a long time and samples memory and per-frame times. The benchmarks' walks run
where :mod:`footfall.reliability.parallel` puts them: in this process, in processes on this
machine, or as tasks on a Ray cluster (:mod:`footfall.reliability.cluster`).
"""
