"""``python -m cadsim …``: the same command line as the ``cadsim`` entry point."""

import sys

from cadsim.cli import main

sys.exit(main())
