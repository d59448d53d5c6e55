"""``trajcomp recalibrate``: carry a model into a later measuring campaign from a few rows measured there."""

from trajcomp.commands._args import add_layout, command_parser, info, layout_of

GROUP_WORDS = ("registration (the tracker's new placement), tool (a remounted probe: TCP and, 6-DoF, the measured "
               "frame's orientation), zeros (joint zero offsets), scale (a thermal scale of the link lengths)")


def add_parser(sub):
    parser = command_parser(
        sub, "recalibrate",
        "Light re-calibration: from some 30 rows measured in a later campaign (trajcomp plan --update chooses "
        "them), re-identify what drifts between campaigns: " + GROUP_WORDS + ", keeping the model's joint-error "
        "curves and residual field. Prints what changed, by how much and with what standard deviation, the "
        "rows' residual before and after (each region of them also predicted from the others) and the verdict of "
        "`trajcomp check`; writes the updated model, its report's update section recording the updated "
        "parameters' covariance. An update the rows cannot identify is refused (exit 2).",
        "trajcomp plan --update model.yaml --candidates plan.csv --count 30 -o update-plan.csv",
        "trajcomp recalibrate model.yaml validation.csv -o model-updated.yaml",
    )
    add_rows_arguments(parser)
    parser.add_argument("-o", "--output", required=True, help="updated model file to write (.yaml)")
    parser.set_defaults(run=run)


def add_rows_arguments(parser):
    """The model, the campaign's rows and their layout (shared with check)."""
    parser.add_argument("model", help="model file from `trajcomp calibrate` (mode composite)")
    parser.add_argument("rows", help="measurement CSV of the new campaign (mx, my, mz; 6-DoF: mrx, mry, mrz)")
    add_layout(parser)
    parser.add_argument("--frame", choices=("base", "tracker"),
                        help="frame of the measured columns (default: as the layout file says, else base)")
    parser.add_argument("--only", metavar="GROUP[,GROUP]",
                        help="update these groups only (default all): " + GROUP_WORDS)


def update_of(args, groups=None):
    """The `trajcomp.calibration.recalibrate.Update` of the command line's model and rows."""
    import numpy as np

    from trajcomp.arm.transforms import abc_to_matrix
    from trajcomp.calibration.calibrate import commanded, register
    from trajcomp.calibration.measurements import read_measurements
    from trajcomp.calibration.recalibrate import GROUPS, update
    from trajcomp.commands.validate import check_data
    from trajcomp.errors import CalibrationError
    from trajcomp.model.model_file import load_model

    model = load_model(args.model)
    meas = read_measurements(args.rows, layout_of(args))
    meas.require_measured()
    frame = args.frame or meas.frame or "base"
    joints, position = commanded(model.nominal, meas)
    if joints is None:
        raise CalibrationError(f"{args.rows}: an update needs the commanded joints j1..j6 or full poses x..c")
    if "composite" not in model.modes:
        raise CalibrationError(f"{args.model}: an update needs a model with mode composite (this one has "
                               f"{', '.join(model.modes)})")
    tracker = frame == "tracker"
    try:  # implausible rows (wrong units, another robot) are refused before any fit
        check_data(model, meas, register(model, joints, position, meas.measured) if tracker else np.eye(4), frame)
        rotation = None if meas.measured_orientation is None else abc_to_matrix(meas.measured_orientation)
        return update(model, joints, position, meas.measured, rotation, groups or GROUPS, tracker=tracker,
                      temperature=meas.temperature)
    except CalibrationError as exc:
        raise exc if str(args.rows) in str(exc) else type(exc)(f"{args.rows}: {exc}") from None


def groups_of(text):
    """The update groups of ``--only`` (None: all)."""
    from trajcomp.calibration.recalibrate import GROUPS
    from trajcomp.errors import TrajcompError

    if text is None:
        return None
    groups = tuple(g.strip() for g in text.split(",") if g.strip())
    unknown = [g for g in groups if g not in GROUPS]
    if unknown or not groups:
        raise TrajcompError(f"--only: expected groups of {', '.join(GROUPS)}, got {text!r}")
    return groups


def held(value):
    """A held-out mean, or why there is none."""
    return "not identified by a part of the rows" if value is None else f"{value:.4f}"


def run(args):
    from trajcomp.model.model_file import model_files, save_model
    from trajcomp.support.atomic import refuse_inputs

    refuse_inputs(model_files(args.output), [*model_files(args.model), args.rows, args.columns_file])
    result = update_of(args, groups_of(args.only))
    record = result.record()
    print(f"{args.rows}: {record['rows']} rows; updated {len(record['names'])} parameters (value +- standard "
          "deviation):")
    for name, value, sigma, unit in result.changes():
        print(f"  {name:10s} {value:+12.4f} +- {sigma:8.4f} {unit}")
    print("the rows' mean |residual| mm (in brackets: each region of the rows predicted from the others): "
          + ", ".join(f"{label} {record[key]['fit']:.4f} ({held(record[key]['held_out'])})" for label, key in
                      (("as the model is", "as_is_mm"), ("registered anew", "registered_mm"),
                       ("updated", "updated_mm"), ("corrected", "corrected_mm"))
                      if (key != "registered_mm" or "base_x" in record["names"]) and record[key] is not None))
    if record["temperature_c"]:
        change = record["temperature_c"]
        print(f"temperature: {change['rows']:.2f} deg C at the rows, {change['model']:.2f} at the model's measurements "
              f"({change['change']:+.2f} K)" + ("" if record["scale_ppm_per_k"] is None else
                                                f": the scale is {record['scale_ppm_per_k']:+.1f} ppm/K (aluminium "
                                                "expands about 23 ppm/K)"))
    print(f"position uncertainty the update adds: {record['added_sigma_mm']['mean']:.4f} mm per axis on average at "
          f"these rows (max {record['added_sigma_mm']['max']:.4f})")
    print({"update": "the rows show the drift: the model written takes the update",
           "registration": "the rows do not show the drift (the update does not predict each region of them "
                           "from the others significantly better): the model written is the model as it was, "
                           "registered anew",
           "none": "the rows show neither drift nor a moved tracker: the model written is the model as it was"}[
              record["applied"]])
    if record["correction"]:
        correction = record["correction"]
        print(f"the model written takes a correction of what the update leaves at the {correction['rows']} rows "
              f"(kriging over commanded positions, correlation length {correction['length_mm']:g} mm, nugget "
              f"{correction['nugget']:g}): it predicts each region of the rows from the others significantly better, "
              "and returns to zero away from the rows")
    print(record["verdict_reason"])
    save_model(args.output, result.model)
    info(f"wrote {args.output}")
    return 0
