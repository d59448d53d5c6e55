"""Compensate a robot program file with a model, from Python.

Reads the program in its language (CSV, KRL, RAPID, FANUC LS, URScript or a
plugin format), replaces every Cartesian target by its command in the
posture the program declares, re-times it and writes it back in the same
language with its verdict, as `trajcomp compensate` does.

    python examples/02_filter_program.py [model.yaml [program [output]]]

Defaults: a UR10-class virtual arm calibrated on the paper's large cube
(trajcomp.paper_protocol), examples/ur10_path.csv, and the output
ur10_path_compensated.csv in the current folder.
"""

import sys
from pathlib import Path

import numpy as np

import trajcomp
from trajcomp.paper_protocol import PAPER_CUBES, run_cube
from trajcomp.arm.robot import load_robot
from trajcomp.calibration.virtual_arm import VirtualRobot

PROGRAM = Path(__file__).with_name("ur10_path.csv")


def main(model_path=None, program=PROGRAM, output=None):
    if model_path is None:
        model_path = run_cube(VirtualRobot.create(load_robot("ur10"), "paper", seed=1), PAPER_CUBES[0]).model
    program = Path(program)
    output = Path(output or f"{program.stem}_compensated{program.suffix}")
    run = trajcomp.filter_program(program, output, model=model_path)
    report = run.report

    size = np.linalg.norm(report.correction[:, :3], axis=1)
    print(f"{program} -> {', '.join(map(str, run.written))}: {'PASS' if run.passed else 'FAIL'}")
    print(f"{len(report.labels)} targets compensated, corrections {size.min():.3f} to {size.max():.3f} mm; "
          f"postures: {', '.join(sorted(set(report.posture_source)))}")
    for line in report.lines_of_text()[1:]:
        print(line)


if __name__ == "__main__":
    main(*sys.argv[1:4])
