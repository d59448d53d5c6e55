"""CLI sub-commands: each module defines ``add_parser(subparsers)`` which sets ``run``.

`COMMANDS` names them, in the order of the work, with their one-line help:
`trajcomp --help` lists them from here without importing a command module
(each imports what its work needs: numpy, scipy, the pipeline).
`EXIT_CODES_HELP` ends the ``--help`` of the tool and of each command.
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

EXIT_CODES_HELP = (
    "exit codes (of every command):\n"
    "  0    success\n"
    "  1    the work ran and its output is written, but it fails the verdict or a limit (see the messages)\n"
    "  2    bad usage or bad input: nothing written (the message names the file, line and field)\n"
    "  3    an internal error: a bug (its traceback is saved, or printed with --debug)\n"
    "  130  interrupted (Ctrl-C), 143 terminated (SIGTERM): what was not finished is not written\n"
    "  141  the reader of the output went away (| head)"
)
