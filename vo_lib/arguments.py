"""Command-line arguments of ``python -m vo_lib``: errors in one line (``PROG: error: MESSAGE``, exit
status 2, without argparse's usage block), counts checked as they parse.
"""

from __future__ import annotations

import argparse
import re


class UsageError(ValueError):
    """A bad argument or bad input: reported by the command line in one line, exit status 2."""


class OneLineParser(argparse.ArgumentParser):
    """argparse with errors in one line, exit 2 (or raised as :attr:`raises`, set by a subclass)."""

    #: The exception class an error is raised as, or None to print it and exit with status 2.
    raises: type[Exception] | None = None

    def __init__(self, *args, **kwargs):
        kwargs.setdefault("allow_abbrev", False)  # --frame is a typo, not --frames
        super().__init__(*args, **kwargs)
        # a value such as ``-1,2`` or ``-1e3`` is a value (which its type then judges), not an option
        self._negative_number_matcher = re.compile(r"^-\.?\d[\d.,eE+-]*$")

    def error(self, message: str):
        if self.raises is not None:
            raise self.raises(message)
        self.exit(2, f"{self.prog}: error: {message}\n")


def one_line(text) -> str:
    """``text`` (an exception, a message) as one line: lines and runs of spaces joined by one space."""
    return " ".join(str(text).split())


def count_at_least(minimum: int, what: str, maximum: int | None = None):
    """An argparse ``type``: a whole number ``>= minimum`` (and ``<= maximum``), ``what`` in errors."""
    bounds = f">= {minimum}" if maximum is None else f"from {minimum} to {maximum}"

    def parse(text: str) -> int:
        shown = text if len(text) <= 40 else f"{text[:20]}...({len(text)} characters)"
        try:
            value = int(text[:40])  # no count has 40 digits; int() refuses over 4,300 with another message
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a whole number ({what}); got {shown!r}") from None
        if len(text) > 40 or value < minimum or (maximum is not None and value > maximum):
            raise argparse.ArgumentTypeError(f"expected a whole number {bounds} ({what}); got {shown!r}")
        return value

    return parse


def non_empty(what: str):
    """An argparse ``type`` refusing an empty text (a path given as ``''``); ``what`` names it."""

    def parse(text: str) -> str:
        if not text.strip():
            raise argparse.ArgumentTypeError(f"expected {what}; got an empty text")
        return text

    return parse
