"""Argument types of the command line, shared by every command.

Each raises :class:`argparse.ArgumentTypeError` with the bad text, which
argparse prints as a usage error naming the option (exit 2).

Examples
--------
>>> positive("2.5"), non_negative_int("0"), unit_interval("0.5")
(2.5, 0, 0.5)
>>> positive("-1")
Traceback (most recent call last):
argparse.ArgumentTypeError: must be > 0, got -1
>>> refinement("1.5")
Traceback (most recent call last):
argparse.ArgumentTypeError: must be a number in [0.25, 1] or a whole number from 2 to 8, got 1.5
"""

from __future__ import annotations

import argparse
import math

__all__ = ["number", "positive", "non_negative", "negative", "non_negative_int",
           "positive_int", "refinement", "unit_interval", "open_unit_interval"]


def number(text: str) -> float:
    """argparse type: a finite number."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"not a finite number: {text!r}")
    return value


def positive(text: str) -> float:
    """argparse type: a number > 0."""
    value = number(text)
    if value <= 0:
        raise argparse.ArgumentTypeError(f"must be > 0, got {text}")
    return value


def non_negative(text: str) -> float:
    """argparse type: a number >= 0."""
    value = number(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"must be >= 0, got {text}")
    return value


def negative(text: str) -> float:
    """argparse type: a number < 0 (a BIC difference a cause must reach)."""
    value = number(text)
    if not value < 0:
        raise argparse.ArgumentTypeError(f"must be negative, got {text}")
    return value


def _whole_number(text: str, minimum: int) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a whole number: {text!r}") from None
    if value < minimum:
        raise argparse.ArgumentTypeError(f"must be >= {minimum}, got {text}")
    return value


def non_negative_int(text: str) -> int:
    """argparse type: an integer >= 0 (seeds)."""
    return _whole_number(text, 0)


def refinement(text: str) -> float:
    """argparse type: a mesh density factor in [0.25, 1] or a whole number 2..8 (the schema's)."""
    value = positive(text)
    if 0.25 <= value <= 1 or (value == int(value) and 2 <= value <= 8):
        return value
    raise argparse.ArgumentTypeError(
        f"must be a number in [0.25, 1] or a whole number from 2 to 8, got {text}")


def unit_interval(text: str) -> float:
    """argparse type: a number in [0, 1]."""
    value = number(text)
    if not 0 <= value <= 1:
        raise argparse.ArgumentTypeError(f"must lie in [0, 1], got {text}")
    return value


def positive_int(text: str) -> int:
    """argparse type: an integer >= 1."""
    return _whole_number(text, 1)


def open_unit_interval(text: str) -> float:
    """argparse type: a number in (0, 1) (a confidence level, a test's level)."""
    value = positive(text)
    if not value < 1:
        raise argparse.ArgumentTypeError(f"must lie in (0, 1), got {text}")
    return value
