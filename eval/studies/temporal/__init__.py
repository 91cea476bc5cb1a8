"""The temporal study (camera and LiDAR): ``evaluation.py`` and its sequences, table layout,
runs, scores, presets, gains, Markdown and report part."""

from eval.studies import forwarding

__getattr__ = forwarding(__name__)  # the previous release's names, deprecated
