"""Former home of `trajcomp.arm.ik`, kept for plugins until trajcomp 0.2 (`trajcomp.support.moved`)."""

from trajcomp.support.moved import forwarding

__getattr__ = forwarding(__name__, "trajcomp.arm.ik")
