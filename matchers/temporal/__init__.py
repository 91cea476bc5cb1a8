"""Temporal matchers: one matching per frame of a
:class:`~matchers.core.sequence_problem.SequenceProblem`, using the frames before it
(:mod:`matchers.core.temporal_registry`)."""
