"""Figures of the paper, one module per figure, sharing :mod:`._style`.

Each module has a ``table_*`` function (the numbers behind the figure, also
written as CSV) and a ``plot_*`` function returning a Matplotlib figure.
"""
