"""Seed derivation. Every random stream of a dataset comes from the root seed (the scenario's or
``--seed``) and the record's identity through ``numpy.random.SeedSequence(root, spawn_key=...)``,
so a record never depends on the order or the process in which it was computed.

stream 0: simulation seed of episode e         spawn_key (0, e)
stream 1: depth noise of (episode, slot, view) spawn_key (1, e, s, v)   v = 1 or 2
stream 3: detector attributes of (e, s, v)     spawn_key (3, e, s, v)   (class confusion, size noise)
stream 4: localisation error of (e, s, v)      spawn_key (4, e, s, v)
stream 6: odometry of a sequence's view v      spawn_key (6, e, s0, v)  s0: the sequence's first slot

SUMO's random demand (``cadsim.sources.sumo.demand``, demand model 1) is stream 9 under the
episode's *simulation seed*: spawn_key (9, kind), kind 0 vehicles, 1 bicycles, 2 persons.

Object sizes (``cadsim.object_sizes``, size model 2; SUMO sources) are drawn per object, not per
record: stream 7 under the episode's *simulation seed* for a vehicle or person
(spawn_key (7, crc32(id), crc32(reversed id + "#"))), the same under the *scenario seed* for
signs, signal poles and roadside clutter, whose placement is stream 8 under the scenario seed
(``cadsim.sources.sumo.roadside_clutter``). An object's size depends on its id and that seed
only, never on which other objects exist.

Redraws at evaluation time (seed scheme 2). ``FramePair.redetect(rate, seed)`` and
``FramePair.localise(…, seed)`` / ``localise_preset(preset, seed)`` draw a *run*'s depth noise and
pose errors from :func:`redraw_seed`: the run seed together with the record's identity *including
its simulation seed*, which is derived from the dataset's own root seed. Two datasets made with
different seeds (a validation and a test split) therefore never share a run's noise, although
their records have the same (episode, slot) numbers — under seed scheme 1 the run seed alone was
the root, so every split saw the same per-view GNSS bias, heading error and outliers in run r.
A sequence's odometry drift is redrawn the same way, per view, from the sequence's first
record (:func:`cadsim.dataset.sequence_odometry.redraw_odometry`, stream :data:`ODOMETRY_STREAM`
with the slot of frame 0). ``seed=None`` gives back the record's own draws (the stored detections, the stored prior: the
seeds written at generation). Across rates the noise field is the same one, scaled (common
random numbers for noise sweeps). The attribute seed is stored in the record and reused by
``redetect`` whatever its seed: which objects a view's detector misclassifies is part of the
dataset, not of a noise run.
"""

from __future__ import annotations

import numpy as np

_SIM, _NOISE, _REDETECT, _ATTRIBUTES, _LOCALISATION = 0, 1, 2, 3, 4
_RUN_EPISODE = 5  # a run's per-episode draws (the GNSS bias and drift of a redrawn prior)
_ODOMETRY = 6  # a sequence's odometry drift, per view (cadsim.sensing.odometry)
SEED_SCHEME = 2
"""Version of the evaluation-time seed derivation (module docstring); the run record states it."""
NOISE_STREAM, LOCALISATION_STREAM, ODOMETRY_STREAM = _NOISE, _LOCALISATION, _ODOMETRY


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


def odometry_seed(root: int, episode: int, first_slot: int, view: int) -> int:
    """Seed of view ``view``'s odometry over the sequence whose first frame is record
    (episode, first_slot) (:class:`cadsim.sensing.odometry.Odometer`)."""
    ss = np.random.SeedSequence(_check(root), spawn_key=(_ODOMETRY, episode, first_slot, view))
    return int(ss.generate_state(1, np.uint64)[0] >> 1)


def redraw_seed(
    stream: int, run_seed: int, sim_seed: int, episode: int, slot: int, view: int
) -> int:
    """Seed of a run's redraw of ``stream`` (:data:`NOISE_STREAM`, :data:`LOCALISATION_STREAM`
    or :data:`ODOMETRY_STREAM`) for view ``view`` of record (episode, slot) whose simulation seed is ``sim_seed`` (which
    carries the dataset's root seed): ``SeedSequence([run_seed, sim_seed], spawn_key=(stream,
    episode, slot, view))``."""
    entropy = [_check(run_seed), _check(sim_seed)]
    ss = np.random.SeedSequence(entropy, spawn_key=(int(stream), episode, slot, view))
    return int(ss.generate_state(1, np.uint64)[0] >> 1)


def redraw_episode_seed(run_seed: int, sim_seed: int, episode: int) -> int:
    """Seed of a run's per-episode draws (a redrawn prior's GNSS bias and drift) for the episode
    simulated with ``sim_seed``; in [0, 2**31) like :func:`simulation_seed`."""
    entropy = [_check(run_seed), _check(sim_seed)]
    ss = np.random.SeedSequence(entropy, spawn_key=(_RUN_EPISODE, episode))
    return int(ss.generate_state(1, np.uint32)[0] >> 1)
