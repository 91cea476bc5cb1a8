"""The transfer study: training and test sets (``sets.py``), the hand-crafted reference
(``reference.py``), the gap metric (``gap.py``), the matrix (``matrix.py``), the evaluation
(``evaluation.py``) and the report part (``report.py``)."""

from eval.studies import forwarding

__getattr__ = forwarding(__name__)  # the previous release's names, deprecated
