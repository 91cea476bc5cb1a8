"""Same answers on every CPU (``../shared/DESIGN.md`` §10): datasets byte-identical and result
tables identical whether numpy runs its AVX-512 code paths, runs without them, or returns results
that differ from the C library's in the last bit (fault injection, which shows on any CPU what
AVX-512 shows on some). Each variant runs in a subprocess (tests/cpu_dispatch.py)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from cpu_dispatch import (
    SAME_EVERYWHERE,
    TRANSCENDENTAL,
    avx512_env,
    avx512_features,
    other_blas_env,
)

from cadsim import portable_math
from cadsim.dataset import Dataset

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[1]
DISPATCH = str(ROOT / "tests" / "cpu_dispatch.py")
# The built-in scenarios and an external SUMO one (SUMO's own game/cross example).
SCENARIOS = (
    "cad-intersection",
    "cad-dense",
    "cad-v2x",  # detector errors, per-episode light, per-camera exposure
    "cad-v2x-lidar",  # LiDAR sweeps, box detector, lidar.npz
    "cad-v2x-seq",  # sequences: consecutive frames of the same observers, odometry
    "mrc-arena",
    "highway-intersection",
    "sumo-game-cross",
)
TIMING = ("time", "seconds", "wall", "ms_per_pair", "ms_per_frame", "_s")
TIMED_CLAIM = r"seconds|^time per"  # claims.csv metrics that are measured times


def _variants() -> dict[str, tuple[list[str], dict[str, str] | None]]:
    """name -> (extra arguments of cpu_dispatch.py, environment)."""
    variants = {"plain": ([], None), "ulp_faults": (["--ulp-faults"], None)}
    if avx512_features():
        variants["no_avx512"] = ([], avx512_env())
    if other_blas_env() is not None:
        variants["other_blas"] = ([], other_blas_env())
    return variants


def _run_all(command: list[str], cwd: Path) -> dict[str, subprocess.CompletedProcess]:
    """`command` (a module and its arguments, "{out}" replaced per variant) in every variant,
    two at a time."""

    def one(item):
        name, (extra, env) = item
        args = [a.replace("{out}", str(cwd / name)) for a in command]
        return name, subprocess.run(
            [sys.executable, DISPATCH, *extra, *args],
            cwd=ROOT,
            env=env,
            capture_output=True,
            text=True,
            timeout=900,
        )

    with ThreadPoolExecutor(2) as pool:
        done = dict(pool.map(one, _variants().items()))
    for name, proc in done.items():
        assert proc.returncode == 0, f"{name}: {proc.stderr[-3000:]}"
    return done


def test_the_injected_functions_are_the_portable_ones_and_the_rest_agree_everywhere():
    assert set(TRANSCENDENTAL) <= set(portable_math.__all__)
    rng = np.random.default_rng(0)
    x = rng.uniform(0.1, 20, 1000)
    for name in TRANSCENDENTAL:
        f = getattr(portable_math, name)
        arg = x / 21 if name in ("arcsin", "arccos", "arctanh") else x + (name == "arccosh")
        args = (arg, x[::-1]) if name in ("arctan2", "power") else (arg,)
        expected = getattr(np, name)(*args)
        np.testing.assert_allclose(f(*args), expected, rtol=1e-14, err_msg=name)
    if not avx512_features():
        pytest.skip("no AVX-512 on this CPU: nothing to compare the dispatch levels with")
    code = (
        "import numpy as np, json; x = np.random.default_rng(1).uniform(0.01, 50, 200000); "
        f"print(json.dumps({{n: getattr(np, n)(x, x[::-1]).tobytes().hex() if n in "
        f"('hypot', 'float_power') else getattr(np, n)(x).tobytes().hex() "
        f"for n in {SAME_EVERYWHERE!r}}}))"
    )
    outs = [
        json.loads(subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                                  text=True, check=True).stdout)
        for env in (None, avx512_env())
    ]  # fmt: skip
    assert outs[0] == outs[1]  # so these need no portable version and no fault injection


def test_datasets_are_byte_identical_on_every_dispatch_level(tmp_path):
    script = tmp_path / "generate_all.py"
    script.write_text(
        "import sys\nfrom cadsim.cli import main\n"
        "for name in sys.argv[2:]:\n"
        "    assert main(['generate', f'scenarios/{name}.toml', '--pairs', '2', '--workers', '1',\n"
        "                 '--no-progress', '--out', f'{sys.argv[1]}/{name}']) == 0\n"
    )
    done = _run_all(["--path", str(script), "{out}", *SCENARIOS], tmp_path)
    checksums = {name: {s: _checksum(tmp_path / name / s) for s in SCENARIOS} for name in done}
    plain = checksums.pop("plain")
    for name, found in checksums.items():
        assert found == plain, name
    # what a sequence dataset gives at read time, which no checksum covers: each run's redrawn
    # odometry and prior, and each agent's own tracks built from them
    draws = tmp_path / "sequence_draws.py"
    draws.write_text(
        "import hashlib, sys\nimport numpy as np\n"
        "from cadsim.dataset import Dataset\n"
        "from cadsim.dataset.sequence_odometry import redraw_odometry\n"
        "from eval.studies.temporal.evaluation import sequence_problem\n"
        "ds = Dataset(sys.argv[1])\nh = hashlib.sha256()\n"
        "for k in range(ds.sequences):\n"
        "    for seed in (None, 0, 1):\n"
        "        frames = redraw_odometry(ds.sequence(k), seed)\n"
        "        h.update(repr([p.as_dict() for f in frames for p in f.odometry]).encode())\n"
        "        item = sequence_problem(frames, 'gnss-urban', 0 if seed is None else seed, k)\n"
        "        for f, a, b in zip(item.seq.frames, item.seq.tracks1, item.seq.tracks2):\n"
        "            for x in (f.points1, f.points2, f.world1, f.world2, a, b):\n"
        "                h.update(np.ascontiguousarray(x).tobytes())\n"
        "open(sys.argv[2], 'w').write(h.hexdigest())\n"
    )
    sequences = tmp_path / "plain" / "cad-v2x-seq"
    assert Dataset(sequences).sequences == 2
    done = _run_all(["--path", str(draws), str(sequences), "{out}.draws"], tmp_path)
    digests = {name: (tmp_path / f"{name}.draws").read_text() for name in done}
    assert len(set(digests.values())) == 1, digests


def _checksum(dataset: Path) -> str:
    return json.loads((dataset / "manifest.json").read_text())["checksum"]


def _tables(out: Path) -> dict[str, pd.DataFrame]:
    """Every result CSV under `out`, timing columns dropped, the variant's folder in paths
    replaced by "ROOT"."""
    tables = {}
    for path in sorted(out.rglob("*.csv")):
        frame = pd.read_csv(path)
        if path.name == "claims.csv":  # a measured time is a claim too: its rows are timing
            frame = frame[~frame["metric"].str.contains(TIMED_CLAIM, regex=True)]
        for column in frame.columns:
            if pd.api.types.is_string_dtype(frame[column]):
                frame[column] = frame[column].str.replace(str(out.parent), "ROOT")
        keep = [c for c in frame.columns if not any(t in c for t in TIMING)]
        tables[str(path.relative_to(out))] = frame[keep]
    return tables


@pytest.mark.timeout(1800)  # four small reproduces, ~190 s on 2 cores; 22 min at load 5-6
def test_a_small_reproduce_gives_the_same_tables_on_every_dispatch_level(tmp_path):
    args = ["eval.reproduce", "--pairs", "2", "--val-pairs", "2", "--matchers", "sm,maximin,mos"]
    args += ["--rates", "0,0.01", "--keep", "1,0.5", "--regime-runs", "2", "--runs", "1"]
    args += ["--spread-runs", "1", "--sweep-runs", "1", "--localisation-sigmas", "0,2"]
    args += ["--localisation-runs", "1", "--external-runs", "1", "--external-tune-pairs", "3"]
    args += ["--workers", "1", "--no-progress", "--out", "{out}/out", "--data", "{out}/data"]
    # --pairs 2 caps the temporal table's sequences too: 2 test + 2 validation sequences
    args += ["--cache", "{out}/cache"]
    done = _run_all(args, tmp_path)
    plain = _tables(tmp_path / "plain" / "out")
    assert {"table1.csv", "regime_sweep.csv", "crossovers.csv", "noise_runs.csv"} <= set(plain)
    assert "localisation_presets.csv" in plain  # cad-v2x: GNSS draws, latency, detector errors
    assert "table_transfer.csv" in plain  # the learned matchers: trained models, their rows
    # the temporal table: own tracks, windowed accumulation, tuning, τ, per-frame scores
    assert {"table_temporal.csv", "temporal/per_frame.csv", "temporal/tuning.csv"} <= set(plain)
    models = {
        name: sorted(p.read_bytes() for p in (tmp_path / name / "data" / "models").glob("*.json"))
        for name in done
    }
    assert len(models["plain"]) == 4 and all(m == models["plain"] for m in models.values())
    record = json.loads((tmp_path / "plain" / "out" / "run_record.json").read_text())
    for name in done:
        if name == "plain":
            continue
        other = _tables(tmp_path / name / "out")
        assert set(other) == set(plain), name
        for file, frame in plain.items():
            pd.testing.assert_frame_equal(other[file], frame, obj=f"{name}: {file}")
        again = json.loads((tmp_path / name / "out" / "run_record.json").read_text())
        assert _checksums(again) == _checksums(record), name
        simd = again["machine"]["numpy_simd"]  # the record says which code paths ran
        if name == "no_avx512":
            assert simd["disabled"] == avx512_features()
            assert not set(simd["found"]) & set(avx512_features())
    # the plain variant runs in this process's environment (which may itself disable some)
    assert (
        record["machine"]["numpy_simd"]["disabled"]
        == os.environ.get("NPY_DISABLE_CPU_FEATURES", "").split()
    )


def _checksums(record: dict) -> list[tuple]:
    return [(d["label"], d["test_checksum"], d.get("val_checksum")) for d in record["datasets"]]


def test_gnss_localisation_draws_are_the_same_on_every_dispatch_level(tmp_path):
    # the GNSS-like prior is drawn at read time, so no dataset checksum covers it: hash its draws
    script = tmp_path / "gnss_draws.py"
    script.write_text(
        "import hashlib, sys\nimport numpy as np\n"
        "from cadsim.sensing.gnss_error import PRESETS, draw_error\n"
        "from cadsim.sensing.pose_error import perturbed_world\n"
        "world = np.random.default_rng(0).uniform(-60, 60, (50, 3))\n"
        "h = hashlib.sha256()\n"
        "for name, model in PRESETS.items():\n"
        "    for e in range(40):\n"
        "        err = draw_error(model, 1000 + e, f'veh{e % 7}', 3.7 * e, 99 + e)\n"
        "        h.update(perturbed_world(world, world[e], err).tobytes())\n"
        "open(sys.argv[1], 'w').write(h.hexdigest())\n"
    )
    done = _run_all(["--path", str(script), "{out}"], tmp_path)
    digests = {name: (tmp_path / name).read_text() for name in done}
    assert len(set(digests.values())) == 1, digests
