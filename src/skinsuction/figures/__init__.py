"""Figures of the paper, one module per figure, sharing :mod:`._style`.

Each module has a ``table_*`` function (the numbers behind the figure, also
written as CSV) and a ``plot_*`` function returning a Matplotlib figure.

The shared look is public here, for the reports of the other packages
(identification, diagnosis, the paper's figures):

* :func:`save_figure` saves a figure atomically and reproducibly (no time stamps:
  the same data give the same bytes);
* :func:`figure_style` is the context of the study's Matplotlib settings
  (:data:`RC`), :func:`panel_label` writes ``(a)`` on a panel, :data:`WIDTH_IN` is
  the width of a two-column figure and :data:`BOTTOM_STYLE` the look of each
  boundary condition.

They are imported on first use, so ``import skinsuction.figures.tables`` does not
load Matplotlib.

Examples
--------
>>> import tempfile, pathlib
>>> from skinsuction.figures import figure_style, save_figure
>>> import matplotlib.pyplot as plt
>>> with figure_style():
...     fig, ax = plt.subplots()
>>> png = pathlib.Path(tempfile.mkdtemp()) / "f.png"
>>> save_figure(fig, png)
>>> png.exists()
True
>>> plt.close(fig)
"""

#: public name -> name in :mod:`._style`
_STYLE = {"save_figure": "save", "figure_style": "style", "panel_label": "panel_label",
          "WIDTH_IN": "WIDTH_IN", "BOTTOM_STYLE": "BOTTOM_STYLE", "RC": "RC"}

__all__ = sorted(_STYLE)


def __getattr__(name):
    if name in _STYLE:
        from . import _style

        value = getattr(_style, _STYLE[name])
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_STYLE))
