"""``make reproduce`` as a declared list of stages: the declarations (:mod:`.stages`), the stage
type and the walk over it (:mod:`.stage`), every split's size at a scale (:mod:`.sizes`) and the
stage functions, one module per study. Imports ``eval/`` folders below the root, never the root
modules (``eval.reproduce``, ``eval.readme_results``)."""
