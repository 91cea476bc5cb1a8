"""Hostile input past the importers (issue 52, findings 1, 3 and 7): absolute times that once
made the GNSS walk allocate per simulated second, ``.npz`` member headers that once were trusted,
and report links that once became live. A dataset is refused with one line naming the file and
the key, exit status 2, nothing written; legitimate values (epoch timestamps) run in bounded
memory."""

from __future__ import annotations

import io
import re
import resource
import tracemalloc
import zipfile
from pathlib import Path

import numpy as np
import pytest
from dataset_forgery import edit_json, record_dirs, reseal
from format_fixtures import write_v2x_seq

from cadsim.cli import main
from cadsim.dataset import Dataset, layout
from cadsim.dataset.encoding import MAX_NPZ_BYTES, load_npz, npz_bytes
from cadsim.sensing.gnss_error import MAX_TIME_S, PRESETS, episode_draws

URBAN = PRESETS["gnss-urban"]


def _peak(call) -> int:
    """Peak bytes traced while ``call()`` runs, under an address-space limit of what the process
    maps now + 1 GiB (so that a regression fails with MemoryError instead of taking gigabytes)."""
    mapped = next(
        int(line.split()[1]) * 1024
        for line in Path("/proc/self/status").read_text().splitlines()
        if line.startswith("VmSize:")
    )
    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    limit = mapped + 2**30
    resource.setrlimit(resource.RLIMIT_AS, (limit if hard < 0 else min(limit, hard), hard))
    tracemalloc.start()
    try:
        call()
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
        resource.setrlimit(resource.RLIMIT_AS, (soft, hard))


def _tree(root: Path) -> dict[str, bytes]:
    return {
        str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()
    }


def _one_line(capsys, command: str, *parts: str) -> str:
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"cadsim {command}: error:"), lines
    for part in parts:
        assert part in lines[0], (part, lines[0])
    return lines[0]


@pytest.mark.parametrize("time_s", [1.6e9, 1e12, 1e15])
def test_the_gnss_walk_is_drawn_in_bounded_memory_at_any_time(time_s):
    """V2X-Seq's epoch seconds asked for 24 GiB, OPV2V's start_time 1e12 for 14.6 TiB."""
    assert _peak(lambda: episode_draws(URBAN, 3, "veh", time_s)) < 2**20
    one, _ = episode_draws(URBAN, 3, "veh", time_s)
    two, _ = episode_draws(URBAN, 3, "veh", time_s)
    assert np.isfinite(one).all() and np.array_equal(one, two)


@pytest.mark.parametrize("time_s", [1e300, MAX_TIME_S * 2, float("nan"), float("inf"), -np.inf])
def test_times_out_of_range_are_refused_naming_the_time(time_s):
    with pytest.raises(ValueError, match=r"^time: expected finite seconds up to"):
        episode_draws(URBAN, 3, "veh", time_s)


def test_far_from_zero_the_walk_keeps_its_increments_and_stays_linear_between_steps():
    t = 1e12 + 17.0
    steps = np.array(
        [episode_draws(URBAN, 5, f"v{k}", t + 1)[0] - episode_draws(URBAN, 5, f"v{k}", t)[0]
         for k in range(400)]
    )  # fmt: skip
    assert steps.std() == pytest.approx(URBAN.walk_m_per_sqrt_s, rel=0.15)
    assert abs(steps.mean()) < 0.05
    a, b, c = (episode_draws(URBAN, 5, "v0", t + d)[0] for d in (0.0, 0.5, 1.0))
    assert np.allclose(b, (a + c) / 2)


def test_an_imported_split_with_epoch_timestamps_draws_gnss_priors(tmp_path):
    """The V2X-Seq fixture's times are seconds since 1970 (~1.6e9): the import counts each
    sequence's time from its first frame (the epoch kept in meta), so a GNSS preset's walk is
    drawn over the sequence's own seconds — metres, not the kilometres 1.6e9 s of walk gives."""
    assert main(["import", "v2x-seq", str(write_v2x_seq(tmp_path / "spd")), "--out", str(tmp_path / "d")]) == 0  # fmt: skip
    pairs = list(Dataset(tmp_path / "d", verify=True))
    assert min(p.time for p in pairs) == 0.0
    assert min(p.record["meta"]["source_time_s"] for p in pairs) > 1e9

    def draw():
        for pair in pairs:
            urban = pair.localise_preset("gnss-urban", seed=0).prior()[0]  # the vehicle
            exact = pair.localise_preset("exact", seed=0).prior()[0]
            assert np.abs(urban[:, :2] - exact[:, :2]).max() < 100.0

    assert _peak(draw) < 32 * 2**20


def _imported(tmp_path: Path) -> Path:
    data = tmp_path / "data"
    assert main(["import", "v2x-seq", str(write_v2x_seq(tmp_path / "spd")), "--out", str(data)]) == 0  # fmt: skip
    return data


def _commands(data: Path, tmp_path: Path) -> dict[str, list[str]]:
    return {
        "info": ["info", str(data)],
        "show": ["show", str(data), "--out", str(tmp_path / "fig.png")],
        "export": ["export", "opv2v", str(data), "--out", str(tmp_path / "exported")],
    }


@pytest.mark.parametrize("time", [1e300, -1e17])
def test_a_resealed_record_time_out_of_range_is_one_line(tmp_path, capsys, time):
    """``"time": 1e300`` gave "Maximum allowed dimension exceeded"; 1e9 passed and was
    OOM-killed — now within range and drawn in bounded memory (above)."""
    data = _imported(tmp_path)
    edit_json(record_dirs(data)[0], lambda r: r.update(time=time))
    reseal(data)
    before = _tree(tmp_path)
    for command, args in _commands(data, tmp_path).items():
        assert main(args) == 2
        _one_line(capsys, command, "record.json", "time: expected seconds within")
    assert _tree(tmp_path) == before


