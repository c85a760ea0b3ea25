"""Sentences written by the code, so that a figure the notebook computes reaches its prose only
through the code.

``display(Markdown(f"... {value:.2f} m ..."))`` typesets the sentence in Jupyter and on the site;
run as a script (``python notebooks/NN_x.py``), IPython's ``display`` prints ``str`` of what it
is given, so :class:`Markdown` here prints its text instead of an object's repr.
"""

from __future__ import annotations

from IPython.display import Markdown as _IPythonMarkdown


class Markdown(_IPythonMarkdown):
    """IPython's Markdown, whose plain-text form is the sentence itself."""

    def __str__(self) -> str:
        return self.data
