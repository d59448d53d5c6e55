"""Kinematics throughput per core: FK, closed-form IK, numerical IK on an identified model.

Run as ``python tests/benchmarks/bench_kinematics.py [N]`` (default N = 100,000
poses per batch; the numerical IK uses N / 10). Threads are pinned to one so
the numbers are per core. Each figure is the best of three runs, in poses per
second.
"""

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMEXPR_NUM_THREADS"):
    os.environ[_var] = "1"

import sys  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from trajcomp.arm.ik import ik, ik_all, ik_near, ik_numeric  # noqa: E402
from trajcomp.arm.kinematics import fk, jacobian  # noqa: E402
from trajcomp.arm.robot import builtin_robot_names, load_robot  # noqa: E402

REPEATS = 3


def rate(n, work):
    """Best-of-REPEATS throughput (items per second) of ``work()`` handling n items."""
    best = min(_timed(work) for _ in range(REPEATS))
    return n / best


def _timed(work):
    start = time.perf_counter()
    work()
    return time.perf_counter() - start


def identified(robot, rng):
    """The nominal arm with DH deltas of a typical identification (0.5 mm, 0.05 deg)."""
    angle = np.radians(0.05)
    return robot.replace(
        a=robot.a + rng.normal(0, 0.5, 6),
        d=robot.d + rng.normal(0, 0.5, 6),
        alpha=robot.alpha + rng.normal(0, angle, 6),
        theta_offset=robot.theta_offset + rng.normal(0, angle, 6),
    )


def main(n):
    columns = ("robot", "FK", "Jacobian", "ik_all (8 br.)", "ik (verified)", "ik_numeric", "ik_near", "near ok")
    print(f"poses/s on one core; FK/Jacobian/closed form N = {n}, numerical N = {n // 10}")
    print("".join(f"{c:>16}" for c in columns))
    for name in builtin_robot_names():
        robot = load_robot(name)
        rng = np.random.default_rng(0)
        q = rng.uniform(robot.q_min + 0.05, robot.q_max - 0.05, (n, 6))
        T = fk(robot, q)
        real = identified(robot, rng)
        m = n // 10
        T_real = fk(real, q[:m])
        start = ik(robot, T_real, seed=q[:m]).q
        near = ik_near(real, robot, T_real, seed=q[:m])
        row = [
            rate(n, lambda: fk(robot, q)),
            rate(n, lambda: jacobian(robot, q)),
            rate(n, lambda: ik_all(robot, T, seed=q)),
            rate(n, lambda: ik(robot, T, seed=q)),
            rate(m, lambda: ik_numeric(real, T_real, start)),
            rate(m, lambda: ik_near(real, robot, T_real, seed=q[:m])),
        ]
        print(f"{name:>16}" + "".join(f"{value:>16,.0f}" for value in row) + f"{near.success.mean():>16.4f}")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 100_000)
