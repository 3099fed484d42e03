"""What a run records: an MCAP file, a rerun recording, or both, tapping one bus."""

from __future__ import annotations

from pathlib import Path
from types import TracebackType

from footfall.nodes.mapping import MappingNode
from footfall.runtime.bus import InProcessBus


class Recorders:
    """The recorders a run asked for, attached to its bus.

    Args:
        record: An ``.mcap`` file to write every bus message to, or None.
        rerun: An ``.rrd`` file to log the run to for the rerun viewer, or None.
        rerun_spawn: Also open a rerun viewer on the run.
        metadata: Metadata records for the MCAP file.
    """

    def __init__(
        self,
        record: Path | None = None,
        rerun: Path | None = None,
        rerun_spawn: bool = False,
        metadata: dict[str, dict[str, str]] | None = None,
    ) -> None:
        self.mcap = None
        self.rerun = None
        if record is not None:
            from footfall.recording.writer import McapRecorder

            self.mcap = McapRecorder(record, metadata)
        if rerun is not None or rerun_spawn:
            from footfall.recording.rerun_log import RerunLogger

            self.rerun = RerunLogger(rerun, spawn=rerun_spawn)

    def attach(self, bus: InProcessBus) -> InProcessBus:
        """Tap ``bus`` (returned, for chaining)."""
        for recorder in (self.mcap, self.rerun):
            if recorder is not None:
                bus.tap(recorder.tap)
        return bus

    def mapping_started(self, node: MappingNode) -> None:
        """Note the mapping node's settings, so a replay builds the same map."""
        if self.mcap is not None:
            from footfall.recording.writer import mapping_metadata

            self.mcap.add_metadata("footfall/mapping", mapping_metadata(node))

    def close(self) -> None:
        """Finish every file."""
        for recorder in (self.mcap, self.rerun):
            if recorder is not None:
                recorder.close()

    def __enter__(self) -> Recorders:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        self.close()
