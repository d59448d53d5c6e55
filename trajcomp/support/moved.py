"""Modules under their names before the wings, for plugins written against them (until trajcomp 0.2).

A former module (``trajcomp/program.py``...) is one line: its module
``__getattr__`` is `forwarding` to the new home, so ``from trajcomp.program
import Program`` still works and warns where to import it from now.
"""

import importlib
import warnings


def forwarding(old, new):
    """A module ``__getattr__`` for module ``old`` that returns the attributes of module ``new`` with a warning.

    Parameters
    ----------
    old, new : str
        Dotted module names: the former and the current home.
    """

    def __getattr__(name):
        if name.startswith("__"):
            raise AttributeError(name)
        value = getattr(importlib.import_module(new), name)  # AttributeError, unwarned, for a name never there
        warnings.warn(f"{old} moved to {new} (trajcomp 0.1 wings); import {name} from {new}: the old name goes "
                      "in trajcomp 0.2", DeprecationWarning, stacklevel=2)
        return value

    return __getattr__
