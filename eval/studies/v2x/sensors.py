"""Camera against LiDAR on the same frames and the same objects (``results/table_v2x_sensors.csv``):
per localisation preset and matcher, the difference LiDAR − camera of the test F1 on each frame
pair of the two-sensor split (``scenarios/cad-v2x-both.toml``: every record holds the camera
detections and the LiDAR boxes of one frame; :mod:`eval.studies.v2x.lidar` evaluates it as each
sensor), each sensor's detections restricted to the region both cover — the camera's frustum up
to its detector's range, within the LiDAR's range — decided from each detection's reported centre
alone (``sensor="lidar-common"`` / ``"camera-common"``, :mod:`cadsim.sensing.lidar.camera_coverage`;
false positives kept or dropped by the same rule, never by ids). So a difference is the sensors',
not their coverage's; the LiDAR's boxes outside that region are counted apart
(:func:`coverage_counts`: the ``*_per_view`` columns).

Protocol. For each (preset, matcher) evaluated on both sensors: F1 per frame pair averaged over
the runs (seeds), d = F1(LiDAR) − F1(camera) per frame pair (a difference of fractions), its
mean with the cluster-robust t-interval over episodes (:mod:`eval.protocol.cluster_interval`:
equal episode sizes give the t-interval of episode means), and the two-sided p-value of the
same t-statistic. Holm's adjustment (:mod:`eval.protocol.holm`) runs over the file's distinct
comparisons: a matcher that reads no prior gives the same per-pair differences under every preset
with the prior (``exact``, ``rtk``, …), and such repeated rows are one comparison in the family,
their adjusted p shared; a sensor is said to favour a matcher only where the Holm-adjusted p is at most
:data:`ALPHA` (so the 95 % interval excludes 0 too). A matcher that cannot run under a preset
(a prior reader under ``denied``, :func:`eval.core.abstention.cannot_run`) is not compared
there: no input, no number (DESIGN §3).

Which matchers are compared: per preset and matcher family (with / without the prior) the
matcher of highest validation F1 averaged over the two sensors' *full* evaluations
(:func:`chosen_per_family`) — a choice made on validation only, and the same method on both
sensors, so a row compares sensors, not methods. Each runs on the common region with the
parameters and τ its sensor's full evaluation chose (the region restricts what is scored, not
how a matcher was tuned; no tuning or calibration is repeated on it). Every row is ``chosen``;
the report's "cameras / LiDAR favour it" lines are made from these rows alone
(:func:`sensor_lines`), Holm's family is theirs.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from eval.core.result_files import write_csv
from eval.protocol.claims import AHEAD, BEHIND, NOT_SHOWN, Claim, printed
from eval.protocol.cluster_interval import t_interval, t_p_value
from eval.protocol.holm import holm_distinct

NAME = "v2x_sensors"
ALPHA = 0.05
LEVEL = 0.95
LIDAR_FAVOURS = "LiDAR favours it"
CAMERA_FAVOURS = "cameras favour it"
INCLUDES_ZERO = "the interval includes 0"
NOT_AFTER_HOLM = "beyond 0 only before Holm's adjustment"
FAMILIES = ((True, "with the prior"), (False, "without a prior"))
COLUMNS = (
    "preset",
    "matcher",
    "family",
    "chosen",
    "lidar_f1",
    "camera_f1",
    "diff",
    "ci_low",
    "ci_high",
    "clusters",
    "pairs",
    "p_value",
    "p_holm",
    "verdict",
    "objects",
    "camera_per_view",
    "lidar_per_view",
    "lidar_extra_per_view",
    "lidar_extra_false_per_view",
)
COVERED = "in both sensors' coverage (camera frustum and range)"
"""The ``objects`` column: which detections the comparison is made on."""


def _pair_means(per_pair: pd.DataFrame) -> pd.DataFrame:
    """Per (preset, matcher, frame pair): F1 averaged over runs, with the pair's episode and
    simulation seed (its identity beside the index)."""
    return (
        per_pair.groupby(["preset", "matcher", "pair"], sort=False)
        .agg(f1=("f1", "mean"), episode=("episode", "first"), sim_seed=("sim_seed", "first"))
        .reset_index()
    )


def sensor_differences(
    lidar: pd.DataFrame,
    camera: pd.DataFrame,
    validation: Mapping[str, Mapping[str, float]] | None = None,
    level: float = LEVEL,
    coverage: Mapping[str, float] | None = None,
) -> pd.DataFrame:
    """:data:`COLUMNS` rows from the per-pair metrics of the same split read as LiDAR and as
    camera (``metrics_per_pair.csv`` of :func:`eval.studies.v2x.table.evaluate_v2x`, with a
    ``preset`` column); ``validation``: {preset: {matcher: validation F1 averaged over the two
    sensors}} to mark the ``chosen`` rows (module docstring); ``coverage``: the split's
    :func:`coverage_counts` (the last columns; absent: empty). ValueError when a frame pair's
    episode or simulation seed differs between the two: they are not the same frames."""
    from eval.core.abstention import cannot_run
    from eval.studies.v2x.table import reads_prior

    joined = _pair_means(lidar).merge(
        _pair_means(camera), on=["preset", "matcher", "pair"], suffixes=("_lidar", "_camera")
    )
    differ = (joined["episode_lidar"] != joined["episode_camera"]) | (
        joined["sim_seed_lidar"] != joined["sim_seed_camera"]
    )
    if differ.any():
        bad = joined[differ].iloc[0]
        raise ValueError(
            f"frame pair {bad.pair} of preset {bad.preset!r}: episode/simulation seed differ "
            "between the LiDAR and the camera runs: not the same frames"
        )
    rows, keys = [], []
    for (preset, matcher), group in joined.groupby(["preset", "matcher"], sort=False):
        if cannot_run(matcher, preset):
            continue  # no input, no number (eval.core.abstention)
        prior = reads_prior(matcher)
        d = (group["f1_lidar"] - group["f1_camera"]).to_numpy()
        episodes = group["episode_lidar"].to_numpy()
        diff, low, high, clusters = t_interval(d, episodes, level, bounds=(-1.0, 1.0))
        keys.append((matcher, tuple(group["pair"]), d.tobytes()))  # the same comparison
        rows.append(
            {"preset": preset, "matcher": matcher, "family": dict(FAMILIES)[prior]}
            | {"lidar_f1": group["f1_lidar"].mean(), "camera_f1": group["f1_camera"].mean()}
            | {"diff": diff, "ci_low": low, "ci_high": high, "clusters": clusters}
            | {"pairs": len(group), "p_value": t_p_value(d, episodes)}
        )
    table = pd.DataFrame(rows, columns=[c for c in COLUMNS if c not in ("chosen", "p_holm", "verdict")])  # fmt: skip
    table["p_holm"] = holm_distinct(table["p_value"].to_numpy(), keys) if len(table) else []
    table["verdict"] = [_verdict(r) for r in table.itertuples(index=False)]
    table["chosen"] = _chosen(table, validation or {})
    for key, value in (coverage or {}).items():
        table[key] = value
    return table.reindex(columns=list(COLUMNS))


def _verdict(row) -> str:
    if np.isfinite(row.p_holm) and row.p_holm <= ALPHA and row.diff != 0:
        return LIDAR_FAVOURS if row.diff > 0 else CAMERA_FAVOURS
    if not (np.isfinite(row.ci_low) and np.isfinite(row.ci_high)):
        return INCLUDES_ZERO if row.diff == 0 else "no interval (one episode)"
    return INCLUDES_ZERO if row.ci_low <= 0 <= row.ci_high else NOT_AFTER_HOLM


def _chosen(table: pd.DataFrame, validation: Mapping[str, Mapping[str, float]]) -> list[bool]:
    """Per row: whether it is its (preset, family)'s matcher of highest validation F1 among the
    table's rows (:func:`chosen_per_family`'s rule; no figures at all: none is chosen)."""
    picked = {
        (preset, name)
        for preset, rows in table.groupby("preset", sort=False)
        for name in chosen_per_family(
            {preset: validation.get(preset) or {}}, list(rows["matcher"])
        ).get(preset, [])
    }
    return [(p, m) in picked for p, m in zip(table["preset"], table["matcher"], strict=True)]


def mean_validation(*tables: Mapping[str, Mapping[str, float]]) -> dict[str, dict[str, float]]:
    """{preset: {matcher: mean of its validation F1 over ``tables``}}, only where every table
    has a figure (each table: {preset: {matcher: validation F1}})."""
    out: dict[str, dict[str, float]] = {}
    for preset in tables[0] if tables else {}:
        common = set.intersection(*(set(t.get(preset, {})) for t in tables))
        out[preset] = {m: float(np.mean([t[preset][m] for t in tables])) for m in sorted(common)}
    return out


_SAME_OBSERVER_KEYS = ("id", "camera", "pose", "noise_seed", "attribute_seed", "localisation_seed")


def same_camera_frames(camera_dir: str | Path, both_dir: str | Path) -> bool:
    """Whether camera dataset ``camera_dir`` holds, record by record, what two-sensor dataset
    ``both_dir`` gives when read as camera: the same record names, ``detections.npz`` bytes,
    time, objects, observers (cameras, poses, seeds) and prior — so every run on one is the
    same run on the other (its runs can stand for the other's)."""
    from cadsim.dataset import Dataset, layout

    a, b = Dataset(camera_dir), Dataset(both_dir)
    if len(a) != len(b) or b.sensor is not None:
        return False

    def frame(pair) -> tuple:
        r = pair.record
        observers = [{k: o.get(k) for k in _SAME_OBSERVER_KEYS} for o in r["observers"]]
        return pair.name, r["time"], r["objects"], observers, r.get("prior")

    for pa, pb in zip(a, b, strict=True):
        files = [p.path / layout.DETECTIONS_NPZ for p in (pa, pb)]
        if frame(pa) != frame(pb) or files[0].read_bytes() != files[1].read_bytes():
            return False
    return True


def camera_fully_covered(dataset_dir: str | Path) -> bool:
    """Whether no camera detection of two-sensor dataset ``dataset_dir`` lies outside the region
    both sensors cover (then its camera runs are its ``"camera-common"`` runs)."""
    from cadsim.dataset import Dataset

    whole, common = Dataset(dataset_dir), Dataset(dataset_dir, sensor="camera-common")
    return all(
        len(a.view1) == len(b.view1) and len(a.view2) == len(b.view2)
        for a, b in zip(whole, common, strict=True)
    )


def coverage_counts(dataset_dir: str | Path) -> dict[str, float]:
    """Per view of two-sensor dataset ``dataset_dir``, on average: the camera's and the LiDAR's
    detections in the region both cover, the LiDAR's boxes outside it and how many of those are
    false positives (no object's id) — the ``objects`` … ``lidar_extra_false_per_view`` columns.
    Counted once per dataset content and code: kept under ``<cadsim cache>/derived/`` in the
    form of :mod:`eval.core.digest_store`, keyed by the dataset's checksum, the result cache's
    code version (the readers) and this module's source."""
    from cadsim.dataset import Dataset
    from eval.core.cache import code_version
    from eval.core.digest_store import DigestStore, key_of, sources_version
    from matchers.core.jit import cache_root

    root = Path(__file__).resolve().parents[3]
    source = sources_version(
        "coverage counts 1", root, [Path(__file__).relative_to(root).as_posix()]
    )
    described = [Dataset(dataset_dir).checksum, code_version(), source]
    key = key_of(described)
    store = DigestStore(cache_root() / "derived", "coverage counts", 1, 1 << 16)
    found = store.load(key, lambda payload: _plain_counts(payload["counts"]))
    if found is None:
        found = _coverage_counts(dataset_dir)
        store.store(key, {"counts": found})
    return found


def _plain_counts(counts) -> dict[str, float]:
    """Stored counts as :func:`coverage_counts` returns them; ValueError unless they have its
    keys, ``objects`` text and the rest numbers."""
    keys = ("objects", "camera_per_view", "lidar_per_view", "lidar_extra_per_view", "lidar_extra_false_per_view")  # fmt: skip
    if not isinstance(counts, dict) or list(counts) != list(keys):
        raise ValueError("counts: not the coverage columns")
    if not isinstance(counts["objects"], str) or not all(
        isinstance(counts[k], int | float) and not isinstance(counts[k], bool) for k in keys[1:]
    ):
        raise ValueError("counts: a value of the wrong type")
    return counts


def _coverage_counts(dataset_dir: str | Path) -> dict[str, float]:
    """:func:`coverage_counts`, counted from the records."""
    from cadsim.dataset import Dataset

    def per_view(sensor: str, false_only: bool = False) -> float:
        views = [v for p in Dataset(dataset_dir, sensor=sensor) for v in (p.view1, p.view2)]
        count = [sum(i.startswith("clutter") for i in v.object_ids) if false_only else len(v) for v in views]  # fmt: skip
        return float(np.mean(count)) if count else 0.0

    lidar = per_view("lidar-common")
    return {
        "objects": COVERED,
        "camera_per_view": round(per_view("camera-common"), 4),
        "lidar_per_view": round(lidar, 4),
        "lidar_extra_per_view": round(per_view("lidar") - lidar, 4),
        "lidar_extra_false_per_view": round(
            per_view("lidar", True) - per_view("lidar-common", True), 4
        ),
    }


def chosen_per_family(
    validation: Mapping[str, Mapping[str, float]], matchers: Sequence[str]
) -> dict[str, list[str]]:
    """{preset: the matchers compared there}: of ``matchers``, per family (with / without the
    prior), the one of highest ``validation`` F1 ({preset: {matcher: F1 averaged over the two
    sensors}}, :func:`mean_validation`; ties: the name), the same rule as the ``chosen`` rows."""
    from eval.studies.v2x.table import reads_prior

    out: dict[str, list[str]] = {}
    for preset, scores in validation.items():
        best: dict[bool, tuple[float, str]] = {}
        for m in matchers:
            if m in scores and np.isfinite(scores[m]):
                key = (-scores[m], m)
                best[reads_prior(m)] = min(best.get(reads_prior(m), key), key)
        out[preset] = [name for prior, (_, name) in sorted(best.items(), reverse=True)]
    return out


def write_sensor_table(
    lidar: pd.DataFrame,
    camera: pd.DataFrame,
    validation: Mapping[str, Mapping[str, float]],
    out_dir: str | Path,
    coverage: Mapping[str, float] | None = None,
) -> pd.DataFrame:
    """``out_dir/table_v2x_sensors.csv`` from the per-pair test metrics of the same split read
    as each sensor's common region (with a ``preset`` column), the validation F1 that chose the
    compared matchers (:func:`mean_validation`) and the split's :func:`coverage_counts`; returns
    the table."""
    table = sensor_differences(lidar, camera, validation, coverage=coverage)
    write_csv(table.round(6), Path(out_dir) / f"table_{NAME}.csv")
    return table


def _pp(value: float) -> str:
    return f"{100 * value:+.1f}"


def _region(row) -> str:
    """ ", same region (…)" for a table with coverage columns, else ""."""
    extra = getattr(row, "lidar_extra_per_view", None)
    if extra is None or not np.isfinite(extra):
        return ""
    return (
        f", same region (camera {row.camera_per_view:.1f} and LiDAR {row.lidar_per_view:.1f} "
        f"detections per view; the LiDAR's {extra:.1f} others, "
        f"{row.lidar_extra_false_per_view:.1f} of them false positives, left out)"
    )


def sensor_lines(results: Path) -> list[str]:
    """The statements of :func:`sensor_claims`, as the report prints them."""
    return [claim.statement for claim in sensor_claims(results)]


def sensor_claims(results: Path) -> list[Claim]:
    """Per preset and family, the ``chosen`` row of ``table_v2x_sensors.csv`` as a claim: the
    paired difference LiDAR − camera with its interval and verdict (ahead where LiDAR is
    favoured after Holm's adjustment, behind where cameras are, else not shown) — read from
    that file alone."""
    path = Path(results) / f"table_{NAME}.csv"
    if not path.is_file():
        return []
    table = pd.read_csv(path, keep_default_na=False, na_values=[""])
    chosen = table[table["chosen"].astype(str) == "True"]
    presets = {p: k for k, p in enumerate(dict.fromkeys(chosen["preset"]))}
    families = {f: k for k, (_, f) in enumerate(FAMILIES)}
    order = sorted(range(len(chosen)), key=lambda i: (presets[chosen["preset"].iat[i]], families.get(chosen["family"].iat[i], 2)))  # fmt: skip
    out = []
    for row in chosen.iloc[order].itertuples(index=False):
        interval = (
            f"[{_pp(row.ci_low)}, {_pp(row.ci_high)}]"
            if np.isfinite(row.ci_low) and np.isfinite(row.ci_high)
            else "(no interval)"
        )
        statement = (
            f"`{row.preset}`, {row.family} (`{row.matcher}`, chosen on validation): F1 on "
            f"LiDAR boxes − on camera detections, same frames{_region(row)}, {_pp(row.diff)} {interval} "
            f"points over {int(row.clusters)} episodes (LiDAR {100 * row.lidar_f1:.1f}, camera "
            f"{100 * row.camera_f1:.1f}; Holm-adjusted p {row.p_holm:.3f}) — {row.verdict}"
        )
        state = {LIDAR_FAVOURS: AHEAD, CAMERA_FAVOURS: BEHIND}.get(row.verdict, NOT_SHOWN)
        subject = f"{row.preset}, {row.family} ({row.matcher}, chosen on validation)"
        out.append(
            Claim(
                "v2x_lidar",
                subject,
                "difference",
                "f1 points",
                printed(row.diff),
                printed(row.ci_low),
                printed(row.ci_high),
                0.0,
                "diff",
                state,
                "validation",
                "simulation episodes",
                f"table_{NAME}.csv",
                statement,
            )  # fmt: skip
        )
    return out


__all__ = [
    "COLUMNS",
    "NAME",
    "camera_fully_covered",
    "coverage_counts",
    "mean_validation",
    "sensor_claims",
    "sensor_differences",
    "sensor_lines",
    "write_sensor_table",
]
