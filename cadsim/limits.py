"""Upper limits on inputs whose memory or run time grows with them.

Every number a user gives (scenario file, command line) must be finite; these are the documented
ceilings where a larger value would exhaust memory or run for days rather than fail cleanly. They
are checked where the value enters (the scenario schema, the command-line types, the pipeline)
and listed with their reasons in docs/reliability.md.
"""

from __future__ import annotations

MAX_IMAGE_SIDE = 4096
"""Camera width/height, pixels. A view holds colour, depth, instance ids and noise fields at
float64 while it is detected: about 30 bytes a pixel, 0.5 GB per 4096 × 4096 view."""

MAX_PAIRS = 100_000
"""Frame pairs in one dataset (``pairs``, ``--pairs``); each record is 1–3 MB on disk."""

MAX_PAIRS_PER_EPISODE = 10_000
"""``[sampling] pairs_per_episode`` and ``pairs_per_snapshot``."""

MAX_WORKERS = 1024
"""Worker processes (``--workers``); each is a Python process with its own simulator."""

MAX_RUNS = 1000
"""Seeds per matcher (``--runs``)."""

MAX_NOISE_RATE = 1.0
"""Depth-noise rate (σ = rate · d²); at 1, σ is 400 m at 20 m depth: far past any useful sweep."""

MAX_SEED = 2**63 - 1
"""Seeds: the largest TOML integer."""

MAX_POSITION_M = 1e7
"""A stored coordinate (object centre, camera, pose, LiDAR box), metres: Earth-scale, as the
importers' ``MAX_MAGNITUDE``. Squared distances of larger ones overflow float64 in matching."""

MAX_SIZE_M = 1e5
"""A stored object's or box's side, metres: static surfaces (a road, the ground under a whole
SUMO network) are objects too, 380 m in the shipped scenarios; 100 km leaves room for any map."""

MAX_PRIOR_SIGMA_M = 1e4
"""A localisation prior's position σ, metres (scenario, record, ``--prior-sigma``): at 10 km
the prior says nothing; its square still fits every likelihood computed from it."""

MAX_SIMULATED_SECONDS = 7 * 86400.0
"""Simulated time (warm-up, sampling interval, max_time, demand end): one week."""
