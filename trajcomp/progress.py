"""Progress bars on stderr for long runs: shown on a terminal, silent in pipelines.

A bar appears only when its stream is a terminal and the work lasts longer
than `DELAY`; in a pipeline, a CI log or a redirected stderr the same object
counts silently, so callers never branch on where their output goes::

    with progress(len(targets), desc="compensate", unit="target") as bar:
        for chunk in chunks:
            ...
            bar.update(len(chunk))
"""

import sys

DELAY = 0.5  # s: runs shorter than this never show a bar


def progress(total, *, desc, unit="it", stream=None, delay=DELAY):
    """A progress bar counting ``total`` units of work.

    Parameters
    ----------
    total : int
        Units of work (e.g. targets) the run will report with ``update``.
    desc : str
        What runs, shown before the bar (e.g. ``"compensate"``).
    unit : str
        Name of one unit, shown with the rate (``"target"`` -> ``target/s``).
    stream : file-like, optional
        Where the bar is drawn; default ``sys.stderr``.
    delay : float
        Seconds before the bar first appears, s.

    Returns
    -------
    tqdm.tqdm
        Use as a context manager and call ``update(n)`` after each piece of
        work; disabled (draws nothing) when ``stream`` is not a terminal.
    """
    from tqdm import tqdm  # imported here: the CLI starts without it

    stream = sys.stderr if stream is None else stream
    return tqdm(total=total, desc=desc, unit=unit, file=stream, delay=delay,
                dynamic_ncols=True, disable=not is_terminal(stream))


def is_terminal(stream):
    """True when ``stream`` is an open terminal."""
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):  # no isatty, or a closed file
        return False
