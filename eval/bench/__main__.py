"""``python -m eval.bench`` (= ``make bench``)."""

import sys

from eval.bench import main

sys.exit(main())
