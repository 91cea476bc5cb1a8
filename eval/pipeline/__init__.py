"""``make reproduce`` as a list of stages derived from the studies: the list (:mod:`.stages`:
every study's declared stages, in order), the stage type, what a run's stages share and the walk
over them (:mod:`.stage`) and every split's size at a scale (:mod:`.sizes`). The stage functions
are the studies' own (``eval/studies/<study>/stages.py``); this package reads the studies only
through their declarations (:func:`eval.studies.studies`). Imports ``eval/`` folders below the
root, never the root modules (``eval.reproduce``, ``eval.readme_results``)."""
