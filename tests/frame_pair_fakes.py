"""In-memory frame-pair datasets for evaluation tests: real ``FramePair`` objects (so thinning,
``problem()`` with box centres and the real matchers work) without rendering anything.

Each pair has `covisible` objects seen by both views and `only1` / `only2` seen by one view;
view 2 sees the scene rotated about the vertical axis and shifted, with small position noise,
and every object has its own appearance vector (plus noise per view).
"""

from __future__ import annotations

import numpy as np

from cadsim.dataset.detections import ViewDetections
from cadsim.dataset.reader import FramePair


def _view(ids, positions, features, rng) -> ViewDetections:
    k = len(ids)
    corner = rng.uniform(0, 600, size=(k, 2))
    return ViewDetections(
        positions=positions,
        boxes=np.hstack([corner, corner + rng.uniform(5, 40, size=(k, 2))]),
        features=features.astype(np.float32),
        object_ids=list(ids),
        true_classes=["car"] * k,
        pixels=rng.integers(50, 500, size=k),
    )


def make_pair(
    index: int,
    sim_seed: int,
    covisible: int = 4,
    only1: int = 6,
    only2: int = 5,
    noise: float = 0.05,
    episode: int | None = None,
) -> FramePair:
    rng = np.random.default_rng(sim_seed)
    n = covisible + only1 + only2
    world = rng.uniform(-10, 10, size=(n, 3))
    looks = rng.normal(size=(n, 8))
    ids = np.array([f"o{sim_seed}_{k}" for k in range(n)])
    in1 = np.r_[np.arange(covisible), covisible + np.arange(only1)]
    in2 = np.r_[covisible + only1 + np.arange(only2), np.arange(covisible)[::-1]]
    angle = rng.uniform(0, 2 * np.pi)
    c, s = np.cos(angle), np.sin(angle)
    rot = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    shift = rng.uniform(-3, 3, size=3)
    p1 = world[in1] + rng.normal(scale=noise, size=(len(in1), 3))
    p2 = world[in2] @ rot.T + shift + rng.normal(scale=noise, size=(len(in2), 3))
    f1 = looks[in1] + rng.normal(scale=0.3, size=(len(in1), 8))
    f2 = looks[in2] + rng.normal(scale=0.3, size=(len(in2), 8))
    entry = {
        "name": f"e{index:05d}_s00",
        "episode": index if episode is None else episode,
        "slot": 0,
        "sim_seed": sim_seed,
        "checksum": f"{sim_seed:064x}",
    }
    views = (_view(ids[in1], p1, f1, rng), _view(ids[in2], p2, f2, rng))
    return FramePair("/nonexistent", index, entry, {}, {}, views, noise_rate=0.0)


class MemoryDataset(list):
    """A list of frame pairs with the attributes the evaluation reads from a ``Dataset``."""

    def __init__(self, pairs, checksum: str, scenario: str):
        super().__init__(pairs)
        self.checksum = checksum
        self.scenario_name = scenario
        self.manifest = {"scenario": {"name": scenario}}

    def verify_once(self) -> None:
        """In memory: nothing to re-hash."""


def make_dataset(
    first_seed: int, pairs: int, scenario: str = "cad-fake", per_episode: int = 2, **kwargs
) -> MemoryDataset:
    items = [make_pair(k, first_seed + k, episode=k // per_episode, **kwargs) for k in range(pairs)]
    return MemoryDataset(items, f"sum-{scenario}-{first_seed}", scenario)
