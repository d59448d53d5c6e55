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


def progress(total, *, desc, unit="it", stream=None, delay=DELAY, enabled=True):
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
    enabled : bool
        False: never drawn (e.g. inside a batch that shows its own bar).

    Returns
    -------
    tqdm.tqdm
        Use as a context manager and call ``update(n)`` after each piece of
        work; disabled (draws nothing) when ``stream`` is not a terminal.
    """
    from tqdm import tqdm  # imported here: the CLI starts without it

    stream = sys.stderr if stream is None else stream
    return tqdm(total=total, desc=desc, unit=unit, file=stream, delay=delay,
                dynamic_ncols=True, disable=not (enabled and is_terminal(stream)))


class Stages:
    """A progress bar over the named stages of one run (`progress`): call ``advance()`` as each stage ends.

    The bar names the stage running (``weld.csv: re-time``); a program of
    a million points spends tens of seconds in each.

    Parameters
    ----------
    names : sequence of str
        The stages in the order they run.
    desc : str
        What runs (e.g. the file name).
    **options
        ``stream``, ``delay``, ``enabled`` of `progress`.
    """

    def __init__(self, names, *, desc, **options):
        self.names, self.desc = tuple(names), desc
        self.bar = progress(len(self.names), desc=f"{desc}: {self.names[0]}", unit="stage", **options)

    def __enter__(self):
        self.bar.__enter__()
        return self

    def __exit__(self, *exc):
        return self.bar.__exit__(*exc)

    def advance(self):
        """End the running stage; the bar names the next one."""
        done = self.bar.n + 1
        if done < len(self.names):
            self.bar.set_description_str(f"{self.desc}: {self.names[done]}", refresh=False)
        self.bar.update(1)


def is_terminal(stream):
    """True when ``stream`` is an open terminal."""
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):  # no isatty, or a closed file
        return False
