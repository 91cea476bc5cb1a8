"""The external benchmark on the DMGM CAD pairs (``evaluation.py``), the prior matchers'
defaults derived from its calibration sequence (``prior_defaults.py``) and whether a ranking on
our simulation predicts the ranking there (``agreement.py``)."""

from eval.studies import forwarding

__getattr__ = forwarding(__name__)  # the previous release's names, deprecated
