"""Names a package exports, imported from their modules on first use (so that importing the package is light)."""

import importlib


def lazy_names(package, modules):
    """A package's module ``__getattr__`` that imports each exported name from its module on first use.

    Parameters
    ----------
    package : str
        The package's dotted name (``__name__``).
    modules : Mapping[str, str]
        Exported name -> the package's module defining it (``{"Report": "document"}``).
    """

    def __getattr__(name):
        if name not in modules:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        return getattr(importlib.import_module(f"{package}.{modules[name]}"), name)

    return __getattr__
