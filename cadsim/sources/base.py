"""The interface every traffic source implements (SUMO, the robot arena, highway-env).

A source runs one seeded simulation (libsumo allows one per process), yields world snapshots at
the scenario's sampling instants, and proposes observer pairs for a snapshot. Everything after
this boundary (rendering, noise, detection, dataset) is source-agnostic.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Iterator
from dataclasses import dataclass, field

from cadsim.camera import Camera
from cadsim.world import Snapshot


@dataclass(frozen=True)
class ObserverPair:
    """Two cameras that may see the same scene. observer*_id: the id of the object carrying the
    camera (excluded from its own view), or "" for a camera on no object. meta: e.g. junction id."""

    camera1: Camera
    camera2: Camera
    observer1_id: str = ""
    observer2_id: str = ""
    meta: dict = field(default_factory=dict)


@dataclass(frozen=True)
class ObserverSet:
    """N cameras of one snapshot that may see the same scene (DESIGN §12), vehicles first, then
    roadside units. observer_ids: per camera, the carrying object's id ("" for none) or a
    roadside unit's id; kinds: per camera "vehicle" or "roadside" (a pole-mounted camera whose
    pose is known exactly). meta: e.g. junction id."""

    cameras: tuple[Camera, ...]
    observer_ids: tuple[str, ...]
    kinds: tuple[str, ...]
    meta: dict = field(default_factory=dict)


class TrafficSource(ABC):
    """One seeded simulation. Use as a context manager: ``with source: for snap in source.snapshots()``."""

    def __enter__(self) -> TrafficSource:
        self.start()
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def start(self) -> None:  # noqa: B027 - optional hook
        """Start the simulation (default: nothing to start)."""

    def close(self) -> None:  # noqa: B027 - optional hook
        """Release the simulation (default: nothing to release)."""

    @abstractmethod
    def snapshots(self) -> Iterator[Snapshot]:
        """Yield snapshots at the scenario's sampling instants, deterministically for the seed."""

    @abstractmethod
    def observer_pairs(self, snapshot: Snapshot) -> list[ObserverPair]:
        """Candidate observer pairs for this snapshot, in a deterministic order."""

    def follow_pair(self, snapshot: Snapshot, pair: ObserverPair) -> ObserverPair | None:
        """``pair``'s two observers at a later ``snapshot`` (a sequence's next frame, docs/
        scenarios.md "[sequence]"): their cameras mounted as at the pair's start, or None when
        one has left the scene. Must not change the source's state. Default: the candidate of
        ``observer_pairs(snapshot)`` with the same two observer ids (None if there is none)."""
        ids = (pair.observer1_id, pair.observer2_id)
        for candidate in self.observer_pairs(snapshot):
            if (candidate.observer1_id, candidate.observer2_id) == ids:
                return candidate
        return None

    def observer_sets(self, snapshot: Snapshot) -> list[ObserverSet]:
        """Candidate N-view observer sets for this snapshot (``[observers] count`` vehicles plus
        ``roadside_units``), in a deterministic order; sources without N-view support raise."""
        raise NotImplementedError(f"{type(self).__name__} gives no N-view observer sets")
