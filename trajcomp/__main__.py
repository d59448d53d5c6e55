"""``python -m trajcomp``: the command line, as the ``trajcomp`` console script runs it."""

import sys

from trajcomp.cli import main

sys.exit(main())
