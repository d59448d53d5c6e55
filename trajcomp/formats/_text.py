"""Former home of `trajcomp.formats.text`, kept for plugins until trajcomp 0.2 (`trajcomp.support.moved`)."""

from trajcomp.support.moved import forwarding

__getattr__ = forwarding(__name__, "trajcomp.formats.text")
