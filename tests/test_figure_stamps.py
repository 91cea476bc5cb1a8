"""Figures drawn once per input (eval/report/figure_stamps.py): a writer is skipped while its
inputs, the drawing code and its outputs are as they were; any change draws again."""

from __future__ import annotations

import pytest

from eval.report import figure_stamps, figures


@pytest.fixture(autouse=True)
def own_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("CADSIM_CACHE_DIR", str(tmp_path / "cadsim-cache"))


def _writer(calls: list):
    @figure_stamps.drawn_once(lambda out: [out / "in.csv"])
    def write_demo(out_dir):
        calls.append(out_dir)
        text = (out_dir / "in.csv").read_text() if (out_dir / "in.csv").is_file() else "none"
        (out_dir / "demo.png").write_text(f"drawn from {text}")
        return [out_dir / "demo.png"]

    return write_demo


def test_a_writer_is_skipped_while_nothing_changed(tmp_path):
    out, calls = tmp_path / "out", []
    out.mkdir()
    (out / "in.csv").write_text("a,b\n1,2\n")
    write = _writer(calls)
    first = write(out)
    assert write(out) == first and len(calls) == 1  # the second call drew nothing


@pytest.mark.parametrize(
    "change",
    [
        lambda out: (out / "in.csv").write_text("a,b\n1,3\n"),  # another input
        lambda out: (out / "in.csv").unlink(),  # a missing input
        lambda out: (out / "demo.png").write_text("edited"),  # an edited figure
        lambda out: (out / "demo.png").unlink(),  # a deleted figure
    ],
)
def test_any_change_draws_again(tmp_path, change):
    out, calls = tmp_path / "out", []
    out.mkdir()
    (out / "in.csv").write_text("a,b\n1,2\n")
    write = _writer(calls)
    write(out)
    change(out)
    write(out)
    assert len(calls) == 2 and (out / "demo.png").read_text().startswith("drawn from")


def test_the_drawing_code_is_in_the_key(tmp_path, monkeypatch):
    inputs = [tmp_path / "in.csv"]
    key = figure_stamps.figure_key("write_demo", inputs)
    assert figure_stamps.figure_key("write_other", inputs) != key
    monkeypatch.setattr(figure_stamps, "_code_version", lambda: "edited drawing code")
    assert figure_stamps.figure_key("write_demo", inputs) != key


def test_a_real_figure_is_redrawn_when_its_csv_changes(tmp_path, monkeypatch):
    out = tmp_path / "out"
    out.mkdir()
    rows = "n_agents,matcher,fusion,preset,f1_pooled,cycle_violation_rate\n"
    rows += "2,sm,independent,denied,0.5,0.0\n4,sm,independent,denied,0.6,0.1\n"
    (out / "table_multiagent.csv").write_text(rows)
    first = figures.write_fig_multiagent(out)
    assert first and all(p.is_file() for p in first)
    drawn = []
    monkeypatch.setattr(figures, "_save", lambda fig, base, *a: drawn.append(base) or [])
    assert figures.write_fig_multiagent(out) == first and not drawn
    (out / "table_multiagent.csv").write_text(rows.replace("0.6", "0.7"))
    figures.write_fig_multiagent(out)
    assert drawn == [out / "fig_multiagent"]
