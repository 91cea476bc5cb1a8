"""The study engine: what every study runs the same way, so that a study is a declaration.

A study (``eval/studies/``) declares its data, methods, conditions, metrics and comparisons; the engine holds the protocol steps they share — the
validation choices (:mod:`eval.engine.validation_choice`), episode-level intervals of per-pair
values (:mod:`eval.engine.episode_interval`), the best-against-runner-up comparison with its MDD
(:mod:`eval.engine.comparison`) and the Markdown cells of every table
(:mod:`eval.engine.cells`). Tuning (equal budget), τ and test runs through the executor are
:mod:`eval.studies.evaluation`'s ``evaluate``, which every study calls.

Imports ``eval/protocol/`` and ``eval/core/`` only; never ``eval/studies/`` (studies import it).
"""
