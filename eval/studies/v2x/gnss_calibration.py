"""The check behind the ``gnss-open-sky`` preset's calibration (docs/localisation.md): how far
apart two vehicles put the same object on the ground plane.

For every frame pair of a dataset, the localisation prior is drawn with a GNSS-like preset on
the record's own localisation seeds (``FramePair.localise_preset(preset, seed=None)``), and for
every ground-truth match (i, j) the distance between view 1's and view 2's world positions of that
object is taken on the ground plane (x, y; metres): the two vehicles' pose errors plus each
detection's own error. The statistic is compared with the same one on the external DMGM pairs
(median 2.95 m, p90 5.68 m on sequence 070). Run it on *validation* or training splits only —
never on a test split, whose noise the preset would then be fitted to:

    python -m eval.studies.v2x.gnss_calibration data/cad-val --preset gnss-open-sky
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Sequence
from pathlib import Path

import numpy as np


def match_disagreement(dataset_dirs: Sequence[str | Path], preset: str) -> np.ndarray:
    """Ground-plane distances (metres) between the two views' world positions of every true
    match of every frame pair of the datasets, under ``preset`` drawn on the records' own
    seeds; an empty array when nothing is matched."""
    from cadsim.dataset import Dataset

    out = []
    for path in dataset_dirs:
        for pair in Dataset(path, verify=True):
            prior = pair.localise_preset(preset, seed=None).prior()
            gt = np.asarray(pair.gt_pairs, dtype=np.int64).reshape(-1, 2)
            if prior is None or not len(gt):
                continue
            world1, world2, _ = prior
            gap = world1[gt[:, 0], :2] - world2[gt[:, 1], :2]
            out.append(np.sqrt((gap**2).sum(axis=1)))
    return np.concatenate(out) if out else np.zeros(0)


def summary(distances: np.ndarray) -> dict[str, float | int]:
    """Median, 90th percentile (metres) and count of the distances (NaN when none)."""
    d = np.asarray(distances, dtype=float)
    if not d.size:
        return {"median_m": float("nan"), "p90_m": float("nan"), "matches": 0}
    return {
        "median_m": round(float(np.median(d)), 3),
        "p90_m": round(float(np.percentile(d, 90)), 3),
        "matches": int(d.size),
    }


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m eval.studies.v2x.gnss_calibration",
        description="Two vehicles' ground-plane disagreement on the same object under a GNSS-like "
        "localisation preset (validation or training splits only).",
    )
    parser.add_argument("datasets", nargs="+", help="dataset folders (validation / training)")
    parser.add_argument("--preset", default="gnss-open-sky", help="localisation preset")
    args = parser.parse_args(argv)
    print(json.dumps(summary(match_disagreement(args.datasets, args.preset))))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
