"""``python -m trajcomp`` and the ``trajcomp`` console script: the command line, stopping signals kept from here on
(`trajcomp.support.signals.hold_from_start`) so that one during its imports ends the run with its code. Nothing
imports this module but the program's start."""

import sys

from trajcomp.support.signals import hold_from_start

hold_from_start()

from trajcomp.cli import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
