"""The README's results section is written from a results directory, between its markers only."""

import json

from eval.readme_results import BEGIN, END, update_readme


def test_results_section_replaces_only_the_marked_part(tmp_path):
    results = tmp_path / "results"
    results.mkdir()
    (results / "table1.md").write_text(
        "| Method | Accuracy |\n|---|---|\n| Maximin | 61.2 ± 0.3 |\n"
    )
    (results / "run_record.json").write_text(
        json.dumps(
            {
                "command": "python -m eval.reproduce",
                "created": "2026-01-01T00:00:00+00:00",
                "git": {"commit": "abcdef1234567890", "dirty": False},
                "wall_s": {"generate": 10.0, "evaluate": 20.0, "total": 30.0},
                "noise_sweep": {"rates": [0.0, 0.01], "seeds": [0, 1], "pairs": 5},
            }
        )
    )
    readme = tmp_path / "README.md"
    readme.write_text(f"# title\n\nbefore\n{BEGIN}\nold numbers 99.9\n{END}\nafter\n")
    assert update_readme(readme, results)
    text = readme.read_text()
    assert text.startswith("# title\n\nbefore\n") and text.endswith(f"{END}\nafter\n")
    assert "old numbers" not in text
    assert "| Maximin | 61.2 ± 0.3 |" in text and "abcdef1234" in text
    assert "](results/fig4.png)" in text and "0, 0.01" in text and "wall time 30 s" in text


def test_readme_without_markers_is_left_alone(tmp_path):
    readme = tmp_path / "README.md"
    readme.write_text("# no markers\n")
    assert not update_readme(readme, tmp_path)
    assert readme.read_text() == "# no markers\n"
