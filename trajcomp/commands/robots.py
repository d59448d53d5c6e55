"""``trajcomp robots``: list the built-in robots."""

from trajcomp.commands._args import command_parser


def add_parser(sub):
    parser = command_parser(
        sub, "robots",
        "List the built-in robots with their DH convention and data sheet.",
        "trajcomp robots",
    )
    parser.set_defaults(run=run)


def run(args):
    from trajcomp.arm.robot import builtin_robot_names, load_robot

    for name in builtin_robot_names():
        robot = load_robot(name)
        print(f"{name:20s} {robot.convention:8s} {robot.source}")
    return 0