def _forged_header(npz: Path, member: str, shape: tuple[int, ...]) -> None:
    """Rewrite one member's ``.npy`` header to declare ``shape`` (its data left as it was)."""
    with zipfile.ZipFile(npz) as zf:
        members = {name: zf.read(name) for name in zf.namelist()}
    raw = io.BytesIO(members[f"{member}.npy"])
    np.lib.format.read_magic(raw)
    _, fortran, dtype = np.lib.format.read_array_header_1_0(raw)
    header = io.BytesIO()
    np.lib.format.write_array_header_1_0(
        header, {"descr": np.lib.format.dtype_to_descr(dtype), "fortran_order": fortran, "shape": shape}
    )  # fmt: skip
    members[f"{member}.npy"] = header.getvalue() + raw.read()
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED) as zf:
        for name, data in members.items():
            zf.writestr(name, data)
    npz.write_bytes(buffer.getvalue())


def test_an_npz_header_declaring_a_trillion_elements_is_one_line(tmp_path, capsys):
    """It was a MemoryError traceback in info, show and export."""
    data = _imported(tmp_path)
    _forged_header(record_dirs(data)[0] / layout.DETECTIONS_NPZ, "view1_positions", (10**12, 3))
    reseal(data)
    before = _tree(tmp_path)
    for command, args in _commands(data, tmp_path).items():
        assert main(args) == 2
        _one_line(capsys, command, "detections.npz", "view1_positions", "header declares")
    assert _tree(tmp_path) == before


def test_npz_members_are_refused_by_their_headers_before_anything_is_inflated():
    """A stray member of 2 GiB (a few MB compressed) was inflated before its name was refused."""
    header = io.BytesIO()
    np.lib.format.write_array_header_1_0(
        header, {"descr": "|u1", "fortran_order": False, "shape": (2 * MAX_NPZ_BYTES,)}
    )
    good = npz_bytes({"a": np.arange(4.0)})
    buffer = io.BytesIO(good)
    with zipfile.ZipFile(buffer, "a", zipfile.ZIP_DEFLATED) as zf:
        zf.writestr("stray.npy", header.getvalue() + bytes(2**20))
    peak = []

    def load():
        with pytest.raises(ValueError, match=r"x.npz: stray: its header declares"):
            load_npz(buffer.getvalue(), "x.npz")

    peak.append(_peak(load))
    assert peak[0] < 8 * 2**20
    lying = io.BytesIO()  # a header smaller than its data, and an object dtype
    with zipfile.ZipFile(lying, "w") as zf:
        small = io.BytesIO()
        np.lib.format.write_array_header_1_0(small, {"descr": "<f8", "fortran_order": False, "shape": (2,)})  # fmt: skip
        zf.writestr("a.npy", small.getvalue() + bytes(8 * 5))
    with pytest.raises(ValueError, match=r"a: its header declares \(2,\) float64 \(16 bytes\), the member holds 40"):  # fmt: skip
        load_npz(lying.getvalue(), "y.npz")
    arrays = {"c": np.arange(6, dtype=">i4").reshape(2, 3), "f": np.asfortranarray(np.eye(3)[:, :2]), "e": np.zeros((0, 4))}  # fmt: skip
    back = load_npz(npz_bytes(arrays), "z.npz")
    for key, value in arrays.items():
        assert back[key].dtype == value.dtype and np.array_equal(back[key], value)
    back["c"][0, 0] = 7  # writable, as np.load's arrays are


HOSTILE_MARKDOWN = """# Report

[run](javascript:alert(1)) [raw](data:text/html,<script>alert(1)</script>) [x](JaVaScRiPt&#58;alert(2)) [t]( \tjavascript:alert(3)) [docs](docs/usage.md) [web](https://example.org) [top](#report)

![fig](data:image/svg+xml,<svg onload=alert(4)>)

| Method | F1 |
|:---|---:|
| {a_b} | 50.0 |
"""


def test_report_links_are_live_only_for_safe_targets_and_a_bar_keeps_its_cell():
    from eval.report.markdown_cell import row
    from eval.report.site import page

    html = page(HOSTILE_MARKDOWN.replace("| {a_b} | 50.0 |", row(["a|b", "50.0"])), "r")
    targets = re.findall(r'(?:href|src)="([^"]*)"', html)
    assert [t for t in targets if not t.startswith("#")] == ["docs/usage.md", "https://example.org"]
    assert "alert" not in "".join(targets)
    rows = re.findall(r"<tr>(.*?)</tr>", html)
    assert rows[1] == '<td>a|b</td><td class="right">50.0</td>'


def test_table_one_escapes_a_matcher_named_with_a_bar():
    import pandas as pd

    from eval.report.site import to_html
    from eval.report.tables import to_markdown

    row = {"dataset": "CAD", "matcher": "a|b", "method": "a|b", "runs": 1, "frames": 2, "time_median_ms": 1.0, "tau": 0.5}  # fmt: skip
    for metric in ("accuracy", "precision", "recall", "f1"):
        row |= {f"{metric}_mean": 0.5, f"{metric}_std": 0.0}
    markdown = to_markdown(pd.DataFrame([row]))
    body = next(line for line in markdown.splitlines() if "a\\|b" in line)
    header = next(line for line in markdown.splitlines() if line.startswith("| Method"))
    assert len(re.split(r"(?<!\\)\|", body)) == len(re.split(r"(?<!\\)\|", header))
    cells = re.findall(r"<td[^>]*>(.*?)</td>", to_html(markdown))
    assert cells[0] == "a|b"
