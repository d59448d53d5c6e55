"""Numpy values as plain Python data, for the YAML of model files and the JSON of reports."""

import math

import numpy as np


def plain(value, *, non_finite_as_none=False):
    """``value`` with numpy scalars and arrays as Python numbers and lists, mapping keys as str.

    Parameters
    ----------
    value : any
        Nested dicts, lists and tuples of numbers, arrays, str, bool, None.
    non_finite_as_none : bool
        Turn NaN and infinite floats into None (JSON has no such numbers;
        YAML states them as ``.nan`` and ``.inf``).
    """
    if isinstance(value, dict):
        return {str(k): plain(v, non_finite_as_none=non_finite_as_none) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [plain(v, non_finite_as_none=non_finite_as_none) for v in value]
    if isinstance(value, np.ndarray):
        return plain(value.tolist(), non_finite_as_none=non_finite_as_none)
    if isinstance(value, np.generic):
        value = value.item()
    if non_finite_as_none and isinstance(value, float) and not math.isfinite(value):
        return None
    return value
