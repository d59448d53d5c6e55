"""``trajcomp demo``: the paper's protocol on the virtual robot, then a program."""

from pathlib import Path

from trajcomp.calibration.profiles import PAPER_ROBOT, PROFILES
from trajcomp.commands._args import command_parser, info, non_negative_int


def add_parser(sub):
    parser = command_parser(
        sub, "demo",
        "Calibrate a virtual arm on the paper's two grids (100 mm and 10 mm steps on its "
        "UR10; scaled to the reach of any other arm, which the output names), validate "
        "compensation at 40 random targets per cube in every mode, print the paper's table "
        "beside ours, write the models, then compensate an example program with the "
        "large-cube model and run it on the virtual arm.",
        "trajcomp demo -o trajcomp-demo",
        "trajcomp demo --robot kuka_kr6_r900 --profile harsh -o trajcomp-demo/kuka-harsh",
    )
    parser.add_argument("--robot", default=PAPER_ROBOT, help=f"robot (default {PAPER_ROBOT}, the paper's arm class)")
    parser.add_argument("--profile", choices=sorted(PROFILES), default="paper", help="error profile (default paper)")
    parser.add_argument("--seed", type=non_negative_int, default=1, help="seed of the virtual robot (default 1)")
    parser.add_argument("-o", "--output-dir", default="trajcomp-demo", help="folder for the models and the program (default trajcomp-demo)")
    parser.set_defaults(run=run)


def run(args):
    from trajcomp.arm.robot import load_robot
    from trajcomp.paper_protocol import format_comparison, run_demo, run_program
    from trajcomp.model.model_file import save_model

    robot = load_robot(args.robot)
    out = Path(args.output_dir)
    out.mkdir(parents=True, exist_ok=True)
    virtual, results = run_demo(robot, args.profile, args.seed, progress=info, robot_ref=args.robot)
    print(f"virtual {robot.name}, profile {args.profile}, seed {args.seed}: compensation validated at 40 random targets per cube")
    for result in results:
        print(f"  {result.cube}")
    print(format_comparison(results, virtual.profile.noise_sigma))
    for result in results:
        path = out / f"model-{result.cube.name}.yaml"
        save_model(path, result.model)
        info(f"wrote {path} ({result.points} grid points)")
    landing = run_program(virtual, results[0], out)
    print(f"example program {out / 'program.csv'} -> {out / 'program-compensated.csv'} "
          "(composite, large-cube model; landing error without repeatability noise):")
    for label, stats in landing.items():
        print(f"  {label:12s} lands {stats.summary()} from its targets")
    return 0
