"""The demo on every built-in arm and error profile: does composite reach the noise floor?

Run:  python tests/benchmarks/bench_demo.py

For each robot and profile (seed 1, as `trajcomp demo`): the cubes the demo
chose, the mean |error| at the 40 validation targets per cube without
compensation and with composite compensation, beside the noise floor of one
measured point (mean |noise| = sigma * sqrt(8 / pi)), and the run time.
A run the library refuses (e.g. calibration rejects the grid) is listed
with its message instead of numbers.
"""

import time

import numpy as np

from trajcomp.paper_protocol import run_demo
from trajcomp.errors import TrajcompError
from trajcomp.arm.robot import builtin_robot_names, load_robot
from trajcomp.calibration.virtual_arm import PROFILES


def main():
    print(f"{'robot':18s} {'profile':7s} {'cube':6s} {'corner':>16s} {'side':>5s} {'step':>5s} "
          f"{'none':>8s} {'composite':>10s} {'floor':>8s} {'time':>6s}   (mm, s)")
    for name in builtin_robot_names():
        robot = load_robot(name)
        for profile in PROFILES:
            start = time.perf_counter()
            try:
                virtual, results = run_demo(robot, profile)
            except TrajcompError as exc:
                print(f"{name:18s} {profile:7s} refused: {exc}")
                continue
            elapsed = time.perf_counter() - start
            floor = virtual.profile.noise_sigma * np.sqrt(8.0 / np.pi)
            for result in results:
                cube = result.cube
                corner = ",".join(f"{v:g}" for v in cube.corner)
                print(f"{name:18s} {profile:7s} {cube.name:6s} {corner:>16s} {cube.side:5g} {cube.step:5g} "
                      f"{result.stats['none'].mean:8.4f} {result.stats['composite'].mean:10.4f} {floor:8.4f} "
                      f"{elapsed:6.1f}")


if __name__ == "__main__":
    main()
