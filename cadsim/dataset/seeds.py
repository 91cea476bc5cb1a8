"""Seed derivation. Every random stream of a dataset comes from the root seed (the scenario's or
``--seed``) and the record's identity through ``numpy.random.SeedSequence(root, spawn_key=...)``,
so a record never depends on the order or the process in which it was computed.

stream 0: simulation seed of episode e         spawn_key (0, e)
stream 1: depth noise of (episode, slot, view) spawn_key (1, e, s, v)   v = 1 or 2
stream 3: detector attributes of (e, s, v)     spawn_key (3, e, s, v)   (class confusion, size noise)
stream 4: localisation error of (e, s, v)      spawn_key (4, e, s, v)

``FramePair.redetect(rate, seed)`` draws its noise from stream 1 with ``seed`` as the root: with
the dataset's own root seed and noise rate it reproduces the stored detections exactly, and across
rates the noise field is the same one, scaled (common random numbers for noise sweeps). The
attribute seed is stored in the record and reused by ``redetect`` whatever its seed: which objects
a view's detector misclassifies is part of the dataset, not of a noise run.
``FramePair.localise(position_sigma_m, yaw_sigma_deg, seed)`` draws the observers' pose errors from
stream 4 the same way (the dataset's root seed gives back the record's own prior).
"""

from __future__ import annotations

import numpy as np

_SIM, _NOISE, _REDETECT, _ATTRIBUTES, _LOCALISATION = 0, 1, 2, 3, 4


def _check(root: int) -> int:
    if not isinstance(root, int | np.integer) or isinstance(root, bool) or root < 0:
        raise ValueError(f"seed: expected a non-negative integer, got {root!r}")
    return int(root)


def simulation_seed(root: int, episode: int) -> int:
    """Seed for episode ``episode``'s simulation, in [0, 2**31) (SUMO's --seed is an int)."""
    ss = np.random.SeedSequence(_check(root), spawn_key=(_SIM, episode))
    return int(ss.generate_state(1, np.uint32)[0] >> 1)


def noise_seed(root: int, episode: int, slot: int, view: int) -> int:
    """Seed of the depth noise of view ``view`` (1 or 2) of record (episode, slot)."""
    ss = np.random.SeedSequence(_check(root), spawn_key=(_NOISE, episode, slot, view))
    return int(ss.generate_state(1, np.uint64)[0] >> 1)


def attribute_seed(root: int, episode: int, slot: int, view: int) -> int:
    """Seed of the detector's attribute errors (class confusion, size noise) of view ``view``
    (1 or 2) of record (episode, slot)."""
    ss = np.random.SeedSequence(_check(root), spawn_key=(_ATTRIBUTES, episode, slot, view))
    return int(ss.generate_state(1, np.uint64)[0] >> 1)


def localisation_seed(root: int, episode: int, slot: int, view: int) -> int:
    """Seed of the localisation (pose) error of view ``view`` (1 or 2) of record (episode, slot)."""
    ss = np.random.SeedSequence(_check(root), spawn_key=(_LOCALISATION, episode, slot, view))
    return int(ss.generate_state(1, np.uint64)[0] >> 1)
