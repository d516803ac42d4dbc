"""Errors that name a bad input: the command line prints them as one line (exit 2)."""

__all__ = ["InputError"]


class InputError(ValueError):
    """An input (a space file, a choice of curves, an option) is unusable.

    The message names the file, row or key and what to do; it is meant for the
    user, not a traceback.
    """
