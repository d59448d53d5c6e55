"""BLAS / OpenMP threads: one per process of a run unless the user set the thread variables.

The linear algebra here is many small products (normal equations of a few
hundred parameters, thousands of 4 x 4 poses): threads of their own only
fight the run's worker processes and whatever else shares the machine
(calibrating 5,892 measurements beside one CPU-bound process took 30-49 s
with OpenBLAS's threads, 13-18 s without). The libraries read the thread
variables when they load: the CLI sets them before numpy loads
(`THREAD_VARIABLES`); a worker process forked from a process that loaded
numpy with its own threads (an application calling the API with
``workers``) limits the libraries it inherited (`pin_loaded`).
"""

import os

THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")  # read when numpy loads


def pin_loaded():
    """Limit the BLAS and OpenMP libraries this process has loaded to one thread, unless the user set
    `THREAD_VARIABLES` (then they govern, as they did when the libraries loaded)."""
    if any(name in os.environ for name in THREAD_VARIABLES):
        return
    from threadpoolctl import threadpool_limits  # here: only a worker of a process without the variables needs it

    threadpool_limits(1)
