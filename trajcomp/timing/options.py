"""The re-timing's methods and path tolerance: what ``trajcomp retime`` and ``compensate --retime`` offer.

Plain constants, no numpy: a command's ``--help`` builds its parser from
them without loading the timing (`trajcomp.timing.retiming` and
`trajcomp.timing.path` import them from here).
"""

RETIME_METHODS = ("auto", "toppra", "ruckig")  # auto: TOPP-RA along continuous runs, ruckig for stops and joint motions
TOLERANCE = 0.005  # mm, largest deviation of the timed path from a waypoint or sample
