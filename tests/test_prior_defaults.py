"""The prior matchers' defaults come from the external calibration split (DMGM sequence 070) only:
the recorded derivation names that split, its checksum matches the shipped data, and every code
default is the recorded option."""

from __future__ import annotations

from cadsim.dataset import Dataset
from eval.studies.external.evaluation import CALIBRATION_DIR, TEST_DIR
from eval.studies.external.prior_defaults import PRIOR_MATCHERS, code_defaults, load_defaults
from matchers import search_space


def test_the_record_is_sequence_070s_and_never_a_test_sequences():
    record = load_defaults()
    source = record["derived_from"]
    assert source["sequences"] == ["070"] and source["dataset"] == CALIBRATION_DIR.name
    assert source["checksum"] == Dataset(CALIBRATION_DIR).checksum
    assert source["checksum"] != Dataset(TEST_DIR).checksum


def test_code_defaults_are_the_recorded_options():
    record = load_defaults()["matchers"]
    assert set(record) == set(PRIOR_MATCHERS)
    for name in PRIOR_MATCHERS:
        defaults = code_defaults(name)
        for option, value in record[name]["options"].items():
            assert defaults[option] == value, (name, option)
        # the derivation settled: at the recorded defaults their own grid keeps them
        assert record[name]["chosen_config"] == {}
        grid = {tuple(sorted(c.items())) for c in search_space(name)}
        assert len(record[name]["grid_val_f1"]) == len(grid) == 8
