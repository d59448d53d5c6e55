"""CLI sub-commands: each module defines ``add_parser(subparsers)`` which sets ``run``.

`COMMANDS` names them, in the order of the work, with their one-line help:
`trajcomp --help` lists them from here without importing a command module
(each imports what its work needs: numpy, scipy, the pipeline).
"""

COMMANDS = {
    "robots": "list the built-in robots",
    "plan": "plan a cubic measurement grid",
    "simulate": "measure a plan on the virtual robot",
    "calibrate": "identify a compensation model",
    "predict": "predict reached TCP positions",
    "validate": "check a model against measurements",
    "check": "say whether a model still holds in a later campaign",
    "recalibrate": "update a model from a few rows of a later campaign",
    "demo": "run the paper's protocol on the virtual robot",
    "compensate": "correct a program with a model",
    "formats": "list the robot program formats",
    "convert": "rewrite a robot program in another language",
    "retime": "time a program under the arm's joint limits",
}
