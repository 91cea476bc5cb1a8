"""A calibrated τ is printed with enough digits and never rounded away in a CSV."""

import numpy as np
import pandas as pd

from eval.report.threshold_format import rounded, tau_text


def test_a_tiny_tau_never_prints_as_zero():
    assert tau_text(3e-9) == "3e-09" and tau_text(1.2345e-7) == "1.23e-07"
    assert tau_text(0.4731) == "0.473" and tau_text(0.0) == "0.000"
    assert tau_text(float("nan")) == "–" and tau_text(None, "--") == "--"


def test_rounding_a_table_keeps_tau_whole():
    table = pd.DataFrame({"tau": [3.2e-9, 0.1234567891], "f1": [0.12345678, np.nan]})
    out = rounded(table)
    assert out["tau"].tolist() == table["tau"].tolist()
    assert out["f1"].iloc[0] == 0.123457
