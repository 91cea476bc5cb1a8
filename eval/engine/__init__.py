"""The study engine: what every study runs the same way, so that a study is a declaration of its
data, methods, conditions, metrics and comparisons.

- loading splits: a test split with its validation split (:mod:`eval.engine.splits`);
- the evaluation: equal tuning budget on validation, τ on validation, test runs through the
  executor scored at τ, the files of each protocol variant (:mod:`eval.engine.protocol_run`,
  :mod:`eval.engine.named_runs`, :mod:`eval.engine.variant_files`, AP and PR curves in
  :mod:`eval.engine.ranking_quality`);
- choices on validation (:mod:`eval.engine.validation_choice`) and goals as declared
  (:mod:`eval.engine.goal`);
- episode-level intervals of per-pair values (:mod:`eval.engine.episode_interval`) and the
  best-against-runner-up comparison with its MDD (:mod:`eval.engine.comparison`);
- a study's result files read back and the Markdown cells of its tables
  (:mod:`eval.engine.result_table`, :mod:`eval.engine.cells`);
- which matchers a ``--matchers`` list names (:mod:`eval.engine.matcher_list`);
- a study as one declaration (:mod:`eval.engine.study`: ``Study``, its ``Data``, report
  parts and the ``ReportContext`` they are built from).

Imports ``eval/protocol/`` and ``eval/core/`` only; never ``eval/studies/`` (studies import it).
"""
