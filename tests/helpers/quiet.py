"""Calls whose warnings (unconverged cells, integration notices) a test does not look at."""

from __future__ import annotations

import warnings


def quietly(function, *args, **kwargs):
    """``function(*args, **kwargs)`` with every warning ignored."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return function(*args, **kwargs)
