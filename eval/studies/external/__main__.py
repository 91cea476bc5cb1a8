"""``python -m eval.studies.external``: this study alone (``--help``; :mod:`eval.run_study`)."""

import sys

from eval.run_study import run_study

if __name__ == "__main__":
    sys.exit(run_study("external"))
