"""The multi-agent study: N agents' pairwise matchings fused (``evaluation.py``), its gains
(``gains.py``), Markdown (``markdown.py``) and report part (``report.py``)."""

from eval.studies import forwarding

__getattr__ = forwarding(__name__)  # the previous release's names, deprecated
