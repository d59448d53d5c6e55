"""``trajcomp robots``: list the built-in robots."""

import argparse

import numpy as np

from trajcomp.robot import builtin_robot_names, load_robot


def add_parser(sub):
    parser = sub.add_parser(
        "robots",
        help="list the built-in robots",
        description="List the built-in robots with their joint ranges and data sheets.",
        epilog="example:\n  trajcomp robots",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.set_defaults(run=run)


def run(args):
    for name in builtin_robot_names():
        robot = load_robot(name)
        reach = np.abs(robot.a).sum() + np.abs(robot.d[1:]).sum()
        print(f"{name:20s} {robot.convention:8s} reach ~{reach:5.0f} mm  {robot.source}")
    return 0
