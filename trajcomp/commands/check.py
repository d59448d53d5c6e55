"""``trajcomp check``: is a model still valid in a later campaign, from a few rows measured there?"""

from trajcomp.commands._args import command_parser


def add_parser(sub):
    from trajcomp.commands.recalibrate import add_rows_arguments

    parser = command_parser(
        sub, "check",
        "Say from some 30 rows measured in a later campaign whether the model is still valid, needs a light "
        "re-calibration (trajcomp recalibrate) or a full one (trajcomp calibrate): the rows' residual as the "
        "model is (registered anew where the tracker moved), each region of the rows predicted from the others, "
        "against the model's own error, and the residual the light update would leave. Exit 0: still valid; 1: re-calibrate "
        "(the verdict says how). Rows that cannot identify the light update are judged on the registration alone, "
        "and the output says what they cannot update.",
        "trajcomp check model.yaml validation.csv --json check.json",
    )
    add_rows_arguments(parser)
    parser.add_argument("--json", metavar="PATH", help="write the verdict and the update's record as JSON")
    parser.set_defaults(run=run)


def run(args):
    import json

    from trajcomp.calibration.recalibrate import UpdateRefused
    from trajcomp.commands.recalibrate import groups_of, update_of
    from trajcomp.errors import ToleranceError
    from trajcomp.model.model_file import model_files
    from trajcomp.support.atomic import refuse_inputs, write_atomic

    if args.json:
        refuse_inputs([args.json], [*model_files(args.model), args.rows, args.columns_file])
    groups = groups_of(args.only)
    try:
        result = update_of(args, groups)
    except UpdateRefused as exc:  # the verdict still stands on the registration: say what the rows cannot update
        if groups == ("registration",):
            raise
        print(f"no light update from these rows: {exc}")
        result = update_of(args, ("registration",))
    word, why = result.verdict()
    print(why)
    if args.json:
        write_atomic(args.json, json.dumps({"verdict": word, "reason": why, "update": result.record()}, indent=1))
    if word != "valid":
        raise ToleranceError(f"{args.model}: {word.replace('recalibrate', 're-calibrate')}")
    return 0
